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
import subprocess
import sys
import tempfile
import unittest

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


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", default=TOOL)
    args, rest = ap.parse_known_args()
    TOOL = os.path.abspath(args.tool)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)
