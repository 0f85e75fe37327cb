#!/usr/bin/env python3
"""Tests of tools/report/ivoa_label_repeatability.py on fabricated datasets
whose answers are worked out by hand.

Three realisations of one session, 100 cells labelled in all of them plus
cells labelled in some only:

* 50 cells TN in all three; 20 cells TP in all three;
* 10 cells FP, FP, TN (the noise tips one realisation in three);
* 20 cells FN, TP, FN.

Run: python3 tests/report/test_label_repeatability.py [--tool tools/report/ivoa_label_repeatability.py]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.normpath(os.path.join(HERE, "..", "..", "tools", "report", "ivoa_label_repeatability.py"))
TP, TN, FP, FN = 0, 1, 2, 3

# Per realisation, the label of each of the 100 shared cells.
GROUPS = [(50, (TN, TN, TN)), (20, (TP, TP, TP)), (10, (FP, FP, TN)), (20, (FN, TP, FN))]


def write_dataset(root, labels, extra_cells=0, detector=None):
    d = os.path.join(root, "office_s31")
    os.makedirs(d)
    if detector:
        with open(os.path.join(d, "session.json"), "w") as f:
            json.dump({"session": "office_s31", "detector": detector}, f)
    with open(os.path.join(d, "samples.csv"), "w") as f:
        f.write("sample,frame,utime,depth_utime,cell,label\n")
        for i, label in enumerate(labels):
            f.write(f"{i},{i // 10},{1000 + i // 10},{1004 + i // 10},{i % 10},{label}\n")
        for j in range(extra_cells):  # cells only this realisation labelled
            i = len(labels) + j
            f.write(f"{i},99,{5000 + j},{5004 + j},0,{TN}\n")


class LabelRepeatabilityTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.data = []
        for r in range(3):
            labels = [g[1][r] for g in GROUPS for _ in range(g[0])]
            root = os.path.join(cls.tmp.name, f"noise{r}")
            write_dataset(root, labels, extra_cells=2 if r == 0 else 0)
            cls.data.append(root)
        cls.json_path = os.path.join(cls.tmp.name, "out.json")
        cls.proc = subprocess.run([sys.executable, TOOL, *cls.data, "--json", cls.json_path],
                                  capture_output=True, text=True, timeout=60)
        with open(cls.json_path) as f:
            cls.r = json.load(f)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_runs_and_counts_cells(self):
        self.assertEqual(self.proc.returncode, 0, self.proc.stderr)
        self.assertEqual(self.r["cells"], 100)
        self.assertEqual(self.r["cells_labelled_in_some_realisations_only"], 2)
        self.assertAlmostEqual(self.r["cells_with_one_label_in_all"], 0.70)
        self.assertIn("100 cells labelled in all", self.proc.stdout)

    def test_pairwise_agreement(self):
        # Ordered pairs (6 per cell). TP: 20 stable cells give 120 TP->TP; the
        # 20 FN,TP,FN cells give TP->FN twice each: 40. TP row: 120/160.
        # FP: 10 cells, pairs from an FP: (0,1) (1,0) FP->FP, (0,2) (1,2) FP->TN: 1/2.
        # FN: 20 cells, FN->FN (0,2) (2,0), FN->TP (0,1) (2,1): 1/2.
        # TN: 50 x 6 = 300 TN->TN, and from the FP cells' TN: TN->FP twice: 20. 300/320.
        a = self.r["agreement_per_class"]
        self.assertAlmostEqual(a[TP], 120 / 160)
        self.assertAlmostEqual(a[TN], 300 / 320)
        self.assertAlmostEqual(a[FP], 0.5)
        self.assertAlmostEqual(a[FN], 0.5)
        self.assertAlmostEqual(self.r["agreement"][TP][FN], 40 / 160)
        self.assertAlmostEqual(self.r["agreement_mean_per_class"], (0.75 + 300 / 320 + 0.5 + 0.5) / 4)

    def test_leave_one_out_majority(self):
        # Two others, ties go to the first of them. FP cells: truth FP (r0) <- others FP,TN: tie -> FP;
        # truth FP (r1) <- others FP,TN: tie -> FP; truth TN (r2) <- FP,FP -> FP (wrong).
        # FN cells: truth FN (r0) <- TP,FN: tie -> TP (wrong); truth TP (r1) <- FN,FN -> FN (wrong);
        # truth FN (r2) <- FN,TP: tie -> FN. TP: 60 right of 80; TN: 150 of 160; FP 20/20; FN 20/40.
        m = self.r["majority_per_class"]
        self.assertAlmostEqual(m[TP], 60 / 80)
        self.assertAlmostEqual(m[TN], 150 / 160)
        self.assertAlmostEqual(m[FP], 1.0)
        self.assertAlmostEqual(m[FN], 0.5)

    def test_a_class_no_realisation_gave_is_left_out_not_scored_zero(self):
        # Only TN and FP cells: TP and FN have no support, so they are NaN
        # in both the agreement and the majority, and both means are over
        # the two classes present (agreement TN 300/320 as above, FP 1/2).
        groups = [(50, (TN, TN, TN)), (10, (FP, FP, TN))]
        roots = []
        for r in range(3):
            root = os.path.join(self.tmp.name, f"no_tp{r}")
            write_dataset(root, [g[1][r] for g in groups for _ in range(g[0])])
            roots.append(root)
        out = os.path.join(self.tmp.name, "no_tp.json")
        proc = subprocess.run([sys.executable, TOOL, *roots, "--json", out], capture_output=True, text=True,
                              timeout=60)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(out) as f:
            r = json.load(f)
        for name in ("agreement_per_class", "majority_per_class"):
            self.assertTrue(np.isnan(r[name][TP]) and np.isnan(r[name][FN]), r[name])
        self.assertAlmostEqual(r["agreement_mean_per_class"], (300 / 320 + 0.5) / 2)
        self.assertIn("TP nan", proc.stdout)

    def test_bad_inputs_are_named(self):
        missing = os.path.join(self.tmp.name, "nowhere")
        proc = subprocess.run([sys.executable, TOOL, self.data[0], missing], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 3)
        self.assertIn("nowhere: dataset folder not found", proc.stderr)
        bad = os.path.join(self.tmp.name, "bad")
        os.makedirs(os.path.join(bad, "office_s31"))
        with open(os.path.join(bad, "office_s31", "samples.csv"), "w") as f:
            f.write("sample,utime,cell,label\n0,1000,0,x\n")
        proc = subprocess.run([sys.executable, TOOL, self.data[0], bad], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 3)
        self.assertIn("samples.csv: line 2", proc.stderr)
        # a label out of range, a row cut short, no rows: named by line, no traceback
        for name, rows, message in (("label9", "0,1000,0,9\n", "line 2: label 9, expected 0..3"),
                                    ("wide", "0,1000,0," + "1" * 200000 + "\n", "line 2: field larger than field limit"),
                                    ("cut", "0,1000,0,1\n1,1000\n", "line 3 does not have the header's 4 fields"),
                                    ("empty", "", "empty: no samples in any session (office_s31)")):
            folder = os.path.join(self.tmp.name, name, "office_s31")
            os.makedirs(folder)
            with open(os.path.join(folder, "samples.csv"), "w") as f:
                f.write("sample,utime,cell,label\n" + rows)
            proc = subprocess.run([sys.executable, TOOL, self.data[0], os.path.dirname(folder)],
                                  capture_output=True, text=True, timeout=60)
            self.assertEqual(proc.returncode, 3, proc.stderr)
            self.assertIn(message, proc.stderr)
            self.assertNotIn("Traceback", proc.stderr)
        # --json is checked before the analysis: an unreadable dataset does not hide it
        proc = subprocess.run([sys.executable, TOOL, self.data[0], missing, "--json",
                               os.path.join(self.tmp.name, "no", "x.json")], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 4, proc.stderr)
        self.assertIn("cannot write " + os.path.join(self.tmp.name, "no", "x.json") + ": its folder", proc.stderr)

    def test_a_dataset_of_a_later_version_is_refused(self):
        # its samples.csv may read as labels yet mean something else
        later = os.path.join(self.tmp.name, "later")
        write_dataset(later, [TN] * 100)
        with open(os.path.join(later, "dataset.json"), "w") as f:
            json.dump({"format": "ivoa-dataset", "version": 7, "sessions": ["office_s31"]}, f)
        proc = subprocess.run([sys.executable, TOOL, self.data[0], later], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 3, proc.stderr)
        self.assertIn("dataset.json: dataset version 7; this report reads 1 to 1", proc.stderr)

    def test_a_session_without_samples_adds_no_cells_and_is_not_refused(self):
        # ivoa-dataset writes (and lists) a session where no frame gave a sample
        root = os.path.join(self.tmp.name, "with_empty")
        shutil.copytree(self.data[1], root)
        os.makedirs(os.path.join(root, "home_s31"))
        with open(os.path.join(root, "home_s31", "samples.csv"), "w") as f:
            f.write("sample,frame,utime,depth_utime,cell,label\n")
        shutil.copytree(os.path.join(root, "home_s31"), os.path.join(self.tmp.name, "with_empty_too", "home_s31"))
        shutil.copytree(os.path.join(self.data[0], "office_s31"),
                        os.path.join(self.tmp.name, "with_empty_too", "office_s31"))
        proc = subprocess.run([sys.executable, TOOL, os.path.join(self.tmp.name, "with_empty_too"), root],
                              capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn(f"2 realisations, 2 sessions, {sum(g[0] for g in GROUPS)} cells labelled in all", proc.stdout)
        # sessions in common, but none with a cell every dataset labelled
        only_empty = os.path.join(self.tmp.name, "only_empty_in_common")
        shutil.copytree(os.path.join(root, "home_s31"), os.path.join(only_empty, "home_s31"))
        os.makedirs(os.path.join(only_empty, "lab_s31"))
        with open(os.path.join(only_empty, "lab_s31", "samples.csv"), "w") as f:
            f.write("sample,frame,utime,depth_utime,cell,label\n0,0,1000,1004,0,1\n")
        proc = subprocess.run([sys.executable, TOOL, only_empty, root], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 3, proc.stderr)
        self.assertIn("no cell is labelled in every dataset (sessions in common: home_s31)", proc.stderr)

    def test_realisations_must_be_distinct_and_of_one_detector(self):
        proc = subprocess.run([sys.executable, TOOL, self.data[0], self.data[0] + "/"], capture_output=True,
                              text=True, timeout=60)
        self.assertEqual(proc.returncode, 2)
        self.assertIn("is given twice", proc.stderr)
        labels = [g[1][0] for g in GROUPS for _ in range(g[0])]
        jppc, dense = os.path.join(self.tmp.name, "jppc"), os.path.join(self.tmp.name, "dense")
        write_dataset(jppc, labels, detector="jppc")
        write_dataset(dense, labels, detector="dense")
        proc = subprocess.run([sys.executable, TOOL, jppc, dense], capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 3)
        self.assertIn("session office_s31 is labelled from different detectors ('jppc' in", proc.stderr)

    def test_the_json_is_never_written_into_an_input_dataset(self):
        target = os.path.join(self.data[1], "office_s31", "samples.csv")
        with open(target) as f:
            before = f.read()
        proc = subprocess.run([sys.executable, TOOL, *self.data[:2], "--json", target], capture_output=True,
                              text=True, timeout=60)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertIn(f"is a file of the dataset {self.data[1]}: it would be written over", proc.stderr)
        with open(target) as f:
            self.assertEqual(f.read(), before)
        proc = subprocess.run([sys.executable, TOOL, *self.data[:2], "--evidence-threshold", "nan"],
                              capture_output=True, text=True, timeout=60)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertIn("--evidence-threshold must be a finite cost", proc.stderr)


def write_evidence_dataset(root, cells, realisation, detector="jppc"):
    """One session whose samples carry JPP-C-like evidence: cells are
    (label per realisation, worst cost per realisation); each sample stores
    [worst, worst - 0.1, NaN] (NaN worst: nothing observed)."""
    d = os.path.join(root, "office_s31")
    os.makedirs(d)
    with open(os.path.join(d, "session.json"), "w") as f:
        json.dump({"session": "office_s31", "detector": detector, "evidence_size": 3}, f)
    with open(os.path.join(d, "samples.csv"), "w") as f:
        f.write("sample,frame,utime,depth_utime,cell,label\n")
        for i, (labels, _) in enumerate(cells):
            f.write(f"{i},0,1000,1004,{i},{labels[realisation]}\n")
    worst = np.array([costs[realisation] for _, costs in cells], np.float64)
    np.stack([worst, worst - 0.1, np.full(len(worst), np.nan)], axis=1).astype("<f4").tofile(
        os.path.join(d, "evidence.f32"))


# (labels in realisations 0, 1 and 2, worst window cost in each); threshold 0.75.
EVIDENCE_CELLS = [
    ((TN, TN, TN), (0.20, 0.22, 0.25)),         # all far below: < -0.3, one verdict
    ((TN, FP, TN), (0.70, 0.78, 0.72)),         # -0.08 … -0.04, 0 … 0.04, -0.04 … 0
    ((TP, TP, TP), (1.20, 1.10, 1.15)),         # all >= 0.3, one verdict
    ((FN, TP, TP), (0.74, 0.76, 0.77)),         # -0.04 … 0, then twice 0 … 0.04
    ((TN, TN, TN), (0.10, float("nan"), 0.12)),  # realisation 1 observed nothing: left out
]


class EvidenceRepeatabilityTest(unittest.TestCase):
    """How far the noise moves the worst cost, and per margin band how often
    another realisation keeps the verdict, worked out by hand."""

    def run_tool(self, write, *extra):
        """Three realisations written by write(root, realisation); the tool's
        process and its JSON (None when it failed)."""
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        roots = [os.path.join(tmp.name, f"noise{r}") for r in range(3)]
        for r, root in enumerate(roots):
            write(root, r)
        out = os.path.join(tmp.name, "out.json")
        proc = subprocess.run([sys.executable, TOOL, *roots, "--json", out, *extra], capture_output=True, text=True,
                              timeout=60)
        if proc.returncode != 0:
            return proc, None
        with open(out) as f:
            return proc, json.load(f)

    def run_on_cells(self, *extra):
        return self.run_tool(lambda root, r: write_evidence_dataset(root, EVIDENCE_CELLS, r), *extra)

    def test_shifts_and_bands(self):
        proc, r = self.run_on_cells()
        self.assertEqual(proc.returncode, 0, proc.stderr)
        e = r["evidence"]
        self.assertEqual(r["detector"], "jppc")
        self.assertEqual(r["session_names"], ["office_s31"])
        self.assertEqual((e["cells"], e["cells_without_evidence"]), (4, 1))
        # |shifts| of the three pairs per cell: 0.02 0.05 0.03, 0.08 0.02 0.06, 0.10 0.05 0.05, 0.02 0.03 0.01;
        # sorted, the 6th and 7th of 12 are 0.03 and 0.05; the 90th percentile 0.06 + 0.9 x 0.02
        self.assertAlmostEqual(e["worst_shift_median"], 0.04, places=5)
        self.assertAlmostEqual(e["worst_shift_p90"], 0.078, places=5)
        # each cell of each realisation in its band once, agreeing with 0-2 of the two others
        bands = {(b["low"], b["high"]): (b["n"], b["verdict_agreement"]) for b in e["bands"]}
        self.assertEqual(set(bands), {(None, -0.3), (-0.08, -0.04), (-0.04, 0.0), (0.0, 0.04), (0.3, None)})
        for key, (n, agreement) in {(None, -0.3): (3, 1.0), (-0.08, -0.04): (1, 0.5), (-0.04, 0.0): (2, 0.25),
                                    (0.0, 0.04): (3, 1 / 3), (0.3, None): (3, 1.0)}.items():
            self.assertEqual(bands[key][0], n, key)
            self.assertAlmostEqual(bands[key][1], agreement, msg=str(key))
        self.assertAlmostEqual(e["verdict_agreement"], 2 / 3)
        self.assertIn("moves by 0.040 (median) and 0.078 (90th percentile)", proc.stdout)

    def test_evidence_must_give_the_labels_verdicts(self):
        proc, _ = self.run_on_cells("--evidence-threshold", "0.5")
        self.assertEqual(proc.returncode, 3)
        self.assertIn("the evidence gives the labels' verdict for only 75.0 % of the cells at threshold 0.5",
                      proc.stderr)

    def test_without_evidence_the_labels_are_still_compared(self):
        proc, r = self.run_tool(lambda root, _: write_dataset(root, [TN] * 10, detector="dense"))
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIsNone(r["evidence"])
        self.assertIn("not every dataset keeps the detector's evidence", proc.stdout)

    def test_bad_evidence_is_named(self):
        def truncated(root, r):
            write_evidence_dataset(root, EVIDENCE_CELLS, r)
            path = os.path.join(root, "office_s31", "evidence.f32")
            if r == 2:
                with open(path, "r+b") as f:
                    f.truncate(os.path.getsize(path) - 4)
        proc, _ = self.run_tool(truncated)
        self.assertEqual(proc.returncode, 3)
        self.assertIn("noise2/office_s31/evidence.f32: 14 values, expected 5 samples x 3", proc.stderr)


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", default=TOOL)
    args, rest = ap.parse_known_args()
    TOOL = os.path.abspath(args.tool)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)
