#!/usr/bin/env python3
"""Tests of tools/report/ivoa_report.py on fabricated inputs whose answers are known.

A small dataset (2 sessions, 16x16 patches) and three ivoa-eval folders are
written to a temporary folder:

* **perfect**: predicted = label, confident; FC2 embeddings of reflection patches
  and of texture-less patches drawn from two well-separated Gaussians. Expect
  mean per-class accuracy 1, AUROC 1, cluster purity 1 with one cluster per
  phenomenon.
* **known**: per-class accuracies 0.75 / 0.9 / 0.7 / 0.6 by construction, and a
  variance that is high exactly on the wrong predictions. Expect mean per-class
  accuracy 0.7375, overall 0.775, failure precision 53/71, recall 53/80,
  AUROC 0.75625, 100 % accuracy at the 70 % operating point, "accuracy rises".
* **degenerate**: a second dataset without FN samples and a model with a single
  predicted failure: the report must say so instead of crashing.

Plus bad inputs (exit code 3 naming the file) and unit checks of the metric
functions against scikit-learn and a negative control for the uncertainty trend.

Run: python3 tests/report/test_report.py [--tool tools/report/ivoa_report.py] [--workdir DIR]
"""

import argparse
import contextlib
import csv
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import types
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.normpath(os.path.join(HERE, "..", "..", "tools", "report", "ivoa_report.py"))
WORKDIR = None
PATCH = 16
DIM = 256
TP, TN, FP, FN = 0, 1, 2, 3
LABEL_NAMES = ("TP", "TN", "FP", "FN")
REFLECTION, TEXTURELESS, DARK_STRIPE = 1, 2, 8
FLOOR, WALL = 1, 2

PRED_HEADER = ("session,environment,split,sample,utime,cell,x,y,u,v,label,predicted,p_tp,p_tn,p_fp,p_fn,"
               "var_predicted,uncertainty,var_tp,var_tn,var_fp,var_fn,phenomena,phenomenon,surface")
VERDICT_HEADER = ",stereo_state,verdict_predicted,p_wrong,var_wrong"


# ----------------------------------------------------------------------------- fabrication

def session_rows(counts, phenomenon_of, surface_of):
    """Sample rows of one session: `counts` samples per class, in class order."""
    rows = []
    for cls, n in enumerate(counts):
        for _ in range(n):
            rows.append({"label": cls, "phenomenon": phenomenon_of[cls], "surface": surface_of[cls]})
    return rows


def write_dataset(root, sessions, detector="jppc"):
    """An IVOA dataset folder (libs/dataset/README.md) with deterministic patch
    pixels: B = sample index, G = phenomenon * 40, R = 200 (so BGR->RGB can be checked)."""
    os.makedirs(root, exist_ok=True)
    with open(os.path.join(root, "dataset.json"), "w") as f:
        json.dump({"format": "ivoa-dataset", "version": 1, "patch_size": PATCH,
                   "label_names": ["TP", "TN", "FP", "FN"], "sessions": [s for s, _, _ in sessions]}, f)
    for name, env, rows in sessions:
        d = os.path.join(root, name)
        os.makedirs(d, exist_ok=True)
        counts = np.bincount([r["label"] for r in rows], minlength=4)
        with open(os.path.join(d, "session.json"), "w") as f:
            json.dump({"session": name, "detector": detector, "environment": env, "patch_size": PATCH,
                       "samples": len(rows), "class_counts": dict(zip(["TP", "TN", "FP", "FN"], counts.tolist()))}, f)
        patches = np.zeros((len(rows), PATCH, PATCH, 3), np.uint8)
        with open(os.path.join(d, "samples.csv"), "w") as f:
            f.write("sample,frame,utime,depth_utime,cell,label,stereo_state,depth_state,x,y,u,v,phenomena,"
                    "phenomenon,surface\n")
            for i, r in enumerate(rows):
                r["utime"] = 1_000_000 + 100_000 * (i // 10)
                r["cell"] = i % 10
                f.write(f"{i},{i // 10},{r['utime']},{r['utime'] + 4000},{r['cell']},{r['label']},0,0,1.0,0.0,"
                        f"480.0,400.0,{r['phenomenon']},{r['phenomenon']},{r['surface']}\n")
                patches[i, :, :, 0] = i % 256
                patches[i, :, :, 1] = 40 * r["phenomenon"]
                patches[i, :, :, 2] = 200
        patches.tofile(os.path.join(d, "patches.bin"))
        with open(os.path.join(d, "frames.csv"), "w") as f:
            f.write("frame,utime,depth_utime,cells_labelled,samples\n")


def write_evidence(root, sessions, margins, threshold=0.75):
    """evidence.f32 for each session of a dataset (3 values a sample: the worst
    at threshold + margin, one lower, one not observed; a NaN margin: none
    observed) and evidence_size in its session.json."""
    k = 0
    for name, _, rows in sessions:
        d = os.path.join(root, name)
        m = np.asarray(margins[k:k + len(rows)], np.float64)
        k += len(rows)
        ev = np.stack([threshold + m, threshold + m - 0.1, np.full(len(m), np.nan)], axis=1)
        ev.astype("<f4").tofile(os.path.join(d, "evidence.f32"))
        info = json.loads(read_text(os.path.join(d, "session.json")))
        info["evidence_size"] = 3
        with open(os.path.join(d, "session.json"), "w") as f:
            json.dump(info, f)


def write_eval(out, sessions, predicted, probs, var, embeddings, detector="jppc", threshold=0.03,
               overlay=False, verdict=None, overlay_dots=None):
    """An ivoa-eval output folder (tools/eval/README.md) for the given rows;
    with `verdict` (predicted, p_wrong, var_wrong arrays), the columns of the
    predictions given the detector's verdict too (stereo_state from the label)."""
    os.makedirs(out, exist_ok=True)
    k = 0
    with open(os.path.join(out, "predictions.csv"), "w") as f:
        f.write(PRED_HEADER + (VERDICT_HEADER if verdict else "") + "\n")
        for name, env, rows in sessions:
            split = "train" if env == "indoor" else "val"
            for i, r in enumerate(rows):
                p = probs[k]
                f.write(f"{name},{env},{split},{i},{r['utime']},{r['cell']},1.0,0.0,480.0,400.0,{r['label']},"
                        f"{predicted[k]},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{p[3]:.6f},{var[k]:.8f},{var[k] / 2:.8f},"
                        f"0,0,0,0,{r['phenomenon']},{r['phenomenon']},{r['surface']}")
                if verdict:
                    state = 1 if r["label"] in (TP, FP) else 0
                    f.write(f",{state},{verdict['predicted'][k]},{verdict['p_wrong'][k]:.5f},{verdict['var'][k]:.8f}")
                f.write("\n")
                k += 1
    np.asarray(embeddings, np.float32).tofile(os.path.join(out, "embeddings.f32"))
    # Per session, the views and patch scale of the dataset (write_dataset's: 1 and the default 0).
    meta = {"model": f"{detector}.pt#0000", "mc_passes": 20, "uncertainty_threshold": threshold,
            "samples": k, "sessions": [{"split": "test", "session": name, "patch_scale": 0, "views": 1}
                                       for name, _, _ in sessions],
            "metadata": {"detector": detector, "architecture": "slidenet", "training": {}}}
    if verdict:
        meta["verdict_uncertainty_threshold"] = threshold
    if overlay_dots:
        meta["overlay_dots"] = overlay_dots
    with open(os.path.join(out, "eval.json"), "w") as f:
        json.dump(meta, f)
    if overlay:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.image as mpimg
        os.makedirs(os.path.join(out, "overlays"), exist_ok=True)
        mpimg.imsave(os.path.join(out, "overlays", "office_s1_1000000.png"), np.zeros((8, 8, 3)))


def sweep_run(**columns):
    """A stand-in for an EvalRun of T = 20 passes with these columns, no run-time gate."""
    return types.SimpleNamespace(meta={"mc_passes": 20}, model_threshold=None, **columns)


def one_hot_probs(predicted, p_top=0.8):
    """Probabilities with p_top on the predicted class and the rest shared."""
    probs = np.full((len(predicted), 4), (1 - p_top) / 3)
    probs[np.arange(len(predicted)), predicted] = p_top
    return probs


# Per session: TP 20, TN 40, FP 25, FN 15 -> totals 40 / 80 / 50 / 30.
COUNTS = (20, 40, 25, 15)
# Wrong predictions per session and what they become: totals 10 / 8 / 15 / 12.
WRONG = {TP: (5, FN), TN: (4, FP), FP: (8, TN), FN: (6, TP)}
WRONG_TOTAL = {TP: (5 + 5), TN: (4 + 4), FP: (8 + 7), FN: (6 + 6)}
# Given the detector's verdict only the other class of its pair is possible:
# wrong predictions per session (TP <-> FP, TN <-> FN).
VERDICT_WRONG = {TP: 2, TN: 3, FP: 1, FN: 4}
VERDICT_OTHER = {TP: FP, FP: TP, TN: FN, FN: TN}


def fabricate(root):
    """Writes the datasets and evals; returns paths and the construction."""
    rng = np.random.default_rng(123)
    phen = {TP: 0, TN: 0, FP: REFLECTION, FN: TEXTURELESS}
    surf = {TP: WALL, TN: FLOOR, FP: FLOOR, FN: WALL}
    sessions = [("office_s1", "indoor", session_rows(COUNTS, phen, surf)),
                ("campus_s2", "outdoor", session_rows(COUNTS, phen, surf))]
    data = os.path.join(root, "data")
    write_dataset(data, sessions)
    rows = [r for _, _, rs in sessions for r in rs]
    label = np.array([r["label"] for r in rows])
    n = len(rows)

    # perfect model; embeddings: two Gaussians by phenomenon (post-ReLU: non-negative).
    mu_a = np.zeros(DIM)
    mu_a[:128] = 1.0
    mu_b = np.zeros(DIM)
    mu_b[128:] = 1.0
    emb = np.abs(rng.normal(0, 0.05, (n, DIM)))
    for i, r in enumerate(rows):
        if r["phenomenon"] == REFLECTION:
            emb[i] += mu_a
        elif r["phenomenon"] == TEXTURELESS:
            emb[i] += mu_b
    p_top = rng.uniform(0.6, 0.95, n)
    perfect_probs = np.zeros((n, 4))
    for i in range(n):
        perfect_probs[i] = (1 - p_top[i]) / 3
        perfect_probs[i, label[i]] = p_top[i]
    perfect = os.path.join(root, "perfect")
    write_eval(perfect, sessions, label, perfect_probs, rng.uniform(0.001, 0.01, n), emb, overlay=True,
               overlay_dots="given_verdict")

    # known model: the first WRONG[c][0] (session 1) / WRONG_TOTAL-that (session 2) samples of each class are wrong.
    predicted = label.copy()
    wrong = np.zeros(n, bool)
    k = 0
    for s, (_, _, rs) in enumerate(sessions):
        start = k
        for cls in range(4):
            idx = [start + i for i, r in enumerate(rs) if r["label"] == cls]
            n_wrong = WRONG[cls][0] if s == 0 else WRONG_TOTAL[cls] - WRONG[cls][0]
            for i in idx[:n_wrong]:
                predicted[i] = WRONG[cls][1]
                wrong[i] = True
        k += len(rs)
    var = np.where(wrong, rng.uniform(0.05, 0.1, n), rng.uniform(0.001, 0.02, n))
    # Given the verdict: the first VERDICT_WRONG[c] samples of each class per
    # session take the other class of the pair, with a high variance.
    v_pred = label.copy()
    v_wrong = np.zeros(n, bool)
    k = 0
    for _, _, rs in sessions:
        for cls in range(4):
            for i in [k + i for i, r in enumerate(rs) if r["label"] == cls][:VERDICT_WRONG[cls]]:
                v_pred[i], v_wrong[i] = VERDICT_OTHER[cls], True
        k += len(rs)
    v_failure = (v_pred == FP) | (v_pred == FN)
    verdict = {"predicted": v_pred, "p_wrong": np.where(v_failure, 0.8, 0.2),
               "var": np.where(v_wrong, rng.uniform(0.05, 0.1, n), rng.uniform(0.001, 0.02, n))}
    known = os.path.join(root, "known")
    write_eval(known, sessions, predicted, one_hot_probs(predicted), var, np.abs(rng.normal(0, 1, (n, DIM))),
               detector="dense", verdict=verdict)

    # JPP-C's evidence: the known model's wrong rows (all of which flip the
    # verdict) lie 0.02 from the threshold, the others 0.5; row 0 unobserved.
    obstacle = np.isin(label, (TP, FP))
    margin = np.where(obstacle, 1.0, -1.0) * np.where(wrong, 0.02, 0.5)
    margin[0] = np.nan
    write_evidence(data, sessions, margin)

    # degenerate: a dataset without FN, one predicted failure.
    d_sessions = [("lab_s3", "indoor", session_rows((10, 15, 5, 0), phen, surf))]
    data2 = os.path.join(root, "data_nofn")
    write_dataset(data2, d_sessions)
    d_label = np.array([r["label"] for r in d_sessions[0][2]])
    d_pred = np.full(len(d_label), TN)
    d_pred[0] = FP
    degenerate = os.path.join(root, "degenerate")
    write_eval(degenerate, d_sessions, d_pred, one_hot_probs(d_pred), rng.uniform(0.001, 0.05, len(d_label)),
               np.abs(rng.normal(0, 1, (len(d_label), DIM))))
    return types.SimpleNamespace(data=data, data2=data2, perfect=perfect, known=known, degenerate=degenerate,
                                 label=label, predicted=predicted, wrong=wrong, var=var, margin=margin,
                                 sessions=sessions,
                                 perfect_confidence=p_top)


# ----------------------------------------------------------------------------- tests

def read_text(path):
    """A file's text (closed promptly)."""
    with open(path, encoding="utf-8") as fh:
        return fh.read()


def load_tool():
    """Imports the tool's modules in-process (for unit checks and fast bad-input runs)."""
    if os.path.dirname(TOOL) not in sys.path:
        sys.path.insert(0, os.path.dirname(TOOL))
    import ivoa_report  # noqa: F401
    return ivoa_report


def run_main(argv):
    """ivoa_report.main in-process; returns (exit code, stdout, stderr)."""
    tool = load_tool()
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = tool.main(argv)
    return code, out.getvalue(), err.getvalue()


class ReportTest(unittest.TestCase):
    """End to end on the fabricated inputs, then the numbers in metrics.json."""

    @classmethod
    def setUpClass(cls):
        if WORKDIR:  # kept after the test for a look at the report; only our subfolder is replaced
            cls.root = os.path.join(WORKDIR, "fabricated")
            shutil.rmtree(cls.root, ignore_errors=True)
            os.makedirs(cls.root)
        else:
            cls.root = tempfile.mkdtemp(prefix="ivoa_report_test_")
        cls.f = fabricate(cls.root)
        cls.out = os.path.join(cls.root, "report")
        cls.proc = subprocess.run(
            [sys.executable, TOOL, "--eval", cls.f.perfect, "--eval", cls.f.known, "--dataset", cls.f.data,
             "--dataset", cls.f.data, "--out", cls.out, "--title", "Fabricated report", "--tsne-iterations", "250"],
            capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
        metrics_path = os.path.join(cls.out, "metrics.json")
        cls.metrics = json.loads(read_text(metrics_path)) if os.path.isfile(metrics_path) else None

    @classmethod
    def tearDownClass(cls):
        if not WORKDIR:
            shutil.rmtree(cls.root, ignore_errors=True)

    def model(self, prefix):
        """metrics.json entry of the model whose slug starts with prefix."""
        self.assertIsNotNone(self.metrics, f"no metrics.json; stderr:\n{self.proc.stderr}")
        hits = [v for k, v in self.metrics["models"].items() if k.startswith(prefix)]
        self.assertEqual(len(hits), 1, f"models: {list(self.metrics['models'])}")
        return hits[0]

    def test_runs_end_to_end(self):
        self.assertEqual(self.proc.returncode, 0, f"stdout:\n{self.proc.stdout}\nstderr:\n{self.proc.stderr}")
        self.assertIn("report:", self.proc.stdout)
        self.assertIn("mean per-class accuracy 1.000", self.proc.stdout)
        report = read_text(os.path.join(self.out, "report.md"))
        for heading in ("# Fabricated report", "## Summary", "### 1. Classification metrics",
                        "### 2. Failure detection", "### 3. Uncertainty", "### 4. Given the detector's verdict",
                        "### 5. Failure clustering", "### 6. Per-frame overlays",
                        "## Comparison of the perception models",
                        "## Method notes"):
            self.assertIn(heading, report)
        # every linked figure exists, is a PNG, and lies inside the report folder
        import re
        links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
        self.assertGreaterEqual(len(links), 20)
        for rel in links:
            self.assertFalse(os.path.isabs(rel), rel)
            path = os.path.join(self.out, rel)
            self.assertTrue(os.path.isfile(path), rel)
            with open(path, "rb") as fh:
                self.assertEqual(fh.read(8), b"\x89PNG\r\n\x1a\n", rel)
        for must in ("confusion.png", "failure_roc.png", "accuracy_vs_threshold.png", "retained_vs_threshold.png",
                     "accuracy_vs_retained.png", "accuracy_by_distance.png", "clusters_tsne.png", "cluster_0_mosaic.png",
                     "cluster_1_mosaic.png", "phenomena_fn_fp.png", "office_s1_1000000.png",
                     "verdict_accuracy_vs_retained.png", "accuracy_by_margin.png"):
            self.assertTrue(any(l.endswith(must) for l in links), must)
        # eval.json says which predictions the overlay dots show
        self.assertIn("inner dot = prediction given the detector's recorded verdict", report)

    def test_perfect_model(self):
        m = self.model("jppc")
        self.assertEqual(m["overall"]["n"], 200)
        self.assertAlmostEqual(m["overall"]["mean_per_class_accuracy"], 1.0)
        self.assertAlmostEqual(m["overall"]["overall_accuracy"], 1.0)
        self.assertEqual(m["overall"]["per_class_accuracy"], [1.0, 1.0, 1.0, 1.0])
        self.assertAlmostEqual(m["failure"]["auroc"], 1.0)
        self.assertAlmostEqual(m["failure"]["precision"], 1.0)
        self.assertAlmostEqual(m["failure"]["recall"], 1.0)
        for g in m["sessions"] + m["environments"]:
            self.assertAlmostEqual(g["mean_per_class_accuracy"], 1.0)
        self.assertEqual(sorted(g["group"] for g in m["environments"]), ["indoor", "outdoor"])
        self.assertEqual([(g["group"], g["n"]) for g in m["distances"]], [("1 m", 200)])  # every row at x = 1 m
        self.assertEqual(m["patch_size"], PATCH)  # the dataset's patches, for the disc-vs-patch column

    def test_perfect_model_clusters_by_phenomenon(self):
        c = self.model("jppc")["clustering"]
        self.assertTrue(c["ok"], c["message"])
        self.assertEqual(c["n_predicted_fp"], 50)
        self.assertEqual(c["n_predicted_fn"], 30)
        self.assertEqual(c["n_selected"], 40)  # the top 50 % by confidence of the 50 predicted FP and the 30 FN
        for cls, n in ((FP, 25), (FN, 15)):
            conf = self.f.perfect_confidence[self.f.label == cls]
            self.assertAlmostEqual(c["confidence_cut"][LABEL_NAMES[cls]], np.sort(conf)[::-1][n - 1], places=5)
        for e in c["clusters"]:
            self.assertGreaterEqual(e["mean_confidence"], min(c["confidence_cut"].values()))
        self.assertEqual(c["pca_components"], 26)
        self.assertGreaterEqual(c["purity"], 0.99)
        dominant = sorted(e["dominant_phenomenon"] for e in c["clusters"])
        self.assertEqual(dominant, [REFLECTION, TEXTURELESS])
        # beside it, what one cluster holding every selected failure scores: the most common phenomenon's share
        self.assertGreaterEqual(c["purity_one_cluster"], 0.5)
        self.assertLess(c["purity_one_cluster"], 0.99)
        summary = read_text(os.path.join(self.out, "report.md")).split("## Inputs")[0]
        self.assertIn(f"{100 * c['purity']:.1f} % ({100 * c['purity_one_cluster']:.1f} %)", summary)
        # purity at other k: the same k-means at k = 2, never above what k clusters could reach
        scan = c["purity_by_k"]
        self.assertEqual([e["k"] for e in scan], [2, 3, 4, 6, 8])
        self.assertAlmostEqual(scan[0]["purity"], c["purity"])
        self.assertAlmostEqual(scan[0]["best_possible"], 1.0)  # two phenomena among the selected failures
        for e in scan:
            self.assertLessEqual(e["purity"], e["best_possible"] + 1e-12)
        self.assertIn("Would more clusters separate the phenomena?", read_text(os.path.join(self.out, "report.md")))

    def test_known_model_metrics(self):
        m = self.model("dense")["overall"]
        expected = [1 - WRONG_TOTAL[c] / (2 * COUNTS[c]) for c in range(4)]  # 0.75, 0.9, 0.7, 0.6
        for got, want in zip(m["per_class_accuracy"], expected):
            self.assertAlmostEqual(got, want)
        self.assertAlmostEqual(m["mean_per_class_accuracy"], 0.7375)
        self.assertAlmostEqual(m["overall_accuracy"], 155 / 200)
        self.assertEqual(m["confusion"][TP][FN], 10)
        self.assertEqual(m["confusion"][TN][FP], 8)
        self.assertAlmostEqual(m["confusion_normalised"][FP][TN], 15 / 50)
        # per session, counted here independently
        f = self.f
        for g in self.model("dense")["sessions"]:
            sel = np.array([s == g["group"] for s, _, rs in f.sessions for _ in rs])
            accs = [np.mean(f.predicted[sel & (f.label == c)] == c) for c in range(4)]
            self.assertAlmostEqual(g["mean_per_class_accuracy"], float(np.mean(accs)))

    def test_known_model_failure_detection(self):
        fd = self.model("dense")["failure"]
        self.assertEqual(fd["failures"], 80)
        self.assertEqual(fd["flagged"], 71)
        self.assertAlmostEqual(fd["precision"], 53 / 71)
        self.assertAlmostEqual(fd["recall"], 53 / 80)
        self.assertAlmostEqual(fd["auroc"], 7260 / 9600)

    def test_known_model_uncertainty(self):
        s = self.model("dense")["sweep"]
        self.assertAlmostEqual(s["unfiltered"]["retained"], 1.0)
        self.assertAlmostEqual(s["unfiltered"]["mean_per_class_accuracy"], 0.7375)
        self.assertEqual(s["at_70"]["retained_count"], 140)
        self.assertAlmostEqual(s["at_70"]["mean_per_class_accuracy"], 1.0)
        self.assertAlmostEqual(s["at_70"]["overall_accuracy"], 1.0)
        # the gate keeps the 140 most certain predictions, all right, and of the true failures only some: the
        # summary and the comparison say how many beside the 1.0, which withholding the others bought
        kept = np.argsort(self.f.var)[:140]
        kept = [100 * np.isin(np.flatnonzero(self.f.label == c), kept).mean() for c in (FP, FN)]
        self.assertLess(max(kept), 70)
        report = read_text(os.path.join(self.out, "report.md"))
        summary, comparison = report.split("## Inputs")[0], report.split("## Comparison")[1]
        said = f"FP {kept[0]:.0f} %, FN {kept[1]:.0f} % kept"
        # no interval there: this data's classes come a frame or two at a time, and the few frames holding
        # the kept FN are missing from more than 2.5 % of the frame resamples
        self.assertRegex(summary, r"70\.0 % → 1\.000 \(" + said + r"\)")
        self.assertIsNone(self.model("dense")["intervals"]["mpca_at_70"])
        row = next(line for line in comparison.splitlines() if line.startswith("| true failures kept at ≥70 % |"))
        self.assertTrue(row.endswith(f"| {said} |"), row)  # the known model is the second column
        self.assertTrue(s["accuracy_rises_as_threshold_falls"])
        self.assertGreater(s["mean_var_wrong"], 0.05)
        self.assertLess(s["mean_var_correct"], 0.02)
        # the model's own threshold (0.03) keeps exactly the correct predictions
        self.assertEqual(s["at_model_threshold"]["retained_count"], 155)
        # the curve runs from high to low threshold with non-increasing retained fraction
        retained = [p["retained"] for p in s["curve"]]
        self.assertTrue(all(a >= b for a, b in zip(retained, retained[1:])))

    def test_known_model_given_the_verdict(self):
        v = self.model("dense")["given_verdict"]
        expected = [1 - VERDICT_WRONG[c] / COUNTS[c] for c in range(4)]  # 0.9, 0.925, 0.96, 0.733
        for got, want in zip(v["overall"]["per_class_accuracy"], expected):
            self.assertAlmostEqual(got, want)
        self.assertAlmostEqual(v["overall"]["mean_per_class_accuracy"], float(np.mean(expected)))
        # the intervals over resampled frames: around the figure, and none at the 70 % point, which keeps only
        # right predictions (their variance is the low one) whatever frames are drawn
        ci = self.model("dense")["intervals"]
        low, high = ci["verdict_mean_per_class_accuracy"]
        self.assertLess(low, float(np.mean(expected)))
        self.assertGreater(high, float(np.mean(expected)))
        self.assertEqual(ci["verdict_mpca_at_70"], [1.0, 1.0])
        # only the verdict's pair is ever predicted
        cm = np.array(v["overall"]["confusion"])
        for t, p in ((TP, TN), (TP, FN), (FP, TN), (FP, FN), (TN, TP), (TN, FP), (FN, TP), (FN, FP)):
            self.assertEqual(cm[t][p], 0)
        self.assertEqual(cm[TP][FP], 2 * VERDICT_WRONG[TP])
        # failures are flagged where P(wrong) > 0.5: true FP/FN flagged unless wrong, TP/TN flagged if wrong
        f = v["failure"]
        flagged_right = 2 * (COUNTS[FP] - VERDICT_WRONG[FP] + COUNTS[FN] - VERDICT_WRONG[FN])
        flagged = flagged_right + 2 * (VERDICT_WRONG[TP] + VERDICT_WRONG[TN])
        self.assertEqual(f["flagged"], flagged)
        self.assertAlmostEqual(f["precision"], flagged_right / flagged)
        # the variance is high exactly on the wrong ones: the gate at 70 % keeps only right ones
        self.assertAlmostEqual(v["sweep"]["at_70"]["mean_per_class_accuracy"], 1.0)
        self.assertTrue(v["sweep"]["accuracy_rises_as_threshold_falls"])
        self.assertEqual(len(v["sessions"]), 2)
        # an eval folder without the columns is reported as such
        self.assertIsNone(self.model("jppc")["given_verdict"])
        self.assertIn("Not in this eval folder", read_text(os.path.join(self.out, "report.md")))

    def test_accuracy_by_the_detectors_margin(self):
        """The known model's verdict errors all lie near JPP-C's threshold."""
        g = self.model("dense")["by_margin"]
        self.assertTrue(g["ok"], g["message"])
        self.assertEqual(g["n_with_evidence"], 199)  # row 0 has no observed value
        self.assertAlmostEqual(g["agreement"], 1.0)
        near = self.f.wrong[1:]
        self.assertAlmostEqual(g["near_share"], near.mean())
        self.assertAlmostEqual(g["near_verdict_error_share"], 1.0)
        self.assertAlmostEqual(g["near_error_share"], 1.0)
        self.assertAlmostEqual(g["verdict_accuracy_far"], 1.0)
        bands = {(b["low"], b["high"]): b for b in g["bands"]}
        self.assertEqual(list(bands), [(None, -0.3), (-0.04, 0.0), (0.0, 0.04), (0.3, None)])
        label = self.f.label[1:]
        for key, verdict_acc, obstacle in (((None, -0.3), 1.0, 0.0), ((-0.04, 0.0), 0.0, 0.0),
                                           ((0.0, 0.04), 0.0, 1.0), ((0.3, None), 1.0, 1.0)):
            self.assertAlmostEqual(bands[key]["verdict_accuracy"], verdict_acc, msg=str(key))
            self.assertAlmostEqual(bands[key]["obstacle_share"], obstacle, msg=str(key))
        want_near_free = int(np.sum(near & np.isin(label, (TN, FN))))
        self.assertEqual(bands[(-0.04, 0.0)]["n"], want_near_free)
        self.assertAlmostEqual(sum(b["share"] for b in g["bands"]), 1.0)
        self.assertIsNotNone(bands[(0.3, None)]["given_verdict_accuracy"])
        # a perfect model reads every verdict; it has no verdict errors to place
        p = self.model("jppc")["by_margin"]
        self.assertTrue(all(b["verdict_accuracy"] == 1.0 for b in p["bands"]))
        self.assertIsNone(p["near_verdict_error_share"])
        self.assertIsNone(p["bands"][0]["given_verdict_accuracy"])  # no verdict columns in that eval
        report = read_text(os.path.join(self.out, "report.md"))
        self.assertIn("By how close the detector came to its threshold", report)
        self.assertIn("| -0.04 … 0 |", report)
        # without --repeatability no noise figure is quoted, only how to measure one
        self.assertIn("`tools/main_job/ivoa-label-repeatability.sh` measures how far", report)
        self.assertNotIn("at the median", report)
        self.assertNotIn("another noise draw keeps the verdict", report)

    def test_comparison_per_phenomenon(self):
        perfect = {e["phenomenon"]: e for e in self.model("jppc")["per_phenomenon"]}
        known = {e["phenomenon"]: e for e in self.model("dense")["per_phenomenon"]}
        self.assertAlmostEqual(perfect[TEXTURELESS]["pred_fn"], 1.0)
        self.assertAlmostEqual(known[TEXTURELESS]["pred_fn"], 18 / 30)
        self.assertAlmostEqual(known[REFLECTION]["pred_fp"], 35 / 50)
        self.assertAlmostEqual(known[REFLECTION]["true_fp"], 1.0)
        sentences = " ".join(self.metrics["models"]["_comparison"]["sentences"])
        self.assertIn("textureless", sentences)
        report = read_text(os.path.join(self.out, "report.md"))
        self.assertIn("| textureless |", report)

    def test_mosaic_shows_the_dataset_patches(self):
        """Tiles are the patches of the chosen rows, converted BGR -> RGB."""
        load_tool()
        from report_figures import make_mosaic
        from report_inputs import Dataset, attach_dataset, load_eval, make_names
        run = load_eval(self.f.perfect)
        make_names([run])
        attach_dataset(run, Dataset(self.f.data))
        rows = np.array([3, 150, 199])
        img = make_mosaic(run, rows, rows_n=1, cols_n=3, border=2)
        for i, r in enumerate(rows):
            tile = img[2:2 + PATCH, i * (PATCH + 4) + 2: i * (PATCH + 4) + 2 + PATCH]
            session = run.dataset.session(str(run.session[r]))
            bgr = np.fromfile(os.path.join(session.path, "patches.bin"), np.uint8).reshape(-1, PATCH, PATCH, 3)
            np.testing.assert_array_equal(tile, bgr[run.sample[r]][:, :, ::-1])
            self.assertEqual(tile[0, 0, 0], 200)  # R came from the file's third (R) byte

    def test_mosaic_is_as_tall_as_the_rows_it_fills(self):
        """A cluster with few samples gets a short mosaic, not rows of white."""
        load_tool()
        from report_figures import make_mosaic
        from report_inputs import Dataset, attach_dataset, load_eval, make_names
        run = load_eval(self.f.perfect)
        make_names([run])
        attach_dataset(run, Dataset(self.f.data))
        tile = PATCH + 2 * 3
        self.assertEqual(make_mosaic(run, np.arange(12), rows_n=5, cols_n=10).shape[:2], (2 * tile, 10 * tile))
        self.assertEqual(make_mosaic(run, np.arange(80), rows_n=5, cols_n=10).shape[:2], (5 * tile, 10 * tile))
        self.assertEqual(make_mosaic(run, np.arange(0), rows_n=5, cols_n=10).shape[:2], (tile, 10 * tile))


class FabricatedInputsCase(unittest.TestCase):
    """Fresh fabricated inputs in a temporary folder for each test class."""
    prefix = "ivoa_report_"

    @classmethod
    def setUpClass(cls):
        cls.root = tempfile.mkdtemp(prefix=cls.prefix)  # removed in tearDownClass
        cls.f = fabricate(cls.root)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.root, ignore_errors=True)


class DegenerateAndBadInputTest(FabricatedInputsCase):
    """Degenerate cases are explained in the report; bad inputs give exit code 3."""
    prefix = "ivoa_report_bad_"

    def copy_eval(self, src, name):
        dst = os.path.join(self.root, name)
        shutil.copytree(src, dst)
        return dst

    def eval_with_predictions(self, name, edit, src=None):
        """A copy of an eval (the known one: it has the verdict columns) whose
        predictions.csv lines, header first, went through edit(lines as lists)."""
        d = self.copy_eval(src or self.f.known, name)
        path = os.path.join(d, "predictions.csv")
        with open(path, newline="") as fh:
            lines = list(csv.reader(fh))
        edit(lines)
        with open(path, "w", newline="") as fh:
            csv.writer(fh, lineterminator="\n").writerows(lines)
        return d

    def eval_with_meta(self, name, edit, src=None):
        """A copy of an eval (the degenerate one: fast to report) whose eval.json is edit(eval.json)."""
        d = self.copy_eval(src or self.f.degenerate, name)
        path = os.path.join(d, "eval.json")
        meta = edit(json.loads(read_text(path)))
        with open(path, "w") as fh:
            json.dump(meta, fh)
        return d

    def test_a_model_has_one_colour_in_its_own_figures_and_the_comparison(self):
        tool = load_tool()
        from unittest import mock
        drawn = []  # (figure, title, [(name, colour)])

        def recorder(figure):
            real = getattr(tool.figures, figure)
            return lambda curves, title, path: (drawn.append((figure, title, [(c[0], c[2]) for c in curves])),
                                                real(curves, title, path))[1]
        out = os.path.join(self.root, "report_colours")
        with mock.patch.object(tool.figures, "plot_roc", recorder("plot_roc")), \
                mock.patch.object(tool.figures, "plot_accuracy_vs_retained", recorder("plot_accuracy_vs_retained")):
            code, _, stderr = run_main(["--eval", self.f.degenerate, "--eval", self.f.known, "--dataset",
                                        self.f.data2, "--dataset", self.f.data, "--out", out])
        self.assertEqual(code, 0, stderr)
        for figure in ("plot_roc", "plot_accuracy_vs_retained"):
            together = [dict(curves) for f, title, curves in drawn if f == figure and title == "all models"]
            self.assertEqual(len(together), 1, drawn)
            self.assertEqual(len(set(together[0].values())), 2, together)  # two models, two colours
            for name, colour in together[0].items():
                # the model's own curve comes first (then the verdict head's, where there is one)
                own = [curves[0][1] for f, title, curves in drawn if f == figure and title == name]
                self.assertTrue(own, f"{figure}: no figure of {name} alone")
                self.assertEqual(set(own), {colour}, f"{figure}: {name}")
                self.assertNotIn(colour, tool.figures.CLASS_COLOURS)  # a model is not read as a class

    def test_an_output_inside_an_input_folder_is_a_usage_error(self):
        for out in (self.f.degenerate, os.path.join(self.f.degenerate, "report"), os.path.join(self.f.data2, "s")):
            code, _, stderr = run_main(["--eval", self.f.degenerate, "--dataset", self.f.data2, "--out", out])
            self.assertEqual(code, 2, stderr)
            self.assertIn("or lies in it: name a folder of its own", stderr)
            self.assertFalse(os.path.exists(os.path.join(out, "report.md")))

    def test_degenerate_inputs_are_reported(self):
        out = os.path.join(self.root, "report_degenerate")
        code, stdout, stderr = run_main(["--eval", self.f.degenerate, "--dataset", self.f.data2, "--out", out])
        self.assertEqual(code, 0, stderr)
        m = json.loads(read_text(os.path.join(out, "metrics.json")))["models"]
        m = next(iter(m.values()))
        self.assertEqual(m["overall"]["absent"], ["FN"])
        self.assertIsNone(m["overall"]["per_class_accuracy"][FN])
        # TP 0/10, TN 15/15, FP 0/5 -> mean over the three present classes
        self.assertAlmostEqual(m["overall"]["mean_per_class_accuracy"], 1 / 3)
        self.assertFalse(m["clustering"]["ok"])
        report = read_text(os.path.join(out, "report.md"))
        self.assertIn("Clustering not possible", report)
        self.assertIn("absent from the truth: FN", report)

    def test_sessions_the_model_was_trained_on_are_warned_of(self):
        """eval.json names the model's training and validation sessions: an
        evaluated one among them is not held out, and the report says so."""
        def trained_on(meta):
            meta["metadata"]["training"] = {"train_sessions": ["lab_s3", "office_s1"], "val_sessions": ["x_s2"]}
            return meta
        d = self.eval_with_meta("trained_on_test", trained_on)
        out = os.path.join(self.root, "report_trained_on")
        code, _, stderr = run_main(["--eval", d, "--dataset", self.f.data2, "--out", out])
        self.assertEqual(code, 0, stderr)
        warning = "its model was trained on 1 of the 1 sessions evaluated (lab_s3): their figures are not held out"
        self.assertIn(warning, stderr)
        self.assertIn(warning, read_text(os.path.join(out, "report.md")))
        self.assertNotIn("validated on", stderr)

    def test_sessions_of_a_camera_the_model_was_not_trained_on_are_warned_of(self):
        """eval.json records the model's training image sizes and each
        session's: a session of another size is of a camera the model never
        saw, and the report says so. Older files record neither: no warning."""
        def report_of(name, model_sizes):
            """stderr and report.md of the degenerate eval, its model trained on model_sizes (None: not
            recorded, as in an eval.json written before sizes were) and its session at 640x480."""
            def edit(meta):
                if model_sizes is not None:
                    meta["metadata"]["image_sizes"] = model_sizes
                meta["sessions"][0]["image_size"] = [640, 480]
                return meta
            out = os.path.join(self.root, "report_" + name)
            code, _, stderr = run_main(["--eval", self.eval_with_meta(name, edit), "--dataset", self.f.data2,
                                        "--out", out])
            self.assertEqual(code, 0, stderr)
            return stderr, read_text(os.path.join(out, "report.md"))

        warning = ("the model was trained on 960x600 images, but 1 of the 1 sessions evaluated is of another size "
                   "(the first, lab_s3, 640x480)")
        stderr, report = report_of("other_camera", [[960, 600]])
        self.assertIn(warning, stderr)
        self.assertIn(warning, report)
        for name, sizes in (("same_camera", [[960, 600], [640, 480]]), ("eval_without_sizes", None)):
            stderr, report = report_of(name, sizes)
            self.assertNotIn("of another size", stderr + report, name)

    def test_evidence_is_optional_and_checked_against_the_labels(self):
        """No evidence: the report says so. Evidence that does not give the
        labels' verdicts at the threshold (here: a wrong --evidence-threshold)
        is not used, and the report says why."""
        out = os.path.join(self.root, "report_no_evidence")
        code, _, stderr = run_main(["--eval", self.f.degenerate, "--dataset", self.f.data2, "--out", out])
        self.assertEqual(code, 0, stderr)
        m = next(iter(json.loads(read_text(os.path.join(out, "metrics.json")))["models"].values()))
        self.assertIsNone(m["by_margin"])
        self.assertIn("Not available: the dataset keeps no evidence", read_text(os.path.join(out, "report.md")))
        out = os.path.join(self.root, "report_other_threshold")
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--out", out,
                                    "--evidence-threshold", "1.2"])
        self.assertEqual(code, 0, stderr)
        m = next(iter(json.loads(read_text(os.path.join(out, "metrics.json")))["models"].values()))
        self.assertFalse(m["by_margin"]["ok"])
        self.assertLess(m["by_margin"]["agreement"], 0.99)
        self.assertIn("Not shown: the evidence gives the labels' verdict for only",
                      read_text(os.path.join(out, "report.md")))

    def test_truncated_evidence(self):
        d = os.path.join(self.root, "data_short_evidence")
        shutil.copytree(self.f.data, d)
        path = os.path.join(d, "campus_s2", "evidence.f32")
        with open(path, "r+b") as fh:
            fh.truncate(os.path.getsize(path) - 4)
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", d], "evidence.f32", "bytes")

    def write_repeatability(self, name, detector="jppc", threshold=0.75, bands=None):
        """An ivoa_label_repeatability.py --json file: the free side's two bands
        nearest the threshold keep the verdict 0.7 and 0.5 of the time, the
        far free side always; no figure for the far obstacle side."""
        if bands is None:
            bands = [{"low": None, "high": -0.3, "n": 40, "verdict_agreement": 1.0},
                     {"low": -0.04, "high": 0.0, "n": 10, "verdict_agreement": 0.7},
                     {"low": 0.0, "high": 0.04, "n": 10, "verdict_agreement": 0.5}]
        path = os.path.join(self.root, name)
        with open(path, "w") as fh:
            json.dump({"datasets": ["a", "b", "c"], "detector": detector, "session_names": ["campus_s2", "other_s9"],
                       "evidence": {"threshold": threshold, "cells": 60, "worst_shift_median": 0.044,
                                    "worst_shift_p90": 0.133, "bands": bands}}, fh)
        return path

    def test_noise_repeatability_beside_the_margin_bands(self):
        """--repeatability: each band gets how often another noise draw keeps
        the verdict, and the model's verdict errors are set against those of a
        predictor blind to the noise, over the bands both have."""
        out = os.path.join(self.root, "report_noise")
        code, _, stderr = run_main(["--eval", self.f.known, "--dataset", self.f.data, "--out", out,
                                    "--repeatability", self.write_repeatability("noise.json"),
                                    "--tsne-iterations", "250"])
        self.assertEqual(code, 0, stderr)
        g = next(iter(json.loads(read_text(os.path.join(out, "metrics.json")))["models"].values()))["by_margin"]
        bands = {(b["low"], b["high"]): b for b in g["bands"]}
        self.assertEqual([bands[k]["noise_agreement"] for k in bands], [1.0, 0.7, 0.5, None])
        n_far, n_free, n_obst = (bands[k]["n"] for k in ((None, -0.3), (-0.04, 0.0), (0.0, 0.04)))
        c = g["noise_comparison"]
        self.assertTrue(c["used"])
        self.assertEqual(c["cells_compared"], n_far + n_free + n_obst)
        self.assertEqual(c["model_verdict_errors"], n_free + n_obst)  # the known model misses every near verdict
        self.assertAlmostEqual(c["noise_verdict_errors"], 0.3 * n_free + 0.5 * n_obst)
        self.assertEqual((c["sessions_in_common"], c["run_sessions"]), (1, len(self.f.sessions)))
        report = read_text(os.path.join(out, "report.md"))
        self.assertIn("another noise draw keeps the verdict", report)
        self.assertIn("moves a cell's worst value by 0.044 at the median and 0.133", report)
        self.assertIn(f"3 draws of 60 cells, which re-recorded 1 of these {len(self.f.sessions)} sessions", report)
        self.assertIn(f"would misread about **{0.3 * n_free + 0.5 * n_obst:.0f}**", report)

    def test_noise_repeatability_of_another_detector_is_not_used(self):
        out = os.path.join(self.root, "report_noise_dense")
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--out", out,
                                    "--repeatability", self.write_repeatability("noise_dense.json", "dense")])
        self.assertEqual(code, 0, stderr)
        g = next(iter(json.loads(read_text(os.path.join(out, "metrics.json")))["models"].values()))["by_margin"]
        self.assertFalse(g["noise_comparison"]["used"])
        self.assertTrue(all("noise_agreement" not in b for b in g["bands"]))
        self.assertIn("were not used: measured for detector 'dense'", read_text(os.path.join(out, "report.md")))

    def test_inputs_that_contradict_themselves_are_named(self):
        """A prediction that is not its row's most probable class, an eval.json
        sample count predictions.csv does not have, a noise agreement outside 0..1."""
        def not_the_most_probable(lines):
            row = lines[4]
            top = max(range(4), key=lambda c: float(row[lines[0].index(("p_tp", "p_tn", "p_fp", "p_fn")[c])]))
            set_cell(lines, 5, "predicted", str((top + 1) % 4))
        d = self.eval_with_predictions("not_argmax", not_the_most_probable)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv: line 5: predicted",
                              "is not the most probable class")
        d = self.eval_with_meta("too_many", lambda m: dict(m, samples=9999))
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data2], "eval.json: says 9999 samples",
                              "predictions.csv has")
        bands = [{"low": None, "high": -0.3, "n": 40, "verdict_agreement": 7.5}]
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", self.f.data, "--repeatability",
                               self.write_repeatability("noise_over.json", bands=bands)],
                              "noise_over.json: evidence.bands[0]: verdict_agreement 7.5")

    def test_bad_noise_repeatability_is_named(self):
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", self.f.data, "--repeatability",
                               self.write_repeatability("noise_thr.json", threshold=0.5)],
                              "noise_thr.json: measured at evidence threshold 0.5, the report uses 0.75")
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", self.f.data, "--repeatability",
                               self.write_repeatability("noise_bad.json", bands=[{"low": None}])],
                              "noise_bad.json: malformed repeatability figures (KeyError")
        path = os.path.join(self.root, "noise_none.json")
        with open(path, "w") as fh:
            json.dump({"datasets": ["a", "b"], "evidence": None}, fh)
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", self.f.data, "--repeatability", path],
                              "noise_none.json: its datasets keep no detector evidence")

    def test_footprint_scaled_dataset_reports_the_cut_sides(self):
        """A dataset that records patch_side per sample (ivoa-dataset --patch-scale):
        the distance table gives the row's median side and names the scale."""
        d = os.path.join(self.root, "data_scaled")
        shutil.copytree(self.f.data, d)
        for name in os.listdir(d):
            session = os.path.join(d, name)
            if not os.path.isdir(session):
                continue
            info = json.loads(read_text(os.path.join(session, "session.json")))
            info["patch_scale"] = 1.6
            with open(os.path.join(session, "session.json"), "w") as fh:
                json.dump(info, fh)
            path = os.path.join(session, "samples.csv")
            lines = read_text(path).splitlines()
            with open(path, "w") as fh:
                fh.write("\n".join([lines[0] + ",patch_side"] + [l + ",196" for l in lines[1:]]) + "\n")
        scaled_eval = self.eval_with_meta("perfect_scaled", lambda m: with_sessions(m, patch_scale=1.6),
                                          self.f.perfect)
        out = os.path.join(self.root, "report_scaled")
        code, _, stderr = run_main(["--eval", scaled_eval, "--dataset", d, "--out", out])
        self.assertEqual(code, 0, stderr)
        m = next(iter(json.loads(read_text(os.path.join(out, "metrics.json")))["models"].values()))
        self.assertEqual(m["patch_scale"], 1.6)
        self.assertEqual([g["patch_px"] for g in m["distances"]], [196.0])
        self.assertIn("Footprint-scaled patches (x1.6)", read_text(os.path.join(out, "report.md")))

    def assert_bad_input(self, argv, *fragments):
        code, _, stderr = run_main(argv + ["--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        for frag in fragments:
            self.assertIn(frag, stderr)

    def test_missing_eval_folder(self):
        self.assert_bad_input(["--eval", os.path.join(self.root, "nope"), "--dataset", self.f.data],
                              "nope", "not found")

    def test_missing_predictions(self):
        d = self.copy_eval(self.f.perfect, "no_predictions")
        os.remove(os.path.join(d, "predictions.csv"))
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv", "missing")

    def test_a_file_that_is_not_text_is_named(self):
        d = self.copy_eval(self.f.perfect, "binary_predictions")
        with open(os.path.join(d, "predictions.csv"), "wb") as fh:
            fh.write(bytes(range(128, 256)) * 10)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv", "not UTF-8 text")
        with open(os.path.join(d, "eval.json"), "wb") as fh:
            fh.write(b"\xff\xfe{}")
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "eval.json", "not UTF-8 text")

    def test_an_out_of_range_seed_is_a_usage_error(self):
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--seed", "-1",
                                    "--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 2, stderr)
        self.assertIn("--seed must be in 0 .. 4294967295", stderr)

    def test_truncated_embeddings(self):
        d = self.copy_eval(self.f.perfect, "short_embeddings")
        path = os.path.join(d, "embeddings.f32")
        with open(path, "r+b") as fh:
            fh.truncate(os.path.getsize(path) - DIM * 4)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "embeddings.f32", "200 rows")

    def test_label_out_of_range(self):
        d = self.copy_eval(self.f.perfect, "bad_label")
        path = os.path.join(d, "predictions.csv")
        lines = read_text(path).splitlines()
        fields = lines[5].split(",")
        fields[10] = "7"
        lines[5] = ",".join(fields)
        with open(path, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv", "line 6", "label")

    def test_verdict_contradicting_the_label(self):
        d = self.copy_eval(self.f.known, "bad_verdict")
        path = os.path.join(d, "predictions.csv")
        lines = read_text(path).splitlines()
        fields = lines[3].split(",")  # a TP row: the detector said obstacle (1)
        self.assertEqual(fields[10], str(TP))
        fields[-4] = "0"
        lines[3] = ",".join(fields)
        with open(path, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv", "line 4",
                              "contradicts label TP")

    def test_empty_predictions(self):
        d = self.copy_eval(self.f.perfect, "empty")
        with open(os.path.join(d, "predictions.csv"), "w") as fh:
            fh.write(PRED_HEADER + "\n")
        with open(os.path.join(d, "embeddings.f32"), "wb"):
            pass
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv", "no predictions")

    def test_wrong_dataset(self):
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", self.f.data2], "session folder not found")

    def test_dataset_labels_disagree(self):
        d = os.path.join(self.root, "data_other_labels")
        shutil.copytree(self.f.data, d)
        path = os.path.join(d, "office_s1", "samples.csv")
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        rows[1][5] = "3" if rows[1][5] != "3" else "0"
        with open(path, "w", newline="") as fh:
            csv.writer(fh).writerows(rows)
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", d], "samples.csv", "does not match")

    def test_patches_size_mismatch(self):
        d = os.path.join(self.root, "data_short_patches")
        shutil.copytree(self.f.data, d)
        path = os.path.join(d, "campus_s2", "patches.bin")
        with open(path, "ab") as fh:
            fh.write(b"\0" * 10)
        self.assert_bad_input(["--eval", self.f.perfect, "--dataset", d], "patches.bin", "bytes")

    def test_some_verdict_columns_missing(self):
        """All four verdict columns or none: three of them is a damaged file, not an older ivoa-eval."""
        d = self.eval_with_predictions("verdict_dropped", lambda lines: drop_column(lines, "stereo_state"))
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv: missing column(s) "
                              "stereo_state (the other verdict columns verdict_predicted, p_wrong, var_wrong")
        d = self.eval_with_predictions("verdict_renamed", lambda lines: set_cell(lines, 1, "p_wrong", "pwrong"))
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv: missing column(s) p_wrong")

    def test_probabilities_and_variances_are_range_checked(self):
        for i, (column, value, why) in enumerate((
                ("p_tp", "1.7", "line 6, column 'p_tp': 1.7 is outside 0 .. 1"),
                ("p_fn", "-0.4", "line 6, column 'p_fn': -0.4 is outside 0 .. 1"),
                ("p_tn", "nan", "line 6, column 'p_tn': nan is not finite"),
                ("var_predicted", "inf", "line 6, column 'var_predicted': inf is not finite"),
                ("var_predicted", "-0.01", "line 6, column 'var_predicted': -0.01 is outside 0 .. 0.2632"),
                ("uncertainty", "0.3", "line 6, column 'uncertainty': 0.3 is outside 0 .. 0.2632"),
                ("p_wrong", "1.5", "line 6, column 'p_wrong': 1.5 is outside 0 .. 1"),
                ("var_wrong", "0.27", "line 6, column 'var_wrong': 0.27 is outside 0 .. 0.2632"))):
            d = self.eval_with_predictions(f"range_{i}", lambda lines: set_cell(lines, 6, column, value))
            self.assert_bad_input(["--eval", d, "--dataset", self.f.data], "predictions.csv: " + why)
        # Swapped columns: every value in range, the row's probabilities no longer sum to 1.
        d = self.eval_with_predictions("swapped", lambda lines: swap_header(lines, "p_fp", "var_predicted"))
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data],
                              "predictions.csv: line 2: p_tp + p_tn + p_fp + p_fn = ")
        # ivoa-eval's variance is over T passes, unbiased: 0.25 T / (T - 1) at most.
        load_tool()
        from report_inputs import max_variance
        self.assertAlmostEqual(max_variance(2), 0.5, places=5)
        self.assertAlmostEqual(max_variance(20), 0.25 * 20 / 19, places=5)

    def test_non_finite_coordinates(self):
        for i, (column, value) in enumerate((("x", "nan"), ("v", "-inf"))):
            d = self.eval_with_predictions(f"coordinate_{i}", lambda lines: set_cell(lines, 9, column, value))
            self.assert_bad_input(["--eval", d, "--dataset", self.f.data],
                                  f"predictions.csv: line 9, column '{column}': {value} is not finite")

    def test_repeated_sample(self):
        """A row given twice (with its embedding) would be counted twice."""
        d = self.eval_with_predictions("repeated", lambda lines: lines.append(lines[4]))
        path = os.path.join(d, "embeddings.f32")
        emb = np.fromfile(path, np.float32).reshape(-1, DIM)
        np.concatenate([emb, emb[3:4]]).tofile(path)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data],
                              "predictions.csv: session office_s1, sample 3 is on line 5 and again on line 202")

    def test_non_finite_embeddings(self):
        d = self.copy_eval(self.f.perfect, "nan_embeddings")
        path = os.path.join(d, "embeddings.f32")
        emb = np.fromfile(path, np.float32).reshape(-1, DIM)
        emb[7, 100] = np.nan
        emb.tofile(path)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data],
                              "embeddings.f32: row 7 (0-based; the prediction on line 9 of predictions.csv) is not "
                              "finite")

    def test_eval_json_fields_are_checked(self):
        """A missing or malformed field used to print as 'None' or drop the run-time gate's row."""
        for name, edit, why in (
                ("meta_empty", lambda m: {}, "eval.json: missing field 'model'"),
                ("meta_no_passes", lambda m: {k: v for k, v in m.items() if k != "mc_passes"},
                 "eval.json: missing field 'mc_passes'"),
                ("meta_threshold", lambda m: dict(m, uncertainty_threshold="abc"),
                 "eval.json: field 'uncertainty_threshold' = 'abc', expected a number"),
                ("meta_views", lambda m: with_sessions(m, views="two"),
                 "eval.json: field 'sessions[0].views' = 'two', expected an integer")):
            self.assert_bad_input(["--eval", self.eval_with_meta(name, edit), "--dataset", self.f.data2], why)
        d = self.eval_with_meta("meta_no_verdict_threshold", lambda m: m, self.f.known)
        meta = json.loads(read_text(os.path.join(d, "eval.json")))
        del meta["verdict_uncertainty_threshold"]
        with open(os.path.join(d, "eval.json"), "w") as fh:
            json.dump(meta, fh)
        self.assert_bad_input(["--eval", d, "--dataset", self.f.data],
                              "eval.json: missing field 'verdict_uncertainty_threshold'")

    def test_one_pass_is_no_uncertainty_not_a_failed_claim(self):
        """With T = 1 every variance is 0: the sweep cannot judge the paper's claim."""
        d = self.eval_with_meta("meta_one_pass", lambda m: dict(m, mc_passes=1), self.f.known)
        out = os.path.join(self.root, "report_one_pass")
        code, _, stderr = run_main(["--eval", d, "--dataset", self.f.data, "--out", out, "--tsne-iterations", "250"])
        self.assertEqual(code, 0, stderr)
        report = read_text(os.path.join(out, "report.md"))
        self.assertIn("Paper's claim met here: **not measured (T = 1)**", report)
        self.assertIn("accuracy rises as the threshold falls: **not measured (T = 1: one pass", report)

    def test_dataset_cut_at_another_patch_scale(self):
        """eval.json's views and patch scale per session against the dataset's
        session.json: the same samples cut otherwise would fill the mosaics with
        other squares. An older eval.json without them is not checked."""
        d = os.path.join(self.root, "data_nofn_scaled")
        shutil.copytree(self.f.data2, d)
        info_path = os.path.join(d, "lab_s3", "session.json")
        info = json.loads(read_text(info_path))
        with open(info_path, "w") as fh:
            json.dump(dict(info, patch_scale=1.6), fh)
        self.assert_bad_input(["--eval", self.f.degenerate, "--dataset", d],
                              os.path.join(self.f.degenerate, "eval.json") + ": session lab_s3 was evaluated at "
                              "patch_scale 0, but " + info_path + " has patch_scale 1.6")
        two_views = self.eval_with_meta("two_views", lambda m: with_sessions(m, views=2))
        self.assert_bad_input(["--eval", two_views, "--dataset", self.f.data2],
                              "session lab_s3 was evaluated at views 2, but", "session.json has views 1")
        older = self.eval_with_meta("older_eval", lambda m: {k: v for k, v in m.items() if k != "sessions"})
        code, _, stderr = run_main(["--eval", older, "--dataset", d, "--out", os.path.join(self.root, "report_old")])
        self.assertEqual(code, 0, stderr)

    def test_session_without_session_json(self):
        """Not a patches.bin size error: without session.json the views are unknown."""
        d = os.path.join(self.root, "data_no_session_json")
        shutil.copytree(self.f.data2, d)
        os.remove(os.path.join(d, "lab_s3", "session.json"))
        self.assert_bad_input(["--eval", self.f.degenerate, "--dataset", d],
                              os.path.join(d, "lab_s3", "session.json") + ": missing")

    def test_unwritable_report_is_exit_code_4(self):
        """The path and the system's reason, exit code 4, no traceback."""
        taken = os.path.join(self.root, "out_taken")
        os.makedirs(os.path.join(taken, "report.md"))                     # report.md is a folder
        os.makedirs(os.path.join(self.root, "out_file"))
        with open(os.path.join(self.root, "out_file", "jppc_degenerate"), "w"):  # a file where the model's folder goes
            pass
        a_file = os.path.join(self.root, "out_file", "jppc_degenerate")
        cases = [(taken, os.path.join(taken, "report.md") + ": Is a directory"),
                 (os.path.join(self.root, "out_file"), a_file + ": File exists"),
                 (os.path.join(a_file, "report"), os.path.join(a_file, "report") + ": Not a directory")]
        if os.geteuid() != 0:  # root writes into a read-only folder anyway
            read_only = os.path.join(self.root, "out_read_only")
            os.makedirs(read_only, mode=0o555)
            cases.append((read_only, read_only + ": this user may not write in it"))
        for out, why in cases:
            code, _, stderr = run_main(["--eval", self.f.degenerate, "--dataset", self.f.data2, "--out", out])
            self.assertEqual(code, 4, stderr)
            self.assertIn("ivoa_report: cannot write the report: " + why, stderr)
            self.assertNotIn("Traceback", stderr)

    def test_dataset_count_must_match(self):
        code, _, _ = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--dataset", self.f.data,
                               "--dataset", self.f.data, "--out", os.path.join(self.root, "x")])
        self.assertEqual(code, 2)

    def test_numeric_flags_out_of_range_are_usage_errors(self):
        # --perplexity -3 used to end in scikit-learn's traceback after the metrics.
        for flag, value, why in (("--perplexity", "-3", "--perplexity must be > 0, not -3"),
                                 ("--threads", "0", "--threads must be at least 1, not 0"),
                                 ("--max-overlays", "-1", "--max-overlays must be >= 0")):
            code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--out",
                                        os.path.join(self.root, "x"), flag, value])
            self.assertEqual(code, 2, stderr)
            self.assertIn(why, stderr)


def set_cell(lines, line, column, value):
    """predictions.csv as lists: the given file line (1 = header) and column (header name) set to value."""
    lines[line - 1][lines[0].index(column)] = value


def drop_column(lines, column):
    i = lines[0].index(column)
    for fields in lines:
        del fields[i]


def swap_header(lines, a, b):
    """Swaps two column names, not their values: each column then reads as the other."""
    i, j = lines[0].index(a), lines[0].index(b)
    lines[0][i], lines[0][j] = b, a


def with_sessions(meta, **keys):
    """eval.json with the given keys set in each "sessions" entry."""
    return dict(meta, sessions=[dict(s, **keys) for s in meta["sessions"]])


def write_causes(path, sessions, detector="jppc", cause_of=None, not_reproduced=0, relabel=None, fixed_by=None):
    """An ivoa-sim-causes CSV for the true FP/FN rows of `sessions`: causes
    bits from cause_of[label]; the first `not_reproduced` rows replayed to the
    other state; `relabel` = (row index, label) writes one row with a wrong label;
    `fixed_by(row index, label)`, if given, the fixed_by column (the tool's
    newer output; older files lack it)."""
    cause_of = cause_of or {FP: REFLECTION, FN: 0}
    k = 0
    with open(path, "w") as f:
        f.write("session,detector,utime,cell,label,x,y,stereo_state,replayed_state,tested,causes,jointly,cause"
                + (",fixed_by\n" if fixed_by else "\n"))
        for name, _, rows in sessions:
            for r in rows:
                if r["label"] not in (FP, FN):
                    continue
                label = "FP" if r["label"] == FP else "FN"
                if relabel and relabel[0] == k:
                    label = relabel[1]
                state = 1 if r["label"] == FP else 0
                replayed = 1 - state if k < not_reproduced else state
                f.write(f"{name},{detector},{r['utime']},{r['cell']},{label},1.0,0.0,{state},{replayed},11,"
                        f"{cause_of[r['label']]},0,x" + (f",{fixed_by(k, label)}\n" if fixed_by else "\n"))
                k += 1


def write_variants(path, rows):
    """An ivoa-sim-causes --variants-out CSV: rows of (detector, variant, label, cells, right, wrong)."""
    with open(path, "w") as f:
        f.write("session,detector,variant,label,cells,right,wrong\n")
        for detector, variant, label, cells, right, wrong in rows:
            f.write(f"s1,{detector},{variant},{label},{cells},{right},{wrong}\n")


class CausesTest(FabricatedInputsCase):
    """--causes: the clusters' composition and purity by cause."""
    prefix = "ivoa_report_causes_"

    def report(self, causes_path, name):
        out = os.path.join(self.root, name)
        code, stdout, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", causes_path,
                                         "--out", out, "--tsne-iterations", "250"])
        metrics = json.loads(read_text(os.path.join(out, "metrics.json"))) if code == 0 else None
        return code, stdout, stderr, metrics, out

    def test_purity_by_cause(self):
        path = os.path.join(self.root, "causes.csv")
        write_causes(path, self.f.sessions, not_reproduced=4)
        code, stdout, stderr, metrics, out = self.report(path, "report_causes")
        self.assertEqual(code, 0, stderr)
        c = next(iter(metrics["models"].values()))["clustering"]
        # The perfect model's clusters are its FP (reflection) and FN (none found) samples.
        self.assertAlmostEqual(c["purity_by_cause"], 1.0)
        self.assertAlmostEqual(c["purity_by_cause_set"], 1.0)
        self.assertLess(c["purity_by_cause_one_cluster"], 0.9)  # FP and FN mixed
        self.assertAlmostEqual(c["purity_by_k"][0]["purity_by_cause"], 1.0)  # k = 2 again
        self.assertAlmostEqual(c["best_possible_by_cause_set"], 1.0)
        self.assertEqual(sorted(e["leading_cause"] for e in c["clusters"]), [0, REFLECTION])
        # Every selected sample is a true failure; those whose replay differed have no cause.
        self.assertLessEqual(c["n_with_cause"], c["n_selected"])
        self.assertGreaterEqual(c["n_with_cause"], c["n_selected"] - 4)
        self.assertEqual({int(k) for e in c["clusters"] for k in e["causes"]}, {0, REFLECTION})
        report = read_text(os.path.join(out, "report.md"))
        self.assertIn("**By cause.**", report)
        self.assertIn("none found", report)
        self.assertIn("by cause 100.0 %", stdout)
        # every true FP is explained by the reflection, every true FN by nothing; the perfect model predicts them
        by_label = next(iter(metrics["models"].values()))["causes_of_failures"]
        self.assertEqual(by_label["FP"]["causes"], [{"cause": REFLECTION, "share": 1.0, "predicted": 1.0}])
        self.assertEqual(by_label["FN"]["causes"], [{"cause": 0, "share": 1.0, "predicted": 1.0}])
        self.assertEqual(by_label["FP"]["n"] + by_label["FN"]["n"], 50 + 30 - 4)  # the true failures less the 4 not replayed

    def test_mixed_causes_lower_the_purity(self):
        # A third of the FP rows (by cell) are caused by something else: purity by cause drops, the
        # presence-based purity does not. A second cause beside the leading one keeps a row explained.
        path = os.path.join(self.root, "causes_mixed.csv")
        sessions = [(n, e, [dict(r) for r in rows]) for n, e, rows in self.f.sessions]
        write_causes(path, sessions, cause_of={FP: REFLECTION, FN: 0})
        with open(path) as fh:
            lines = fh.read().splitlines()
        for i in range(1, len(lines)):
            fields = lines[i].split(",")
            if fields[4] == "FP" and int(fields[3]) % 4 == 0:
                fields[10] = str(DARK_STRIPE)
            elif fields[4] == "FP" and int(fields[3]) % 4 == 1:
                fields[10] = str(REFLECTION | TEXTURELESS)
            lines[i] = ",".join(fields)
        with open(path, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        code, _, stderr, metrics, _ = self.report(path, "report_causes_mixed")
        self.assertEqual(code, 0, stderr)
        c = next(iter(metrics["models"].values()))["clustering"]
        self.assertGreaterEqual(c["purity"], 0.99)
        self.assertLess(c["purity_by_cause"], 0.9)
        self.assertLess(c["purity_by_cause_set"], c["purity_by_cause"])
        self.assertLessEqual(c["purity_by_cause_set"], c["best_possible_by_cause_set"] + 1e-12)
        fp_cluster = next(e for e in c["clusters"] if e["leading_cause"] != 0)
        self.assertEqual(fp_cluster["leading_cause"], REFLECTION)
        # the FP cluster's members: reflection alone, reflection+textureless, dark stripe; reflection explains
        # the first two kinds
        n = fp_cluster["n_with_cause"]
        dark = fp_cluster["causes"].get(str(DARK_STRIPE), fp_cluster["causes"].get(DARK_STRIPE, 0))
        self.assertAlmostEqual(fp_cluster["cause_purity"], (n - dark) / n)

    def test_causes_of_another_detector_are_not_used(self):
        path = os.path.join(self.root, "causes_dense.csv")
        write_causes(path, self.f.sessions, detector="dense")
        code, _, stderr, metrics, _ = self.report(path, "report_causes_dense")
        self.assertEqual(code, 0, stderr)
        self.assertIn("no causes for it", stderr)
        self.assertIsNone(next(iter(metrics["models"].values()))["clustering"]["purity_by_cause"])

    def test_one_causes_file_per_detector(self):
        dense, jppc = os.path.join(self.root, "causes_d.csv"), os.path.join(self.root, "causes_j.csv")
        write_causes(dense, self.f.sessions, detector="dense")
        write_causes(jppc, self.f.sessions)
        out = os.path.join(self.root, "report_two_causes")
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", dense,
                                    "--causes", jppc, "--out", out, "--tsne-iterations", "250"])
        self.assertEqual(code, 0, stderr)
        self.assertNotIn("no causes for it", stderr)
        metrics = json.loads(read_text(os.path.join(out, "metrics.json")))
        self.assertAlmostEqual(next(iter(metrics["models"].values()))["clustering"]["purity_by_cause"], 1.0)

    def test_causes_from_other_logs_are_refused(self):
        path = os.path.join(self.root, "causes_wrong.csv")
        write_causes(path, self.f.sessions, relabel=(0, "FN"))
        code, _, stderr, _, _ = self.report(path, "report_causes_wrong")
        self.assertEqual(code, 3, stderr)
        self.assertIn("causes_wrong.csv", stderr)
        self.assertIn("are the causes from the logs this dataset was built from?", stderr)


class DetectorSettingsTest(FabricatedInputsCase):
    """--variants (with --causes): what other detector settings fix and break."""
    prefix = "ivoa_report_settings_"

    def test_fixes_and_breaks_per_setting(self):
        causes, variants = os.path.join(self.root, "causes.csv"), os.path.join(self.root, "variants.csv")
        # Every FN has no cause found; "full resolution" fixes every other failure, "stricter" none.
        fixed = []

        def fixed_by(k, label):
            fixed.extend([label] if k % 2 else [])
            return "full resolution" if k % 2 else ""
        write_causes(causes, self.f.sessions, fixed_by=fixed_by)
        write_variants(variants, [("jppc", "full resolution", "TP", 10, 9, 1), ("jppc", "full resolution", "TN", 100, 60, 40),
                                  ("jppc", "full resolution", "FP", 50, 5, 45), ("jppc", "full resolution", "FN", 30, 15, 15),
                                  ("jppc", "stricter", "TN", 100, 100, 0), ("jppc", "stricter", "FN", 30, 0, 30)])
        out = os.path.join(self.root, "report_settings")
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", causes,
                                    "--variants", variants, "--out", out, "--tsne-iterations", "250"])
        self.assertEqual(code, 0, stderr)
        settings = json.loads(read_text(os.path.join(out, "metrics.json")))["detector_settings"]["jppc"]
        full = next(e for e in settings if e["variant"] == "full resolution")
        self.assertEqual((full["FN"]["changed"], full["FN"]["n"]), (15, 30))
        self.assertAlmostEqual(full["TN"]["share"], 0.4)  # TP and TN: the right verdicts it gets wrong
        self.assertAlmostEqual(full["TP"]["share"], 0.1)
        n_fn = full["FN_none_found"]["n"]
        self.assertEqual(n_fn, 30)  # every true FN row, none found
        self.assertEqual(full["FN_none_found"]["changed"], fixed.count("FN"))
        self.assertGreater(fixed.count("FN"), 0)
        self.assertEqual(full["FP_none_found"]["n"], 0)  # the FP are the reflection's
        stricter = next(e for e in settings if e["variant"] == "stricter")
        self.assertEqual(stricter["FN"]["share"], 0.0)
        self.assertEqual(stricter["TP"]["n"], 0)
        self.assertEqual(stricter["FN_none_found"]["changed"], 0)
        report = read_text(os.path.join(out, "report.md"))
        self.assertIn("## Other detector settings on the same frames", report)
        self.assertIn("| jppc | full resolution | 10 % of 50 | 50 % of 30 |", report)

    def test_impossible_counts_are_refused(self):
        variants = os.path.join(self.root, "variants_bad.csv")
        write_variants(variants, [("jppc", "full resolution", "TN", 10, 8, 5)])
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--variants", variants,
                                    "--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        self.assertIn("variants_bad.csv: line 2: 8 right and 5 wrong of 10 cells", stderr)


class CauseAndSettingsRowsTest(FabricatedInputsCase):
    """Rows of --causes and --variants that cannot be true are named."""
    prefix = "ivoa_report_rows_"

    def test_a_cause_outside_the_phenomena_tested_is_refused(self):
        causes = os.path.join(self.root, "causes_untested.csv")
        write_causes(causes, self.f.sessions, cause_of={FP: 16, FN: 0})  # 16 (repetitive) is not in tested 11
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", causes,
                                    "--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        self.assertIn("causes_untested.csv: line 2: causes 16 is not a set of the phenomena tested there (11)", stderr)

    def test_a_causes_file_without_rows_is_said_so(self):
        causes = os.path.join(self.root, "causes_empty.csv")
        write_causes(causes, [])
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", causes,
                                    "--out", os.path.join(self.root, "report_empty_causes"), "--tsne-iterations", "250"])
        self.assertEqual(code, 0, stderr)
        self.assertIn("the causes given hold no rows", stderr)

    def test_a_cell_given_twice_is_refused(self):
        """The later row won silently: two answers for one cell, one of them wrong."""
        causes = os.path.join(self.root, "causes_twice.csv")
        write_causes(causes, self.f.sessions)
        lines = read_text(causes).splitlines()
        with open(causes, "a") as fh:
            fh.write(lines[1] + "\n")
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--causes", causes,
                                    "--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        self.assertIn(f"causes_twice.csv: line {len(lines) + 1}: session ", stderr)
        self.assertIn("again (first on line 2; files concatenated?)", stderr)

    def test_a_dataset_of_a_later_version_is_refused(self):
        """Another layout read as this one would give wrong patches."""
        for name, key, value, message in (("data_v2", "version", 2, "dataset version 2; this report reads 1 to 1"),
                                          ("data_v_text", "version", "1", 'version "1" is not a version number'),
                                          ("data_v_bool", "version", True, "version true is not a version number"),
                                          ("data_other", "format", "x", 'format "x", not "ivoa-dataset"')):
            d, _ = self.dataset_copy(name)
            path = os.path.join(d, "dataset.json")
            meta = json.loads(read_text(path))
            meta[key] = value
            with open(path, "w") as fh:
                json.dump(meta, fh)
            self.assert_refused(d, "dataset.json: " + message)

    def test_a_key_given_twice_is_refused(self):
        """json keeps the last of two, the C++ tools the first: neither is a safe guess."""
        d, _ = self.dataset_copy("data_key_twice")
        path = os.path.join(d, "dataset.json")
        text = read_text(path).strip()
        with open(path, "w") as fh:
            fh.write(text[:-1].rstrip() + ', "version": 2}\n')
        self.assert_refused(d, 'dataset.json: key "version" is given twice')

    def dataset_copy(self, name):
        """A copy of the fabricated dataset and the folder of its first session."""
        d = os.path.join(self.root, name)
        shutil.copytree(self.f.data, d)
        return d, os.path.join(d, sorted(n for n in os.listdir(d) if os.path.isdir(os.path.join(d, n)))[0])

    def dataset_with_sample_value(self, name, column, value):
        """A copy of the dataset whose first session's samples.csv has `value` in `column` on line 4."""
        d, session = self.dataset_copy(name)
        path = os.path.join(session, "samples.csv")
        lines = read_text(path).splitlines()
        fields = lines[3].split(",")
        fields[lines[0].split(",").index(column)] = value
        lines[3] = ",".join(fields)
        with open(path, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        return d

    def assert_refused(self, dataset, message):
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", dataset, "--out",
                                    os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        self.assertIn(message, stderr)
        self.assertNotIn("Traceback", stderr)

    def test_a_dataset_value_that_is_not_an_integer_is_named_by_line(self):
        self.assert_refused(self.dataset_with_sample_value("data_not_int", "label", "x"),
                            "samples.csv: line 4, column 'label': 'x' is not an integer")

    def test_a_dataset_value_too_large_for_64_bits_is_named_by_line(self):
        """It was an OverflowError's traceback, exit code 1."""
        self.assert_refused(self.dataset_with_sample_value("data_huge_utime", "utime", "9" * 20),
                            "samples.csv: line 4, column 'utime': '" + "9" * 20 + "' does not fit a 64-bit integer")

    def test_a_field_over_the_csv_limit_is_named_by_line(self):
        """It was csv.Error's traceback (the csv module stops at 128 kB a field)."""
        self.assert_refused(self.dataset_with_sample_value("data_huge_field", "label", "1" * 200000),
                            "samples.csv: line 4: field larger than field limit")

    def test_dataset_sizes_of_the_wrong_type_are_named(self):
        """patch_size and evidence_size were read with int(): a TypeError's traceback for a list."""
        for name, file, key, value in (("ds_patch", "dataset.json", "patch_size", "big"),
                                       ("s_patch", "session.json", "patch_size", [100]),
                                       ("s_evidence", "session.json", "evidence_size", -1)):
            d, session = self.dataset_copy("data_field_" + name)
            path = os.path.join(d if file == "dataset.json" else session, file)
            meta = json.loads(read_text(path)) if os.path.isfile(path) else {}
            meta[key] = value
            with open(path, "w") as fh:
                json.dump(meta, fh)
            least = 0 if key == "evidence_size" else 1
            self.assert_refused(d, f"{file}: field '{key}' = {value!r}, expected an integer >= {least}")

    def test_an_unwritable_out_is_found_before_the_inputs_are_read(self):
        a_file = os.path.join(self.root, "out_is_a_file")
        with open(a_file, "w"):
            pass
        code, _, stderr = run_main(["--eval", os.path.join(self.root, "no_eval"), "--dataset", self.f.data,
                                    "--out", os.path.join(a_file, "r")])
        self.assertEqual(code, 4, stderr)
        self.assertIn("cannot write the report: " + os.path.join(a_file, "r") + ": Not a directory", stderr)

    def test_a_settings_row_given_twice_is_refused(self):
        variants = os.path.join(self.root, "variants_twice.csv")
        write_variants(variants, [("jppc", "stricter", "TN", 100, 100, 0), ("jppc", "stricter", "TN", 100, 100, 0)])
        code, _, stderr = run_main(["--eval", self.f.perfect, "--dataset", self.f.data, "--variants", variants,
                                    "--out", os.path.join(self.root, "report_bad")])
        self.assertEqual(code, 3, stderr)
        self.assertIn("variants_twice.csv: line 3: session s1, jppc variant 'stricter', label TN again (first on "
                      "line 2)", stderr)


class MetricUnitTest(unittest.TestCase):
    """The metric functions against scikit-learn and a negative control."""

    def test_mean_per_class_accuracy_is_balanced_accuracy(self):
        load_tool()
        from sklearn.metrics import accuracy_score, balanced_accuracy_score
        from report_metrics import class_metrics
        rng = np.random.default_rng(5)
        y = rng.integers(0, 4, 500)
        p = np.where(rng.random(500) < 0.6, y, rng.integers(0, 4, 500))
        m = class_metrics(y, p)
        self.assertAlmostEqual(m["mean_per_class_accuracy"], balanced_accuracy_score(y, p))
        self.assertAlmostEqual(m["overall_accuracy"], accuracy_score(y, p))

    def test_uncertainty_on_correct_predictions_does_not_rise(self):
        """Negative control: variance high on the *correct* predictions, so
        filtering removes good predictions and accuracy falls."""
        load_tool()
        from report_metrics import uncertainty_sweep
        rng = np.random.default_rng(9)
        y = np.repeat(np.arange(4), 50)
        p = np.where(rng.random(200) < 0.7, y, (y + 1) % 4)
        var = np.where(p == y, rng.uniform(0.05, 0.1, 200), rng.uniform(0.001, 0.02, 200))
        run = sweep_run(label=y, predicted=p, var_predicted=var)
        s = uncertainty_sweep(run)
        self.assertFalse(s["accuracy_rises_as_threshold_falls"])
        self.assertLess(s["at_70"]["overall_accuracy"], s["unfiltered"]["overall_accuracy"])

    def test_the_bootstrap_interval_resamples_whole_frames(self):
        """40 frames of 4 cells, one of each class. Where every frame has the same right and wrong cells, any
        resample of frames scores the same; where whole frames are right or wrong, the interval widens around
        the figure; kept rows only count."""
        load_tool()
        from report_metrics import bootstrap_interval, class_metrics, frame_ids
        frames, label = np.repeat(np.arange(40), 4), np.tile(np.arange(4), 40)
        run = types.SimpleNamespace(session=np.array(["s"] * 160), utime=frames * 1000)
        ids = frame_ids(run)
        self.assertEqual(list(ids), list(frames))
        same = np.where(label == FN, TN, label)  # FN wrong in every frame: 0.75 whatever is drawn
        self.assertEqual(bootstrap_interval(label, same, ids), [0.75, 0.75])
        predicted = np.where(frames < 10, (label + 1) % 4, label)  # frames 0-9 wholly wrong: 0.75 again
        low, high = bootstrap_interval(label, predicted, ids)
        self.assertLess(low, 0.75)
        self.assertGreater(high, 0.75)
        self.assertLess(high - low, 0.35)
        self.assertAlmostEqual(class_metrics(label, predicted)["mean_per_class_accuracy"], 0.75)
        self.assertEqual(bootstrap_interval(label, predicted, ids, keep=frames >= 10), [1.0, 1.0])
        # frames are (session, utime): 0-19 in session a and 20-39 in b, with the same utimes, are 40 frames
        run = types.SimpleNamespace(session=np.where(frames < 20, "a", "b"), utime=(frames % 20) * 1000)
        self.assertEqual(list(frame_ids(run)), list(frames))

    def test_the_session_interval_counts_which_sessions_were_tested(self):
        """MIN_SESSIONS_FOR_INTERVAL sessions of 10 frames of 4 cells, the first two wholly wrong: resampling
        frames draws about the same share of wrong frames every time, resampling sessions anywhere from none to
        most of them, so its interval is wider around the same figure. One session fewer gives none."""
        load_tool()
        from report_markdown import intervals_text
        from report_metrics import MIN_SESSIONS_FOR_INTERVAL, headline_intervals
        n = MIN_SESSIONS_FOR_INTERVAL
        session, frame = np.repeat(np.arange(n), 40), np.tile(np.repeat(np.arange(10), 4), n)
        label = np.tile(np.arange(4), 10 * n)
        predicted = np.where(session < 2, (label + 1) % 4, label)
        figure = 1 - 2 / n

        def run_of(rows):
            return types.SimpleNamespace(label=label[rows], predicted=predicted[rows], var_predicted=np.zeros(rows.sum()),
                                         verdict=None, session=np.array([f"s{i}" for i in session[rows]]),
                                         utime=frame[rows] * 1000)

        sweep = {"at_70": {"threshold": 0.0}}
        ci = headline_intervals(run_of(session >= 0), sweep, None)
        self.assertEqual(ci["sessions"], n)
        frames_low, frames_high = ci["mean_per_class_accuracy"]
        low, high = ci["by_session"]["mean_per_class_accuracy"]
        self.assertLess(low, frames_low)
        self.assertGreater(high, frames_high)
        self.assertLess(low, figure)
        self.assertGreater(high, figure)
        self.assertIn("mpca_at_70", ci["by_session"])
        text = intervals_text(ci, "mean_per_class_accuracy")
        self.assertIn(f"{low:.3f}–{high:.3f} over the {n} sessions resampled whole", text)
        self.assertIn(f"{frames_low:.3f}–{frames_high:.3f} over 1000 resamples of whole frames", text)
        ci = headline_intervals(run_of(session < n - 1), sweep, None)
        self.assertIsNone(ci["by_session"])
        self.assertIsNotNone(ci["mean_per_class_accuracy"])
        self.assertIn(f"none over whole sessions: {n - 1} are too few", intervals_text(ci, "mean_per_class_accuracy"))

    def test_no_session_interval_mixes_in_resamples_without_a_class(self):
        """FN only in one of nine sessions: a third of the session resamples have no FN, and their mean over three
        classes is another figure (0.9 against 0.7 here), so there is no session interval; frames rarely lose a
        class and keep theirs."""
        load_tool()
        from report_markdown import intervals_text
        from report_metrics import headline_intervals
        session = np.repeat(np.arange(9), 40)
        frame = np.tile(np.repeat(np.arange(10), 4), 9)
        label = np.tile(np.arange(4), 90)
        label = np.where((label == FN) & (session > 0), TN, label)  # FN in session 0 only
        rng = np.random.default_rng(3)
        predicted = np.where(rng.random(360) < 0.9, label, (label + 1) % 4)
        predicted = np.where(label == FN, TN, predicted)  # FN always missed
        run = types.SimpleNamespace(label=label, predicted=predicted, var_predicted=np.zeros(360), verdict=None,
                                    session=np.array([f"s{i}" for i in session]), utime=frame * 1000)
        ci = headline_intervals(run, {"at_70": {"threshold": 0.0}}, None)
        self.assertIsNotNone(ci["by_session"])
        self.assertIsNone(ci["by_session"]["mean_per_class_accuracy"])
        self.assertIsNotNone(ci["mean_per_class_accuracy"])
        self.assertIn("none over the 9 sessions resampled whole: a class is in too few of them",
                      intervals_text(ci, "mean_per_class_accuracy"))

    def test_a_purity_target_one_cluster_meets_says_nothing(self):
        load_tool()
        from report_markdown import _purity_target_text
        self.assertTrue(_purity_target_text(0.95, 0.60).endswith(": met"))
        self.assertIn("says nothing", _purity_target_text(0.95, 0.82))
        self.assertTrue(_purity_target_text(0.70, 0.50).endswith("not met"))
        self.assertTrue(_purity_target_text(None, None).endswith("not met"))

    def test_clusters_that_are_only_the_predicted_fp_and_fn_are_called_so(self):
        load_tool()
        from report_markdown import _split_by_predicted_class
        split = [{"n": 10, "predicted_fp": 10, "predicted_fn": 0}, {"n": 4, "predicted_fp": 0, "predicted_fn": 4}]
        self.assertIn("The two clusters are the predicted FP and the predicted FN", _split_by_predicted_class(split))
        mixed = [{"n": 10, "predicted_fp": 9, "predicted_fn": 1}, {"n": 4, "predicted_fp": 1, "predicted_fn": 3}]
        self.assertEqual(_split_by_predicted_class(mixed), "")
        both_fp = [{"n": 10, "predicted_fp": 10, "predicted_fn": 0}, {"n": 4, "predicted_fp": 4, "predicted_fn": 0}]
        self.assertEqual(_split_by_predicted_class(both_fp), "")

    def test_per_class_selection_keeps_the_confident_half_of_each_failure_class(self):
        """Pooled, the confident half of ten predicted FP (p 0.90-0.99) and six predicted FN (p 0.50-0.55) is
        eight FP; split by class it is five FP and three FN."""
        load_tool()
        from report_clustering import select_failures
        predicted = np.array([FP] * 10 + [FN] * 6 + [TP] * 4)
        conf = np.concatenate([np.linspace(0.90, 0.99, 10), np.linspace(0.50, 0.55, 6), [0.99] * 4])
        probs = np.zeros((20, 4))
        probs[np.arange(20), predicted] = conf
        run = types.SimpleNamespace(predicted=predicted, probs=probs)
        pooled, cut = select_failures(run, "confidence")
        self.assertEqual(list(pooled), list(range(2, 10)))
        self.assertAlmostEqual(cut, 0.92)
        split, cuts = select_failures(run, "confidence-per-class")
        self.assertEqual(list(split), [5, 6, 7, 8, 9, 13, 14, 15])
        self.assertAlmostEqual(cuts["FP"], 0.95)
        self.assertAlmostEqual(cuts["FN"], 0.53)

    def test_whether_accuracy_rises_is_judged_where_every_class_keeps_enough_cells(self):
        """Three classes of 200, their wrong predictions the most uncertain; FN 40, of which the 10 wrong ones
        are the most certain of all. Under τ = 0.03 the FN kept are those 10 alone, and the mean per-class
        accuracy falls to 0.75 there: 10 cells would decide the rank correlation over most of the sweep."""
        load_tool()
        from report_metrics import uncertainty_sweep
        rng = np.random.default_rng(4)
        y = np.repeat(np.arange(4), [200, 200, 200, 40])
        wrong = np.concatenate([rng.random(600) < 0.2, np.arange(40) < 10])
        p = np.where(wrong, (y + 1) % 4, y)
        var = np.where(wrong, rng.uniform(0.05, 0.1, 640), rng.uniform(0.001, 0.02, 640))
        var[600:] = np.where(wrong[600:], rng.uniform(0.0001, 0.0005, 40), 0.03)
        run = sweep_run(label=y, predicted=p, var_predicted=var)
        s = uncertainty_sweep(run)
        self.assertLess(s["spearman_threshold_vs_mpca"], -0.9)  # over the points keeping ≥ 20 FN: it rises
        # the 70 % point keeps the 10 sure-and-wrong FN only (a loss of 5 points there): not held against it
        self.assertLess(s["gain_at_70"], 0)
        self.assertEqual(s["verdict"], "yes")
        # a class with fewer than 20 cells in all does not stop the judgement
        y = np.repeat(np.arange(4), [300, 300, 300, 18])
        wrong = rng.random(918) < 0.2
        var = np.where(wrong, rng.uniform(0.05, 0.1, 918), rng.uniform(0.001, 0.02, 918))
        run = sweep_run(label=y, predicted=np.where(wrong, (y + 1) % 4, y), var_predicted=var)
        self.assertEqual(uncertainty_sweep(run)["verdict"], "yes")
        # no class with 20 cells: nothing to judge by, and said so
        y = np.repeat(np.arange(4), 10)
        var = rng.uniform(0.001, 0.1, 40)
        run = sweep_run(label=y, predicted=np.where(rng.random(40) < 0.2, (y + 1) % 4, y), var_predicted=var)
        self.assertEqual(uncertainty_sweep(run)["verdict"], "undetermined (no class has 20 cells: too few to judge)")

    def test_sweep_points_say_how_few_cells_the_smallest_class_keeps(self):
        load_tool()
        from report_markdown import _few_cells_note
        from report_metrics import _point
        label = np.array([0] * 23 + [1] * 50 + [2] * 50 + [3] * 50)
        var = np.concatenate([[0.5] * 20 + [0.1] * 3, np.linspace(0, 0.4, 150)])
        p = _point(label, label.copy(), var, 0.45)  # 20 of the 23 TP withheld
        self.assertEqual(p["fewest_kept"], 3)
        self.assertEqual(_point(label, label.copy(), var, 0.05)["fewest_kept"], 0)  # every TP withheld
        self.assertEqual(_point(label, label.copy(), var, 0.6)["fewest_kept"], 23)
        self.assertEqual(_point(label[23:], label[23:].copy(), var[23:], 0.45)["fewest_kept"], 50)  # no TP at all
        # a class with fewer than 20 cells in all is a handful at every threshold: it is not counted, or
        # nothing would be judged
        self.assertEqual(_point(label[20:], label[20:].copy(), var[20:], 0.6)["fewest_kept"], 50)
        # no class has 20: the smallest present counts, a handful everywhere (19 TP, 7 TN)
        self.assertEqual(_point(label[4:30], label[4:30].copy(), var[4:30], 0.6)["fewest_kept"], 7)
        ladder = [{"retained": 1.0, "fewest_kept": 30}, {"retained": 0.5, "fewest_kept": 3}]
        self.assertIn("From ≥ 50 % retained down, some class with 20 cells or more keeps fewer than 20 (3 there)",
                      _few_cells_note(ladder))
        self.assertIn("No class has 20 cells here (the smallest present has 7)",
                      _few_cells_note([{"retained": 1.0, "fewest_kept": 7}, {"retained": 0.5, "fewest_kept": 2}]))
        self.assertEqual(_few_cells_note([{"retained": 1.0, "fewest_kept": 50}]), "")

    def test_bars_a_few_cells_decide_are_the_ones_drawn_faint(self):
        load_tool()
        from report_figures import few_cell_groups
        groups = [{"n": 6, "support": [0, 5, 1, 0]},       # 0.5 m ahead: six cells in all
                  {"n": 1573, "support": [8, 1000, 500, 65]},  # eight TP decide a quarter of the mean
                  {"n": 2360, "support": [40, 1500, 700, 120]},
                  {"n": 900, "support": [0, 600, 300, 0]}]      # absent classes are not few
        mean, overall = few_cell_groups(groups)
        self.assertEqual(mean, [True, True, False, False])
        self.assertEqual(overall, [True, False, False, False])

    def test_sweep_points_a_few_cells_decide_are_the_ones_drawn_faint_on_both_axes(self):
        load_tool()
        from report_figures import sweep_series
        curve = [{"threshold": 0.1, "retained": 1.0, "fewest_kept": 300, "mean_per_class_accuracy": 0.86},
                 {"threshold": 0.0, "retained": 0.01, "fewest_kept": 0, "mean_per_class_accuracy": 1.0},
                 {"threshold": 1e-5, "retained": 0.02, "fewest_kept": 3, "mean_per_class_accuracy": 0.75},
                 {"threshold": 1e-3, "retained": 0.5, "fewest_kept": 20, "mean_per_class_accuracy": 0.99},
                 {"threshold": 1e-9, "retained": 0.0, "fewest_kept": 0, "mean_per_class_accuracy": None}]
        t, solid, v = sweep_series(curve, "threshold", ["mean_per_class_accuracy"])
        self.assertEqual(t.tolist(), [1e-5, 1e-3, 0.1])  # τ = 0 has no place on the log axis
        self.assertEqual(solid.tolist(), [False, True, True])
        self.assertEqual(v["mean_per_class_accuracy"].tolist(), [0.75, 0.99, 0.86])
        r, solid, _ = sweep_series(curve, "retained", ["mean_per_class_accuracy"])
        self.assertEqual(r.tolist(), [0.01, 0.02, 0.5, 1.0])
        self.assertEqual(solid.tolist(), [False, False, True, True])

    def test_phenomenon_bars_a_few_cells_decide_are_the_ones_drawn_faint(self):
        load_tool()
        from report_figures import few_cell_phenomena
        entries = [{"phenomenon": 0, "n": 1884}, {"phenomenon": 64, "n": 9},  # nine saturated cells
                   {"phenomenon": 8, "n": 20}]
        self.assertEqual(few_cell_phenomena(entries, [0, 2, 8, 64]), [False, False, False, True])  # 2: absent

    def test_a_bar_value_goes_over_its_true_rate_tick_where_the_tick_would_cross_it(self):
        load_tool()
        from report_figures import value_label_heights
        nan = float("nan")
        h = value_label_heights([0.49, 0.58, 0.04, 0.72, nan], [0.55, 0.55, 0.09, 0.55, 0.2])
        self.assertAlmostEqual(h[0], 0.565)  # the tick 0.06 over the bar: the label over the tick
        self.assertAlmostEqual(h[1], 0.595)  # the tick just under the bar's top: over the bar
        self.assertAlmostEqual(h[2], 0.105)
        self.assertAlmostEqual(h[3], 0.735)  # the tick well inside the bar: no clash
        self.assertAlmostEqual(h[4], 0.015)  # no bar (drawn without a label)

    def test_a_cause_has_one_colour_in_every_figure_whatever_its_rank(self):
        load_tool()
        from report_figures import PHENOMENON_COLOURS, _cause_panel
        few_reflections = np.array([REFLECTION] * 2 + [TEXTURELESS] * 5 + [REFLECTION | TEXTURELESS] * 3)
        many_reflections = np.array([REFLECTION] * 9 + [TEXTURELESS] * 1 + [REFLECTION | TEXTURELESS] * 4)
        colour_of = [dict(zip(legend, colours)) for _, _, legend, colours in
                     (_cause_panel(few_reflections), _cause_panel(many_reflections))]
        self.assertEqual(colour_of[0], colour_of[1])
        self.assertEqual(colour_of[0]["reflection"], PHENOMENON_COLOURS[REFLECTION])  # as in the phenomenon panel
        self.assertNotIn(colour_of[0]["reflection+textureless"], PHENOMENON_COLOURS.values())
        # two sets whose own colours are the same get different ones in the same panel
        both = np.array([REFLECTION | DARK_STRIPE] * 3 + [REFLECTION | 16] * 2)
        _, _, legend, colours = _cause_panel(both)
        self.assertEqual(len(set(colours[:2])), 2, dict(zip(legend, colours)))

    def test_withheld_failures_are_named_only_where_the_gate_sets_them_aside(self):
        load_tool()
        from report_markdown import _withheld_failures
        point = {"retained": 0.70, "retained_per_class": [0.36, 0.72, 0.74, 0.47]}  # TP, TN, FP, FN
        text = _withheld_failures(point)
        self.assertIn("withholds these failures more often than other cells: it keeps 47 % of the true FN, "
                      "against 70 % of all cells", text)
        self.assertNotIn("true FP", text)  # kept at about its share
        self.assertEqual(_withheld_failures({"retained": 0.70, "retained_per_class": [0.5, 0.7, 0.7, None]}), "")

    def test_the_weights_step_says_how_far_the_run_went_where_the_file_records_it(self):
        load_tool()
        from ivoa_report import _training_steps
        self.assertEqual(_training_steps({"steps": "6999", "best_step": "6999"}), "6999")  # files before 2026-12-03
        self.assertEqual(_training_steps({"steps": "6999", "best_step": "6999", "steps_planned": "14000",
                                          "kept": "best_validated"}), "6999 of 14000, best on validation")
        self.assertEqual(_training_steps({"steps": "1400", "best_step": "1400", "steps_planned": "1400",
                                          "kept": "last"}), "1400 of 1400, the last")
        self.assertEqual(_training_steps({}), "n/a")

    def test_phenomena_present_counts_every_bit_and_its_lift(self):
        """Co-occurring phenomena: each bit counts for every patch that shows
        it, and the lift compares with all clustered samples."""
        load_tool()
        from report_clustering import _phenomena_present
        # 10 clustered patches: 6 reflective (4 of them also texture-less), 4 dark stripe only.
        bits = np.array([REFLECTION | TEXTURELESS] * 4 + [REFLECTION] * 2 + [DARK_STRIPE] * 4)
        overall = {REFLECTION: 0.6, TEXTURELESS: 0.4, DARK_STRIPE: 0.4}
        stripes = _phenomena_present(bits[6:], overall)
        self.assertEqual([(e["phenomenon"], e["share"], e["lift"]) for e in stripes], [(DARK_STRIPE, 1.0, 2.5)])
        shiny = {e["phenomenon"]: e for e in _phenomena_present(bits[:6], overall)}
        self.assertEqual(sorted(shiny), [REFLECTION, TEXTURELESS])
        self.assertAlmostEqual(shiny[REFLECTION]["share"], 1.0)
        self.assertAlmostEqual(shiny[REFLECTION]["lift"], 1 / 0.6)
        self.assertAlmostEqual(shiny[TEXTURELESS]["share"], 4 / 6)
        self.assertEqual(_phenomena_present(bits, overall)[0]["lift"], 1.0)  # the whole set: no lift

    def test_by_distance_groups_rows_and_sizes_the_safety_disc(self):
        """Two grid rows over two frames: per-row accuracies, and the disc's
        width from the image spacing of neighbouring cells (200 px and 50 px
        per 0.25 m: 800 and 200 px/m, so 160 and 40 px for r = 0.1 m)."""
        load_tool()
        from report_metrics import by_distance
        ys = np.tile([-0.25, 0.0, 0.25], 4)
        xs = np.repeat([1.0, 2.0, 1.0, 2.0], 3)
        us = np.where(xs == 1.0, 480 + 800 * ys, 480 + 200 * ys)
        label = np.array([TP, TN, FP] * 4)
        predicted = label.copy()
        predicted[[0, 3]] = FN  # one TP wrong in each row
        run = types.SimpleNamespace(session=np.array(["s"] * 12), utime=np.repeat([1, 2], 6), x=xs + 1e-6, y=ys,
                                    u=us, label=label, predicted=predicted)
        rows = by_distance(run, 0.1)
        self.assertEqual([r["group"] for r in rows], ["1 m", "2 m"])
        self.assertEqual([r["n"] for r in rows], [6, 6])
        for r, disc in zip(rows, (160, 40)):
            self.assertAlmostEqual(r["disc_px"], disc)
            self.assertEqual(r["per_class_accuracy"][:3], [0.5, 1.0, 1.0])
        self.assertIsNone(by_distance(run)[0]["disc_px"])  # no safety radius known
        self.assertIsNone(rows[0]["patch_px"])  # no per-sample sides given

        # Footprint-scaled patches: each row reports its median side, and the
        # table says the near row's disc (160 px) now fits in its 256 px square.
        sides = np.where(xs == 1.0, 256, 100)
        sides[0] = 250
        scaled = by_distance(run, 0.1, sides)
        self.assertEqual([r["patch_px"] for r in scaled], [256.0, 100.0])
        from report_markdown import distance_table
        text = distance_table({"distances": scaled, "patch_size": 100, "patch_scale": 1.6})
        self.assertIn("Footprint-scaled patches (x1.6)", text)
        self.assertIn("| 256 |", text)
        self.assertNotIn("wider than the patch", text)
        self.assertIn("1 m the safety disc is wider than the patch",
                      distance_table({"distances": rows, "patch_size": 100, "patch_scale": 0}))

    def test_by_margin_puts_the_threshold_itself_on_the_obstacle_side(self):
        """JPP-C calls a cell an obstacle when its worst cost reaches the
        threshold: a margin of exactly 0 is an obstacle's, in band [0, 0.04)."""
        load_tool()
        from report_metrics import by_margin
        label = np.array([TP, TN, FN, FP])
        run = types.SimpleNamespace(label=label, predicted=np.array([TP, TN, TP, TN]), verdict=None)
        g = by_margin(run, np.array([0.0, -0.5, -0.001, 0.5]), 0.75)
        self.assertTrue(g["ok"], g["message"])
        bands = {(b["low"], b["high"]): b["n"] for b in g["bands"]}
        self.assertEqual(bands, {(0.0, 0.04): 1, (None, -0.3): 1, (-0.04, 0.0): 1, (0.3, None): 1})
        self.assertAlmostEqual(g["near_share"], 0.5)
        self.assertAlmostEqual(g["near_verdict_error_share"], 0.5)  # the FN read as obstacle; the far FP too
        self.assertIsNone(by_margin(run, None, 0.75))

    def test_auroc_undefined_without_failures(self):
        load_tool()
        from report_metrics import failure_detection
        y = np.array([TP, TN, TN, TP])
        fd = failure_detection(y, y, np.full((4, 4), 0.25))
        self.assertIsNone(fd["auroc"])
        self.assertIn("no true failure", fd["message"])


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", default=TOOL)
    ap.add_argument("--workdir", default=None, help="keep the fabricated inputs and report here")
    args, rest = ap.parse_known_args()
    TOOL = os.path.abspath(args.tool)
    WORKDIR = os.path.abspath(args.workdir) if args.workdir else None
    os.environ.setdefault("MPLBACKEND", "Agg")
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)
