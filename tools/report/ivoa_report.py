#!/usr/bin/env python3
"""ivoa_report: turn ivoa-eval outputs into the IVOA paper's metrics, figures,
failure clustering and one Markdown report.

    python3 tools/report/ivoa_report.py --eval EVAL_DIR [--eval EVAL_DIR2 ...] \\
        --dataset DATASET_DIR [--dataset DATASET_DIR2 ...] --out REPORT_DIR [--title ...]

Each EVAL_DIR is one ``ivoa-eval --out`` folder (one introspection model, e.g.
trained for JPP-C, another for the dense SGBM detector). ``--dataset`` is the
dataset the evals ran on: give it once for all, or once per ``--eval`` in the
same order (models of different detectors have different datasets). The report
folder gets ``report.md``, ``metrics.json`` (every number in the report) and the
PNG figures, one subfolder per model plus ``comparison/``.

Exit codes: 0 done, 2 bad command line, 3 bad input (the message names the file
and the problem), 4 the report cannot be written (the message names the path and
the system's reason), 1 anything else (a bug: please report it with the traceback).
See tools/report/README.md for what the report holds.
"""

from __future__ import annotations

import os
import sys

# OpenMP threads (scikit-learn's t-SNE and k-means) that spin while waiting are
# several times slower when the cores are shared with other jobs; sleep instead.
# Must be set before the OpenMP runtime loads, i.e. before numpy/sklearn.
os.environ.setdefault("OMP_WAIT_POLICY", "passive")

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_BAD_INPUT, EXIT_CANNOT_WRITE = 0, 1, 2, 3, 4


if __name__ == "__main__":
    import scientific_python
    scientific_python.ensure(("matplotlib", "numpy", "sklearn"), "python3-numpy python3-matplotlib python3-sklearn")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import argparse  # noqa: E402
import datetime  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import shlex  # noqa: E402
import shutil  # noqa: E402
from typing import Dict, List, Optional  # noqa: E402

import numpy as np  # noqa: E402

import report_figures as figures  # noqa: E402
import report_markdown as md  # noqa: E402
import report_metrics as metrics  # noqa: E402
from report_clustering import ClusterOptions, cluster_failures  # noqa: E402
from report_inputs import (Dataset, EvalRun, InputError, attach_causes, attach_dataset, evidence_margin,  # noqa: E402
                           load_causes, load_eval, load_repeatability, load_variants, make_names, other_camera,
                           patch_scale, patch_sides, patch_size, query_grid, seen_in_training)


class _ShowDefaults(argparse.ArgumentDefaultsHelpFormatter):
    """--help shows each option's default, where it has one."""

    def _get_help_string(self, action):
        if action.required or action.default in (None, argparse.SUPPRESS, False):
            return action.help
        return super()._get_help_string(action)


def parse_args(argv: Optional[List[str]]) -> argparse.Namespace:
    """Command line; usage errors exit with argparse's code 2."""
    p = argparse.ArgumentParser(
        prog="ivoa_report.py",
        description="IVOA analysis report: metrics, failure detection, uncertainty sweep, failure clustering, "
                    "model comparison, as PNG figures and report.md.",
        formatter_class=_ShowDefaults)
    p.add_argument("--eval", action="append", required=True, metavar="EVAL_DIR",
                   help="an ivoa-eval output folder (repeat for several models)")
    p.add_argument("--dataset", action="append", required=True, metavar="DATASET_DIR",
                   help="the dataset the eval ran on: once for all evals, or once per --eval in the same order")
    p.add_argument("--out", required=True, metavar="REPORT_DIR", help="report folder (created)")
    p.add_argument("--title", default="IVOA introspection report", help="the report's heading")
    p.add_argument("--clusters", type=int, default=2, metavar="K", help="k-means clusters (paper: 2)")
    p.add_argument("--select", choices=("confidence-per-class", "confidence", "variance"),
                   default="confidence-per-class",
                   help="failures to cluster: the top 50%% by confidence of the predicted FP and of the predicted "
                        "FN, of both pooled, or var_predicted <= 0.03 (reference)")
    p.add_argument("--embedding-norm", choices=("l2", "softmax", "none"), default="l2",
                   help="FC2 embedding normalisation before clustering (reference code: softmax)")
    p.add_argument("--cluster-space", choices=("embedding", "pca"), default="embedding",
                   help="where k-means runs: normalised 256-d embeddings (paper) or their PCA scores")
    p.add_argument("--tsne-max", type=int, default=3000, help="subsample t-SNE input to this many points")
    p.add_argument("--tsne-iterations", type=int, default=500, help="t-SNE iterations (>= 250)")
    p.add_argument("--perplexity", type=float, default=40.0,
                   help="t-SNE perplexity: about how many neighbours each point keeps close")
    p.add_argument("--seed", type=int, default=0, help="k-means, t-SNE, subsampling and mosaic seed")
    p.add_argument("--threads", type=int, default=1,
                   help="OpenMP threads for t-SNE and k-means (1 is fastest on a busy shared machine)")
    p.add_argument("--causes", action="append", metavar="CAUSES_CSV",
                   help="ivoa-sim-causes output for the test sessions' logs (once per detector): composition and "
                        "purity of the clusters by what causes each failure (simulated sessions only)")
    p.add_argument("--variants", action="append", metavar="VARIANTS_CSV",
                   help="ivoa-sim-causes --variants-out output: what other detector settings fix and break on the "
                        "same frames (with --causes from the same run, also among the failures with no cause found)")
    p.add_argument("--evidence-threshold", type=float, default=0.75, metavar="COST",
                   help="the labels' detector's threshold on its evidence (JPP-C's conf_pos_thresh: a cell is an "
                        "obstacle iff its worst window cost reaches it), for accuracy by the detector's margin")
    p.add_argument("--repeatability", metavar="JSON",
                   help="ivoa_label_repeatability.py --json output for the test sessions (simulator only): sets "
                        "how often another sensor-noise draw keeps the detector's verdict beside the model, band "
                        "by band of the margin")
    p.add_argument("--max-overlays", type=int, default=0,
                   help="copy at most this many overlay figures per model into the report (0 = all)")
    a = p.parse_args(argv)
    if a.clusters < 2:
        p.error("--clusters must be at least 2")
    if len(a.dataset) not in (1, len(a.eval)):
        p.error(f"give --dataset once, or once per --eval ({len(a.eval)}); got {len(a.dataset)}")
    if a.tsne_max < 5:
        p.error("--tsne-max must be at least 5")
    if a.tsne_iterations < 250:
        p.error("--tsne-iterations must be at least 250 (scikit-learn's minimum)")
    if not a.perplexity > 0:
        p.error(f"--perplexity must be > 0, not {a.perplexity:g}")
    if a.threads < 1:
        p.error(f"--threads must be at least 1, not {a.threads}")
    if a.max_overlays < 0:
        p.error(f"--max-overlays must be >= 0 (0 = all), not {a.max_overlays}")
    if not 0 <= a.seed < 2**32:
        p.error(f"--seed must be in 0 .. 4294967295 (numpy's and scikit-learn's range), not {a.seed}")
    if not math.isfinite(a.evidence_threshold):
        p.error(f"--evidence-threshold must be a number, not {a.evidence_threshold}")
    # Inside an input its files mixed with the eval's, or a later ivoa-dataset
    # build refused the session folder they landed in.
    for folder in a.eval + a.dataset:
        if _inside(a.out, folder):
            p.error(f"--out {a.out} is the input {folder} or lies in it: name a folder of its own")
    return a


def load_inputs(args: argparse.Namespace):
    """Reads every eval folder and its dataset, checking they agree, and the
    causes and variants CSVs and the noise repeatability figures. Raises
    InputError on bad input; returns the runs, the detector settings'
    figures, the repeatability figures (or None) and warnings for the report."""
    runs = [load_eval(p) for p in args.eval]
    make_names(runs)
    datasets: Dict[str, Dataset] = {}
    warnings: List[str] = []
    for i, run in enumerate(runs):
        path = args.dataset[i if len(args.dataset) > 1 else 0]
        key = os.path.realpath(path)
        if key not in datasets:
            datasets[key] = Dataset(path)
        warnings += attach_dataset(run, datasets[key])
        warnings += seen_in_training(run)
        warnings += other_camera(run)
    causes = [load_causes(path) for path in args.causes or []]
    if causes:
        for run in runs:
            warnings += attach_causes(run, causes)
    settings = metrics.detector_settings([load_variants(path) for path in args.variants or []], causes)
    noise = load_repeatability(args.repeatability, args.evidence_threshold) if args.repeatability else None
    return runs, settings, noise, warnings


def analyse_run(run: EvalRun, args: argparse.Namespace, opt: ClusterOptions, out_dir: str, colour: str,
                noise: Optional[dict] = None):
    """All numbers and figures for one model, drawn in its colour. Returns
    (numbers for metrics.json, figure paths relative to the report,
    clustering result, overlay paths)."""
    d = os.path.join(out_dir, run.slug)
    os.makedirs(d, exist_ok=True)
    rm = run_numbers(run, args, noise)
    figs = run_figures(run, rm, d, colour)
    res = cluster_failures(run, opt)
    if res.ok:
        figs["scatter"] = figures.plot_cluster_scatter(run, res, run.name, os.path.join(d, "clusters_tsne.png"))
        for c in sorted(res.mosaic_rows):
            figs[f"mosaic_{c}"] = figures.plot_mosaic(run, res, c, f"{run.name}: cluster {c}",
                                                     os.path.join(d, f"cluster_{c}_mosaic.png"))
    rm["clustering"] = clustering_numbers(res, opt)
    overlays = run.overlays[: args.max_overlays] if args.max_overlays > 0 else run.overlays
    copied = copy_overlays(overlays, os.path.join(d, "overlays"), out_dir)
    rel_figs = {k: os.path.relpath(v, out_dir) for k, v in figs.items()}
    return rm, rel_figs, res, copied


def run_numbers(run: EvalRun, args: argparse.Namespace, noise: Optional[dict]) -> dict:
    """The metrics of one model, as metrics.json holds them (clustering added later)."""
    grid = query_grid(run)
    sweep = metrics.uncertainty_sweep(run)
    verdict = metrics.given_verdict(run)
    return {
        "name": run.name, "eval_dir": run.path, "dataset": run.dataset.path if run.dataset else None,
        "detector": run.detector, "model": run.meta.get("model"), "mc_passes": run.meta.get("mc_passes"),
        "overall": metrics.class_metrics(run.label, run.predicted),
        "intervals": metrics.headline_intervals(run, sweep, verdict["sweep"] if verdict else None),
        "environments": metrics.grouped_metrics(run, run.environment),
        "sessions": metrics.grouped_metrics(run, run.session, describe_sessions=True),
        "distances": metrics.by_distance(run, grid.get("safety_radius"), patch_sides(run)),
        "patch_size": patch_size(run),
        "patch_scale": patch_scale(run),
        "failure": metrics.failure_detection(run.label, run.predicted, run.probs),
        "sweep": sweep,
        "per_phenomenon": metrics.per_phenomenon(run),
        "given_verdict": verdict,
        "by_margin": metrics.by_margin(run, evidence_margin(run, args.evidence_threshold), args.evidence_threshold,
                                       noise),
        "causes_of_failures": metrics.causes_of_failures(run),
    }


def run_figures(run: EvalRun, rm: dict, d: str, colour: str) -> Dict[str, str]:
    """The figures of one model's numbers, in its colour, written into d: {name: path}."""
    figs = {
        "confusion": figures.plot_confusion(rm["overall"], run.name, os.path.join(d, "confusion.png")),
        "sessions": figures.plot_group_bars(rm["sessions"], f"{run.name}: accuracy per session", "session",
                                            os.path.join(d, "accuracy_per_session.png")),
        "distances": figures.plot_group_bars(rm["distances"], f"{run.name}: accuracy by distance ahead",
                                             "query point ahead of the robot (x)",
                                             os.path.join(d, "accuracy_by_distance.png")),
        "accuracy_vs_threshold": figures.plot_accuracy_vs_threshold(
            rm["sweep"], run.name, os.path.join(d, "accuracy_vs_threshold.png"), colour),
        "retained_vs_threshold": figures.plot_retained_vs_threshold(
            rm["sweep"], run.name, os.path.join(d, "retained_vs_threshold.png")),
        "accuracy_vs_retained": figures.plot_accuracy_vs_retained(
            [(run.name, rm["sweep"], colour)], run.name, os.path.join(d, "accuracy_vs_retained.png")),
    }
    if rm["given_verdict"] is not None:
        figs["verdict_accuracy_vs_retained"] = figures.plot_accuracy_vs_retained(
            [("image alone", rm["sweep"], colour),
             ("given the detector's verdict", rm["given_verdict"]["sweep"], figures.GIVEN_VERDICT_COLOUR)],
            run.name, os.path.join(d, "verdict_accuracy_vs_retained.png"))
    if rm["by_margin"] and rm["by_margin"]["ok"]:
        figs["margin_bands"] = figures.plot_margin_bands(rm["by_margin"], run.name,
                                                         os.path.join(d, "accuracy_by_margin.png"))
    if rm["failure"]["roc"]:
        figs["roc"] = figures.plot_roc([(run.name, rm["failure"], colour)], run.name,
                                       os.path.join(d, "failure_roc.png"))
    return figs


def clustering_numbers(res, opt: ClusterOptions) -> dict:
    """What metrics.json keeps of a clustering result."""
    return {
        "ok": res.ok, "message": res.message, "selection": opt.select, "embedding_norm": opt.embedding_norm,
        "space": opt.space, "k": opt.k, "n_predicted_fp": res.n_predicted_fp, "n_predicted_fn": res.n_predicted_fn,
        "n_selected": res.n_selected, "confidence_cut": res.confidence_cut,
        "n_reference_rule": res.n_reference_rule, "pca_components": res.pca_components,
        "pca_explained": res.pca_explained, "tsne_points": int(len(res.tsne_index)), "clusters": res.clusters,
        "purity": res.purity if res.has_truth else None,
        "purity_one_cluster": res.purity_one_cluster if res.has_truth else None, "nmi": res.nmi, "ari": res.ari,
        "purity_by_k": res.k_scan if res.has_truth else [], "has_ground_truth": res.has_truth,
        "n_with_cause": res.n_with_cause, "purity_by_cause": res.cause_purity,
        "purity_by_cause_one_cluster": res.cause_purity_one_cluster,
        "purity_by_cause_set": res.cause_set_purity, "best_possible_by_cause_set": res.cause_set_best_possible,
        "nmi_by_cause_set": res.cause_nmi,
    }


def copy_overlays(overlays: List[str], into: str, out_dir: str) -> List[str]:
    """Copies the overlay pictures into the report; their paths relative to out_dir."""
    if overlays:
        os.makedirs(into, exist_ok=True)
    copied = []
    for src in overlays:
        dst = os.path.join(into, os.path.basename(src))
        shutil.copyfile(src, dst)
        copied.append(os.path.relpath(dst, out_dir))
    return copied


def compare(runs: List[EvalRun], numbers: Dict[str, dict], out_dir: str) -> str:
    """The comparison section (two or more models): figures and Markdown."""
    d = os.path.join(out_dir, "comparison")
    names = [r.name for r in runs]
    colours = [figures.model_colour(i) for i in range(len(runs))]
    figs = {
        "phenomena": figures.plot_phenomenon_comparison(
            names, [numbers[r.slug]["per_phenomenon"] for r in runs], os.path.join(d, "phenomena_fn_fp.png"),
            "all models", colours),
        "roc": figures.plot_roc([(r.name, numbers[r.slug]["failure"], c) for r, c in zip(runs, colours)],
                                "all models", os.path.join(d, "failure_roc.png")),
        "accuracy_vs_retained": figures.plot_accuracy_vs_retained(
            [(r.name, numbers[r.slug]["sweep"], c) for r, c in zip(runs, colours)], "all models",
            os.path.join(d, "accuracy_vs_retained.png")),
    }
    rel = {k: os.path.relpath(v, out_dir) for k, v in figs.items()}
    sentences = md.comparison_sentences(runs, numbers)
    numbers["_comparison"] = {"sentences": sentences}
    return md.comparison_section(runs, numbers, rel, sentences)


def summary_section(runs: List[EvalRun], numbers: Dict[str, dict]) -> str:
    """Headline numbers, one row per model, at the top of the report."""
    rows = []
    for r in runs:
        h = metrics.headline(numbers[r.slug])
        c = numbers[r.slug]["clustering"]
        given = (f"{_shown(h, 'verdict_mean_per_class_accuracy')}; {md.pct(h['verdict_retained_at_70'])} → "
                 f"{_shown(h, 'verdict_mpca_at_70')} ({md.failures_kept(h['verdict_at_70'])})"
                 if h["verdict_mean_per_class_accuracy"] is not None else "n/a")
        rows.append([r.name, r.detector, h["samples"], _shown(h, "mean_per_class_accuracy"),
                     md.fmt(h["overall_accuracy"]), md.fmt(h["failure_auroc"]),
                     f"{md.pct(h['retained_at_70'])} → {_shown(h, 'mpca_at_70')} ({md.failures_kept(h['at_70'])})",
                     given,
                     _purity_with_base(c, "purity", "purity_one_cluster"),
                     _purity_with_base(c, "purity_by_cause", "purity_by_cause_one_cluster")])
    key = ("Each sample is a ground cell ahead of the robot, labelled by the depth monitor against the stereo "
           "detector's verdict: TP = an obstacle the detector reports, TN = free space it reports free, FP = an "
           "obstacle it reports where there is none, FN = an obstacle it misses. The introspection model predicts "
           "that label from the image; FP and FN are the detector's failures. \"FP x %, FN y % kept\": the share of "
           "the true FP and FN whose prediction the uncertainty gate still passes at that point. [a, b]: the 95 % "
           "interval over 1000 resamples of whole frames (a frame's cells share its image and noise); each model's "
           "sections 1, 3 and 4 also give the one over whole test sessions where there are enough (wider: it also "
           "counts which scenes were tested).\n\n")
    return key + md.table(["model", "detector", "samples", "mean per-class acc.", "overall acc.", "failure AUROC",
                     "≥70 % retained → mean per-class acc.", "given the detector's verdict: mean per-class acc.; "
                     "≥70 % retained →", "cluster purity by dominant phenomenon (one cluster)",
                     "cluster purity by cause (one cluster)"], rows)


def _shown(h: dict, key: str) -> str:
    """A headline figure with its frame-bootstrap interval, where it has one."""
    return md.with_interval(h[key], h["intervals"].get(key))


def _purity_with_base(c: dict, key: str, base_key: str) -> str:
    """A purity beside what one cluster holding every sample would score: what the clusters add."""
    if not c["ok"] or c.get(key) is None:
        return "n/a"
    base = c.get(base_key)
    return md.pct(c[key]) + (f" ({md.pct(base)})" if base is not None else "")


def inputs_section(runs: List[EvalRun]) -> str:
    """Where each model's numbers come from."""
    rows = []
    for r in runs:
        tr = (r.meta.get("metadata") or {}).get("training") or {}
        sessions = ", ".join(f"{s} ({sp})" for s, sp in sorted({(a, b) for a, b in zip(r.session, r.split)}))
        rows.append([r.name, r.meta.get("model", "n/a"), (r.meta.get("metadata") or {}).get("architecture", "n/a"),
                     r.meta.get("mc_passes", "n/a"), r.path, r.dataset.path if r.dataset else "n/a", sessions,
                     _training_steps(tr)])
    return md.table(["model", "model file", "architecture", "T (MC passes)", "eval folder", "dataset",
                     "evaluated sessions (split)", "weights from training step"], rows)


def _training_steps(training: dict) -> str:
    """The training step whose weights the file holds, and, where the file records them (ivoa-train
    since 2026-12-03), the steps the run was set to and which model it kept."""
    step = training.get("best_step", training.get("steps"))
    if step is None:
        return "n/a"
    planned, kept = training.get("steps_planned"), training.get("kept")
    if planned is None:
        return str(step)
    return f"{step} of {planned}" + {"best_validated": ", best on validation", "last": ", the last"}.get(kept, "")


def _json_default(o):
    """numpy scalars/arrays in metrics.json."""
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(type(o).__name__)


class OutputError(Exception):
    """The report folder or a file in it cannot be written (exit code 4); the
    message names the path and the system's reason."""


def run_report(args: argparse.Namespace, argv: List[str]) -> int:
    """Loads, analyses, writes report.md + metrics.json, prints the summary."""
    try:  # before minutes of loading and analysis, not after
        os.makedirs(args.out, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{e.filename or args.out}: {e.strerror or e}") from None
    if not os.access(args.out, os.W_OK | os.X_OK):
        raise OutputError(f"{args.out}: this user may not write in it")
    runs, settings, noise, warnings = load_inputs(args)
    try:
        numbers, report_path = write_report(args, argv, runs, settings, noise, warnings)
    except OSError as e:  # the report's own files cannot be written, or an input read late cannot be read
        where = e.filename or args.out
        if _inside(where, args.out):
            raise OutputError(f"{where}: {e.strerror or e}") from None
        raise InputError(f"{where}: cannot read ({e.strerror or e})") from None
    print_summary(runs, numbers, warnings, report_path)
    return EXIT_OK


def _inside(path, folder: str) -> bool:
    """Whether `path` is `folder` or lies under it."""
    path, folder = os.path.realpath(str(path)), os.path.realpath(folder)
    return path == folder or path.startswith(folder + os.sep)


def write_report(args: argparse.Namespace, argv: List[str], runs: List[EvalRun], settings, noise: Optional[dict],
                 warnings: List[str]):
    """The analysis, its figures, report.md and metrics.json; returns (numbers per model, report.md's path)."""
    out_dir = args.out
    os.makedirs(out_dir, exist_ok=True)
    opt = ClusterOptions(k=args.clusters, select=args.select, embedding_norm=args.embedding_norm,
                         space=args.cluster_space, tsne_max=args.tsne_max, perplexity=args.perplexity,
                         tsne_iterations=args.tsne_iterations, seed=args.seed, threads=max(1, args.threads))
    numbers: Dict[str, dict] = {}
    sections = []
    for i, run in enumerate(runs):
        rm, figs, res, overlays = analyse_run(run, args, opt, out_dir, figures.model_colour(i), noise)
        numbers[run.slug] = rm
        sections.append("\n".join([
            f"## Model: {run.name}\n",
            f"Eval folder `{run.path}`, dataset `{rm['dataset']}`, detector **{run.detector}**, "
            f"model `{rm['model']}`, T = {rm['mc_passes']} MC-dropout passes.\n",
            md.metrics_section(run, rm, figs), md.failure_section(rm, figs), md.uncertainty_section(rm, figs),
            md.verdict_section(rm, figs), md.clustering_section(run, res, opt, figs),
            md.overlays_section(overlays, str(run.meta.get("overlay_dots", "image")))]))
    comparison = compare(runs, numbers, out_dir) if len(runs) > 1 else ""

    cmd = "python3 tools/report/ivoa_report.py " + " ".join(shlex.quote(a) for a in argv)
    parts = [f"# {args.title}\n",
             f"Generated {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')} by `{cmd}`. All numbers are also in "
             f"[metrics.json](metrics.json).\n",
             "## Summary\n", summary_section(runs, numbers), "\n## Inputs\n", inputs_section(runs)]
    if warnings:
        parts.append("\n**Warnings**\n\n" + "\n".join(f"- {w}" for w in sorted(set(warnings))) + "\n")
    parts += sections
    if comparison:
        parts.append(comparison)
    parts.append(md.settings_section(settings))
    parts.append(md.method_notes(opt))
    report_path = os.path.join(out_dir, "report.md")
    with open(report_path, "w", encoding="utf-8") as f:
        f.write("\n".join(parts))
    with open(os.path.join(out_dir, "metrics.json"), "w", encoding="utf-8") as f:
        json.dump({"title": args.title, "models": numbers, "detector_settings": settings,
                   "warnings": sorted(set(warnings))}, f, indent=1, default=_json_default)
    return numbers, report_path


def print_summary(runs: List[EvalRun], numbers: Dict[str, dict], warnings: List[str], report_path: str) -> None:
    """The warnings on stderr; the headline numbers per model and report.md's path on stdout."""
    for w in sorted(set(warnings)):
        print(f"warning: {w}", file=sys.stderr)
    for run in runs:
        h = metrics.headline(numbers[run.slug])
        c = numbers[run.slug]["clustering"]
        print(f"{run.name}: {h['samples']} samples, mean per-class accuracy {_shown(h, 'mean_per_class_accuracy')}, "
              f"overall {md.fmt(h['overall_accuracy'])}, failure AUROC {md.fmt(h['failure_auroc'])}, "
              f"at {md.pct(h['retained_at_70'])} retained {_shown(h, 'mpca_at_70')} ({md.failures_kept(h['at_70'])}), "
              + (f"given the detector's verdict {_shown(h, 'verdict_mean_per_class_accuracy')} "
                 f"({_shown(h, 'verdict_mpca_at_70')} at {md.pct(h['verdict_retained_at_70'])}, "
                 f"{md.failures_kept(h['verdict_at_70'])}), "
                 if h["verdict_mean_per_class_accuracy"] is not None else "")
              + (f"cluster purity {_purity_with_base(c, 'purity', 'purity_one_cluster')}"
                 if c["ok"] and c["purity"] is not None
                 else "clustering: " + (c["message"] or "no phenomenon ground truth"))
              + (f", by cause {_purity_with_base(c, 'purity_by_cause', 'purity_by_cause_one_cluster')}"
                 if c["ok"] and c.get("purity_by_cause") is not None else "")
              + (" (in brackets: all in one cluster)" if c["ok"] and c["purity"] is not None else ""))
    print(f"report: {report_path}")


def main(argv: Optional[List[str]] = None) -> int:
    """Entry point; returns the exit code (bad input -> 3, unwritable report -> 4, with one message)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = parse_args(argv)
    except SystemExit as e:  # argparse: --help (0) or usage error (2)
        return int(e.code or 0)
    try:
        return run_report(args, argv)
    except InputError as e:
        print(f"ivoa_report: bad input: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OutputError as e:
        print(f"ivoa_report: cannot write the report: {e}", file=sys.stderr)
        return EXIT_CANNOT_WRITE


if __name__ == "__main__":
    sys.exit(main())
