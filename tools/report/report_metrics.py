"""The paper's numbers: per-class metrics, failure detection, uncertainty sweep,
per-phenomenon comparison.

Conventions (spec §4.3):

* labels 0 TP, 1 TN, 2 FP, 3 FN;
* per-class accuracy = recall of the true class = the diagonal of the
  row-normalised confusion matrix;
* **mean per-class accuracy** (the paper's headline, balanced accuracy) = the mean
  of that diagonal over the classes present in the truth. The reference code's
  ``analyze_results.py`` reported plain overall accuracy instead; we report both
  and follow the paper for the headline;
* the uncertainty gate is ``var_predicted``, the variance over MC passes of the
  predicted class's probability (the reference's analysis script), not the
  heatmap's mean-over-classes variance.
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Optional

import numpy as np
from sklearn.metrics import roc_auc_score, roc_curve

from margin_bands import MARGIN_AGREEMENT_MIN, NEAR_MARGIN, margin_bands, share
from report_inputs import FN, FP, LABEL_NAMES, NO_CAUSE, ONLY_TOGETHER, STATE_OBSTACLE, TP, EvalRun

N_CLASSES = 4
# The reference code's threshold sweep (analyze_results.py).
REFERENCE_SWEEP = np.linspace(2e-5, 0.12, 100)
RETAIN_TARGET = 0.70          # the paper's operating point: > 96 % mean per-class accuracy at 70 % retained
PAPER_MPCA_AT_70 = 0.96
FEW_CELLS = 20                # fewer retained cells than this in some class: its mean per-class accuracy is noise


def confusion_counts(label: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """4x4 counts, rows = true class, columns = predicted class."""
    return np.bincount(label * N_CLASSES + predicted, minlength=N_CLASSES * N_CLASSES).reshape(N_CLASSES, N_CLASSES)


def class_metrics(label: np.ndarray, predicted: np.ndarray) -> dict:
    """Per-class accuracy (recall), mean per-class accuracy, overall accuracy and
    the row-normalised confusion matrix of one set of predictions.

    A class absent from the truth has no accuracy (None): it is left out of the
    mean and listed in ``absent`` so that the report can say so, rather than
    counting it as 0 or 1."""
    cm = confusion_counts(label, predicted)
    support = cm.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        norm = cm / support[:, None]
    per_class = [float(cm[c, c] / support[c]) if support[c] else None for c in range(N_CLASSES)]
    present = [a for a in per_class if a is not None]
    n = int(support.sum())
    return {
        "n": n,
        "support": support.tolist(),
        "per_class_accuracy": per_class,
        "mean_per_class_accuracy": float(np.mean(present)) if present else None,
        "overall_accuracy": float(np.trace(cm) / n) if n else None,
        "confusion": cm.tolist(),
        "confusion_normalised": [[None if not support[r] else float(norm[r, c]) for c in range(N_CLASSES)]
                                 for r in range(N_CLASSES)],
        "absent": [LABEL_NAMES[c] for c in range(N_CLASSES) if not support[c]],
        "predicted_counts": cm.sum(axis=0).tolist(),
    }


BOOTSTRAP_RESAMPLES = 1000
MAX_SHARE_LACKING_A_CLASS = 0.025  # of the resamples: more, and bootstrap_interval gives none


def frame_ids(run: EvalRun) -> np.ndarray:
    """Each row's frame, numbered 0.. over the distinct (session, utime)."""
    session = np.unique(run.session, return_inverse=True)[1]
    return np.unique(np.stack([session, run.utime]), axis=1, return_inverse=True)[1].reshape(-1)


def bootstrap_interval(label: np.ndarray, predicted: np.ndarray, groups: np.ndarray,
                       keep: Optional[np.ndarray] = None, resamples: int = BOOTSTRAP_RESAMPLES,
                       seed: int = 0) -> Optional[List[float]]:
    """95 % interval of the mean per-class accuracy of `predicted` over the
    rows in `keep` (all by default), resampling whole groups with replacement
    (`groups` numbers each row's group 0..: its frame, `frame_ids`, or its
    session): the cells of a frame share its image and its noise, so they
    are not independent draws and a per-cell interval would be too narrow.
    None with fewer than two groups, or where more than
    MAX_SHARE_LACKING_A_CLASS of the resamples lack a class the rows have."""
    keep = np.ones(len(label), bool) if keep is None else keep
    n_groups = int(groups.max()) + 1 if len(groups) else 0
    if n_groups < 2:
        return None
    pair = label * N_CLASSES + predicted
    counts = np.zeros((n_groups, N_CLASSES * N_CLASSES))
    np.add.at(counts, (groups[keep], pair[keep]), 1)
    weights = np.random.default_rng(seed).multinomial(n_groups, np.full(n_groups, 1.0 / n_groups), size=resamples)
    cm = (weights @ counts).reshape(resamples, N_CLASSES, N_CLASSES)
    support = cm.sum(axis=2)
    # A resample without a class the figure has is a mean over fewer classes:
    # another figure. Where that is more than a rare draw (a class in one
    # session only), the interval would mix the two, so there is none.
    present = counts.reshape(n_groups, N_CLASSES, N_CLASSES).sum(axis=(0, 2)) > 0
    if np.mean((support[:, present] == 0).any(axis=1)) > MAX_SHARE_LACKING_A_CLASS:
        return None
    with np.errstate(invalid="ignore", divide="ignore"):
        per_class = np.diagonal(cm, axis1=1, axis2=2) / support
    mean = np.nanmean(np.where(support > 0, per_class, np.nan), axis=1)
    low, high = np.nanpercentile(mean, [2.5, 97.5])
    return [float(low), float(high)]


# Fewer sessions than this give no session interval: a percentile bootstrap
# over a handful of units says more about the handful than about the spread.
MIN_SESSIONS_FOR_INTERVAL = 5


def _intervals(run: EvalRun, groups: np.ndarray, sweep: dict, verdict_sweep: Optional[dict]) -> dict:
    """The headline figures' intervals resampling `groups` whole: from the
    image alone and given the verdict, unfiltered and at the ≥ 70 % point
    (its threshold held fixed)."""
    out = {"mean_per_class_accuracy": bootstrap_interval(run.label, run.predicted, groups),
           "mpca_at_70": bootstrap_interval(run.label, run.predicted, groups,
                                            run.var_predicted <= sweep["at_70"]["threshold"])}
    if run.verdict is not None and verdict_sweep is not None:
        v = run.verdict
        out["verdict_mean_per_class_accuracy"] = bootstrap_interval(run.label, v.predicted, groups)
        out["verdict_mpca_at_70"] = bootstrap_interval(run.label, v.predicted, groups,
                                                       v.var_wrong <= verdict_sweep["at_70"]["threshold"])
    return out


def headline_intervals(run: EvalRun, sweep: dict, verdict_sweep: Optional[dict]) -> dict:
    """Bootstrap intervals of the headline figures. Resampling frames says how
    much chance in the test frames moves them; resampling whole sessions
    (`by_session`, with MIN_SESSIONS_FOR_INTERVAL or more) also how much
    which sessions, and so which scenes, were tested does: wider, since a
    scene's cells fail together."""
    out = {"resamples": BOOTSTRAP_RESAMPLES, **_intervals(run, frame_ids(run), sweep, verdict_sweep)}
    sessions = np.unique(run.session, return_inverse=True)[1].reshape(-1)
    n_sessions = int(sessions.max()) + 1 if len(sessions) else 0
    out["sessions"] = n_sessions
    out["by_session"] = (_intervals(run, sessions, sweep, verdict_sweep)
                         if n_sessions >= MIN_SESSIONS_FOR_INTERVAL else None)
    return out


def grouped_metrics(run: EvalRun, key: np.ndarray, describe_sessions: bool = False) -> List[dict]:
    """class_metrics per value of a column (session, environment), sorted by
    value; with describe_sessions, each entry also names its split and
    environment so the per-session table says where a session was used."""
    out = []
    for value in sorted(set(key.tolist())):
        m = key == value
        entry = class_metrics(run.label[m], run.predicted[m])
        entry["group"] = str(value)
        if describe_sessions:
            entry["split"] = ",".join(sorted(set(run.split[m].tolist())))
            entry["environment"] = ",".join(sorted(set(run.environment[m].tolist())))
        out.append(entry)
    return out


def by_distance(run: EvalRun, safety_radius_m: Optional[float] = None,
                patch_sides: Optional[np.ndarray] = None) -> List[dict]:
    """class_metrics per query-grid row (distance ahead, x), nearest first.

    With the safety radius, each row also gives the width in pixels of the
    disc its labels are about, measured from the image spacing of neighbouring
    cells of one frame and row: where the disc is wider than the patch, the
    patch cannot show everything its label depends on. With the per-row
    patch sides (footprint-scaled datasets), the row's median side too."""
    xs = np.round(run.x, 3)
    scale = _pixels_per_metre_across(run, xs)
    out = []
    for value in sorted(set(xs.tolist())):
        m = xs == value
        entry = class_metrics(run.label[m], run.predicted[m])
        entry["group"] = f"{value:g} m"
        entry["x"] = value
        ppm = scale.get(value)
        entry["disc_px"] = 2 * safety_radius_m * ppm if ppm and safety_radius_m else None
        entry["patch_px"] = float(np.median(patch_sides[m])) if patch_sides is not None else None
        out.append(entry)
    return out


def _pixels_per_metre_across(run: EvalRun, xs: np.ndarray) -> Dict[float, float]:
    """Median |du / dy| over neighbouring cells of one frame and grid row, per row."""
    order = np.lexsort((run.y, xs, run.utime, run.session))
    s, t, x, y, u = run.session[order], run.utime[order], xs[order], run.y[order], run.u[order]
    same_row = (s[1:] == s[:-1]) & (t[1:] == t[:-1]) & (x[1:] == x[:-1]) & (y[1:] != y[:-1])
    if not np.any(same_row):
        return {}
    ratio = np.abs(np.diff(u)[same_row] / np.diff(y)[same_row])
    rows = x[1:][same_row]
    return {float(v): float(np.median(ratio[rows == v])) for v in np.unique(rows)}


def failure_detection(label: np.ndarray, predicted: np.ndarray, probs: np.ndarray) -> dict:
    """Failure detection as a binary problem: positive = the detector failed
    (true FP or FN), predicted positive = the model predicts FP or FN.

    AUROC uses the score P(FP) + P(FN) (the paper's failure heatmap), and each
    failure type one-vs-rest its own probability. With only one class in the
    truth AUROC is undefined and the entry says why."""
    everywhere = np.ones(len(label), bool)
    return scored_failure_detection(label, predicted, probs[:, FP] + probs[:, FN],
                                    {FP: (probs[:, FP], everywhere), FN: (probs[:, FN], everywhere)})


def scored_failure_detection(label: np.ndarray, predicted: np.ndarray, score: np.ndarray, type_scores: dict) -> dict:
    """failure_detection with the ranking given: `score` for FP ∪ FN, and per
    failure type (FP, FN) a (score, mask) pair: its one-vs-rest AUROC over the
    masked samples."""
    truth = (label == FP) | (label == FN)
    flag = (predicted == FP) | (predicted == FN)
    tp = int(np.sum(truth & flag))
    fp = int(np.sum(~truth & flag))
    fn = int(np.sum(truth & ~flag))
    out = {
        "n": int(len(label)), "failures": int(truth.sum()), "non_failures": int((~truth).sum()),
        "flagged": int(flag.sum()),
        "precision": tp / (tp + fp) if tp + fp else None,
        "recall": tp / (tp + fn) if tp + fn else None,
        "auroc": None, "roc": None, "auroc_fp": None, "auroc_fn": None, "message": None,
    }
    p, r = out["precision"], out["recall"]
    out["f1"] = 2 * p * r / (p + r) if p is not None and r is not None and p + r > 0 else None
    if truth.all() or not truth.any():
        out["message"] = ("AUROC undefined: every sample is a failure" if truth.all()
                          else "AUROC undefined: no true failure (FP/FN) among the samples")
        return out
    out["auroc"] = float(roc_auc_score(truth, score))
    fpr, tpr, _ = roc_curve(truth, score)
    out["roc"] = {"fpr": fpr.tolist(), "tpr": tpr.tolist()}
    for cls, key in ((FP, "auroc_fp"), (FN, "auroc_fn")):
        cls_score, mask = type_scores[cls]
        t = label[mask] == cls
        if t.any() and not t.all():
            out[key] = float(roc_auc_score(t, cls_score[mask]))
    return out


def _spearman(a: np.ndarray, b: np.ndarray) -> Optional[float]:
    """Spearman rank correlation with average ranks for ties (numpy only)."""
    if len(a) < 3:
        return None

    def ranks(x):
        order = np.argsort(x, kind="mergesort")
        r = np.empty(len(x))
        r[order] = np.arange(len(x))
        # average ranks of tied values
        _, inv, counts = np.unique(x, return_inverse=True, return_counts=True)
        sums = np.bincount(inv, weights=r)
        return sums[inv] / counts[inv]

    ra, rb = ranks(a), ranks(b)
    if ra.std() == 0 or rb.std() == 0:
        return None
    return float(np.corrcoef(ra, rb)[0, 1])


def _fewest_kept(kept: np.ndarray, support: np.ndarray) -> int:
    """The fewest cells any class with FEW_CELLS or more in all keeps; where
    no class has that many, the fewest any class present keeps (under
    FEW_CELLS at every threshold: nothing rests on enough cells)."""
    counted = support >= FEW_CELLS
    if not counted.any():
        counted = support > 0
    return int(kept[counted].min()) if counted.any() else 0


def _point(label, predicted, var, tau) -> dict:
    """Metrics of the predictions kept by the gate var_predicted <= tau."""
    keep = var <= tau
    m = class_metrics(label[keep], predicted[keep])
    support_all = np.bincount(label, minlength=N_CLASSES)
    kept = np.bincount(label[keep], minlength=N_CLASSES)
    return {
        "threshold": float(tau),
        "retained": float(keep.mean()),
        "retained_count": int(keep.sum()),
        "retained_per_class": [float(kept[c] / support_all[c]) if support_all[c] else None for c in range(N_CLASSES)],
        "kept_per_class": kept.tolist(),
        # the mean per-class accuracy leans on its smallest retained class: a handful of cells make it noise,
        # and a class withheld whole (0 kept) leaves it a mean over the other classes. Counted over the
        # classes with FEW_CELLS or more in all: one with fewer is a handful at every threshold, and would
        # leave no point to judge by (the per-class tables give its count)
        "fewest_kept": _fewest_kept(kept, support_all),
        "mean_per_class_accuracy": m["mean_per_class_accuracy"],
        "overall_accuracy": m["overall_accuracy"],
        "per_class_accuracy": m["per_class_accuracy"],
    }


def threshold_for_retained(var: np.ndarray, fraction: float) -> float:
    """The strictest threshold tau with count(var <= tau) >= fraction * N: the
    operating point "as close to `fraction` retained as the data allow"."""
    s = np.sort(var)
    k = max(1, int(math.ceil(fraction * len(s) - 1e-9)))
    return float(s[k - 1])


def _accuracy_trend(pts: List[dict], unfiltered: dict, at70: dict) -> dict:
    """Does accuracy rise as the threshold falls? The rank correlation between
    the threshold and mean per-class accuracy over the quantile thresholds
    that keep at least 10 % of the cells and FEW_CELLS of every class that has
    as many (fewer, and a handful of cells decide the mean, or a class withheld
    whole leaves it to the others); "yes" takes -0.5 or less and a gain at the
    70 % point, where that point rests on enough cells too."""
    def enough_cells(p):
        return p["fewest_kept"] >= FEW_CELLS

    pts = [p for p in pts if p["retained"] >= 0.10 and enough_cells(p) and p["mean_per_class_accuracy"] is not None]
    thresholds = np.array([p["threshold"] for p in pts])
    rho = _spearman(thresholds, np.array([p["mean_per_class_accuracy"] for p in pts]))
    gain = (at70["mean_per_class_accuracy"] - unfiltered["mean_per_class_accuracy"]
            if at70["mean_per_class_accuracy"] is not None and unfiltered["mean_per_class_accuracy"] is not None
            else None)
    gain_counts = gain is not None and enough_cells(at70)
    if not enough_cells(unfiltered):  # only where no class has FEW_CELLS in all
        verdict, rises = f"undetermined (no class has {FEW_CELLS} cells: too few to judge)", None
    elif rho is None and len(pts) < 3:
        verdict, rises = (f"undetermined (fewer than three thresholds keep ≥ 10 % of the cells and ≥ {FEW_CELLS} "
                          "of every class that has as many)"), None
    elif rho is None:
        verdict, rises = "undetermined (the accuracy does not change over the sweep)", None
    elif rho <= -0.5 and (not gain_counts or gain > 0):
        verdict, rises = "yes", True
    elif rho <= -0.5:
        verdict, rises = "over the sweep, but not at 70 % retained", None
    elif rho < 0:
        verdict, rises = "weakly (noisy)", None
    else:
        verdict, rises = "no", False
    return {"spearman_threshold_vs_mpca": rho,
            "spearman_threshold_vs_accuracy": _spearman(thresholds, np.array([p["overall_accuracy"] for p in pts])),
            "spearman_points": len(pts), "gain_at_70": gain, "accuracy_rises_as_threshold_falls": rises,
            "verdict": verdict}


NO_UNCERTAINTY = "not measured (T = 1: one pass without dropout, so no uncertainty to gate by)"


def _unless_deterministic(run: EvalRun, sweep: dict) -> dict:
    """With one pass every variance is 0 and the gate keeps everything: the
    sweep says nothing of the uncertainty, and must not read as a failed claim."""
    if run.meta.get("mc_passes") == 1:
        sweep.update(verdict=NO_UNCERTAINTY, accuracy_rises_as_threshold_falls=None)
    return sweep


def uncertainty_sweep(run: EvalRun, quantiles: int = 101) -> dict:
    """gate_sweep of the model's own predictions, gated by var_predicted."""
    return _unless_deterministic(run, gate_sweep(run.label, run.predicted, run.var_predicted, run.model_threshold,
                                                 quantiles))


def gate_sweep(label: np.ndarray, predicted: np.ndarray, var: np.ndarray, model_thr: Optional[float],
               quantiles: int = 101) -> dict:
    """Accuracy of the retained predictions as the uncertainty gate tightens.

    Thresholds are the union of quantiles of var_predicted (so that retained
    fractions are spread evenly from 100 % down) and the reference code's
    linspace(2e-5, 0.12, 100). Reported: the curve, the numbers at no filtering,
    at the strictest threshold keeping >= 70 % (the paper's operating point) and
    at the model's own run-time threshold, whether accuracy rises as the
    threshold falls, and the mean variance of correct vs wrong predictions."""
    qs = np.quantile(var, np.linspace(0.0, 1.0, quantiles))
    taus = np.unique(np.concatenate([qs, REFERENCE_SWEEP, [var.max()]]))[::-1]  # high -> low
    curve = [_point(label, predicted, var, t) for t in taus]

    unfiltered = _point(label, predicted, var, float(var.max()))
    at70 = _point(label, predicted, var, threshold_for_retained(var, RETAIN_TARGET))
    at_model = _point(label, predicted, var, model_thr) if model_thr is not None else None
    table = [_point(label, predicted, var, threshold_for_retained(var, f))
             for f in (1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2)]

    trend = _accuracy_trend([_point(label, predicted, var, t) for t in np.unique(qs)], unfiltered, at70)

    correct = label == predicted
    return {
        "gate": "var_predicted",
        "curve": curve,
        "unfiltered": unfiltered,
        "at_70": at70,
        "at_model_threshold": at_model,
        "model_threshold": model_thr,
        "retained_table": table,
        **trend,
        "mean_var_correct": float(var[correct].mean()) if correct.any() else None,
        "mean_var_wrong": float(var[~correct].mean()) if (~correct).any() else None,
        "n_correct": int(correct.sum()),
        "n_wrong": int((~correct).sum()),
    }


def given_verdict(run: EvalRun) -> Optional[dict]:
    """The same metrics for the predictions given the detector's verdict (the
    detector's output is known wherever the model runs, and it rules out two
    of the four classes): per class, the failure detection with P(wrong) as
    the score, and the sweep gated by P(wrong)'s variance. None for eval
    folders written before ivoa-eval recorded them."""
    v = run.verdict
    if v is None:
        return None
    said_obstacle = v.stereo_state == STATE_OBSTACLE
    # Per verdict: FP among the cells called obstacles, FN among those called free.
    failure = scored_failure_detection(run.label, v.predicted, v.p_wrong,
                                       {FP: (v.p_wrong, said_obstacle), FN: (v.p_wrong, ~said_obstacle)})
    return {
        "overall": class_metrics(run.label, v.predicted),
        "sessions": [dict(class_metrics(run.label[run.session == s], v.predicted[run.session == s]), group=str(s))
                     for s in sorted(set(run.session.tolist()))],
        "failure": failure,
        "sweep": _unless_deterministic(run, gate_sweep(run.label, v.predicted, v.var_wrong, run.verdict_threshold)),
    }


def by_margin(run: EvalRun, margin: Optional[np.ndarray], threshold: float,
              noise: Optional[dict] = None) -> Optional[dict]:
    """How the model does by how close the labels' detector came to its
    threshold: per band of the evidence margin, the share of cells, how often
    the detector said obstacle, how often the model reads that verdict from the
    image alone (its predicted class TP/FP vs TN/FN), its four-class overall
    accuracy, and given the verdict; then which share of its verdict errors
    lies near the threshold. With noise (report_inputs.load_repeatability),
    each band also gets how often another sensor-noise draw keeps the verdict
    (noise_agreement), and the whole how many verdict errors a predictor that
    knew the scene but not the noise would make (noise_comparison). None
    without evidence; ok False (with a message) where the evidence does not
    reproduce the labels' verdicts."""
    if margin is None:
        return None
    seen = ~np.isnan(margin)
    said_obstacle = np.isin(run.label, (TP, FP))[seen]
    m = margin[seen]
    agreement = share((m >= 0) == said_obstacle)
    out = {"ok": False, "message": "", "threshold": threshold, "n_with_evidence": int(seen.sum()),
           "agreement": agreement, "near": NEAR_MARGIN, "bands": [], "noise_comparison": None}
    if agreement is None:
        out["message"] = "no sample has an observed evidence value"
        return out
    if agreement < MARGIN_AGREEMENT_MIN:
        out["message"] = (f"the evidence gives the labels' verdict for only {100 * agreement:.1f} % of the samples at "
                          f"threshold {threshold:g} (is --evidence-threshold the detector's?)")
        return out
    verdict_hit = np.isin(run.predicted, (TP, FP))[seen] == said_obstacle
    correct = (run.predicted == run.label)[seen]
    given = (run.verdict.predicted == run.label)[seen] if run.verdict is not None else None
    out["bands"] = margin_bands(m, said_obstacle, {"verdict_accuracy": verdict_hit, "overall_accuracy": correct,
                                                    "given_verdict_accuracy": given})
    near = np.abs(m) < NEAR_MARGIN
    out.update(ok=True, near_share=float(near.mean()),
               near_verdict_error_share=share(near[~verdict_hit]), near_error_share=share(near[~correct]),
               verdict_accuracy=share(verdict_hit), verdict_accuracy_far=share(verdict_hit[~near]))
    if noise is not None:
        out["noise_comparison"] = compare_with_noise(run, out["bands"], noise)
    return out


def compare_with_noise(run: EvalRun, bands: List[dict], noise: dict) -> dict:
    """Sets each band's noise_agreement from the repeatability figures (None
    where they have no cell in that band) and counts, over the bands both
    have, the model's verdict errors against those of a predictor that knew
    the scene but not the noise (sum of n x (1 - agreement)). Figures about
    another detector are not used (used False, with the reason)."""
    out = {k: noise[k] for k in ("path", "detector", "realisations", "cells", "worst_shift_median",
                                 "worst_shift_p90")}
    run_sessions = set(run.session.tolist())
    out.update(run_sessions=len(run_sessions), sessions_in_common=len(run_sessions & set(noise["sessions"])),
               used=not noise["detector"] or noise["detector"] == run.label_detector, cells_compared=0,
               model_verdict_errors=0, noise_verdict_errors=0.0)
    if not out["used"]:
        out["message"] = (f"measured for detector '{noise['detector']}'; the labels here are about "
                          f"'{run.label_detector}'")
        return out
    by_edges = {(b["low"], b["high"]): b["verdict_agreement"] for b in noise["bands"]}
    for b in bands:
        b["noise_agreement"] = by_edges.get((b["low"], b["high"]))
        if b["noise_agreement"] is not None and b["verdict_accuracy"] is not None:
            out["cells_compared"] += b["n"]
            out["model_verdict_errors"] += int(round(b["n"] * (1 - b["verdict_accuracy"])))
            out["noise_verdict_errors"] += b["n"] * (1 - b["noise_agreement"])
    return out


def per_phenomenon(run: EvalRun) -> List[dict]:
    """For each phenomenon under the patch centre: how many samples, how often the
    detector truly failed (true FP / FN) and how often the model predicts a
    failure (predicted FP / FN). This is what tells "a texture-less wall is a
    predicted FN for JPP-C and not for the dense detector"."""
    out = []
    for code in sorted(set(run.phenomenon.tolist())):
        m = run.phenomenon == code
        n = int(m.sum())
        out.append({
            "phenomenon": int(code), "n": n,
            "true_fp": float(np.mean(run.label[m] == FP)), "true_fn": float(np.mean(run.label[m] == FN)),
            "pred_fp": float(np.mean(run.predicted[m] == FP)), "pred_fn": float(np.mean(run.predicted[m] == FN)),
        })
    return out


def causes_of_failures(run: EvalRun) -> Optional[dict]:
    """Per true failure class (FP, FN) with a known cause (ivoa-sim-causes):
    for each cause, the share of those failures it explains (a phenomenon
    whose removal alone fixes them; 'only together'; 'none found') and how
    many of them the model predicts as that failure. None without causes."""
    if run.cause is None:
        return None
    out = {}
    for cls in (FP, FN):
        rows = np.flatnonzero((run.label == cls) & (run.cause != NO_CAUSE))
        cause, hit = run.cause[rows], run.predicted[rows] == cls
        single = cause != ONLY_TOGETHER
        masks = {1 << b: single & ((cause & (1 << b)) != 0) for b in range(7)}
        masks.update({ONLY_TOGETHER: ~single, 0: cause == 0})
        out[LABEL_NAMES[cls]] = {"n": len(rows), "causes": [
            {"cause": code, "share": float(m.mean()), "predicted": float(hit[m].mean())}
            for code, m in masks.items() if m.any()]}
    return out


def headline(run_metrics: dict) -> Dict[str, Any]:
    """The few numbers quoted per model in the summary and comparison tables,
    and the ≥70 % operating points they come from (for the failures kept)."""
    m, f, s = run_metrics["overall"], run_metrics["failure"], run_metrics["sweep"]
    v = run_metrics.get("given_verdict")
    return {
        "verdict_mean_per_class_accuracy": v["overall"]["mean_per_class_accuracy"] if v else None,
        "verdict_mpca_at_70": v["sweep"]["at_70"]["mean_per_class_accuracy"] if v else None,
        "verdict_retained_at_70": v["sweep"]["at_70"]["retained"] if v else None,
        "verdict_at_70": v["sweep"]["at_70"] if v else None,
        "samples": m["n"],
        "mean_per_class_accuracy": m["mean_per_class_accuracy"],
        "overall_accuracy": m["overall_accuracy"],
        "failure_precision": f["precision"], "failure_recall": f["recall"], "failure_auroc": f["auroc"],
        "retained_at_70": s["at_70"]["retained"],
        "mpca_at_70": s["at_70"]["mean_per_class_accuracy"],
        "accuracy_at_70": s["at_70"]["overall_accuracy"],
        "at_70": s["at_70"],
        "intervals": run_metrics.get("intervals") or {},
    }


def detector_settings(variants: List[Dict[tuple, Dict[str, int]]], causes: list) -> Dict[str, List[dict]]:
    """Per detector, each variant tried by ivoa-sim-causes on the same frames:
    the share of the FP and FN it fixes (of all, and of those no phenomenon
    explains) and the share of the right TP and TN verdicts it gets wrong."""
    out: Dict[str, List[dict]] = {}
    for table in variants:
        for detector, variant in sorted({(d, v) for d, v, _ in table}):
            entry = {"variant": variant}
            for label in LABEL_NAMES:
                c = table.get((detector, variant, label), {"cells": 0, "right": 0, "wrong": 0})
                changed = c["right"] if label in ("FP", "FN") else c["wrong"]
                entry[label] = {"n": c["cells"], "changed": changed,
                                "share": changed / c["cells"] if c["cells"] else None}
            for label in ("FP", "FN"):
                n = sum(x.unexplained.get((detector, label), 0) for x in causes)
                fixed = sum(x.unexplained_fixed.get((detector, label, variant), 0) for x in causes)
                entry[f"{label}_none_found"] = {"n": n, "changed": fixed, "share": fixed / n if n else None}
            out.setdefault(detector, []).append(entry)
    return out

