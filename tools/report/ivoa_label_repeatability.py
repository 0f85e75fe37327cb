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
  for a model that cannot see which way the noise will tip a verdict.

Usage: ivoa_label_repeatability.py DATASET DATASET [DATASET ...] [--json FILE]
(tools/main_job/ivoa-label-repeatability.sh records and labels them).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from typing import Dict, List, Tuple

import numpy as np

LABEL_NAMES = ("TP", "TN", "FP", "FN")
EXIT_BAD_INPUT = 3


class InputError(Exception):
    pass


def read_labels(dataset: str) -> Dict[str, Dict[Tuple[int, int], int]]:
    """session -> {(utime, cell): label} for every session folder of a dataset."""
    if not os.path.isdir(dataset):
        raise InputError(f"{dataset}: dataset folder not found")
    sessions = {}
    for name in sorted(os.listdir(dataset)):
        path = os.path.join(dataset, name, "samples.csv")
        if not os.path.isfile(path):
            continue
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = {"utime", "cell", "label"} - set(reader.fieldnames or [])
            if missing:
                raise InputError(f"{path}: missing column(s) {', '.join(sorted(missing))}")
            labels = {}
            for row_number, row in enumerate(reader, start=2):
                try:
                    labels[(int(row["utime"]), int(row["cell"]))] = int(row["label"])
                except ValueError:
                    raise InputError(f"{path}: line {row_number}: utime, cell and label must be integers") from None
        sessions[name] = labels
    if not sessions:
        raise InputError(f"{dataset}: no session folders with a samples.csv")
    return sessions


def session_detector(dataset: str, session: str) -> str:
    """The detector a session's labels are about (session.json), or "" if it does not say."""
    path = os.path.join(dataset, session, "session.json")
    try:
        with open(path) as f:
            return str(json.load(f).get("detector", ""))
    except FileNotFoundError:
        return ""
    except (OSError, ValueError, AttributeError) as e:
        raise InputError(f"{path}: cannot read session metadata: {e}") from None


def check_one_detector(datasets: List[str], sessions) -> None:
    """Realisations labelled from different detectors differ by more than the noise."""
    for name in sorted(sessions):
        detectors = {d: session_detector(d, name) for d in datasets}
        named = {d: det for d, det in detectors.items() if det}
        if len(set(named.values())) > 1:
            listed = ", ".join(f"'{det}' in {d}" for d, det in named.items())
            raise InputError(f"session {name} is labelled from different detectors ({listed}): the realisations "
                             "must differ only in their noise seed")


def common_cells(realisations: List[Dict[str, Dict[Tuple[int, int], int]]]) -> Tuple[np.ndarray, int, int]:
    """(cells x K) label matrix over the sessions and cells all realisations
    labelled, plus how many cells some but not all of them labelled, and
    the number of sessions used."""
    names = set.intersection(*(set(r) for r in realisations))
    if not names:
        raise InputError("the datasets have no session in common")
    rows, partial = [], 0
    for name in sorted(names):
        keys = [set(r[name]) for r in realisations]
        shared = set.intersection(*keys)
        partial += len(set.union(*keys)) - len(shared)
        rows += [[r[name][k] for r in realisations] for k in sorted(shared)]
    return np.array(rows, dtype=np.int64).reshape(-1, len(realisations)), partial, len(names)


def per_class(truth: np.ndarray, predicted: np.ndarray) -> List[float]:
    return [float(np.mean(predicted[truth == c] == c)) if np.any(truth == c) else float("nan") for c in range(4)]


def pairwise_agreement(labels: np.ndarray) -> np.ndarray:
    """Row-normalised 4x4: P(another realisation's label | this one's), over all ordered pairs."""
    counts = np.zeros((4, 4))
    k = labels.shape[1]
    for i in range(k):
        for j in range(k):
            if i != j:
                np.add.at(counts, (labels[:, i], labels[:, j]), 1)
    return counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)


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


def analyse(datasets: List[str]) -> dict:
    realisations = [read_labels(d) for d in datasets]
    check_one_detector(datasets, set.intersection(*(set(r) for r in realisations)))
    labels, partial, n_sessions = common_cells(realisations)
    agreement = pairwise_agreement(labels)
    diag = [float(agreement[c, c]) for c in range(4)]
    majority = leave_one_out_majority(labels)
    support = [int(np.sum(labels[:, 0] == c)) for c in range(4)]
    return {
        "datasets": datasets, "sessions": n_sessions, "cells": int(len(labels)),
        "cells_labelled_in_some_realisations_only": partial, "support_first": support,
        "agreement": agreement.tolist(), "agreement_per_class": diag,
        "agreement_mean_per_class": float(np.nanmean(diag)),
        "majority_per_class": majority, "majority_mean_per_class": float(np.nanmean(majority)),
        "cells_with_one_label_in_all": float(np.mean((labels == labels[:, :1]).all(axis=1))),
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("datasets", nargs="+", help="datasets of the same sessions with different noise seeds")
    ap.add_argument("--json", help="also write the numbers here")
    args = ap.parse_args(argv)
    if len(args.datasets) < 2:
        ap.error("give at least two datasets (noise realisations) of the same sessions")
    seen = {}
    for d in args.datasets:  # one folder twice would agree with itself
        if os.path.realpath(d) in seen:
            ap.error(f"{d} is given twice (as {seen[os.path.realpath(d)]} too): give each realisation once")
        seen[os.path.realpath(d)] = d
    try:
        result = analyse(args.datasets)
    except InputError as e:
        print(f"ivoa_label_repeatability: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print_summary(result)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
