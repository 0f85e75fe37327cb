"""Clustering of predicted failures, to discover *sources* of stereo error (paper §V).

Pipeline, with the paper's choices and where the reference code differed:

1. **Selection**: samples the model *predicts* FP or FN, keeping the top 50 % by
   confidence (predicted-class mean probability, median split) of the
   predicted FP and, apart, of the predicted FN (at k = 2 the clusters tend
   to be those two halves, and the report says when they are). The paper
   keeps "the top 50 % most confident" failures; pooled (``--select
   confidence``), the less confident class can all but vanish (JPP-C's FN in
   the default main job: 16 among 1902 selected; the dense model's FN are the
   more confident class), and with it the cluster of misses the paper found
   beside the reflections. The reference script kept
   var_predicted <= 0.03 instead (0.005 at HEAD); ``--select variance``
   reproduces that, and the report counts it beside the rule used.
2. **Embedding**: the 256-d post-ReLU FC2 activation (embeddings.f32). The
   reference softmax-normalised it over the 256 dims; we L2-normalise by default
   (``--embedding-norm``): the direction of the activation pattern is what
   separates failure sources, and unit length makes the mosaic weight
   1/(0.1 + distance) meaningful (raw activations have distances of tens, which
   flattens the weights). softmax and none are available for comparison.
3. **PCA** to a tenth of the dimension (256 -> 26) as the paper says; the reference
   used 20 (paper era) or 50 (HEAD).
4. **k-means** (k = 2 by default, random_state 0, 10 restarts) in the normalised
   256-d embedding space, as the paper and the paper-era script do; PCA and t-SNE
   are only for viewing. ``--cluster-space pca`` clusters the 26-d PCA scores
   instead (less noise, nearly the same Euclidean geometry).
5. **t-SNE** to 2-D (perplexity 40, 500 iterations instead of the reference's
   300, random_state 0) on the PCA scores, on at most ``tsne_max`` points drawn
   with a fixed seed, to keep it fast on a 2-core machine. On the probe data
   (1367 points) the KL divergence is 0.85 after 300 iterations, 0.53 after
   500 and 0.50 after 1000 (twice the time): 500 is converged enough for a
   picture; the report prints the final KL divergence.
6. **Mosaics**: per cluster, up to 50 patches sampled without replacement with
   weight 1/(0.1 + distance to the cluster centre), as in the reference.
"""

from __future__ import annotations

import contextlib
import inspect
import warnings
from collections import Counter
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple, Union

import numpy as np
from sklearn.cluster import KMeans
from sklearn.decomposition import PCA
from sklearn.manifold import TSNE
from sklearn.metrics import adjusted_rand_score, normalized_mutual_info_score

from report_inputs import FN, FP, LABEL_NAMES, NO_CAUSE, ONLY_TOGETHER, EvalRun

try:
    from threadpoolctl import threadpool_limits  # a scikit-learn dependency
except ImportError:  # pragma: no cover
    threadpool_limits = None

REFERENCE_VAR_CUT = 0.03      # paper-era reference script's selection
MOSAIC_ROWS, MOSAIC_COLS = 5, 10


@dataclass
class ClusterOptions:
    """Knobs of the clustering step (command-line options)."""
    k: int = 2
    select: str = "confidence-per-class"  # the confident half of the predicted FP and of the predicted FN;
                                          # "confidence": of both pooled; "variance": var <= 0.03 (reference)
    embedding_norm: str = "l2"          # "l2", "softmax" (reference), "none"
    space: str = "embedding"            # where k-means runs: "embedding" (paper) or "pca"
    tsne_max: int = 3000
    perplexity: float = 40.0
    tsne_iterations: int = 500
    seed: int = 0
    threads: int = 1                    # OpenMP threads for t-SNE / k-means
    k_scan: Tuple[int, ...] = (2, 3, 4, 6, 8)  # other k to report purity for (simulated data)


@dataclass
class ClusterResult:
    """What the clustering found, or why it could not run (``message``)."""
    ok: bool
    message: str = ""
    n_predicted_fp: int = 0
    n_predicted_fn: int = 0
    n_selected: int = 0
    confidence_cut: Union[None, float, Dict[str, Optional[float]]] = None  # per class: {"FP": .., "FN": ..}
    n_reference_rule: int = 0
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))   # selected rows of predictions.csv
    pca_components: int = 0
    pca_explained: float = 0.0
    cluster: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # cluster id per selected row
    distance: np.ndarray = field(default_factory=lambda: np.zeros(0))           # to its cluster centre
    tsne_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # into rows
    tsne_xy: Optional[np.ndarray] = None
    tsne_note: str = ""
    tsne_kl: Optional[float] = None
    clusters: List[dict] = field(default_factory=list)
    purity: Optional[float] = None
    purity_one_cluster: Optional[float] = None  # the same with every sample in one cluster (base rate)
    nmi: Optional[float] = None
    ari: Optional[float] = None
    # Purity at other k (k, purity, nmi, best possible purity with k clusters).
    k_scan: List[dict] = field(default_factory=list)
    mosaic_rows: Dict[int, np.ndarray] = field(default_factory=dict)
    has_truth: bool = False
    # By cause (ivoa-sim-causes): over the clustered samples that are true
    # failures with a known cause; None without causes.
    n_with_cause: int = 0
    cause_purity: Optional[float] = None           # by each cluster's leading cause
    cause_purity_one_cluster: Optional[float] = None  # the same with every sample in one cluster (base rate)
    cause_set_purity: Optional[float] = None       # by exact cause set (strict)
    cause_set_best_possible: Optional[float] = None
    cause_nmi: Optional[float] = None              # with the exact cause set


def normalise_embeddings(x: np.ndarray, how: str) -> np.ndarray:
    """Row-normalises FC2 activations (see module doc for why L2 by default)."""
    x = np.asarray(x, dtype=np.float64)
    if how == "l2":
        return x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-12)
    if how == "softmax":
        z = np.exp(x - x.max(axis=1, keepdims=True))
        return z / z.sum(axis=1, keepdims=True)
    if how == "none":
        return x
    raise ValueError(f"unknown embedding normalisation '{how}'")


def _more_confident_half(run: EvalRun, rows: np.ndarray):
    """The ceil(n/2) rows of the highest predicted-class probability (ranked,
    so exactly that many even with ties) and the lowest probability kept."""
    conf = run.probs[rows, run.predicted[rows]]
    order = np.argsort(-conf, kind="mergesort")
    n_keep = int(np.ceil(len(rows) / 2))
    return rows[order[:n_keep]], (float(conf[order[n_keep - 1]]) if n_keep else None)


def select_failures(run: EvalRun, select: str):
    """Rows predicted FP or FN that pass the selection rule, plus the cut used
    (for per-class, a dict of the FP and FN cuts).

    confidence: the predicted-class probability at or above the median of the
    predicted failures; confidence-per-class: the same split within the
    predicted FP and within the predicted FN, so that the less confident class
    is not left out; variance: var_predicted <= 0.03
    (reference script)."""
    failures = np.flatnonzero((run.predicted == FP) | (run.predicted == FN))
    if select == "variance":
        keep = failures[run.var_predicted[failures] <= REFERENCE_VAR_CUT]
        return keep, REFERENCE_VAR_CUT
    if select == "confidence-per-class":
        halves = {LABEL_NAMES[c]: _more_confident_half(run, np.flatnonzero(run.predicted == c)) for c in (FP, FN)}
        keep = np.concatenate([rows for rows, _ in halves.values()])
        return np.sort(keep), {name: cut for name, (_, cut) in halves.items()}
    keep, cut = _more_confident_half(run, failures)
    return np.sort(keep), cut


def _tsne(x: np.ndarray, perplexity: float, iterations: int, seed: int):
    """t-SNE 2-D, returning (points, final KL divergence); the iteration
    argument is n_iter before scikit-learn 1.5 and max_iter after, so pass
    whichever this version has."""
    params = inspect.signature(TSNE).parameters
    kw = {"max_iter": iterations} if "max_iter" in params else {"n_iter": iterations}
    tsne = TSNE(n_components=2, perplexity=perplexity, init="pca", learning_rate="auto",
                random_state=seed, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        xy = tsne.fit_transform(x)
    return xy, float(tsne.kl_divergence_)


def _composition(values: np.ndarray) -> Dict[int, int]:
    """Counts per code, most common first."""
    return dict(Counter(values.tolist()).most_common())


def _phenomena_present(bits: np.ndarray, overall: Dict[int, float]) -> List[dict]:
    """For each phenomenon present under some members' patch centre: the share
    of members that have it and its over-representation against all clustered
    failures (lift). Phenomena co-occur (a polished floor is texture-less and
    reflects), so this says what sets a cluster apart where the single
    dominant phenomenon cannot. Most over-represented first."""
    out = []
    for code, base in overall.items():
        share = float(np.mean((bits & code) != 0)) if len(bits) else 0.0
        if share > 0:
            out.append({"phenomenon": code, "share": share, "lift": share / base if base > 0 else None})
    return sorted(out, key=lambda e: -(e["lift"] or 0))


def _purity(phen: np.ndarray, cluster: np.ndarray) -> float:
    """Share of samples in their cluster's most common phenomenon."""
    return sum(Counter(phen[cluster == c].tolist()).most_common(1)[0][1] for c in np.unique(cluster)) / len(phen)


def _explained_by(cause: np.ndarray, code: int) -> np.ndarray:
    """Which failures `code` explains: a phenomenon bit explains those whose
    removal of it alone fixes them (it is in their cause set); 'none found' (0)
    and 'only together' explain only themselves."""
    if code in (0, ONLY_TOGETHER):
        return cause == code
    return (cause != ONLY_TOGETHER) & ((cause & code) != 0)


def _leading_cause(cause: np.ndarray):
    """(code, count) of the cause explaining the most of `cause`."""
    single = cause != ONLY_TOGETHER
    codes = {0, ONLY_TOGETHER} | {1 << b for b in range(7) if np.any(single & (((cause >> b) & 1) == 1))}
    counts = {c: int(_explained_by(cause, c).sum()) for c in sorted(codes)}
    return max(counts.items(), key=lambda kv: kv[1])


def _cause_composition(res: ClusterResult, cause: np.ndarray, k: int) -> None:
    """Composition and purity of the clusters by what ivoa-sim-causes found
    causes each failure, over the clustered samples that are true failures
    with a known cause. The presence-based purity asks which phenomenon covers
    most of the patch; this asks which one made the detector fail.

    A failure may have several causes (on a polished tiled floor, taking away
    the reflection or the tiles' pattern each fixes it). Purity by cause: the
    share of members their cluster's leading cause explains (the phenomenon
    whose removal alone fixes the most members; 'none found' and 'only
    together' count as causes of their own). Purity by cause set: the share
    in their cluster's most common exact set, the strict variant."""
    known = cause != NO_CAUSE
    res.n_with_cause = int(known.sum())
    if res.n_with_cause == 0:
        return
    explained = exact = 0
    for c in range(k):
        m = known & (res.cluster == c)
        entry = res.clusters[c]
        entry["causes"], entry["n_with_cause"] = _composition(cause[m]), int(m.sum())
        entry["leading_cause"], entry["cause_purity"] = None, None
        if m.any():
            code, count = _leading_cause(cause[m])
            entry["leading_cause"], entry["cause_purity"] = code, count / int(m.sum())
            explained += count
            exact += next(iter(entry["causes"].values()))
    res.cause_purity = explained / res.n_with_cause
    res.cause_purity_one_cluster = _leading_cause(cause[known])[1] / res.n_with_cause
    res.cause_set_purity = exact / res.n_with_cause
    counts = sorted(Counter(cause[known].tolist()).values(), reverse=True)
    res.cause_set_best_possible = sum(counts[:k]) / res.n_with_cause
    if len(counts) > 1:
        res.cause_nmi = float(normalized_mutual_info_score(cause[known], res.cluster[known]))


def _purity_by_k(space: np.ndarray, phen: np.ndarray, opt: ClusterOptions,
                 cause: Optional[np.ndarray] = None) -> List[dict]:
    """Purity and NMI of k-means at each k of opt.k_scan, beside the best any
    partition into k clusters could score (the k most common phenomena each
    alone in a cluster): whether more clusters find more phenomena, and how
    far the embedding is from separating them."""
    counts = sorted(Counter(phen.tolist()).values(), reverse=True)
    out = []
    for k in sorted(set(opt.k_scan)):
        if k < 2 or k > len(phen):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cluster = KMeans(n_clusters=k, n_init=10, random_state=opt.seed).fit(space).labels_
        entry = {"k": k, "purity": _purity(phen, cluster),
                 "nmi": float(normalized_mutual_info_score(phen, cluster)),
                 "best_possible": sum(counts[:k]) / len(phen)}
        if cause is not None and np.any(cause != NO_CAUSE):
            known = cause != NO_CAUSE
            entry["purity_by_cause"] = sum(_leading_cause(cause[known & (cluster == c)])[1]
                                           for c in np.unique(cluster[known])) / int(known.sum())
        out.append(entry)
    return out


def _thread_limit(threads: int):
    """Caps OpenMP/BLAS threads: on the project's 2-core machine shared with
    other jobs, t-SNE on 1367 points takes 3.5 s with one thread and 5.5-9 s
    with two (threads wait for each other's time slices)."""
    if threadpool_limits is None:
        return contextlib.nullcontext()
    return threadpool_limits(limits=threads)


def cluster_failures(run: EvalRun, opt: ClusterOptions) -> ClusterResult:
    """Runs selection -> normalisation -> PCA -> k-means -> t-SNE -> mosaics.

    Degenerate inputs (no predicted failures, fewer selected samples than
    clusters) return ok=False with a message for the report instead of raising."""
    with _thread_limit(opt.threads):
        return _cluster_failures(run, opt)


def _cluster_failures(run: EvalRun, opt: ClusterOptions) -> ClusterResult:
    """cluster_failures without the thread cap."""
    res = _select(run, opt)
    if res.message:
        return res
    rows = res.rows
    x = normalise_embeddings(np.asarray(run.embeddings[rows]), opt.embedding_norm)
    if np.allclose(x, x[0]):
        res.message = (f"All {len(rows)} selected embeddings are identical: clustering skipped "
                       "(is embeddings.f32 all zeros?).")
        return res
    z, space = _pca_and_kmeans(res, x, opt)
    rng = np.random.default_rng(opt.seed)  # one stream: the t-SNE subsample, then the mosaics
    _tsne_picture(res, z, opt, rng)
    _describe_clusters(res, run, opt, rng)
    phen = run.phenomenon[rows]
    if len(set(phen.tolist())) > 1:
        res.nmi = float(normalized_mutual_info_score(phen, res.cluster))
        res.ari = float(adjusted_rand_score(phen, res.cluster))
        res.k_scan = _purity_by_k(space, phen, opt, run.cause[rows] if run.cause is not None else None)
    if run.cause is not None:
        _cause_composition(res, run.cause[rows], opt.k)
    empty = [e["cluster"] for e in res.clusters if e["n"] == 0]
    if empty:
        res.message = f"k-means left cluster(s) {empty} empty (fewer distinct embeddings than clusters)."
    res.ok = True
    return res


def _select(run: EvalRun, opt: ClusterOptions) -> ClusterResult:
    """The counts and the selected rows; a message where there is too little to cluster."""
    res = ClusterResult(ok=False)
    res.n_predicted_fp = int(np.sum(run.predicted == FP))
    res.n_predicted_fn = int(np.sum(run.predicted == FN))
    failures = (run.predicted == FP) | (run.predicted == FN)
    res.n_reference_rule = int(np.sum(failures & (run.var_predicted <= REFERENCE_VAR_CUT)))
    rows, cut = select_failures(run, opt.select)
    res.rows, res.confidence_cut, res.n_selected = rows, cut, len(rows)
    res.has_truth = run.has_ground_truth_phenomena
    n_fail = res.n_predicted_fp + res.n_predicted_fn
    if n_fail == 0:
        res.message = "No sample is predicted FP or FN: there are no predicted failures to cluster."
    elif len(rows) < max(opt.k, 2):
        res.message = (f"Only {len(rows)} selected predicted failure(s) (of {n_fail} predicted FP/FN) for "
                       f"k = {opt.k} clusters: clustering skipped.")
    return res


def _pca_and_kmeans(res: ClusterResult, x: np.ndarray, opt: ClusterOptions):
    """PCA to a tenth of the dimension; k-means in the space chosen. Returns (PCA scores, that space)."""
    n_comp = min(max(2, int(round(x.shape[1] / 10))), len(res.rows), x.shape[1])
    pca = PCA(n_components=n_comp, random_state=opt.seed)
    z = pca.fit_transform(x)
    res.pca_components = n_comp
    res.pca_explained = float(np.sum(pca.explained_variance_ratio_))
    space = z if opt.space == "pca" else x
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "fewer distinct clusters than k" is reported instead
        km = KMeans(n_clusters=opt.k, n_init=10, random_state=opt.seed).fit(space)
    res.cluster = km.labels_.astype(np.int64)
    res.distance = np.linalg.norm(space - km.cluster_centers_[res.cluster], axis=1)
    return z, space


def _tsne_picture(res: ClusterResult, z: np.ndarray, opt: ClusterOptions, rng) -> None:
    """t-SNE of the PCA scores for the scatter plot, on a subsample drawn from rng."""
    idx = np.arange(len(res.rows))
    if len(idx) > opt.tsne_max:
        idx = np.sort(rng.choice(idx, size=opt.tsne_max, replace=False))
        res.tsne_note = f"t-SNE on a random subsample of {opt.tsne_max} of {len(res.rows)} points (seed {opt.seed})."
    if len(idx) >= 5:
        perplexity = min(opt.perplexity, (len(idx) - 1) / 3.0)
        res.tsne_xy, res.tsne_kl = _tsne(z[idx], perplexity, opt.tsne_iterations, opt.seed)
        if perplexity < opt.perplexity:
            res.tsne_note = (res.tsne_note + " " if res.tsne_note else "") + \
                f"Perplexity lowered to {perplexity:.1f} for {len(idx)} points."
    else:
        res.tsne_xy = z[idx, :2]
        res.tsne_note = "Too few points for t-SNE: the picture shows the first two PCA components."
    res.tsne_index = idx


def _describe_clusters(res: ClusterResult, run: EvalRun, opt: ClusterOptions, rng) -> None:
    """Composition, purity and the mosaic samples (drawn from rng) of each cluster."""
    rows = res.rows
    phen = run.phenomenon[rows]
    bits = run.phenomena[rows]
    overall = {1 << b: float(np.mean((bits >> b) & 1)) for b in range(8) if np.any((bits >> b) & 1)}
    dominant_total = 0
    for c in range(opt.k):
        m = res.cluster == c
        members = np.flatnonzero(m)
        entry = {
            "cluster": c, "n": int(m.sum()),
            "predicted_fp": int(np.sum(run.predicted[rows][m] == FP)),
            "predicted_fn": int(np.sum(run.predicted[rows][m] == FN)),
            "true_labels": _composition(run.label[rows][m]),
            "phenomena": _composition(phen[m]),
            "present": _phenomena_present(bits[m], overall),
            "surfaces": _composition(run.surface[rows][m]),
            "mean_confidence": float(run.probs[rows[m], run.predicted[rows[m]]].mean()) if m.any() else None,
            "dominant_phenomenon": None, "purity": None,
        }
        if m.any():
            dom, cnt = next(iter(entry["phenomena"].items()))
            entry["dominant_phenomenon"], entry["purity"] = int(dom), cnt / int(m.sum())
            dominant_total += cnt
            w = 1.0 / (0.1 + res.distance[members])
            take = min(MOSAIC_ROWS * MOSAIC_COLS, len(members))
            chosen = rng.choice(members, size=take, replace=False, p=w / w.sum())
            res.mosaic_rows[c] = rows[chosen[np.argsort(res.distance[chosen])]]  # nearest the centre first
        res.clusters.append(entry)
    res.purity = dominant_total / len(rows)
    res.purity_one_cluster = next(iter(_composition(phen).values())) / len(rows)
