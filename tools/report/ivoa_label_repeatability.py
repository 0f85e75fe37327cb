#!/usr/bin/env python3
"""How much of a dataset's labels the sensor noise decides.

Input: K datasets of the same sessions recorded with different simulator
noise seeds (``ivoa-sim-driver --noise-seed``: same scene, poses and
exposures, other camera and depth noise), labelled the same way. For the
cells labelled in every realisation it prints

* how often another realisation gives the same label, per class (the mean
  per-class accuracy of one realisation's labels used as predictions of
  another's), and
* the leave-one-out majority vote: each realisation's labels predicted by
  the most common label of the other K - 1. This predictor knows the scene
  exactly but not the noise; as K grows it approaches the best any such
  predictor can do, so its mean per-class accuracy estimates the ceiling
  for a model that cannot see which way the noise will tip a verdict;
* where the datasets keep the detector's evidence (JPP-C's window costs),
  how far the noise moves a cell's worst value, and per band of its margin
  to the threshold how often another realisation gives the same verdict.
  ``ivoa_report.py --repeatability`` sets the model's verdict accuracy
  beside these, band by band.

Usage: ivoa_label_repeatability.py DATASET DATASET [DATASET ...] [--json FILE]
                                   [--evidence-threshold COST]
(tools/main_job/ivoa-label-repeatability.sh records and labels them).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
from typing import Dict, List, Optional, Tuple

if __name__ == "__main__":
    import scientific_python
    scientific_python.ensure(("numpy",), "python3-numpy")

import numpy as np  # noqa: E402

from margin_bands import MARGIN_AGREEMENT_MIN, band_name, margin_bands  # noqa: E402
from report_inputs import InputError, read_dataset_index  # noqa: E402

LABEL_NAMES = ("TP", "TN", "FP", "FN")
TP, FP = 0, 2  # the labels whose detector verdict is "obstacle"
EXIT_BAD_INPUT = 3
EXIT_CANNOT_WRITE = 4  # as the C++ tools: an output that cannot be written


def read_labels(dataset: str) -> Dict[str, Dict[Tuple[int, int], int]]:
    """session -> {(utime, cell): label} for every session folder of a dataset.
    A session without samples is kept, empty (ivoa-dataset writes one where
    no frame gave a sample); a dataset with no sample at all is refused."""
    if not os.path.isdir(dataset):
        raise InputError(f"{dataset}: dataset folder not found")
    read_dataset_index(dataset)  # a later layout's labels could be read wrong, without an error
    sessions = {}
    for name in sorted(os.listdir(dataset)):
        if name.startswith("."):  # .NAME.partial: a session ivoa-dataset is building, or was killed building
            continue
        path = os.path.join(dataset, name, "samples.csv")
        if not os.path.isfile(path):
            continue
        sessions[name] = _read_session_labels(path)
    if not sessions:
        raise InputError(f"{dataset}: no session folders with a samples.csv")
    if not any(sessions.values()):
        raise InputError(f"{dataset}: no samples in any session ({', '.join(sessions)})")
    return sessions


def _read_session_labels(path: str) -> Dict[Tuple[int, int], int]:
    """{(utime, cell): label} of one samples.csv, each row checked."""
    labels = {}
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            missing = {"utime", "cell", "label"} - set(reader.fieldnames or [])
            if missing:
                raise InputError(f"{path}: missing column(s) {', '.join(sorted(missing))}")
            for row_number, row in enumerate(reader, start=2):
                if None in row.values() or None in row:  # DictReader: too few fields, or too many
                    raise InputError(f"{path}: line {row_number} does not have the header's "
                                     f"{len(reader.fieldnames)} fields (a truncated or damaged file?)")
                try:
                    label = int(row["label"])
                    labels[(int(row["utime"]), int(row["cell"]))] = label
                except ValueError:
                    raise InputError(f"{path}: line {row_number}: utime, cell and label must be integers") from None
                if not 0 <= label < len(LABEL_NAMES):
                    raise InputError(f"{path}: line {row_number}: label {label}, expected 0..3 (TP, TN, FP, FN)")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not UTF-8 text, so not a dataset's samples.csv") from None
    except csv.Error as e:  # a field over the csv module's limit (128 kB), a NUL byte, ...
        raise InputError(f"{path}: line {reader.reader.line_num}: {e}") from None  # DictReader's own lags
    return labels


def _why_cannot_write(path: str) -> str:
    """Why `path` could not be written, or "" if it looks writable."""
    folder = os.path.dirname(path) or "."
    if os.path.isdir(path):
        return "it is a folder"
    if not os.path.isdir(folder):
        return f"its folder {folder} does not exist"
    if not os.access(path if os.path.exists(path) else folder, os.W_OK):
        return "this user may not write it"
    return ""


def session_info(dataset: str, session: str) -> dict:
    """A session's session.json, or {} where it has none."""
    path = os.path.join(dataset, session, "session.json")
    try:
        with open(path) as f:
            info = json.load(f)
    except FileNotFoundError:
        return {}
    except (OSError, ValueError) as e:
        raise InputError(f"{path}: cannot read session metadata: {e}") from None
    if not isinstance(info, dict):
        raise InputError(f"{path}: cannot read session metadata: not a JSON object")
    return info


def session_detector(dataset: str, session: str) -> str:
    """The detector a session's labels are about (session.json), or "" if it does not say."""
    return str(session_info(dataset, session).get("detector", ""))


def read_worst_costs(dataset: str, session: str) -> Optional[Dict[Tuple[int, int], float]]:
    """{(utime, cell): the detector's worst evidence value} of one session
    (JPP-C: its worst ground sample's window cost; NaN where it observed
    none), or None when the session keeps no evidence (session.json's
    evidence_size 0: the dense detector, or --no-evidence)."""
    folder = os.path.join(dataset, session)
    try:
        size = int(session_info(dataset, session).get("evidence_size", 0) or 0)
    except (TypeError, ValueError) as e:
        raise InputError(f"{folder}/session.json: cannot read evidence_size: {e}") from None
    if size <= 0:
        return None
    path = os.path.join(folder, "evidence.f32")
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (session.json says evidence_size {size})")
    values = np.fromfile(path, dtype="<f4")
    with open(os.path.join(folder, "samples.csv"), newline="") as f:
        try:
            rows = [(int(r["sample"]), int(r["utime"]), int(r["cell"])) for r in csv.DictReader(f)]
        except (KeyError, ValueError, TypeError, csv.Error) as e:  # TypeError: a row short of fields
            raise InputError(f"{folder}/samples.csv: evidence needs integer sample, utime and cell columns "
                             f"({type(e).__name__}: {e})") from None
    if values.size != len(rows) * size:
        raise InputError(f"{path}: {values.size} values, expected {len(rows)} samples x {size}")
    if any(not 0 <= sample < len(rows) for sample, _, _ in rows):
        raise InputError(f"{folder}/samples.csv: sample numbers must index the {len(rows)} rows of evidence.f32")
    values = values.reshape(len(rows), size)
    observed = ~np.all(np.isnan(values), axis=1)
    worst = np.full(len(rows), np.nan)
    worst[observed] = np.nanmax(values[observed], axis=1)
    return {(utime, cell): float(worst[sample]) for sample, utime, cell in rows}


def check_one_detector(datasets: List[str], sessions) -> None:
    """Realisations labelled from different detectors differ by more than the noise."""
    for name in sorted(sessions):
        detectors = {d: session_detector(d, name) for d in datasets}
        named = {d: det for d, det in detectors.items() if det}
        if len(set(named.values())) > 1:
            listed = ", ".join(f"'{det}' in {d}" for d, det in named.items())
            raise InputError(f"session {name} is labelled from different detectors ({listed}): the realisations "
                             "must differ only in their noise seed")


Key = Tuple[str, Tuple[int, int]]  # (session, (utime, cell))


def common_cells(realisations: List[Dict[str, Dict[Tuple[int, int], int]]]) -> Tuple[List[Key], int, List[str]]:
    """The (session, (utime, cell)) keys every realisation labelled, in a fixed
    order, plus how many cells some but not all of them labelled, and the
    sessions they have in common."""
    names = sorted(set.intersection(*(set(r) for r in realisations)))
    if not names:
        raise InputError("the datasets have no session in common")
    keys, partial = [], 0
    for name in names:
        cells = [set(r[name]) for r in realisations]
        shared = set.intersection(*cells)
        partial += len(set.union(*cells)) - len(shared)
        keys += [(name, k) for k in sorted(shared)]
    if not keys:
        raise InputError(f"no cell is labelled in every dataset (sessions in common: {', '.join(names)})")
    return keys, partial, names


def label_matrix(realisations, keys: List[Key]) -> np.ndarray:
    """(cells x K) labels of the keys in each realisation."""
    rows = [[r[name][k] for r in realisations] for name, k in keys]
    return np.array(rows, dtype=np.int64).reshape(-1, len(realisations))


def per_class(truth: np.ndarray, predicted: np.ndarray) -> List[float]:
    return [float(np.mean(predicted[truth == c] == c)) if np.any(truth == c) else float("nan") for c in range(4)]


def pairwise_agreement(labels: np.ndarray) -> np.ndarray:
    """Row-normalised 4x4: P(another realisation's label | this one's), over
    all ordered pairs; a class no realisation gave is a row of NaN (no
    support), which the means leave out, as per_class does."""
    counts = np.zeros((4, 4))
    k = labels.shape[1]
    for i in range(k):
        for j in range(k):
            if i != j:
                np.add.at(counts, (labels[:, i], labels[:, j]), 1)
    totals = counts.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(totals > 0, counts / totals, np.nan)


def leave_one_out_majority(labels: np.ndarray) -> List[float]:
    """Per-class accuracy of predicting each realisation by the majority of
    the others (ties go to the label realisation 0 of the others gave)."""
    k = labels.shape[1]
    truth, predicted = [], []
    for i in range(k):
        others = np.delete(labels, i, axis=1)
        votes = np.stack([(others == c).sum(axis=1) for c in range(4)], axis=1)
        best = votes.max(axis=1, keepdims=True)
        tied = (votes == best).sum(axis=1) > 1
        vote = votes.argmax(axis=1)
        vote[tied] = others[tied, 0]
        truth.append(labels[:, i])
        predicted.append(vote)
    return per_class(np.concatenate(truth), np.concatenate(predicted))


def worst_cost_matrix(datasets: List[str], keys: List[Key]) -> Optional[np.ndarray]:
    """(cells x K) worst evidence value of each key in each realisation, or
    None when a session of a realisation keeps no evidence."""
    columns = []
    for d in datasets:
        per_session = {}
        for name in sorted({name for name, _ in keys}):
            worst = read_worst_costs(d, name)
            if worst is None:
                return None
            per_session[name] = worst
        columns.append([per_session[name][k] for name, k in keys])
    return np.array(columns, dtype=np.float64).T.reshape(len(keys), len(datasets))


def evidence_repeatability(worst: np.ndarray, labels: np.ndarray, threshold: float) -> dict:
    """How far another noise draw moves a cell's worst evidence value, and,
    per band of one draw's margin (margin_bands.MARGIN_EDGES), how often
    another draw gives the same verdict (obstacle iff worst >= threshold):
    the verdict accuracy a predictor that knew the scene but not the noise
    would have, band by band. Cells some draw observed no evidence for are
    left out. Raises InputError when the evidence does not give the labels'
    verdicts at this threshold."""
    observed = ~np.isnan(worst).any(axis=1)
    w, said_obstacle = worst[observed], np.isin(labels[observed], (TP, FP))
    k = w.shape[1]
    if not len(w):
        raise InputError("no cell has an observed evidence value in every realisation")
    agreement = float(np.mean((w >= threshold) == said_obstacle))
    if agreement < MARGIN_AGREEMENT_MIN:
        raise InputError(f"the evidence gives the labels' verdict for only {100 * agreement:.1f} % of the cells at "
                         f"threshold {threshold:g} (is --evidence-threshold the detector's?)")
    shifts = np.concatenate([np.abs(w[:, i] - w[:, j]) for i in range(k) for j in range(i + 1, k)])
    pairs = [(i, j) for i in range(k) for j in range(k) if i != j]
    margin = np.concatenate([w[:, i] - threshold for i, _ in pairs])
    same = np.concatenate([(w[:, i] >= threshold) == (w[:, j] >= threshold) for i, j in pairs])
    bands = margin_bands(margin, margin >= 0, {"verdict_agreement": same})
    for b in bands:  # every cell of a realisation counted once per other realisation
        b["n"] //= k - 1
    return {"threshold": threshold, "cells": int(len(w)), "cells_without_evidence": int((~observed).sum()),
            "evidence_agreement": agreement,
            "worst_shift_median": float(np.median(shifts)), "worst_shift_p90": float(np.percentile(shifts, 90)),
            "verdict_agreement": float(np.mean(same)), "bands": bands}


def analyse(datasets: List[str], threshold: float) -> dict:
    realisations = [read_labels(d) for d in datasets]
    check_one_detector(datasets, set.intersection(*(set(r) for r in realisations)))
    keys, partial, names = common_cells(realisations)
    labels = label_matrix(realisations, keys)
    agreement = pairwise_agreement(labels)
    diag = [float(agreement[c, c]) for c in range(4)]
    majority = leave_one_out_majority(labels)
    support = [int(np.sum(labels[:, 0] == c)) for c in range(4)]
    worst = worst_cost_matrix(datasets, keys)
    return {
        "datasets": datasets, "detector": session_detector(datasets[0], names[0]), "sessions": len(names),
        "session_names": names, "cells": int(len(labels)),
        "cells_labelled_in_some_realisations_only": partial, "support_first": support,
        "agreement": agreement.tolist(), "agreement_per_class": diag,
        "agreement_mean_per_class": float(np.nanmean(diag)),
        "majority_per_class": majority, "majority_mean_per_class": float(np.nanmean(majority)),
        "cells_with_one_label_in_all": float(np.mean((labels == labels[:, :1]).all(axis=1))),
        "evidence": evidence_repeatability(worst, labels, threshold) if worst is not None else None,
    }


def print_summary(r: dict) -> None:
    print(f"{len(r['datasets'])} realisations, {r['sessions']} sessions, {r['cells']} cells labelled in all "
          f"({r['cells_labelled_in_some_realisations_only']} in some only); "
          f"{100 * r['cells_with_one_label_in_all']:.1f} % of them get one label in every realisation")
    print("another realisation's label given this one's (rows; support in the first realisation):")
    print("        " + "  ".join(f"{n:>6}" for n in LABEL_NAMES))
    for c in range(4):
        print(f"{LABEL_NAMES[c]:>3} n={r['support_first'][c]:<5}" + "  ".join(f"{v:6.3f}" for v in r["agreement"][c]))
    print("same label, per class: " + ", ".join(f"{n} {v:.3f}" for n, v in zip(LABEL_NAMES, r["agreement_per_class"]))
          + f"; mean per-class {r['agreement_mean_per_class']:.3f}")
    print("majority of the other realisations, per class: "
          + ", ".join(f"{n} {v:.3f}" for n, v in zip(LABEL_NAMES, r["majority_per_class"]))
          + f"; mean per-class {r['majority_mean_per_class']:.3f}")
    e = r["evidence"]
    if e is None:
        print("not every dataset keeps the detector's evidence (the dense detector keeps none): no cost shifts")
        return
    print(f"the detector's worst evidence value moves by {e['worst_shift_median']:.3f} (median) and "
          f"{e['worst_shift_p90']:.3f} (90th percentile) between realisations ({e['cells']} cells)")
    print(f"another realisation gives the same verdict, by band of this one's margin (worst - {e['threshold']:g}; "
          "n: cells x realisations):")
    for b in e["bands"]:
        print(f"  {band_name(b):>14}  n={b['n']:<6} {b['verdict_agreement']:.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("datasets", nargs="+", help="datasets of the same sessions with different noise seeds")
    ap.add_argument("--json", help="also write the numbers here (ivoa_report.py --repeatability reads them)")
    ap.add_argument("--evidence-threshold", type=float, default=0.75, metavar="COST",
                    help="the detector's threshold on its evidence (JPP-C's conf_pos_thresh 0.75)")
    args = ap.parse_args(argv)
    if len(args.datasets) < 2:
        ap.error("give at least two datasets (noise realisations) of the same sessions")
    seen = {}
    for d in args.datasets:  # one folder twice would agree with itself
        if os.path.realpath(d) in seen:
            ap.error(f"{d} is given twice (as {seen[os.path.realpath(d)]} too): give each realisation once")
        seen[os.path.realpath(d)] = d
    if not math.isfinite(args.evidence_threshold):
        ap.error(f"--evidence-threshold must be a finite cost, not {args.evidence_threshold}")
    if args.json and os.path.exists(args.json):
        out = os.path.realpath(args.json)
        for d in args.datasets:  # written over, a dataset's own file (dataset.json) would break it
            if os.path.commonpath([out, os.path.realpath(d)]) == os.path.realpath(d):
                ap.error(f"--json {args.json} is a file of the dataset {d}: it would be written over")
    if args.json and (why := _why_cannot_write(args.json)):  # before the analysis, not after
        print(f"ivoa_label_repeatability: cannot write {args.json}: {why}", file=sys.stderr)
        return EXIT_CANNOT_WRITE
    try:
        result = analyse(args.datasets, args.evidence_threshold)
    except InputError as e:
        print(f"ivoa_label_repeatability: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print_summary(result)
    if args.json:
        try:
            with open(args.json, "w") as f:
                json.dump(result, f, indent=1)
        except OSError as e:
            print(f"ivoa_label_repeatability: cannot write {args.json}: {e.strerror}", file=sys.stderr)
            return EXIT_CANNOT_WRITE
    return 0


if __name__ == "__main__":
    sys.exit(main())
