"""report.md: the numbers as Markdown tables, with the figures linked relatively
so that the report folder can be moved or zipped as a whole."""

from __future__ import annotations

import os
from typing import Dict, List, Optional, Sequence

from margin_bands import band_name
from report_clustering import REFERENCE_VAR_CUT, ClusterOptions
from report_inputs import FN, FP, LABEL_NAMES, EvalRun, cause_name, phenomenon_name, surface_name
from report_metrics import FEW_CELLS, NO_UNCERTAINTY, PAPER_MPCA_AT_70, RETAIN_TARGET

PURITY_TARGET = 0.80


def fmt(x, digits: int = 3) -> str:
    """A number for a table; None/NaN become 'n/a' so absent classes are visible."""
    if x is None:
        return "n/a"
    if isinstance(x, str):
        return x
    if isinstance(x, float) and x != x:
        return "n/a"
    if isinstance(x, int):
        return str(x)
    return f"{x:.{digits}f}"


def pct(x, digits: int = 1) -> str:
    """A fraction as a percentage for prose and tables."""
    return "n/a" if x is None else f"{100 * x:.{digits}f} %"


def with_interval(value: Optional[float], interval: Optional[Sequence[float]]) -> str:
    """A figure with its 95 % interval, where there is one."""
    return fmt(value) + (f" [{interval[0]:.3f}, {interval[1]:.3f}]" if value is not None and interval else "")


def failures_kept(point: Optional[dict]) -> str:
    """What share of the true failures an operating point still judges: a gate
    can raise the mean per-class accuracy by withholding the failures it is
    meant to find."""
    if point is None:
        return "n/a"
    kept = point["retained_per_class"]
    return f"FP {pct(kept[FP], 0)}, FN {pct(kept[FN], 0)} kept"


def _points(x: float) -> str:
    """A difference of two fractions in percentage points."""
    return f"{100 * x:.1f} points"


def table(headers: Sequence[str], rows: Sequence[Sequence]) -> str:
    """A GitHub-flavoured Markdown table (| escaped in cells)."""
    def cell(v):
        return str(v).replace("|", "\\|").replace("\n", " ")
    lines = ["| " + " | ".join(cell(h) for h in headers) + " |",
             "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(cell(v) for v in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def image(rel: str, alt: str) -> str:
    """A Markdown image link (relative path, forward slashes)."""
    return f"![{alt}]({rel.replace(os.sep, '/')})\n"


def _class_cells(m: dict) -> List[str]:
    """Per-class accuracy cells with their sample counts, e.g. '0.912 (n=34)'."""
    return [f"{fmt(a)} (n={s})" for a, s in zip(m["per_class_accuracy"], m["support"])]


def metrics_section(run: EvalRun, rm: dict, figs: Dict[str, str]) -> str:
    """§1: per-class / mean per-class / overall accuracy, confusion, per
    environment and per session."""
    m = rm["overall"]
    out = ["### 1. Classification metrics\n"]
    out.append(f"Mean per-class accuracy (the paper's headline metric, the mean of the confusion diagonal over the "
               f"classes present): **{fmt(m['mean_per_class_accuracy'])}**"
               + intervals_text(rm.get("intervals", {}), "mean_per_class_accuracy")
               + f"; overall accuracy (the reference code's metric): **{fmt(m['overall_accuracy'])}**, on {m['n']} "
               "samples.\n")
    if m["absent"]:
        out.append(f"> Class(es) absent from the truth: {', '.join(m['absent'])}. Their accuracy is undefined "
                   f"(n/a) and they are left out of the mean per-class accuracy.\n")
    out.append(table(["true class", "samples", "predicted as this class", "accuracy (recall)"],
                     [[LABEL_NAMES[c], m["support"][c], m["predicted_counts"][c], fmt(m["per_class_accuracy"][c])]
                      for c in range(4)]))
    out.append("\nRow-normalised confusion matrix (rows: true class, columns: predicted; each row sums to 1):\n")
    out.append(table(["true \\ predicted"] + list(LABEL_NAMES),
                     [[f"{LABEL_NAMES[r]} (n={m['support'][r]})"] + [fmt(v) for v in m["confusion_normalised"][r]]
                      for r in range(4)]))
    out.append("\n" + image(figs["confusion"], "confusion matrix"))
    headers = ["n"] + [f"{n} acc." for n in LABEL_NAMES] + ["mean per-class", "overall"]
    out.append("\n**Per environment**\n\n")
    out.append(table(["environment"] + headers,
                     [[g["group"], g["n"]] + _class_cells(g) + [fmt(g["mean_per_class_accuracy"]),
                                                               fmt(g["overall_accuracy"])]
                      for g in rm["environments"]]))
    out.append(distance_table(rm))
    out.append("\n" + image(figs["distances"], "accuracy by distance ahead"))
    out.append("\n**Per session**\n\n")
    out.append(table(["session", "split", "environment"] + headers,
                     [[g["group"], g["split"], g["environment"], g["n"]] + _class_cells(g)
                      + [fmt(g["mean_per_class_accuracy"]), fmt(g["overall_accuracy"])] for g in rm["sessions"]]))
    out.append("\n" + image(figs["sessions"], "accuracy per session"))
    return "\n".join(out)


def intervals_text(ci: dict, key: str) -> str:
    """' (95 % interval …)' of a headline figure: over resampled frames and,
    where there are enough sessions, over resampled sessions."""
    if not ci.get(key):
        return ""
    parts = [f"{ci[key][0]:.3f}–{ci[key][1]:.3f} over {ci['resamples']} resamples of whole frames"]
    n = ci.get("sessions")
    if ci.get("by_session") is None:
        if n:  # an older metrics.json says nothing of sessions
            parts.append(f"none over whole sessions: {n} {'is' if n == 1 else 'are'} too few")
    elif ci["by_session"].get(key):
        low, high = ci["by_session"][key]
        parts.append(f"{low:.3f}–{high:.3f} over the {n} sessions resampled whole, which also counts which scenes "
                     "were tested")
    else:
        parts.append(f"none over the {n} sessions resampled whole: a class is in too few of them")
    return f" (95 % interval {'; '.join(parts)})"


def distance_table(rm: dict) -> str:
    """Accuracy per query-grid row, with how wide the safety disc appears
    against the patch: a label about a disc wider than the patch depends on
    things the patch does not show."""
    rows, patch, scale = rm["distances"], rm.get("patch_size"), rm.get("patch_scale") or 0
    out = ["\n**Per distance ahead** (query-grid rows)\n\n"]
    headers = ["x", "n"] + [f"{n} acc." for n in LABEL_NAMES] + ["mean per-class", "overall", "safety disc across (px)",
                                                                "patch cut (px)"]
    out.append(table(headers, [[g["group"], g["n"]] + _class_cells(g)
                               + [fmt(g["mean_per_class_accuracy"]), fmt(g["overall_accuracy"]),
                                  fmt(g["disc_px"], 0), fmt(g.get("patch_px") or patch, 0)] for g in rows]))
    if scale > 0:
        out.append(f"\nFootprint-scaled patches (x{scale:g}): the square cut around a cell is {scale:g} disc widths "
                   f"(at least {patch} px, shrunk to stay in the image), resized to {patch} px; 'patch cut' is the "
                   f"row's median side.\n")
    wide = [g for g in rows if g["disc_px"] is not None and (g.get("patch_px") or patch)
            and g["disc_px"] > (g.get("patch_px") or patch)]
    if wide:
        share = sum(g["n"] for g in wide) / max(1, sum(g["n"] for g in rows))
        out.append(f"\nAt {', '.join(g['group'] for g in wide)} the safety disc is wider than the patch "
                   f"({pct(share)} of the samples): the patch cannot show all of what the label is about there.\n")
    return "".join(out)


def failure_section(rm: dict, figs: Dict[str, str]) -> str:
    """§2: failure detection as a binary problem."""
    f = rm["failure"]
    out = ["### 2. Failure detection (FP ∪ FN vs TP ∪ TN)\n",
           "A sample is a *failure* when the stereo detector was wrong (true FP or FN); the model *flags* it when "
           "it predicts FP or FN. AUROC ranks samples by P(FP) + P(FN) (the paper's failure heatmap).\n"]
    out.append(table(["true failures", "non-failures", "flagged", "precision", "recall", "F1",
                      "AUROC (FP∪FN)", "AUROC FP vs rest", "AUROC FN vs rest"],
                     [[f["failures"], f["non_failures"], f["flagged"], fmt(f["precision"]), fmt(f["recall"]),
                       fmt(f["f1"]), fmt(f["auroc"]), fmt(f["auroc_fp"]), fmt(f["auroc_fn"])]]))
    if f["message"]:
        out.append(f"\n> {f['message']}.\n")
    if "roc" in figs:
        out.append("\n" + image(figs["roc"], "failure detection ROC"))
    return "\n".join(out)


def _point_row(name: str, p: Optional[dict]) -> List[str]:
    """One operating point of the uncertainty sweep as table cells."""
    if p is None:
        return [name] + ["n/a"] * 9
    return ([name, f"{p['threshold']:.4g}", pct(p["retained"]), p["retained_count"],
             fmt(p["mean_per_class_accuracy"]), fmt(p["overall_accuracy"])]
            + [pct(r, 0) for r in p["retained_per_class"]])


def _few_cells_note(ladder: List[dict]) -> str:
    """Where the ladder's mean per-class accuracy starts to rest on a handful of cells of some class."""
    few = next((p for p in ladder if p.get("fewest_kept", FEW_CELLS) < FEW_CELLS), None)
    if few is None:
        return ""
    if few["retained"] >= 1.0:  # kept == support there: no class has FEW_CELLS at all
        return (f"\nNo class has {FEW_CELLS} cells here (the smallest present has {few['fewest_kept']}): every row, "
                "and the whole of the curves, rest on a handful of cells.\n")
    return (f"\nFrom ≥ {pct(few['retained'], 0)} retained down, some class with {FEW_CELLS} cells or more keeps "
            f"fewer than {FEW_CELLS} ({few['fewest_kept']} there): those rows, and the curves' faint part, rest on a "
            "handful of cells.\n")


def _withheld_failures(p: dict) -> str:
    """Which true classes the gate withholds more than its share of: where they are the failures,
    part of the accuracy gained is the failures set aside, and a robot must treat those cells as unknown."""
    kept = p["retained_per_class"]
    fewer = [f"{pct(kept[c], 0)} of the true {LABEL_NAMES[c]}" for c in (FP, FN)
             if kept[c] is not None and kept[c] < p["retained"] - 0.05]
    if not fewer:
        return ""
    # Only the classes named: the other failure class may be kept at its share.
    return (f"The gate withholds these failures more often than other cells: it keeps {' and '.join(fewer)}, "
            f"against {pct(p['retained'], 0)} of all cells. Part of the gain is the "
            "failures set aside, and a withheld cell is one the model declines to judge: a planner should treat "
            "it as unknown, not as free.\n")


def _claim_met(sweep: dict, mpca_at_70: Optional[float]) -> str:
    """'yes', 'no', or not measured where the run had no uncertainty (T = 1)."""
    if sweep["verdict"] == NO_UNCERTAINTY:
        return "not measured (T = 1)"
    return "yes" if mpca_at_70 is not None and mpca_at_70 > PAPER_MPCA_AT_70 else "no"


def uncertainty_section(rm: dict, figs: Dict[str, str]) -> str:
    """§3: accuracy and retained data vs the uncertainty threshold."""
    s = rm["sweep"]
    out = ["### 3. Uncertainty: accuracy vs threshold\n",
           "Gate: keep a prediction iff `var_predicted` (the variance over the MC-dropout passes of the predicted "
           "class's probability) ≤ τ. τ sweeps from high to low over 101 quantiles of var_predicted and the "
           "reference code's linspace(2e-5, 0.12, 100). Mean per-class accuracy is over the classes that still "
           "have retained samples. The model's run-time τ is the gate `ivoa-train` calibrated to keep 70 % of "
           "its validation samples, which the live process uses to announce or withhold a prediction; 'X kept' "
           "is the share of the cells of true class X whose prediction passes the gate.\n"]
    headers = ["operating point", "τ", "retained", "retained n", "mean per-class acc.", "overall acc."] + \
        [f"{n} kept" for n in LABEL_NAMES]
    rows = [_point_row("no filtering", s["unfiltered"]),
            _point_row(f"strictest τ keeping ≥ {int(100 * RETAIN_TARGET)} %", s["at_70"])]
    if s["at_model_threshold"] is not None:
        rows.append(_point_row("model's run-time τ (eval.json)", s["at_model_threshold"]))
    out.append(table(headers, rows))
    gain = s["gain_at_70"]
    a70 = s["at_70"]["mean_per_class_accuracy"]
    out.append(
        f"\nAt ≥ {int(100 * RETAIN_TARGET)} % retained ({pct(s['at_70']['retained'])}), mean per-class accuracy is "
        f"**{fmt(a70)}**{intervals_text(rm.get('intervals', {}), 'mpca_at_70')} vs "
        f"{fmt(s['unfiltered']['mean_per_class_accuracy'])} unfiltered "
        f"({'+' if gain is not None and gain >= 0 else ''}{fmt(None if gain is None else 100 * gain, 1)} points; "
        f"the paper reports > {int(100 * PAPER_MPCA_AT_70)} % at 70 % retained, +6 points). "
        f"Paper's claim met here: **{_claim_met(s, a70)}**.\n")
    out.append(_withheld_failures(s["at_70"]))
    rho = s["spearman_threshold_vs_mpca"]
    out.append(
        f"Does accuracy rise as the threshold falls? **{s['verdict']}** (Spearman rank correlation between τ and mean "
        f"per-class accuracy over the {s['spearman_points']} quantile thresholds keeping ≥ 10 % of the cells and "
        f"≥ {FEW_CELLS} of every class that has as many: {fmt(rho, 2)}; for overall accuracy: "
        f"{fmt(s['spearman_threshold_vs_accuracy'], 2)}; negative = accuracy rises as τ falls; 'yes' takes a "
        f"correlation of −0.5 or less and a gain at 70 % retained, where that point keeps as many cells).\n")
    out.append(f"Mean var_predicted of correct predictions: **{fmt(s['mean_var_correct'], 5)}** (n = {s['n_correct']}) "
               f"vs wrong predictions: **{fmt(s['mean_var_wrong'], 5)}** (n = {s['n_wrong']})"
               + (" — wrong predictions are more uncertain, as they should be.\n"
                  if s["mean_var_correct"] is not None and s["mean_var_wrong"] is not None
                  and s["mean_var_wrong"] > s["mean_var_correct"] else ".\n"))
    out.append("\nRetained fraction ladder:\n")
    out.append(table(headers, [_point_row(f"≥ {pct(p['retained'], 0)}", p) for p in s["retained_table"]]))
    out.append(_few_cells_note(s["retained_table"]))
    out.append("\n" + image(figs["accuracy_vs_threshold"], "accuracy vs threshold"))
    out.append(image(figs["retained_vs_threshold"], "retained data vs threshold"))
    out.append(image(figs["accuracy_vs_retained"], "accuracy vs retained data"))
    return "\n".join(out)


def verdict_section(rm: dict, figs: Dict[str, str]) -> str:
    """§4: the predictions given the detector's verdict."""
    v = rm.get("given_verdict")
    out = ["### 4. Given the detector's verdict\n"]
    if v is None:
        out.append("Not in this eval folder (written by an ivoa-eval older than the `stereo_state`, "
                   "`verdict_predicted`, `p_wrong` and `var_wrong` columns).\n")
        out.append(margin_text(rm, figs))
        return "\n".join(out)
    m, f, s = v["overall"], v["failure"], v["sweep"]
    out.append(
        "Wherever the model runs, the detector's verdict for the cell is known too (the live process reads it from "
        "the obstacle grid; the dataset records it), and it rules out two of the four classes: a cell the detector "
        "called an obstacle is TP or FP, one it called free is TN or FN. What is left to predict is whether that "
        "verdict is wrong: P(FP | obstacle) = p_FP / (p_TP + p_FP) and P(FN | free) = p_FN / (p_TN + p_FN), taken "
        "pass by pass over the MC-dropout passes of the same network; the gate is the variance of that "
        "probability. The paper's measure above asks the network for all four classes from the image alone; this "
        "one is what a planner holding both outputs can use.\n")
    ci = rm.get("intervals", {})
    out.append(f"Mean per-class accuracy given the verdict: **{fmt(m['mean_per_class_accuracy'])}**"
               f"{intervals_text(ci, 'verdict_mean_per_class_accuracy')} "
               f"(image alone: {fmt(rm['overall']['mean_per_class_accuracy'])}); overall "
               f"**{fmt(m['overall_accuracy'])}**; at ≥ {int(100 * RETAIN_TARGET)} % retained "
               f"({pct(s['at_70']['retained'])}) **{fmt(s['at_70']['mean_per_class_accuracy'])}**"
               f"{intervals_text(ci, 'verdict_mpca_at_70')}; "
               f"accuracy rises as the threshold falls: **{s['verdict']}** "
               f"(Spearman {fmt(s['spearman_threshold_vs_mpca'], 2)}).\n")
    out.append(table(["true \\ predicted"] + list(LABEL_NAMES) + ["accuracy"],
                     [[f"{LABEL_NAMES[r]} (n={m['support'][r]})"] + [fmt(x) for x in m["confusion_normalised"][r]]
                      + [fmt(m["per_class_accuracy"][r])] for r in range(4)]))
    out.append("\nFailure detection with P(wrong | verdict) as the score: precision "
               f"{fmt(f['precision'])}, recall {fmt(f['recall'])}, AUROC {fmt(f['auroc'])} (FP among the cells called "
               f"obstacles: {fmt(f['auroc_fp'])}; FN among those called free: {fmt(f['auroc_fn'])}).\n")
    headers = ["operating point", "τ", "retained", "retained n", "mean per-class acc.", "overall acc."] + \
        [f"{n} kept" for n in LABEL_NAMES]
    rows = [_point_row(f"≥ {pct(p['retained'], 0)}", p) for p in s["retained_table"]]
    if s["at_model_threshold"] is not None:
        rows.append(_point_row("model's run-time τ (its own gate, calibrated as in §3)", s["at_model_threshold"]))
    out.append(table(headers, rows))
    out.append(_few_cells_note(s["retained_table"]))
    out.append("\n" + _withheld_failures(s["at_70"]))
    headers = ["n"] + [f"{n} acc." for n in LABEL_NAMES] + ["mean per-class", "overall"]
    out.append("\n**Per session, given the verdict**\n\n")
    out.append(table(["session"] + headers,
                     [[g["group"], g["n"]] + _class_cells(g) + [fmt(g["mean_per_class_accuracy"]),
                                                               fmt(g["overall_accuracy"])] for g in v["sessions"]]))
    out.append("\n" + image(figs["verdict_accuracy_vs_retained"], "accuracy vs retained, image alone and given the verdict"))
    out.append(margin_text(rm, figs))
    return "\n".join(out)


def margin_text(rm: dict, figs: Dict[str, str]) -> str:
    """§4's last part: accuracy by how close the detector came to its threshold."""
    g = rm.get("by_margin")
    out = ["\n**By how close the detector came to its threshold**\n"]
    if g is None:
        out.append("Not available: the dataset keeps no evidence of the labels' detector (the dense detector keeps "
                   "none; `ivoa-dataset build --no-evidence` skips it).\n")
        return "\n".join(out)
    if not g["ok"]:
        out.append(f"Not shown: {g['message']}.\n")
        return "\n".join(out)
    noise = g["noise_comparison"]
    with_noise = noise is not None and noise["used"]
    out.append(
        f"The dataset records the detector's evidence for each cell (JPP-C: the window cost of each of its ground "
        f"samples; the cell is an obstacle iff the worst reaches {g['threshold']:g}), so each cell's margin is its "
        f"worst value minus the threshold. Near zero a little image noise decides the verdict "
        f"({noise_context(noise)}). "
        f"{pct(g['near_share'])} of the {g['n_with_evidence']} cells lie within ±{g['near']:g} of the threshold; "
        f"they hold **{pct(g['near_verdict_error_share'])}** of the model's errors in reading the verdict from the "
        f"image (verdict read right in {pct(g['verdict_accuracy'])} of all cells, "
        f"{pct(g['verdict_accuracy_far'])} of those farther out) and {pct(g['near_error_share'])} of its "
        f"four-class errors.\n")
    rows = [[band_name(b), b["n"], pct(b["share"]), pct(b["obstacle_share"], 0), fmt(b["verdict_accuracy"])]
            + ([fmt(b.get("noise_agreement"))] if with_noise else [])
            + [fmt(b["overall_accuracy"]), fmt(b["given_verdict_accuracy"])] for b in g["bands"]]
    out.append(table(["margin", "cells", "share", "detector said obstacle", "verdict read from the image"]
                     + (["another noise draw keeps the verdict"] if with_noise else [])
                     + ["four classes", "given the verdict"], rows))
    if with_noise:
        out.append(f"\nOver these {noise['cells_compared']} cells the model misreads {noise['model_verdict_errors']} "
                   f"verdicts; a predictor that knew each scene exactly but not the noise would misread about "
                   f"**{noise['noise_verdict_errors']:.0f}**: where the model falls below the noise column, a better "
                   f"model could still gain.\n")
    out.append("\n" + image(figs["margin_bands"], "accuracy by the detector's margin"))
    return "\n".join(out)


def noise_context(noise: Optional[dict]) -> str:
    """The parenthesis on how far the sensor noise moves the evidence: measured
    (ivoa_report.py --repeatability), not applicable, or how to measure it."""
    if noise is None:
        return ("on simulated sessions, `tools/main_job/ivoa-label-repeatability.sh` measures how far another draw "
                "of the sensor noise moves it; `--repeatability` sets its figures beside the model's")
    if not noise["used"]:
        return f"the repeatability figures in `{noise['path']}` were not used: {noise['message']}"
    where = (f"re-recorded {noise['sessions_in_common']} of these {noise['run_sessions']} sessions"
             if noise["sessions_in_common"] else "recorded other sessions than these")
    return (f"another draw of the sensor noise moves a cell's worst value by {noise['worst_shift_median']:.3f} at "
            f"the median and {noise['worst_shift_p90']:.3f} at the 90th percentile; `{noise['path']}`: "
            f"{noise['realisations']} draws of {noise['cells']} cells, which {where}")


def _counts_text(d: Dict[int, int], namer, total: int, top: int = 4) -> str:
    """'reflection 120 (80 %), none 30 (20 %)' for a composition dict."""
    items = list(d.items())
    txt = ", ".join(f"{namer(k)} {v} ({100 * v / total:.0f} %)" for k, v in items[:top])
    if len(items) > top:
        txt += f", +{len(items) - top} more"
    return txt


def _present_text(present, min_share: float = 0.1, top: int = 4) -> str:
    """'dark stripe 51 % (×5.7), low light 55 % (×2.3)': phenomena under at
    least min_share of a cluster's patches, most over-represented first."""
    items = [e for e in present if e["share"] >= min_share][:top]
    return ", ".join(f"{phenomenon_name(e['phenomenon'])} {100 * e['share']:.0f} % (×{e['lift']:.1f})"
                     for e in items) or "none ≥ 10 %"


def _split_by_predicted_class(clusters: List[dict]) -> str:
    """Says so where the clusters are no more than the predicted FP and the
    predicted FN: then what they add over one cluster is that split's doing,
    not a failure source the embedding found within either."""
    fp_only = [e for e in clusters if e["n"] and e["predicted_fn"] == 0]
    fn_only = [e for e in clusters if e["n"] and e["predicted_fp"] == 0]
    if len(clusters) != 2 or len(fp_only) != 1 or len(fn_only) != 1:
        return ""
    return ("\nThe two clusters are the predicted FP and the predicted FN, each whole: k-means finds the split the "
            "model's own prediction makes, and what the clusters score over one cluster below is that split's. "
            "Whether the embedding tells failure sources apart within FP or FN shows at larger k.\n")


def clustering_section(run: EvalRun, res, opt: ClusterOptions, figs: Dict[str, str]) -> str:
    """§4: clustering of confident predicted failures, composition and purity."""
    out = ["### 5. Failure clustering\n"]
    if opt.select == "confidence-per-class":
        cuts = ", ".join(f"{fmt(cut)} for {name}" for name, cut in res.confidence_cut.items())
        rule = ("the top 50 % by confidence of the predicted FP and, apart, of the predicted FN (predicted-class "
                f"probability ≥ {cuts}; median splits)")
    elif opt.select == "confidence":
        rule = (f"the top 50 % by confidence (predicted-class probability ≥ {fmt(res.confidence_cut)}, median split "
                "over the predicted FP and FN together)")
    else:
        rule = f"var_predicted ≤ {REFERENCE_VAR_CUT} (the reference script's rule)"
    out.append(f"Predicted failures: {res.n_predicted_fp} predicted FP, {res.n_predicted_fn} predicted FN. Selected "
               f"**{res.n_selected}** by {rule}. (The reference script's rule, var_predicted ≤ {REFERENCE_VAR_CUT}, "
               f"would keep {res.n_reference_rule}.)\n")
    if not res.ok:
        out.append(f"> **Clustering not possible:** {res.message}\n")
        return "\n".join(out)
    space = ("the L2-normalised 256-d FC2 embedding space" if opt.space == "embedding"
             else f"the {res.pca_components}-d PCA space")
    out.append(
        f"Embeddings: {opt.embedding_norm}-normalised FC2 activations; PCA 256 → {res.pca_components} (a tenth, as "
        f"in the paper; explains {pct(res.pca_explained)} of the variance); k-means with k = {opt.k} "
        f"(10 restarts, random_state {opt.seed}) in {space}; t-SNE of the PCA scores for the picture only "
        f"(perplexity {opt.perplexity:g}, {opt.tsne_iterations} iterations, random_state {opt.seed}"
        + (f", final KL divergence {res.tsne_kl:.2f}" if res.tsne_kl is not None else "") + f"). {res.tsne_note}\n")
    if res.message:
        out.append(f"> {res.message}\n")
    out.append(image(figs["scatter"], "t-SNE of predicted failures"))
    rows = []
    for e in res.clusters:
        n = max(e["n"], 1)
        row = [e["cluster"], e["n"], f"{e['predicted_fp']} / {e['predicted_fn']}",
               _counts_text(e["true_labels"], lambda c: LABEL_NAMES[c], n)]
        if res.has_truth:
            row += [phenomenon_name(e["dominant_phenomenon"]) if e["dominant_phenomenon"] is not None else "n/a",
                    pct(e["purity"]), _counts_text(e["phenomena"], phenomenon_name, n),
                    _present_text(e.get("present", [])), _counts_text(e["surfaces"], surface_name, n)]
        rows.append(row)
    headers = ["cluster", "samples", "predicted FP / FN", "true labels"]
    if res.has_truth:
        headers += ["dominant phenomenon", "purity", "phenomena", "present under the patch (× all clustered)",
                    "surfaces"]
    out.append(table(headers, rows))
    out.append(_split_by_predicted_class(res.clusters))
    if res.has_truth:
        out.append(
            f"\nOverall purity (samples in their cluster's dominant phenomenon / all clustered): "
            f"**{pct(res.purity)}** ({_purity_target_text(res.purity, res.purity_one_cluster)}; "
            f"all of them in one cluster would score {pct(res.purity_one_cluster)}); "
            f"normalised mutual information with the phenomenon: {fmt(res.nmi)}, adjusted Rand index: "
            f"{fmt(res.ari)}. 'none' counts as a phenomenon: failures with no simulated phenomenon under the "
            f"patch centre (e.g. geometry, distance). Phenomena co-occur (a polished floor is texture-less and "
            f"reflects), so a patch has one dominant phenomenon but may show several: 'present under the patch' "
            f"gives the share of a cluster's patches showing each one anywhere under the patch centre, and in "
            f"brackets how over-represented that is against all clustered failures (×1 = no more than anywhere "
            f"else): what sets the cluster apart.\n")
        out.append(_purity_by_k_text(res))
        out.append(_cause_text(res))
    else:
        out.append("\nNo simulator ground truth in these sessions (surface = unknown everywhere): cluster composition by "
                   "phenomenon and purity are not available; judge the clusters by their mosaics.\n")
    out.append("\nSample patches per cluster (frame colour = true label):\n")
    for c in sorted(res.mosaic_rows):
        out.append(image(figs[f"mosaic_{c}"], f"cluster {c} mosaic"))
    return "\n".join(out)


def _purity_target_text(purity: Optional[float], one_cluster: Optional[float]) -> str:
    """Whether a purity meets the target, and whether that says anything:
    where one cluster holding every failure already meets it, the clusters
    are not what meets it."""
    head = f"target ≥ {int(100 * PURITY_TARGET)} %: "
    if purity is None or purity < PURITY_TARGET:
        return head + "not met"
    if one_cluster is not None and one_cluster >= PURITY_TARGET:
        return head + "met, but one cluster holding all of them would meet it too, so here it says nothing"
    return head + "met"


def _cause_text(res) -> str:
    """Composition and purity by cause (ivoa-sim-causes), when the report has them."""
    if res.cause_purity is None:
        return ""
    rows = [[e["cluster"], e.get("n_with_cause", 0),
             cause_name(e["leading_cause"]) if e.get("leading_cause") is not None else "n/a",
             pct(e.get("cause_purity")),
             _counts_text(e.get("causes", {}), cause_name, max(e.get("n_with_cause", 0), 1))] for e in res.clusters]
    return ("\n**By cause.** `ivoa-sim-causes` re-rendered each failure frame once per phenomenon taken out of the "
            "scene and re-ran the detector: a failure's causes are the phenomena whose removal alone makes the "
            "verdict right ('only together': only removing all of the scene's phenomena at once does; 'none found': "
            "not even that, so geometry or the detector's own limits). A cluster's leading cause is the one that "
            "explains most of its members; purity by cause is the share of clustered true failures (with a known "
            f"cause: {res.n_with_cause}) that their cluster's leading cause explains: **{pct(res.cause_purity)}** "
            f"({_purity_target_text(res.cause_purity, res.cause_purity_one_cluster)}; all of them in one cluster "
            f"would already score {pct(res.cause_purity_one_cluster)}, so the clusters add "
            f"{_points(res.cause_purity - res.cause_purity_one_cluster)}: what they add is that each has a leading "
            "cause of its own). Counting only the exact "
            f"set of causes (reflection+repetitive apart from reflection): {pct(res.cause_set_purity)}, where the "
            f"best any partition into {len(res.clusters)} clusters could reach is "
            f"{pct(res.cause_set_best_possible)} (NMI {fmt(res.cause_nmi)}).\n\n"
            + table(["cluster", "true failures with a cause", "leading cause", "purity by cause", "cause sets"], rows))


def _purity_by_k_text(res) -> str:
    """The k-scan: purity at other k beside the best a partition into k could score."""
    if not res.k_scan:
        return ""
    by_cause = any("purity_by_cause" in e for e in res.k_scan)
    rows = [[e["k"], pct(e["purity"]), fmt(e["nmi"]), pct(e["best_possible"])]
            + ([pct(e.get("purity_by_cause"))] if by_cause else []) for e in res.k_scan]
    return ("\nWould more clusters separate the phenomena? k-means at other k on the same embeddings, beside the "
            "best purity any partition into k clusters could reach (each of the k most common phenomena alone in "
            "its cluster). Purity that stays flat as k grows, far under that bound, means the embedding does not "
            "tell those phenomena apart: to the network they are one kind of failure.\n\n"
            + table(["k", "purity", "NMI", "best possible with k clusters"]
                    + (["purity by cause (leading cause)"] if by_cause else []), rows))


def overlays_section(overlays: List[str], dots: str = "image") -> str:
    """§6: ivoa-eval's per-frame figures, copied next to the report; dots is
    eval.json's overlay_dots ("image" or "given_verdict")."""
    out = ["### 6. Per-frame overlays\n"]
    if not overlays:
        out.append("No overlay figures in this eval folder (run ivoa-eval with `--logs`).\n")
        return "\n".join(out)
    what = ("prediction given the detector's recorded verdict (`--dots-given-verdict`)" if dots == "given_verdict"
            else "prediction from the image alone")
    out.append(f"From ivoa-eval: left image with the ground grid (outer ring = label, inner dot = {what}; hollow = "
               "withheld by the uncertainty gate), the P(FP)+P(FN) heatmap and the uncertainty heatmap, whose "
               "colour scale its title gives (one scale for every overlay of a model unless ivoa-eval was given "
               "`--uncertainty-max 0`).\n")
    for rel in overlays:
        out.append(f"**{os.path.basename(rel)}**\n\n" + image(rel, os.path.basename(rel)))
    return "\n".join(out)


def comparison_section(runs: List[EvalRun], metrics: Dict[str, dict], figs: Dict[str, str],
                       sentences: List[str]) -> str:
    """Side-by-side metrics and per-phenomenon predicted FN/FP rates."""
    names = [r.name for r in runs]
    out = ["## Comparison of the perception models\n"]
    rows = []

    def row(label, getter, digits=3):
        rows.append([label] + [fmt(getter(metrics[r.slug]), digits) for r in runs])

    row("detector", lambda m: m["detector"])
    row("samples", lambda m: m["overall"]["n"])
    row("mean per-class accuracy", lambda m: m["overall"]["mean_per_class_accuracy"])
    row("overall accuracy", lambda m: m["overall"]["overall_accuracy"])
    for c in range(4):
        row(f"{LABEL_NAMES[c]} accuracy (n)",
            lambda m, c=c: f"{fmt(m['overall']['per_class_accuracy'][c])} ({m['overall']['support'][c]})")
    row("failure precision", lambda m: m["failure"]["precision"])
    row("failure recall", lambda m: m["failure"]["recall"])
    row("failure AUROC", lambda m: m["failure"]["auroc"])
    row("retained at the ≥70 % point", lambda m: pct(m["sweep"]["at_70"]["retained"]))
    row("mean per-class acc. at ≥70 %", lambda m: m["sweep"]["at_70"]["mean_per_class_accuracy"])
    row("true failures kept at ≥70 %", lambda m: failures_kept(m["sweep"]["at_70"]))
    row("accuracy rises as τ falls", lambda m: m["sweep"]["verdict"])
    row("cluster purity by dominant phenomenon", lambda m: pct(m["clustering"].get("purity")))
    out.append(table(["metric"] + names, rows))
    counts = ", ".join(f"{r.name} {len(r.label)}" for r in runs)
    coverage = (f" A cell is labelled only where its detector gave a verdict (cells: {counts}); SGBM finds no "
                "disparity on much of a texture-less or dark floor, so each detector's failures are counted among "
                "the cells it judged, not among the same cells." if "dense" in {r.detector for r in runs}
                and len({r.detector for r in runs}) > 1 else "")
    out.append("\nNote: each model is evaluated on its own detector's labels (its own dataset), so the sample sets "
               "differ; accuracies compare how well each introspection model predicts its own detector's failures."
               + coverage + "\n")
    out.append("\n**Per phenomenon** — fraction of the phenomenon's samples that each model predicts as FN / FP, "
               "next to the detector's true FN / FP rate (from the labels):\n\n")
    codes = sorted({e["phenomenon"] for r in runs for e in metrics[r.slug]["per_phenomenon"]})
    headers = ["phenomenon"]
    for n in names:
        headers += [f"{n}: n", f"{n}: predicted FN (true)", f"{n}: predicted FP (true)"]
    trows = []
    for c in codes:
        cells = [phenomenon_name(c)]
        for r in runs:
            e = next((e for e in metrics[r.slug]["per_phenomenon"] if e["phenomenon"] == c), None)
            if e is None:
                cells += [0, "n/a", "n/a"]
            else:
                cells += [e["n"], f"{pct(e['pred_fn'], 0)} ({pct(e['true_fn'], 0)})",
                          f"{pct(e['pred_fp'], 0)} ({pct(e['true_fp'], 0)})"]
        trows.append(cells)
    out.append(table(headers, trows))
    if sentences:
        out.append("\nNotable differences:\n\n" + "\n".join(f"- {s}" for s in sentences) + "\n")
    else:
        out.append("\nNo phenomenon's predicted FN or FP rate differs by 20 points or more between the models.\n")
    out.append(_causes_comparison(runs, metrics))
    out.append("\n" + image(figs["phenomena"], "predicted FN/FP per phenomenon"))
    out.append(image(figs["roc"], "ROC, all models"))
    out.append(image(figs["accuracy_vs_retained"], "accuracy vs retained, all models"))
    return "\n".join(out)


def _causes_comparison(runs: List[EvalRun], metrics: Dict[str, dict]) -> str:
    """Per cause, the share of each detector's true FP and FN it explains and
    how many of those the model predicts: each detector fails for its own
    reasons, and its model should see them."""
    have = [r for r in runs if metrics[r.slug].get("causes_of_failures")]
    if not have:
        return ""
    codes = sorted({e["cause"] for r in have for k in ("FP", "FN")
                    for e in metrics[r.slug]["causes_of_failures"][k]["causes"]},
                   key=lambda c: (c in (0, 128), c))
    headers = ["cause"] + [f"{r.name}: {k} (n = {metrics[r.slug]['causes_of_failures'][k]['n']})"
                           for r in have for k in ("FP", "FN")]
    rows = []
    for code in codes:
        cells = [cause_name(code)]
        for r in have:
            for k in ("FP", "FN"):
                e = next((e for e in metrics[r.slug]["causes_of_failures"][k]["causes"] if e["cause"] == code), None)
                cells.append(f"{pct(e['share'], 0)} ({pct(e['predicted'], 0)})" if e else "–")
        rows.append(cells)
    return ("\n**By cause** (`ivoa-sim-causes`) — share of each detector's true FP and FN (with a known cause) "
            "that removing the phenomenon alone fixes, and in brackets how many of those the model predicts as "
            "that failure. A failure can have several causes, so a column can add up to more than 100 %. "
            "'0 %': the cause explains a few failures, under half a percent; '–': none.\n\n"
            + table(headers, rows))


def settings_section(settings: Dict[str, List[dict]]) -> str:
    """Other settings of each detector, tried on the same frames: what they
    fix and what they break."""
    if not settings:
        return ""
    rows = []
    for detector, entries in sorted(settings.items()):
        for e in entries:
            def cell(key):
                return f"{pct(e[key]['share'], 0)} of {e[key]['n']}" if e[key]["n"] else "–"
            rows.append([detector, e["variant"], cell("FP"), cell("FN"), cell("FP_none_found"),
                         cell("FN_none_found"), cell("TP"), cell("TN")])
    return ("\n## Other detector settings on the same frames\n\n"
            "`ivoa-sim-causes --variant` re-ran each detector with other settings on the frames as they were "
            "(those with failures). *Fixes*: the failures it gets right; *breaks*: the right verdicts it gets "
            "wrong. A setting explains failures only where it fixes far more of them than it breaks: one that "
            "fixes the misses and breaks free cells at a similar rate merely says \"obstacle\" more often.\n\n"
            + table(["detector", "setting", "fixes FP", "fixes FN", "fixes FP with no cause found",
                     "fixes FN with no cause found", "breaks TP", "breaks TN"], rows) + "\n")


def _rate_extremes(runs: List[EvalRun], metrics: Dict[str, dict], code, key: str, min_samples: int):
    """(highest, lowest) of one per-phenomenon rate over the models with enough
    samples of that phenomenon, each as (rate, model name, entry); None if fewer
    than two models qualify."""
    vals = []
    for r in runs:
        e = next((e for e in metrics[r.slug]["per_phenomenon"] if e["phenomenon"] == code), None)
        if e is not None and e["n"] >= min_samples:
            vals.append((e[key], r.name, e))
    if len(vals) < 2:
        return None
    return max(vals, key=lambda t: t[0]), min(vals, key=lambda t: t[0])


def comparison_sentences(runs: List[EvalRun], metrics: Dict[str, dict], min_diff: float = 0.2,
                         min_samples: int = 30) -> List[str]:
    """Plain-language differences such as
    "textureless patches are a predicted FN for jppc (60 %) and not for dense
    (3 %)", for predicted rates differing by >= 20 points on phenomena with at
    least min_samples cells in both models (fewer make the rates noise); then
    the same for the true rates (which detector really fails where, from the
    labels)."""
    out = []
    codes = sorted({e["phenomenon"] for r in runs for e in metrics[r.slug]["per_phenomenon"]})
    for c in codes:
        for key, kind in (("pred_fn", "FN"), ("pred_fp", "FP")):
            extremes = _rate_extremes(runs, metrics, c, key, min_samples)
            if extremes is None:
                continue
            hi, lo = extremes
            if hi[0] - lo[0] >= min_diff:
                truth = "true_fn" if kind == "FN" else "true_fp"
                out.append(
                    f"**{phenomenon_name(c)}** patches are a predicted {kind} for {hi[1]} ({pct(hi[0], 0)} of "
                    f"{hi[2]['n']}; true {kind} rate {pct(hi[2][truth], 0)}) and "
                    f"{'not' if lo[0] < 0.05 else 'less often'} for {lo[1]} ({pct(lo[0], 0)} of {lo[2]['n']}; "
                    f"true {kind} rate {pct(lo[2][truth], 0)}).")
    for c in codes:
        for key, kind in (("true_fn", "FN"), ("true_fp", "FP")):
            extremes = _rate_extremes(runs, metrics, c, key, min_samples)
            if extremes is None:
                continue
            hi, lo = extremes
            det = {r.name: r.label_detector or r.detector for r in runs}
            if hi[0] - lo[0] >= min_diff:
                out.append(f"Labels: on **{phenomenon_name(c)}** the {det[hi[1]]} detector (labels of {hi[1]}) truly "
                           f"fails as {kind} {pct(hi[0], 0)} of the time, the {det[lo[1]]} detector (labels of "
                           f"{lo[1]}) {pct(lo[0], 0)}.")
    return out


def method_notes(opt: ClusterOptions) -> str:
    """Where the paper and the reference code disagree and what this report
    does (spec §4); the numbers follow the options actually used."""
    norm = {"l2": "L2 (default)", "softmax": "softmax over the 256 dims, as the reference code",
            "none": "none (raw post-ReLU activations)"}[opt.embedding_norm]
    space = ("the normalised 256-d embedding space (paper and paper-era script; HEAD clustered after PCA to 100)"
             if opt.space == "embedding" else "the PCA space (`--cluster-space pca`; HEAD clustered after PCA to 100)")
    select = {"confidence": "top 50 % most confident of the predicted FP and FN pooled (`--select confidence`, one "
                            "reading of the paper; median split of the predicted-class probability) instead of the "
                            "reference's var_predicted ≤ 0.03; the report counts what the reference rule keeps",
              "confidence-per-class": "the top 50 % most confident of the predicted FP and of the predicted FN, each "
                                      "split at its own median (default), where the paper's words (\"the top 50 % "
                                      "most confident\") leave open whether FP and FN are pooled; pooled "
                                      "(`--select confidence`), the less confident of the two can all but vanish "
                                      "from the selection (JPP-C's FN did in the default main job, 16 of 1902). "
                                      "The reference kept var_predicted ≤ 0.03; the report counts what that rule "
                                      "keeps",
              "variance": "var_predicted ≤ 0.03 (the reference script's rule, `--select variance`; the paper keeps "
                          "the top 50 % most confident)"}[opt.select]
    return f"""## Method notes: paper vs reference code

Where the paper (Rabiee & Biswas, IROS 2019) and the public reference code disagree, this report follows the
paper (see `shared/reference/ivoa_jpp_spec.md` §4):

- **Headline metric**: mean of per-class accuracies (paper) rather than the reference `analyze_results.py`'s
  plain overall accuracy; both are reported. A class absent from the truth is left out of the mean.
- **Uncertainty gate**: the variance of the predicted class's probability over the MC-dropout passes
  (`var_predicted`, as in the reference analysis script); the heatmaps' mean-over-classes variance
  (`uncertainty`) is not used for the sweep. The sweep uses 101 quantiles of var_predicted plus the reference's
  linspace(2e-5, 0.12, 100); the "≥ 70 %" operating point is the strictest threshold that keeps at least 70 %.
- **Clustering selection**: {select}.
- **Dimensionality**: PCA to a tenth of the dimension (256 → 26, paper) instead of the reference's 20 (paper era)
  or 50 (HEAD); t-SNE (for the picture only) runs {opt.tsne_iterations} iterations (reference: 300),
  perplexity {opt.perplexity:g}, random_state {opt.seed}, on at most {opt.tsne_max} points drawn with a fixed seed
  (2-core machine).
- **k-means** (k = {opt.k}, 10 restarts) runs in {space}.
- **Embedding normalisation**: {norm}; the reference softmax-normalised the 256 activations
  (`--embedding-norm softmax` reproduces it). L2 keeps the direction of the activation pattern and makes the
  mosaic weight 1/(0.1 + distance) meaningful (raw distances are tens, which makes the weights nearly uniform).
- **Mosaics**: 5 × 10 patches per cluster sampled without replacement with weight 1/(0.1 + distance to the
  centre), as in the reference.
- **Patch-level predictions** are at each sample's exact pixel (the reference's patch-level test), not the nearest
  heatmap cell.
"""
