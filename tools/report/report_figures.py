"""The report's figures (PNG, matplotlib's Agg backend: no display needed).

Every figure has a title naming the model, labelled axes with units, and a
legend where more than one thing is drawn; class colours are the same
everywhere (TP green, TN blue, FP orange, FN red), and so is each model's
colour (model_colour: its place among the report's models, in hues that are
not the classes'), so figures read together.
"""

from __future__ import annotations

import os
from collections import Counter
from typing import List, Sequence, Tuple

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from margin_bands import band_name  # noqa: E402
from report_inputs import LABEL_NAMES, NO_CAUSE, ONLY_TOGETHER, EvalRun, cause_name, phenomenon_name  # noqa: E402
from report_metrics import FEW_CELLS  # noqa: E402

CLASS_COLOURS = ("#2ca02c", "#1f77b4", "#ff7f0e", "#d62728")   # TP, TN, FP, FN
# One colour per phenomenon code, the same in every figure and model.
PHENOMENON_COLOURS = {0: "#9e9e9e", 1: "#1f77b4", 2: "#2ca02c", 4: "#e6b800", 8: "#8c564b", 16: "#9467bd",
                      32: "#17becf", 64: "#e377c2"}
# Sets of causes (reflection+glare): colours none of the single phenomena use.
SET_COLOURS = ("#d62728", "#bcbd22", "#ff9896", "#98df8a", "#c49c94", "#f7b6d2", "#393b79", "#9edae5", "#ad494a",
               "#637939")
# A model's lines and bars, by its place in the report: no TP green, TN blue,
# FP orange or FN red, so a model is never read as a class.
MODEL_COLOURS = ("#6a3d9a", "#a6611a", "#018571", "#c51b7d", "#4d4d4d", "#8c8c00", "#2c3e94", "#b2182b")
GIVEN_VERDICT_COLOUR = "#777777"   # the verdict head's curve beside its model's own
CLUSTER_CMAP = "Dark2"
DPI = 110


def model_colour(index: int) -> str:
    """The colour of the report's index-th model in every figure."""
    return MODEL_COLOURS[index % len(MODEL_COLOURS)]


def _save(fig, path: str) -> str:
    """Writes the figure and frees it (long reports make many figures)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_confusion(metrics: dict, title: str, path: str) -> str:
    """Row-normalised confusion matrix: each cell = fraction of the true class,
    with its count; the diagonal is the per-class accuracy."""
    norm = np.array([[np.nan if v is None else v for v in row] for row in metrics["confusion_normalised"]])
    counts = np.array(metrics["confusion"])
    fig, ax = plt.subplots(figsize=(5.6, 4.8))
    im = ax.imshow(np.nan_to_num(norm, nan=0.0), vmin=0, vmax=1, cmap="Blues")
    for r in range(4):
        for c in range(4):
            if np.isnan(norm[r, c]):
                text, colour = "no\nsamples", "grey"
            else:
                text = f"{norm[r, c]:.2f}\n({counts[r, c]})"
                colour = "white" if norm[r, c] > 0.55 else "black"
            ax.text(c, r, text, ha="center", va="center", color=colour, fontsize=9)
    ax.set_xticks(range(4), LABEL_NAMES)
    ax.set_yticks(range(4), [f"{n}\n(n={s})" for n, s in zip(LABEL_NAMES, metrics["support"])])
    ax.set_xlabel("predicted class")
    ax.set_ylabel("true class (label from the depth sensor)")
    mpca = metrics["mean_per_class_accuracy"]
    ax.set_title(f"{title}\nrow-normalised confusion matrix"
                 + (f"\nmean per-class accuracy {mpca:.3f}" if mpca is not None else ""), fontsize=10)
    fig.colorbar(im, ax=ax, label="fraction of the true class", fraction=0.046, pad=0.04)
    return _save(fig, path)


def plot_roc(curves: Sequence[Tuple[str, dict, str]], title: str, path: str) -> str:
    """ROC of failure detection (true FP/FN vs TP/TN) scored by P(FP)+P(FN),
    one curve per (model name, failure numbers, colour)."""
    fig, ax = plt.subplots(figsize=(5.2, 5.0))
    for name, f, colour in curves:
        if f.get("roc"):
            ax.plot(f["roc"]["fpr"], f["roc"]["tpr"], lw=1.8, color=colour, label=f"{name}: AUROC {f['auroc']:.3f}")
    ax.plot([0, 1], [0, 1], "k--", lw=0.8, label="chance")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.01)
    ax.set_xlabel("false-alarm rate: TP/TN samples flagged as failures")
    ax.set_ylabel("detection rate: true FP/FN samples flagged")
    ax.set_title(f"{title}\nfailure detection ROC, score P(FP)+P(FN)")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def _threshold_axis(ax, sweep: dict) -> None:
    """Log threshold axis with the 70 %-retained and model thresholds marked,
    limited to where the retained fraction changes (the reference sweep starts
    at 2e-5, far below any real variance)."""
    ax.set_xscale("log")
    kept = [p["threshold"] for p in sweep["curve"] if p["retained_count"] > 0 and p["threshold"] > 0]
    if kept:
        ax.set_xlim(min(kept) / 1.5, max(p["threshold"] for p in sweep["curve"]) * 1.3)
    ax.set_xlabel("uncertainty threshold τ on var_predicted (variance of P(predicted class), keep if ≤ τ)")
    t70 = sweep["at_70"]["threshold"]
    ax.axvline(t70, color="k", ls=":", lw=1, label=f"≥70 % retained: τ = {t70:.3g}")
    if sweep.get("model_threshold"):
        ax.axvline(sweep["model_threshold"], color="purple", ls="-.", lw=1,
                   label=f"model's run-time τ = {sweep['model_threshold']:.3g}")


def sweep_series(curve: List[dict], x_key: str, keys: Sequence[str]):
    """x, solid and each key's values of a sweep curve, in x order, where
    every key has a value (and, for the log threshold axis, τ > 0); solid is
    False where a class keeps fewer than FEW_CELLS cells: the curves go faint
    there."""
    pts = sorted((p for p in curve if all(p[k] is not None for k in keys)
                  and (x_key != "threshold" or p["threshold"] > 0)), key=lambda p: p[x_key])
    x = np.array([p[x_key] for p in pts], dtype=float)
    solid = np.array([p.get("fewest_kept", FEW_CELLS) >= FEW_CELLS for p in pts], dtype=bool)
    return x, solid, {k: np.array([p[k] for p in pts], dtype=float) for k in keys}


def plot_accuracy_vs_threshold(sweep: dict, title: str, path: str, colour: str) -> str:
    """Mean per-class (solid) and overall (dashed) accuracy of the retained
    predictions vs τ, in the model's colour; faint where a class keeps fewer
    than FEW_CELLS cells, as in plot_accuracy_vs_retained (a dip there is one
    or two cells)."""
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    faint_drawn = False
    for key, label, style in (("mean_per_class_accuracy", "mean per-class accuracy (paper's metric)", "-"),
                              ("overall_accuracy", "overall accuracy (reference code's metric)", "--")):
        t, solid, values = sweep_series(sweep["curve"], "threshold", [key])
        if not len(t):
            continue
        v = values[key]
        ax.plot(t, np.where(solid, v, np.nan), style, lw=1.8 if style == "-" else 1.2, color=colour, label=label)
        if not solid.all():
            ax.plot(t[~solid], v[~solid], ".", ms=2, alpha=0.35, color=colour,
                    label=None if faint_drawn else f"fewer than {FEW_CELLS} cells kept in a class")
            faint_drawn = True
    _threshold_axis(ax, sweep)
    ax.set_ylabel("accuracy of retained predictions")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3, which="both")
    ax2 = ax.twinx()  # how much data each accuracy is computed on
    t, _, v = sweep_series(sweep["curve"], "threshold", ["retained"])
    ax2.plot(t, 100 * v["retained"], color="grey", lw=1, alpha=0.7, label="retained samples (%, right axis)")
    ax2.set_ylim(0, 102)
    ax2.set_ylabel("retained samples (%)", color="grey")
    ax.set_title(f"{title}\naccuracy vs uncertainty threshold (lower τ = stricter filter)")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    # under the plot: inside, it would cover one curve or another, whichever run it shows
    ax.legend(h1 + h2, l1 + l2, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    return _save(fig, path)


def plot_retained_vs_threshold(sweep: dict, title: str, path: str) -> str:
    """Fraction of samples kept by the gate vs τ, overall and per true class."""
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    t, _, v = sweep_series(sweep["curve"], "threshold", ["retained"])
    ax.plot(t, 100 * v["retained"], "k-", lw=2.2, label="all samples")
    for c in range(4):
        pts = [(p["threshold"], p["retained_per_class"][c]) for p in sweep["curve"]
               if p["retained_per_class"][c] is not None and p["threshold"] > 0]
        if pts:
            tc, vc = np.array(pts).T
            ax.plot(tc, 100 * vc, lw=1.4, color=CLASS_COLOURS[c], label=f"true {LABEL_NAMES[c]}")
    _threshold_axis(ax, sweep)
    ax.set_ylabel("retained samples (%)")
    ax.set_ylim(0, 102)
    ax.grid(alpha=0.3, which="both")
    ax.set_title(f"{title}\nretained data vs uncertainty threshold")
    ax.legend(fontsize=8, loc="upper left")
    return _save(fig, path)


def plot_accuracy_vs_retained(sweeps: Sequence[Tuple[str, dict, str]], title: str, path: str) -> str:
    """Mean per-class accuracy vs retained fraction, one line per (name, sweep,
    colour), with the paper's claim (> 96 % at 70 % retained) marked. Where a
    class keeps fewer than FEW_CELLS cells the lines go faint: one or two
    cells decide there."""
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    faint_drawn = False
    for name, s, colour in sweeps:
        r, solid, values = sweep_series(s["curve"], "retained", ["mean_per_class_accuracy", "overall_accuracy"])
        if not len(r):
            continue
        mp, oa = values["mean_per_class_accuracy"], values["overall_accuracy"]  # NaN breaks them where not solid
        ax.plot(100 * r, np.where(solid, mp, np.nan), lw=1.8, color=colour, label=f"{name}: mean per-class accuracy")
        ax.plot(100 * r, np.where(solid, oa, np.nan), "--", lw=1.2, color=colour,
                label=f"{name}: overall accuracy")
        if not solid.all():
            ax.plot(100 * r[~solid], mp[~solid], ".", ms=2, alpha=0.35, color=colour,
                    label=None if faint_drawn else f"fewer than {FEW_CELLS} cells kept in a class")
            faint_drawn = True
        a70 = s["at_70"]
        if a70["mean_per_class_accuracy"] is not None:
            ax.plot(100 * a70["retained"], a70["mean_per_class_accuracy"], "o", color=colour)
    ax.axvline(70, color="k", ls=":", lw=1)
    ax.plot([70], [0.96], "k*", ms=10, label="paper (from the image alone): > 96 % at 70 % retained")
    ax.set_xlim(102, 0)  # stricter filtering to the right
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("retained samples (%)  (← no filtering ... strict filtering →)")
    ax.set_ylabel("accuracy of retained predictions")
    ax.grid(alpha=0.3)
    ax.set_title(f"{title}\naccuracy vs retained data")
    ax.legend(fontsize=7, loc="lower left")
    return _save(fig, path)


def _category_colours(n: int):
    """n distinguishable colours (tab10, then tab20)."""
    cmap = plt.get_cmap("tab10" if n <= 10 else "tab20")
    return [cmap(i % cmap.N) for i in range(n)]


def _cause_panel(cause: np.ndarray, top: int = 6):
    """The cluster picture's panel by cause (ivoa-sim-causes): the `top` most
    common cause sets, the rest as 'other causes', and the predicted failures
    that are no true failure (or were not reproduced) in grey."""
    known = cause[cause != NO_CAUSE]
    common = [c for c, _ in Counter(known.tolist()).most_common(top)]
    names = [cause_name(c) if c in common else "other causes" if c != NO_CAUSE else "no true failure / not replayed"
             for c in cause.tolist()]
    greys = {"other causes": (0.45, 0.45, 0.45, 1.0), "no true failure / not replayed": (0.82, 0.82, 0.82, 1.0)}
    legend = [cause_name(c) for c in common] + [n for n in greys if n in names]
    colours = _cause_colours(common) + [greys[n] for n in legend[len(common):]]
    return ("what causes the failure (re-rendered without each phenomenon)", names, legend, colours)


def _cause_colours(codes: List[int]) -> list:
    """_cause_colour of each code, but a set whose colour another cause in the
    panel already has takes the next free one (in code order, so the same
    causes get the same colours in every figure)."""
    colours = {c: _cause_colour(c) for c in codes if not _is_set(c)}
    for c in sorted(c for c in codes if _is_set(c)):
        start = (c * 5) % len(SET_COLOURS)
        free = [SET_COLOURS[(start + i) % len(SET_COLOURS)] for i in range(len(SET_COLOURS))]
        colours[c] = next((x for x in free if x not in colours.values()), free[0])
    return [colours[c] for c in codes]


def _is_set(code: int) -> bool:
    """Two phenomena or more (reflection+glare), not 'none found' or 'only together'."""
    return code not in (0, ONLY_TOGETHER) and code & (code - 1) != 0


def _cause_colour(code: int):
    """The same colour for a cause in every figure: a single phenomenon's own
    colour (as in the phenomenon panel), fixed ones for 'none found' and 'only
    together', and for a set of causes one of SET_COLOURS chosen by the set."""
    if code == 0:
        return "black"
    if code == ONLY_TOGETHER:
        return "#ff7f0e"
    if not _is_set(code) and code in PHENOMENON_COLOURS:
        return PHENOMENON_COLOURS[code]
    return SET_COLOURS[(code * 5) % len(SET_COLOURS)]


def plot_cluster_scatter(run: EvalRun, res, title: str, path: str) -> str:
    """t-SNE of the selected predicted failures coloured by k-means cluster, by
    true phenomenon (simulated data), by cause (with causes) and by true label:
    the panels show whether the clusters follow physical sources of error."""
    xy = res.tsne_xy
    rows = res.rows[res.tsne_index]
    cl = res.cluster[res.tsne_index]
    # (title, category per point, categories in legend order, colour per category)
    k = len(res.clusters)
    cmap = plt.get_cmap(CLUSTER_CMAP)
    panels = [("k-means cluster", [f"cluster {c}" for c in cl], [f"cluster {c}" for c in range(k)],
               [cmap(c % cmap.N) for c in range(k)])]
    if res.has_truth:
        codes = run.phenomenon[rows]
        present = sorted(set(codes.tolist()), key=lambda c: -np.sum(codes == c))
        extra = iter(_category_colours(len(present) + 10)[10:] if len(present) > 0 else [])
        panels.append(("true phenomenon under the patch centre", [phenomenon_name(p) for p in codes],
                       [phenomenon_name(c) for c in present],
                       [PHENOMENON_COLOURS.get(c) or next(extra, "black") for c in present]))
    if run.cause is not None:
        panels.append(_cause_panel(run.cause[rows]))
    present = [c for c in range(4) if np.any(run.label[rows] == c)]
    panels.append(("true label (did the detector fail?)", [LABEL_NAMES[l] for l in run.label[rows]],
                   [LABEL_NAMES[c] for c in present], [CLASS_COLOURS[c] for c in present]))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.9), squeeze=False)
    for ax, (what, cats, names, colours) in zip(axes[0], panels):
        cats = np.array(cats)
        for name, colour in zip(names, colours):
            m = cats == name
            ax.scatter(xy[m, 0], xy[m, 1], s=8, color=colour, alpha=0.75, label=f"{name} ({m.sum()})",
                       edgecolors="none")
        ax.set_title(f"coloured by {what}", fontsize=10)
        ax.set_xlabel("t-SNE 1 (arbitrary units)")
        ax.set_ylabel("t-SNE 2 (arbitrary units)")
        ax.legend(fontsize=7, markerscale=2, loc="best")
    fig.suptitle(f"{title}: {len(rows)} confident predicted failures (FP/FN), t-SNE of FC2 embeddings")
    fig.tight_layout()
    return _save(fig, path)


def make_mosaic(run: EvalRun, rows: np.ndarray, rows_n: int = 5, cols_n: int = 10, border: int = 3) -> np.ndarray:
    """RGB mosaic of the given samples' patches (read from the dataset's
    patches.bin through its memmap; BGR -> RGB), each framed in its true-label
    colour. At most rows_n rows, no more than the samples fill; missing
    tiles stay white."""
    ds = run.dataset
    p = ds.session(run.session[rows[0]]).patch_size if len(rows) else ds.patch_size
    tile = p + 2 * border
    shown = rows[: rows_n * cols_n]
    filled_rows = max(1, -(-len(shown) // cols_n))  # ceiling division
    out = np.full((filled_rows * tile, cols_n * tile, 3), 255, np.uint8)
    for i, r in enumerate(shown):
        s = ds.session(str(run.session[r]))
        patch = np.asarray(s.patches()[run.sample[r]])[:, :, ::-1]  # BGR -> RGB
        if patch.shape[0] != p:
            continue
        y, x = (i // cols_n) * tile, (i % cols_n) * tile
        colour = (np.array(matplotlib.colors.to_rgb(CLASS_COLOURS[run.label[r]])) * 255).astype(np.uint8)
        out[y:y + tile, x:x + tile] = colour
        out[y + border:y + border + p, x + border:x + border + p] = patch
    return out


def _mosaic_caption(res, cluster: int) -> str:
    """What a cluster holds: counts; on simulated data the phenomenon covering most patch
    centres, the one most over-represented anywhere under them, and the leading cause."""
    e = res.clusters[cluster]
    caption = f"cluster {cluster}: {e['n']} samples, predicted FP {e['predicted_fp']} / FN {e['predicted_fn']}"
    if not res.has_truth or e["dominant_phenomenon"] is None:
        return caption
    caption += f"; dominant phenomenon {phenomenon_name(e['dominant_phenomenon'])} ({100 * e['purity']:.0f} %)"
    top = e["present"][0] if e["present"] else None
    if top is not None and top["lift"] is not None and top["lift"] > 1.5:
        caption += f"; {phenomenon_name(top['phenomenon'])} under {100 * top['share']:.0f} % (×{top['lift']:.1f})"
    if e.get("leading_cause") is not None:
        caption += f"; leading cause {cause_name(e['leading_cause'])} ({100 * e['cause_purity']:.0f} %)"
    return caption


def plot_mosaic(run: EvalRun, res, cluster: int, title: str, path: str) -> str:
    """Sample patches of one cluster (weighted towards its centre), with a
    caption saying what the cluster holds."""
    rows = res.mosaic_rows[cluster]
    img = make_mosaic(run, rows)
    h, w = img.shape[:2]
    fig, ax = plt.subplots(figsize=(w / 90 + 0.5, h / 90 + 1.2))
    ax.imshow(img, interpolation="nearest")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(f"{title}\n{_mosaic_caption(res, cluster)}\n"
                 f"{len(rows)} patches sampled with weight 1/(0.1 + distance to centre), "
                 "nearest first", fontsize=9)
    ax.legend(handles=[Patch(color=CLASS_COLOURS[c], label=f"true {LABEL_NAMES[c]}") for c in range(4)],
              loc="upper center", bbox_to_anchor=(0.5, -0.01), ncol=4, fontsize=8, title="frame = true label",
              title_fontsize=8)
    return _save(fig, path)


def plot_phenomenon_comparison(names: Sequence[str], per_phen: Sequence[List[dict]], path: str,
                               title: str, colours: Sequence[str]) -> str:
    """Two panels (predicted FN on top, predicted FP below): for each phenomenon,
    the fraction of its samples each model predicts as that failure (bars, one
    colour per model), with the detector's true rate from the labels as a black
    tick on each bar, so "predicted" and "true" can be read together. A
    model's bars for a phenomenon under fewer than FEW_CELLS of its cells are
    faint, and each bar carries its value, so that 0 is not read as "absent"."""
    codes = sorted({e["phenomenon"] for entries in per_phen for e in entries})
    n_models = len(names)
    x = np.arange(len(codes))
    # room under each group for "(n = 2549 / 1234 / 2549)" at fontsize 8 (about 0.07 in a character)
    fig, axes = plt.subplots(2, 1, figsize=(max(6.5, 0.6 * len(codes) * max(n_models, 2) + 3.0), 7.0), sharex=True)
    for ax, panel in zip(axes, (("pred_fn", "true_fn", "FN"), ("pred_fp", "true_fp", "FP"))):
        _phenomenon_panel(ax, names, per_phen, codes, colours, *panel)
    counts = [" / ".join(str(next((e["n"] for e in en if e["phenomenon"] == c), 0)) for en in per_phen) for c in codes]
    axes[1].set_xticks(x, [f"{phenomenon_name(c)}\n(n = {n})" for c, n in zip(codes, counts)], fontsize=8)
    axes[1].set_xlabel("phenomenon under the patch centre (sample count per model, in legend order)")
    fig.suptitle(f"{title}: which phenomena each model predicts as stereo failures")
    fig.tight_layout()
    return _save(fig, path)


def _phenomenon_panel(ax, names: Sequence[str], per_phen: Sequence[List[dict]], codes: List[int],
                      colours: Sequence[str], key: str, truth: str, kind: str) -> None:
    """One panel of plot_phenomenon_comparison: each model's bars for `key`
    (pred_fn or pred_fp), in its colour, with its true rate (`truth`) as ticks."""
    width = 0.8 / len(names)
    faint_by_model = [few_cell_phenomena(entries, codes) for entries in per_phen]
    for i, (entries, faint) in enumerate(zip(per_phen, faint_by_model)):
        by = {e["phenomenon"]: e for e in entries}
        vals = [by[c][key] if c in by else np.nan for c in codes]
        true = [by[c][truth] if c in by else np.nan for c in codes]
        pos = np.arange(len(codes)) - 0.4 + width * (i + 0.5)
        ax.bar(pos, vals, width * 0.92, color=[matplotlib.colors.to_rgba(colours[i], 0.3 if f else 1.0) for f in faint])
        for px, v, y in zip(pos, vals, value_label_heights(vals, true)):
            if v == v:
                ax.text(px, y, f"{v:.2f}", ha="center", va="bottom", fontsize=6)
        ax.scatter(pos, true, marker="_", s=max(60, 400 * width), linewidths=2.2, zorder=3,
                   color=[(0, 0, 0, 0.3 if f else 1.0) for f in faint])
    ax.set_ylabel(f"fraction predicted {kind}")
    ax.set_ylim(0, 1.05)
    ax.grid(axis="y", alpha=0.3)
    # Patches and a line, not the bars: a model's first bar may be a faint one.
    handles = [Line2D([], [], marker="_", markersize=12, markeredgewidth=2.2, linestyle="", color="black",
                      label=f"true {kind} rate (labels)")]
    handles += [Patch(color=colours[i], label=f"{name}: predicted {kind}") for i, name in enumerate(names)]
    if any(any(faint) for faint in faint_by_model):
        handles.append(Patch(color="grey", alpha=0.3, label=f"faint: fewer than {FEW_CELLS} cells"))
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.set_title(f"predicted {kind} per phenomenon", fontsize=10)


def value_label_heights(values: Sequence[float], ticks: Sequence[float]) -> List[float]:
    """Where each bar's value label sits (its bottom, in data units): just over
    the bar, or over the bar's true-rate tick where that tick would run
    through the label (a label is about 0.05 tall at these figures' size)."""
    heights = []
    for v, t in zip(values, ticks):
        top = 0.0 if v != v else v
        if t == t and top - 0.02 < t < top + 0.07:
            top = max(top, t)
        heights.append(top + 0.015)
    return heights


def few_cell_phenomena(entries: List[dict], codes: Sequence[int]) -> List[bool]:
    """For each phenomenon code, whether one model's fractions rest on fewer
    than FEW_CELLS cells (a phenomenon absent from its cells draws no bar)."""
    n = {e["phenomenon"]: e["n"] for e in entries}
    return [0 < n.get(c, 0) < FEW_CELLS for c in codes]


def few_cell_groups(groups: List[dict]) -> Tuple[List[bool], List[bool]]:
    """Which groups' bars a few cells decide: the mean per-class accuracy where
    a class present has fewer than FEW_CELLS cells, the overall accuracy where
    the whole group has (as the accuracy-vs-retained curves go faint)."""
    mean = [any(0 < s < FEW_CELLS for s in g["support"]) for g in groups]
    overall = [g["n"] < FEW_CELLS for g in groups]
    return mean, overall


def plot_group_bars(groups: List[dict], title: str, xlabel: str, path: str) -> str:
    """Mean per-class and overall accuracy per group (session, environment or
    distance ahead); bars a few cells decide are faint (few_cell_groups)."""
    names = [g["group"] for g in groups]
    mp = [g["mean_per_class_accuracy"] if g["mean_per_class_accuracy"] is not None else np.nan for g in groups]
    oa = [g["overall_accuracy"] if g["overall_accuracy"] is not None else np.nan for g in groups]
    faint_mp, faint_oa = few_cell_groups(groups)
    x = np.arange(len(names))
    # Each group gets room for its label at fontsize 8 (about 0.08 in a
    # character), so long session names do not run into each other.
    per_group = max(1.3, 0.08 * max((len(n) for n in names), default=0))
    fig, ax = plt.subplots(figsize=(max(5.0, per_group * len(names) + 2), 4.2))
    series = ((-0.2, mp, faint_mp, "#444466", "mean per-class accuracy"),
              (0.2, oa, faint_oa, "#aaaacc", "overall accuracy"))
    for offset, values, faint, colour, _ in series:
        colours = [matplotlib.colors.to_rgba(colour, 0.3 if f else 1.0) for f in faint]
        bars = ax.bar(x + offset, values, 0.4, color=colours)
        # a value on each bar, so that an accuracy of 0 is not read as "no data"
        ax.bar_label(bars, labels=["" if v != v else f"{v:.2f}" for v in values], fontsize=6, padding=1)
    ax.set_xticks(x, [f"{n}\n({g['split'] + ', ' if g.get('split') else ''}n = {g['n']})"
                      for n, g in zip(names, groups)], fontsize=8)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("accuracy")
    ax.set_xlabel(xlabel)
    ax.grid(axis="y", alpha=0.3)
    # Patches, not the bars: the first bar may be a faint one.
    handles = [Patch(color=colour, label=label) for _, _, _, colour, label in series]
    if any(faint_mp) or any(faint_oa):
        handles.append(Patch(color=series[0][3], alpha=0.3, label=f"faint: a class with fewer than {FEW_CELLS} cells"))
    # Beside the axes: the bars reach the top, where a legend inside would hide them.
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.set_title(title)
    fig.tight_layout()
    return _save(fig, path)


def plot_margin_bands(margin: dict, title: str, path: str) -> str:
    """Per band of the detector's evidence margin: how often the model reads the
    verdict from the image, its four-class accuracy, and the share of the cells;
    with repeatability figures, how often another noise draw keeps the verdict."""
    bands = margin["bands"]
    x = np.arange(len(bands))
    fig, ax = plt.subplots(figsize=(max(6.0, 1.2 * len(bands) + 2), 4.4))
    ax.bar(x - 0.2, [b["verdict_accuracy"] for b in bands], 0.4, color="#444466",
           label="detector's verdict read from the image (obstacle or free)")
    noisy = [(i, b["noise_agreement"]) for i, b in enumerate(bands) if b.get("noise_agreement") is not None]
    if noisy:
        ax.scatter([i - 0.2 for i, _ in noisy], [a for _, a in noisy], marker="_", s=500, linewidths=2.5,
                   color="#dd5500", zorder=3, label="another sensor-noise draw keeps the verdict")
    ax.bar(x + 0.2, [b["overall_accuracy"] for b in bands], 0.4, color="#aaaacc", label="four classes")
    near = [i for i, b in enumerate(bands) if b["low"] is not None and b["high"] is not None
            and b["low"] >= -margin["near"] and b["high"] <= margin["near"]]
    if near:
        ax.axvspan(min(near) - 0.5, max(near) + 0.5, color="#ffdd99", alpha=0.35, zorder=0,
                   label=f"within {margin['near']:g} of the threshold")
    first_obstacle = next((i for i, b in enumerate(bands) if b["low"] is not None and b["low"] >= 0), len(bands))
    ax.axvline(first_obstacle - 0.5, color="k", lw=1)
    ax.set_xticks(x, [f"{band_name(b)}\n{100 * b['share']:.0f} % of cells\nn = {b['n']}" for b in bands], fontsize=8)
    ax.set_xlabel(f"detector's worst evidence value minus its threshold {margin['threshold']:g} "
                  "(left of the line: free; right: obstacle)")
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("accuracy")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.set_title(f"{title}: accuracy by how close the detector came to its threshold")
    fig.tight_layout()
    return _save(fig, path)
