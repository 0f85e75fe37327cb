"""Reading and validating the report's inputs.

Two kinds of input feed the report:

* an **eval folder** written by the C++ tool ``ivoa-eval`` (``predictions.csv``,
  ``embeddings.f32``, ``eval.json``, ``overlays/*.png``; see tools/eval/README.md);
* the **dataset** the eval ran on (libs/dataset/README.md), needed only for the
  image patches shown in the cluster mosaics.

Everything is checked up front, so that a wrong path or a truncated file stops
the tool with one message naming the file and the problem (``InputError``, exit
code 3) instead of a traceback half-way through the figures.
"""

from __future__ import annotations

import csv
import json
import os
import re
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

LABEL_NAMES = ("TP", "TN", "FP", "FN")
TP, TN, FP, FN = 0, 1, 2, 3
EMBEDDING_DIM = 256

# predictions.csv columns the report uses (ivoa-eval writes more, in this order).
REQUIRED_COLUMNS = (
    "session", "environment", "split", "sample", "utime", "cell", "x", "y", "u", "v",
    "label", "predicted", "p_tp", "p_tn", "p_fp", "p_fn", "var_predicted",
    "uncertainty", "phenomena", "phenomenon", "surface",
)
# Written by ivoa-eval since the predictions given the detector's verdict
# (introspection::given_verdict); older eval folders lack them.
VERDICT_COLUMNS = ("stereo_state", "verdict_predicted", "p_wrong", "var_wrong")
STATE_FREE, STATE_OBSTACLE = 0, 1   # obstacle_grid_t.STATE_*

# Fallback names when lcmtypes/sim_ground_truth_t.lcm cannot be found next to the
# tool (e.g. the tool was copied elsewhere). The .lcm file is the source of truth.
_FALLBACK_PHENOMENA = {
    0: "none", 1: "reflection", 2: "textureless", 4: "glare", 8: "dark stripe",
    16: "repetitive", 32: "low light", 64: "saturated",
}
_FALLBACK_SURFACES = {
    0: "sky", 1: "floor", 2: "wall", 3: "baseboard", 4: "door", 5: "box",
    6: "cylinder", 7: "chair", 8: "curb", 9: "pit", 10: "ceiling", 255: "unknown",
}


class InputError(Exception):
    """Bad input (missing or malformed file, inconsistent sizes).

    The message always names the offending file and says what is wrong; the
    command line turns it into exit code 3 so that scripts can tell bad input
    from a bug (exit code 1).
    """


def _lcm_constants(prefix: str) -> Dict[int, str]:
    """Reads ``const int8_t <prefix>_<NAME> = <value>;`` from the simulator's
    ground-truth message so that phenomenon/surface names never drift from the
    codes the simulator writes. Returns {} when the file is not found."""
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.join(here, "..", "..", "lcmtypes", "sim_ground_truth_t.lcm")
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return {}
    out = {}
    for name, value in re.findall(r"const\s+int\d+_t\s+" + prefix + r"_(\w+)\s*=\s*(-?\d+)\s*;", text):
        out[int(value)] = name.lower().replace("_", " ")
    return out


def phenomenon_names() -> Dict[int, str]:
    """Code -> readable name for the single-bit ``phenomenon`` column (0 = none)."""
    names = _lcm_constants("PHENOMENON") or dict(_FALLBACK_PHENOMENA)
    names[0] = "none"
    return names


def surface_names() -> Dict[int, str]:
    """Code -> readable name for the ``surface`` column (255 = unknown)."""
    names = _lcm_constants("SURFACE") or dict(_FALLBACK_SURFACES)
    names[255] = "unknown"
    return names


def phenomenon_name(code: int, names: Optional[Dict[int, str]] = None) -> str:
    """Readable name of one phenomenon code; unknown codes keep their number."""
    names = names if names is not None else phenomenon_names()
    return names.get(int(code), f"code {int(code)}")


def cause_name(bits: int, names: Optional[Dict[int, str]] = None) -> str:
    """'reflection+glare' for a set of PHENOMENON_* bits found to cause a
    failure (ivoa-sim-causes); 'none found' for 0, 'only together' for ONLY_TOGETHER."""
    names = names if names is not None else phenomenon_names()
    if bits == 0:
        return "none found"
    if bits == ONLY_TOGETHER:
        return "only together"
    return "+".join(phenomenon_name(1 << b, names) for b in range(8) if bits & (1 << b))


def surface_name(code: int, names: Optional[Dict[int, str]] = None) -> str:
    """Readable name of one surface code; unknown codes keep their number."""
    names = names if names is not None else surface_names()
    return names.get(int(code), f"code {int(code)}")


# --------------------------------------------------------------------------- dataset


@dataclass
class DatasetSession:
    """One session folder of a dataset: its samples.csv key columns and a lazily
    memory-mapped patches.bin (patches are read only for the few tiles shown)."""

    name: str
    path: str
    patch_size: int
    info: dict
    utime: np.ndarray
    cell: np.ndarray
    label: np.ndarray
    patch_side: Optional[np.ndarray] = None  # square cut around each cell, px (datasets that record it)
    _patches: Optional[np.memmap] = None
    _evidence: Optional[np.ndarray] = None

    @property
    def size(self) -> int:
        return len(self.utime)

    @property
    def views(self) -> int:
        """Squares per patch: 1, or 2 with the warped right view (1 in datasets older than views)."""
        return int(self.info.get("views", 1))

    @property
    def patch_scale(self) -> float:
        """The footprint patch scale the session was cut at (0: fixed squares, and datasets older than it)."""
        return float(self.info.get("patch_scale", 0) or 0)

    def patches(self) -> np.ndarray:
        """(N, P, P, 3) uint8 BGR view of the left-image squares in patches.bin
        (a two-view dataset stores the warped right square below each), size-checked
        on first use."""
        if self._patches is None:
            p = os.path.join(self.path, "patches.bin")
            if not os.path.isfile(p):
                raise InputError(f"{p}: missing (the patches of session {self.name})")
            views = self.views
            per = self.patch_size * self.patch_size * 3 * views
            got = os.path.getsize(p)
            if got != per * self.size:
                raise InputError(
                    f"{p}: {got} bytes, expected {self.size} patches x {per} bytes = {self.size * per} "
                    f"(samples.csv has {self.size} rows, patch size {self.patch_size})")
            if self.size == 0:
                self._patches = np.zeros((0, self.patch_size, self.patch_size, 3), np.uint8)
            else:
                stacked = np.memmap(p, dtype=np.uint8, mode="r",
                                    shape=(self.size, views * self.patch_size, self.patch_size, 3))
                self._patches = stacked[:, :self.patch_size]
        return self._patches

    def evidence(self) -> Optional[np.ndarray]:
        """(N, evidence_size) float32 from evidence.f32: the labels' detector's
        evidence per sample (JPP-C: the window cost of each ground sample, NaN
        where not observed), size-checked; None where the session has none."""
        size = int(self.info.get("evidence_size", 0) or 0)
        if size <= 0:
            return None
        if self._evidence is not None:
            return self._evidence
        p = os.path.join(self.path, "evidence.f32")
        if not os.path.isfile(p):
            raise InputError(f"{p}: missing (session.json of {self.name} says evidence_size {size})")
        got, want = os.path.getsize(p), self.size * size * 4
        if got != want:
            raise InputError(f"{p}: {got} bytes, expected {self.size} samples x {size} float32 = {want}")
        evidence = np.fromfile(p, dtype="<f4").reshape(self.size, size)
        bad = np.flatnonzero(np.isinf(evidence).any(axis=1))  # NaN is "not observed"; an infinity is damage
        if len(bad):
            raise InputError(f"{p}: sample {bad[0]} holds an infinite value ({len(bad)} such samples)")
        self._evidence = evidence
        return self._evidence


DATASET_INDEX_VERSION = 1  # dataset.json's "version", as ivoa-dataset writes it


def _check_dataset_version(path: str, meta: dict) -> None:
    """A later layout read as this one would give wrong patches, not an error."""
    if "format" in meta and meta["format"] != "ivoa-dataset":
        raise InputError(f"{path}: format {json.dumps(meta['format'])}, not \"ivoa-dataset\": not this project's "
                         "dataset index")
    version = meta.get("version", 1)
    if not _is_integer(version) or version < 1:
        raise InputError(f"{path}: version {json.dumps(version)} is not a version number (1, 2, ...)")
    if version > DATASET_INDEX_VERSION:
        raise InputError(f"{path}: dataset version {version}; this report reads 1 to {DATASET_INDEX_VERSION} "
                         "(written by a newer ivoa-dataset?)")


def read_dataset_index(dataset: str) -> dict:
    """A dataset folder's dataset.json, its format and version checked; {}
    where there is none (the earliest datasets wrote none)."""
    meta_path = os.path.join(dataset, "dataset.json")
    meta = _read_json(meta_path) if os.path.isfile(meta_path) else {}
    _check_dataset_version(meta_path, meta)
    return meta


class Dataset:
    """An IVOA dataset folder; sessions are loaded on demand and cached."""

    def __init__(self, path: str):
        self.path = path
        if not os.path.isdir(path):
            raise InputError(f"{path}: dataset folder not found")
        self.meta = read_dataset_index(path)
        self.patch_size = _checked_field(os.path.join(path, "dataset.json"), self.meta, "patch_size", 100, 1)
        self._sessions: Dict[str, DatasetSession] = {}

    def session(self, name: str) -> DatasetSession:
        """The named session, read and checked once."""
        if name not in self._sessions:
            self._sessions[name] = self._load_session(name)
        return self._sessions[name]

    def _load_session(self, name: str) -> DatasetSession:
        d = os.path.join(self.path, name)
        if not os.path.isdir(d):
            raise InputError(f"{d}: session folder not found in dataset {self.path}")
        info_path = os.path.join(d, "session.json")
        info = _read_session_info(info_path)
        patch_size = _checked_field(info_path, info, "patch_size", self.patch_size, 1)
        samples_path = os.path.join(d, "samples.csv")
        cols = _read_csv_columns(samples_path, ("sample", "utime", "cell", "label"))
        sample, utime, cell, label = (_numeric(samples_path, cols, c, int) for c in ("sample", "utime", "cell", "label"))
        side = _numeric(samples_path, cols, "patch_side", int) if "patch_side" in cols else None
        if len(sample) and not np.array_equal(sample, np.arange(len(sample))):
            raise InputError(f"{samples_path}: column 'sample' must equal the row number (0, 1, 2, ...)")
        return DatasetSession(name, d, patch_size, info, utime, cell, label, side)


def _read_session_info(path: str) -> dict:
    """session.json, required: without it views and patch scale are unknown and
    the patches.bin size check would blame the wrong file."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (every session folder of a dataset has one)")
    info = _read_json(path)
    views, scale = info.get("views", 1), info.get("patch_scale", 0)
    if not _is_integer(views) or views < 1:
        raise InputError(f"{path}: field 'views' = {views!r}, expected an integer >= 1")
    if not _is_number(scale) or not scale >= 0:
        raise InputError(f"{path}: field 'patch_scale' = {scale!r}, expected a number >= 0")
    _checked_field(path, info, "evidence_size", 0, 0)
    return info


def _checked_field(path: str, info: dict, key: str, default: int, least: int) -> int:
    """An integer field of a dataset's JSON, at least `least`, or `default` where it is missing."""
    value = info.get(key, default)
    if not _is_integer(value) or not least <= value < 2**31:
        raise InputError(f"{path}: field '{key}' = {value!r}, expected an integer >= {least}")
    return value


def _is_number(x) -> bool:
    """A finite JSON number (bool is not one, although Python says it is an int)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and bool(np.isfinite(x))


def _is_integer(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


# --------------------------------------------------------------------------- eval runs


@dataclass
class VerdictColumns:
    """Predictions given the detector's verdict: TP/FP where it said obstacle,
    TN/FN where it said free (ivoa-eval's last four columns)."""
    stereo_state: np.ndarray        # the detector's verdict, obstacle_grid_t.STATE_*
    predicted: np.ndarray           # class index
    p_wrong: np.ndarray             # P(FP | obstacle) or P(FN | free)
    var_wrong: np.ndarray           # its variance over the MC passes (the gate)


@dataclass
class EvalRun:
    """One ivoa-eval output folder: per-sample predictions, embeddings, metadata.

    Arrays all have one entry per row of predictions.csv, in file order, which is
    also the order of embeddings.f32.
    """

    path: str
    name: str                       # display name, unique among the report's models
    slug: str                       # file-system-safe unique name for its figure folder
    meta: dict                      # eval.json as read
    detector: str
    session: np.ndarray
    environment: np.ndarray
    split: np.ndarray
    sample: np.ndarray
    utime: np.ndarray
    cell: np.ndarray
    x: np.ndarray                   # the query point ahead of the robot, m
    y: np.ndarray                   # ... and to its left, m
    u: np.ndarray
    v: np.ndarray
    label: np.ndarray
    predicted: np.ndarray
    probs: np.ndarray               # (N, 4) mean softmax over the MC passes
    var_predicted: np.ndarray       # variance of the predicted class's probability (the gate)
    uncertainty: np.ndarray         # mean per-class variance (the heatmap's)
    phenomena: np.ndarray
    phenomenon: np.ndarray
    surface: np.ndarray
    embeddings: np.ndarray          # (N, 256) float32, memory-mapped
    # Given the verdict the detector recorded (None for older eval folders):
    verdict: Optional["VerdictColumns"] = None
    overlays: List[str] = field(default_factory=list)
    dataset: Optional[Dataset] = None
    label_detector: str = ""        # the detector the dataset's labels are about (session.json), if one
    # What ivoa-sim-causes found causes each true FP/FN row (PHENOMENON_* bits,
    # 0 = none of the removable phenomena); NO_CAUSE where not known. None: no --causes.
    cause: Optional[np.ndarray] = None

    @property
    def size(self) -> int:
        return len(self.label)

    def _meta_number(self, key: str) -> Optional[float]:
        """A number from eval.json, or None where it is missing or not a number."""
        t = self.meta.get(key)
        try:
            return float(t) if t is not None else None
        except (TypeError, ValueError):
            return None

    @property
    def model_threshold(self) -> Optional[float]:
        """The model's own run-time uncertainty gate from eval.json, if any."""
        return self._meta_number("uncertainty_threshold")

    @property
    def verdict_threshold(self) -> Optional[float]:
        """The gate of the predictions given the verdict from eval.json, if any."""
        return self._meta_number("verdict_uncertainty_threshold")

    @property
    def has_ground_truth_phenomena(self) -> bool:
        """True for simulated sessions, where phenomenon/surface come from the
        simulator's per-pixel truth (a real robot's rows have surface 255)."""
        return bool(np.any(self.surface != 255) or np.any(self.phenomenon != 0))


class _RepeatedKey(ValueError):
    pass


def _refuse_repeated_keys(pairs: list) -> dict:
    """json's object_pairs_hook: a key given twice (json keeps the last, the
    C++ tools' yaml-cpp the first) is an error, not a silent choice."""
    seen = set()
    for key, _ in pairs:
        if key in seen:
            raise _RepeatedKey(key)
        seen.add(key)
    return dict(pairs)


def _read_json(path: str) -> dict:
    """json.load with an InputError naming the file on failure."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f, object_pairs_hook=_refuse_repeated_keys)
    except _RepeatedKey as e:
        raise InputError(f"{path}: key {json.dumps(e.args[0])} is given twice") from None
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not UTF-8 text, so not the JSON file expected here") from None
    except json.JSONDecodeError as e:
        raise InputError(f"{path}: not valid JSON ({e})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object")
    return data


def _read_csv_columns(path: str, required) -> Dict[str, List[str]]:
    """Reads a CSV with a header into {column: [strings]}, checking that the
    required columns exist and every row has as many fields as the header."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing")
    reader = None
    try:
        with open(path, newline="", encoding="utf-8") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise InputError(f"{path}: empty file (no header)")
            header = [h.strip() for h in header]
            missing = [c for c in required if c not in header]
            if missing:
                raise InputError(f"{path}: missing column(s) {', '.join(missing)}")
            cols: Dict[str, List[str]] = {h: [] for h in header}
            for lineno, row in enumerate(reader, start=2):
                if not row:
                    continue
                if len(row) != len(header):
                    raise InputError(f"{path}: line {lineno} has {len(row)} fields, the header has {len(header)}")
                for h, value in zip(header, row):
                    cols[h].append(value)
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not UTF-8 text, so not the CSV file expected here") from None
    except csv.Error as e:  # a field over the csv module's limit (128 kB), a NUL byte, ...
        raise InputError(f"{path}: line {reader.line_num if reader else 1}: {e}") from None
    return cols


def _numeric(path: str, cols: Dict[str, List[str]], name: str, dtype):
    """One column as a numpy array; a bad value is an InputError naming the row."""
    values = cols[name]
    try:
        return np.array([dtype(x) for x in values], dtype=np.int64 if dtype is int else np.float64)
    except (ValueError, OverflowError):  # OverflowError: an integer numpy's int64 cannot hold
        for i, x in enumerate(values):
            where = f"{path}: line {_line(i)}, column '{name}': '{x}'"
            try:
                value = dtype(x)
            except ValueError:
                raise InputError(f"{where} is not {'an integer' if dtype is int else 'a number'}") from None
            if dtype is int and not -2**63 <= value < 2**63:
                raise InputError(f"{where} does not fit a 64-bit integer") from None
        raise


def load_eval(path: str) -> EvalRun:
    """Reads and checks one ivoa-eval output folder (no dataset yet)."""
    if not os.path.isdir(path):
        raise InputError(f"{path}: eval folder not found")
    meta_path = os.path.join(path, "eval.json")
    meta = _read_json(meta_path)
    pred_path = os.path.join(path, "predictions.csv")
    cols = _read_csv_columns(pred_path, REQUIRED_COLUMNS)
    has_verdict = _has_verdict_columns(pred_path, cols)
    _check_eval_meta(meta_path, meta, has_verdict)
    n = len(cols["label"])
    if n == 0:
        raise InputError(f"{pred_path}: no predictions (header only); nothing to report")
    label = _numeric(pred_path, cols, "label", int)
    predicted = _numeric(pred_path, cols, "predicted", int)
    for name, arr in (("label", label), ("predicted", predicted)):
        bad = np.flatnonzero((arr < 0) | (arr > 3))
        if len(bad):
            raise InputError(f"{pred_path}: line {_line(bad[0])}, column '{name}' = {arr[bad[0]]}, "
                             f"expected 0..3 (TP, TN, FP, FN)")
    max_var = max_variance(meta["mc_passes"])
    probs = np.stack([_checked(pred_path, cols, c, 0, 1) for c in PROBABILITY_COLUMNS], axis=1)
    _check_probabilities_sum(pred_path, probs)
    _check_predicted_is_most_probable(pred_path, predicted, probs)
    coords = {c: _checked(pred_path, cols, c, -np.inf, np.inf) for c in ("x", "y", "u", "v")}
    session, sample = np.array(cols["session"]), _numeric(pred_path, cols, "sample", int)
    _check_unique_samples(pred_path, session, sample)
    if _is_integer(meta.get("samples")) and meta["samples"] != n:
        raise InputError(f"{meta_path}: says {meta['samples']} samples, {pred_path} has {n} rows "
                         "(a file cut short, or the two from different runs?)")
    embeddings = _load_embeddings(os.path.join(path, "embeddings.f32"), n)

    overlay_dir = os.path.join(path, "overlays")
    overlays = []
    if os.path.isdir(overlay_dir):
        overlays = sorted(os.path.join(overlay_dir, f) for f in os.listdir(overlay_dir) if f.lower().endswith(".png"))

    verdict = _verdict_columns(pred_path, cols, label, max_var) if has_verdict else None
    md = meta.get("metadata") if isinstance(meta.get("metadata"), dict) else {}
    detector = str(md.get("detector") or "unknown")
    return EvalRun(
        path=path, name="", slug="", meta=meta, detector=detector,
        session=session, environment=np.array(cols["environment"]), split=np.array(cols["split"]),
        sample=sample, utime=_numeric(pred_path, cols, "utime", int),
        cell=_numeric(pred_path, cols, "cell", int), **coords,
        label=label, predicted=predicted, probs=probs,
        var_predicted=_checked(pred_path, cols, "var_predicted", 0, max_var, VARIANCE_BOUND_NOTE),
        uncertainty=_checked(pred_path, cols, "uncertainty", 0, max_var, VARIANCE_BOUND_NOTE),
        phenomena=_numeric(pred_path, cols, "phenomena", int),
        phenomenon=_numeric(pred_path, cols, "phenomenon", int),
        surface=_numeric(pred_path, cols, "surface", int),
        embeddings=embeddings, verdict=verdict, overlays=overlays,
    )


PROBABILITY_COLUMNS = ("p_tp", "p_tn", "p_fp", "p_fn")
# ivoa-eval writes 5 decimals, so the four sum to 1 within 2e-5; a wider miss
# means swapped columns or values that are no probabilities.
PROBABILITY_SUM_TOLERANCE = 1e-3
VARIANCE_BOUND_NOTE = "a probability's variance over the MC passes cannot exceed it"


def max_variance(mc_passes: int) -> float:
    """The largest variance over T MC passes a probability can have: ivoa-eval's
    is the unbiased one (libs/introspection mc_dropout.cpp), at most
    0.25 T / (T - 1), for values half at 0 and half at 1. Plus float slack."""
    return 0.25 * mc_passes / max(mc_passes - 1, 1) + 1e-6


def _line(row: int) -> int:
    """The line of a CSV file holding data row `row` (0-based): the header is line 1."""
    return row + 2


def _checked(path: str, cols: Dict[str, List[str]], name: str, low: float, high: float, note: str = ""):
    """A float column whose values must be finite and within [low, high]:
    InputError naming the first line and the column otherwise."""
    values = _numeric(path, cols, name, float)
    bad = np.flatnonzero(~(np.isfinite(values) & (values >= low) & (values <= high)))
    if len(bad):
        v = values[bad[0]]
        why = "is not finite" if not np.isfinite(v) else f"is outside {low:g} .. {high:.4g}"
        raise InputError(f"{path}: line {_line(bad[0])}, column '{name}': {v:g} {why}"
                         + (f" ({note})" if note else ""))
    return values


def _check_probabilities_sum(path: str, probs: np.ndarray) -> None:
    """Each row's four class probabilities are a softmax mean: they sum to 1."""
    total = probs.sum(axis=1)
    bad = np.flatnonzero(np.abs(total - 1) > PROBABILITY_SUM_TOLERANCE)
    if len(bad):
        raise InputError(f"{path}: line {_line(bad[0])}: {' + '.join(PROBABILITY_COLUMNS)} = {total[bad[0]]:.6g}, "
                         f"expected 1 (columns swapped, or not probabilities?)")


def _check_predicted_is_most_probable(path: str, predicted: np.ndarray, probs: np.ndarray) -> None:
    """ivoa-eval predicts the class of the largest mean probability (written to
    5 decimals, hence the slack): another one means shifted or edited columns."""
    chosen = probs[np.arange(len(predicted)), predicted]
    bad = np.flatnonzero(chosen < probs.max(axis=1) - 1e-4)
    if len(bad):
        r = bad[0]
        top = int(np.argmax(probs[r]))
        raise InputError(f"{path}: line {_line(r)}: predicted {predicted[r]} ({LABEL_NAMES[predicted[r]]}, "
                         f"p {chosen[r]:.5f}) is not the most probable class ({LABEL_NAMES[top]}, p {probs[r, top]:.5f})")


def _check_unique_samples(path: str, session: np.ndarray, sample: np.ndarray) -> None:
    """Each (session, sample) once: a repeated row would be counted twice in every metric."""
    first_row = {}
    for row, key in enumerate(zip(session.tolist(), sample.tolist())):
        if key in first_row:
            raise InputError(f"{path}: session {key[0]}, sample {key[1]} is on line {_line(first_row[key])} "
                             f"and again on line {_line(row)}")
        first_row[key] = row


def _load_embeddings(path: str, n: int) -> np.ndarray:
    """embeddings.f32 memory-mapped as (n, 256), size- and finiteness-checked (PCA and
    k-means stop with a traceback at the first NaN)."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (one float32 x {EMBEDDING_DIM} FC2 embedding per prediction)")
    size = os.path.getsize(path)
    expected = n * EMBEDDING_DIM * 4
    if size != expected:
        raise InputError(
            f"{path}: {size} bytes, expected {n} rows x {EMBEDDING_DIM} float32 = {expected} bytes "
            f"(predictions.csv has {n} rows)")
    embeddings = np.memmap(path, dtype=np.float32, mode="r", shape=(n, EMBEDDING_DIM))
    bad = np.flatnonzero(~np.all(np.isfinite(embeddings), axis=1))
    if len(bad):
        raise InputError(f"{path}: row {bad[0]} (0-based; the prediction on line {_line(bad[0])} of "
                         f"predictions.csv) is not finite ({len(bad)} such rows)")
    return embeddings


def _has_verdict_columns(pred_path: str, cols: Dict[str, List[str]]) -> bool:
    """True with all four verdict columns, False with none (an older ivoa-eval);
    some of them is a damaged file, not an older one."""
    present = [c for c in VERDICT_COLUMNS if c in cols]
    if present and len(present) < len(VERDICT_COLUMNS):
        missing = [c for c in VERDICT_COLUMNS if c not in cols]
        raise InputError(f"{pred_path}: missing column(s) {', '.join(missing)} (the other verdict columns "
                         f"{', '.join(present)} are there; ivoa-eval writes all four or none)")
    return bool(present)


def _check_eval_meta(path: str, meta: dict, has_verdict: bool) -> None:
    """The eval.json fields the report quotes or uses, type-checked: a missing one
    would print as 'None' or drop the run-time gate's row without a word."""
    _check_field(path, meta, "model", lambda v: isinstance(v, str) and v != "", "the model's name")
    _check_field(path, meta, "mc_passes", lambda v: _is_integer(v) and v >= 1, "an integer >= 1")
    _check_field(path, meta, "uncertainty_threshold", lambda v: _is_number(v) and v >= 0, "a number >= 0")
    if has_verdict or "verdict_uncertainty_threshold" in meta:
        _check_field(path, meta, "verdict_uncertainty_threshold", lambda v: _is_number(v) and v >= 0,
                     "a number >= 0")
    # Per session, the dataset's views and patch scale (newer ivoa-eval; checked against --dataset).
    _check_field(path, meta, "sessions", lambda v: isinstance(v, list), "a list", required=False)
    for i, entry in enumerate(meta.get("sessions", [])):
        where = f"sessions[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("session"), str):
            raise InputError(f"{path}: field '{where}' = {entry!r}, expected an object with a 'session' name")
        _check_field(path, entry, "views", lambda v: _is_integer(v) and v >= 1, "an integer >= 1",
                     required=False, where=where)
        _check_field(path, entry, "patch_scale", lambda v: _is_number(v) and v >= 0, "a number >= 0",
                     required=False, where=where)


def _check_field(path: str, obj: dict, key: str, ok, expected: str, required: bool = True, where: str = "") -> None:
    """InputError naming the file and the field when obj[key] is missing (if required) or not ok()."""
    name = f"{where}.{key}" if where else key
    if key not in obj:
        if required:
            raise InputError(f"{path}: missing field '{name}' ({expected})")
        return
    if not ok(obj[key]):
        raise InputError(f"{path}: field '{name}' = {obj[key]!r}, expected {expected}")


def _verdict_columns(pred_path: str, cols: Dict[str, List[str]], label: np.ndarray,
                     max_var: float) -> VerdictColumns:
    """The verdict columns, checked against the labels: a TP or FP label means
    the detector said obstacle, a TN or FN label that it said free."""
    v = VerdictColumns(
        stereo_state=_numeric(pred_path, cols, "stereo_state", int),
        predicted=_numeric(pred_path, cols, "verdict_predicted", int),
        p_wrong=_checked(pred_path, cols, "p_wrong", 0, 1),
        var_wrong=_checked(pred_path, cols, "var_wrong", 0, max_var, VARIANCE_BOUND_NOTE))
    said_obstacle = (label == TP) | (label == FP)
    expected = np.where(said_obstacle, STATE_OBSTACLE, STATE_FREE)
    bad = np.flatnonzero(v.stereo_state != expected)
    if len(bad):
        r = bad[0]
        raise InputError(f"{pred_path}: line {_line(r)}: stereo_state {v.stereo_state[r]} contradicts label "
                         f"{LABEL_NAMES[label[r]]} (TP/FP need {STATE_OBSTACLE} = obstacle, TN/FN {STATE_FREE} = free)")
    possible = np.where(said_obstacle[:, None], [TP, FP], [TN, FN])
    bad = np.flatnonzero((v.predicted != possible[:, 0]) & (v.predicted != possible[:, 1]))
    if len(bad):
        r = bad[0]
        raise InputError(f"{pred_path}: line {_line(r)}: verdict_predicted {v.predicted[r]} is impossible for "
                         f"stereo_state {v.stereo_state[r]}")
    return v


def patch_size(run: EvalRun) -> Optional[int]:
    """Side in pixels of the patches the run's model saw (its first session's)."""
    return run.dataset.session(str(run.session[0])).patch_size if run.dataset is not None and run.size else None


def patch_sides(run: EvalRun) -> Optional[np.ndarray]:
    """Per prediction row, the side in pixels of the square its patch was cut
    from (footprint-scaled datasets record it per sample; otherwise every
    patch is patch_size); None without a dataset."""
    if run.dataset is None or not run.size:
        return None
    out = np.zeros(run.size, dtype=np.int64)
    for name in dict.fromkeys(run.session.tolist()):
        s = run.dataset.session(name)
        rows = np.flatnonzero(run.session == name)
        out[rows] = s.patch_side[run.sample[rows]] if s.patch_side is not None else s.patch_size
    return out


def patch_scale(run: EvalRun) -> float:
    """The footprint patch scale of the run's dataset (0: fixed squares)."""
    if run.dataset is None or not run.size:
        return 0.0
    return run.dataset.session(str(run.session[0])).patch_scale


def query_grid(run: EvalRun) -> dict:
    """The query grid of the run's sessions (session.json "grid": spacing,
    safety radius, patch size), from the first session that records one."""
    if run.dataset is None:
        return {}
    for name in dict.fromkeys(run.session.tolist()):
        grid = run.dataset.session(name).info.get("grid")
        if isinstance(grid, dict):
            return grid
    return {}


def seen_in_training(run: EvalRun) -> List[str]:
    """Warnings for evaluated sessions the model was trained or validated on
    (eval.json's metadata.training): their figures are not held out."""
    md = run.meta.get("metadata") if isinstance(run.meta.get("metadata"), dict) else {}
    training = md.get("training") if isinstance(md.get("training"), dict) else {}
    evaluated = set(run.session.tolist())
    warnings = []
    for key, how in (("train_sessions", "trained on"),
                     ("val_sessions", "validated on (they chose its kept step and set its gate)")):
        names = training.get(key)
        seen = sorted(evaluated & {str(n) for n in names}) if isinstance(names, list) else []
        if seen:
            listed = ", ".join(seen[:5]) + (f" and {len(seen) - 5} more" if len(seen) > 5 else "")
            warnings.append(f"{run.name}: its model was {how} {len(seen)} of the {len(evaluated)} sessions "
                            f"evaluated ({listed}): their figures are not held out")
    return warnings


def _sizes(value) -> List[tuple]:
    """[[w, h], ...] as (w, h) tuples; what is not such a pair is left out."""
    pairs = value if isinstance(value, list) else []
    return [tuple(p) for p in pairs
            if isinstance(p, list) and len(p) == 2 and all(_is_number(v) and v > 0 for v in p)]


def other_camera(run: EvalRun) -> List[str]:
    """A warning when sessions were recorded at an image size the model was not
    trained on (eval.json's metadata.image_sizes and sessions[].image_size;
    older files record neither): the figures are of a camera it never saw."""
    md = run.meta.get("metadata") if isinstance(run.meta.get("metadata"), dict) else {}
    trained = _sizes(md.get("image_sizes"))
    if not trained:
        return []
    entries = run.meta.get("sessions") if isinstance(run.meta.get("sessions"), list) else []
    other = [(e.get("session"), _sizes([e.get("image_size")])) for e in entries if isinstance(e, dict)]
    other = [(name, sizes[0]) for name, sizes in other if sizes and sizes[0] not in trained]
    if not other:
        return []
    known = ", ".join(f"{w:g}x{h:g}" for w, h in trained)
    (name, (w, h)) = other[0]
    return [f"{run.name}: the model was trained on {known} images, but {len(other)} of the {len(entries)} sessions "
            f"evaluated {'is' if len(other) == 1 else 'are'} of another size (the first, {name}, {w:g}x{h:g}): "
            f"these figures are of a camera it has not seen (fine-tune it on that camera's sessions: "
            f"ivoa-train --init)"]


def attach_dataset(run: EvalRun, dataset: Dataset) -> List[str]:
    """Links an eval to the dataset it ran on and checks that they agree.

    Every prediction row must point at an existing sample whose utime, cell and
    label are the ones in predictions.csv: otherwise the mosaics would show the
    wrong patches, so a mismatch is an InputError. Returns warnings (e.g. the
    dataset's labels are about another detector than the model's)."""
    warnings = []
    other_detector = {}
    label_detectors = set()
    pred_path = os.path.join(run.path, "predictions.csv")
    for name in sorted(set(run.session.tolist())):
        s = dataset.session(name)
        _check_session_cut(run, s)
        rows = np.flatnonzero(run.session == name)
        idx = run.sample[rows]
        bad = np.flatnonzero((idx < 0) | (idx >= s.size))
        if len(bad):
            r = rows[bad[0]]
            raise InputError(
                f"{pred_path}: line {_line(r)} refers to sample {run.sample[r]} of session {name}, "
                f"but {os.path.join(s.path, 'samples.csv')} has {s.size} samples "
                f"(is --dataset the dataset this eval ran on?)")
        mismatch = np.flatnonzero((s.utime[idx] != run.utime[rows]) | (s.cell[idx] != run.cell[rows])
                                  | (s.label[idx] != run.label[rows]))
        if len(mismatch):
            r = rows[mismatch[0]]
            raise InputError(
                f"{pred_path}: line {_line(r)} (session {name}, sample {run.sample[r]}) does not match "
                f"{os.path.join(s.path, 'samples.csv')} (utime/cell/label differ in {len(mismatch)} of "
                f"{len(rows)} rows): is --dataset the dataset this eval ran on?")
        s.patches()  # size checks now, not in the middle of the figures
        s.evidence()
        det = s.info.get("detector")
        label_detectors.add(det or "unknown")
        if det and run.detector != "unknown" and det != run.detector:
            other_detector.setdefault(det, []).append(name)
    for det, names in sorted(other_detector.items()):
        warnings.append(
            f"{run.name}: the model was trained for detector '{run.detector}' but the labels of session(s) "
            f"{', '.join(names)} in {dataset.path} are about '{det}'")
    run.dataset = dataset
    run.label_detector = label_detectors.pop() if len(label_detectors) == 1 else run.detector
    return warnings


def _check_session_cut(run: EvalRun, s: DatasetSession) -> None:
    """Newer eval.json files record each session's views and patch scale: a
    dataset cut otherwise has the same samples.csv but other squares, so the
    mosaics would show patches the model never saw. Older files: no check."""
    entry = next((e for e in run.meta.get("sessions", []) if e["session"] == s.name), {})
    for key, in_dataset in (("patch_scale", s.patch_scale), ("views", s.views)):
        if key in entry and abs(entry[key] - in_dataset) > 1e-6:
            raise InputError(
                f"{os.path.join(run.path, 'eval.json')}: session {s.name} was evaluated at {key} {entry[key]:g}, "
                f"but {os.path.join(s.path, 'session.json')} has {key} {in_dataset:g}: is --dataset the dataset "
                f"this eval ran on?")


def evidence_margin(run: EvalRun, threshold: float) -> Optional[np.ndarray]:
    """Per prediction row, how far the labels' detector was from its verdict:
    the largest of the cell's evidence values (for JPP-C, the worst window cost
    of its ground samples; the cell is an obstacle iff it is >= threshold)
    minus the threshold. NaN where no value was observed. None when the run
    has no dataset or a session of it has no evidence."""
    if run.dataset is None:
        return None
    margin = np.full(run.size, np.nan)
    for name in sorted(set(run.session.tolist())):
        ev = run.dataset.session(name).evidence()
        if ev is None:
            return None
        rows = np.flatnonzero(run.session == name)
        values = ev[run.sample[rows]]
        seen = ~np.all(np.isnan(values), axis=1)
        margin[rows[seen]] = np.nanmax(values[seen], axis=1) - threshold
    return margin


NO_CAUSE = -1
ONLY_TOGETHER = 1 << 7  # no single removal fixes the failure, removing all the scene's phenomena does
# causes.csv columns (ivoa-sim-causes) the report uses.
CAUSE_COLUMNS = ("session", "detector", "utime", "cell", "label", "stereo_state", "replayed_state", "causes",
                 "jointly")


@dataclass
class Causes:
    """One causes.csv: per (session, detector, utime, cell) of a failure cell,
    its label and the causes bits, or NO_CAUSE where the re-rendered verdict
    differed from the recorded one (the frame was not reproduced)."""
    path: str
    rows: Dict[tuple, tuple]
    detectors: set
    # Failures no phenomenon explains ("none found"), by (detector, label
    # name), and how many of them each detector variant fixes, by
    # (detector, label name, variant): from the fixed_by column, when present.
    unexplained: Dict[tuple, int] = field(default_factory=dict)
    unexplained_fixed: Dict[tuple, int] = field(default_factory=dict)


def load_causes(path: str) -> Causes:
    """Reads ivoa-sim-causes' CSV; bad content is an InputError naming the row."""
    cols = _read_csv_columns(path, CAUSE_COLUMNS)
    utime, cell = _numeric(path, cols, "utime", int), _numeric(path, cols, "cell", int)
    stereo, replayed = _numeric(path, cols, "stereo_state", int), _numeric(path, cols, "replayed_state", int)
    bits = _numeric(path, cols, "causes", int)
    if "tested" in cols:  # a cause is one of the phenomena re-rendered away
        tested = _numeric(path, cols, "tested", int)
        bad = np.flatnonzero((bits < 0) | (tested < 0) | ((bits & ~tested) != 0))
        if len(bad):
            raise InputError(f"{path}: line {_line(bad[0])}: causes {bits[bad[0]]} is not a set of the phenomena "
                             f"tested there ({tested[bad[0]]})")
    bits = np.where((bits == 0) & (_numeric(path, cols, "jointly", int) != 0), ONLY_TOGETHER, bits)
    rows = {}
    first_line: Dict[tuple, int] = {}
    for i, (session, detector, label) in enumerate(zip(cols["session"], cols["detector"], cols["label"])):
        if label not in ("FP", "FN"):
            raise InputError(f"{path}: line {_line(i)}: label '{label}' (causes are for FP and FN cells)")
        key = (session, detector, int(utime[i]), int(cell[i]))
        if key in first_line:  # two answers for one cell: which is right cannot be told
            raise InputError(f"{path}: line {_line(i)}: session {session}, detector {detector}, utime {key[2]}, "
                             f"cell {key[3]} again (first on line {first_line[key]}; files concatenated?)")
        first_line[key] = _line(i)
        cause = int(bits[i]) if stereo[i] == replayed[i] else NO_CAUSE
        rows[key] = (LABEL_NAMES.index(label), cause)
    causes = Causes(path=path, rows=rows, detectors=set(cols["detector"]))
    if "fixed_by" in cols:  # older files lack it
        none_found = (stereo == replayed) & (bits == 0)
        for detector, label, fixed_by in zip(*(np.array(cols[k])[none_found] for k in ("detector", "label", "fixed_by"))):
            key = (str(detector), str(label))
            causes.unexplained[key] = causes.unexplained.get(key, 0) + 1
            for variant in filter(None, str(fixed_by).split("+")):
                causes.unexplained_fixed[key + (variant,)] = causes.unexplained_fixed.get(key + (variant,), 0) + 1
    return causes


# The --variants-out CSV of ivoa-sim-causes: per session, detector variant
# and label, the labelled cells of the re-rendered frames and how many the
# variant gets right (the depth monitor's state) and wrong.
VARIANT_COLUMNS = ("session", "detector", "variant", "label", "cells", "right", "wrong")


def load_variants(path: str) -> Dict[tuple, Dict[str, int]]:
    """Sums of cells/right/wrong by (detector, variant, label name); bad
    content is an InputError naming the row."""
    cols = _read_csv_columns(path, VARIANT_COLUMNS)
    counts = {k: _numeric(path, cols, k, int) for k in ("cells", "right", "wrong")}
    out: Dict[tuple, Dict[str, int]] = {}
    first_line: Dict[tuple, int] = {}
    for i, (session, detector, variant, label) in enumerate(zip(cols["session"], cols["detector"], cols["variant"],
                                                                 cols["label"])):
        row = (session, detector, variant, label)
        if row in first_line:  # summed twice, it would double the session's cells
            raise InputError(f"{path}: line {_line(i)}: session {session}, {detector} variant '{variant}', label "
                             f"{label} again (first on line {first_line[row]})")
        first_line[row] = _line(i)
        if label not in LABEL_NAMES:
            raise InputError(f"{path}: line {_line(i)}: label '{label}' (expected one of {', '.join(LABEL_NAMES)})")
        n, right, wrong = (int(counts[k][i]) for k in ("cells", "right", "wrong"))
        if min(n, right, wrong) < 0 or right + wrong > n:
            raise InputError(f"{path}: line {_line(i)}: {right} right and {wrong} wrong of {n} cells")
        sums = out.setdefault((detector, variant, label), {"cells": 0, "right": 0, "wrong": 0})
        for k, v in (("cells", n), ("right", right), ("wrong", wrong)):
            sums[k] += v
    return out


def load_repeatability(path: str, threshold: float) -> dict:
    """The evidence part of an ivoa_label_repeatability.py --json file: how far
    another sensor-noise draw moves the detector's worst evidence value and,
    per margin band, how often it keeps the verdict. Adds the file's path,
    detector and sessions. InputError when it has none, or was measured at
    another threshold than the report's."""
    data = _read_json(path)
    if "evidence" not in data:
        raise InputError(f"{path}: no 'evidence' entry (written by an older ivoa_label_repeatability.py? run it again)")
    e = data["evidence"]
    if e is None:
        raise InputError(f"{path}: its datasets keep no detector evidence (the dense detector keeps none)")
    try:
        if abs(float(e["threshold"]) - threshold) > 1e-9:
            raise InputError(f"{path}: measured at evidence threshold {float(e['threshold']):g}, the report uses "
                             f"{threshold:g} (--evidence-threshold)")
        bands = [{"low": b["low"], "high": b["high"], "n": int(b["n"]),
                  "verdict_agreement": float(b["verdict_agreement"])} for b in e["bands"]]
        for i, b in enumerate(bands):
            if not (0 <= b["verdict_agreement"] <= 1 and b["n"] >= 0):
                raise InputError(f"{path}: evidence.bands[{i}]: verdict_agreement {b['verdict_agreement']:g} and n "
                                 f"{b['n']}, expected a fraction 0..1 of n >= 0 cells")
        return {"path": path, "detector": str(data.get("detector", "")), "realisations": len(data["datasets"]),
                "sessions": [str(s) for s in data["session_names"]], "cells": int(e["cells"]),
                "worst_shift_median": float(e["worst_shift_median"]), "worst_shift_p90": float(e["worst_shift_p90"]),
                "bands": bands}
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"{path}: malformed repeatability figures ({type(err).__name__}: {err})") from None


def attach_causes(run: EvalRun, all_causes: List[Causes]) -> List[str]:
    """Sets run.cause for the true FP/FN rows that the causes CSV about the
    detector of the run's labels covers (same session, utime and cell). A
    row there with another label means the CSV is from other logs:
    InputError. Returns warnings (no CSV for this run's detector, failures
    not covered)."""
    detector = run.label_detector or run.detector
    matching = [c for c in all_causes if detector in c.detectors]
    if not matching:
        about = sorted(set().union(*(c.detectors for c in all_causes)))
        if not about:
            return [f"{run.name}: the causes given hold no rows (no FP or FN cell in their logs): no causes for it"]
        return [f"{run.name}: the causes given explain failures of {', '.join(about)}, this model's labels are "
                f"about '{detector}': no causes for it"]
    causes = matching[0]
    run.cause = np.full(run.size, NO_CAUSE, dtype=np.int64)
    failures = np.flatnonzero((run.label == FP) | (run.label == FN))
    missing = 0
    for r in failures:
        hit = causes.rows.get((run.session[r], detector, int(run.utime[r]), int(run.cell[r])))
        if hit is None:
            missing += 1
            continue
        if hit[0] != run.label[r]:
            raise InputError(
                f"{causes.path}: session {run.session[r]}, utime {run.utime[r]}, cell {run.cell[r]} is "
                f"{LABEL_NAMES[hit[0]]} there but {LABEL_NAMES[run.label[r]]} in {run.path}/predictions.csv: "
                f"are the causes from the logs this dataset was built from?")
        run.cause[r] = hit[1]
    if missing:
        return [f"{run.name}: {missing} of {len(failures)} true FP/FN samples are not in {causes.path} "
                f"(sessions it was not run on): no cause for them"]
    return []


def make_names(runs: List[EvalRun]) -> None:
    """Gives each run a display name "<detector> (<folder>)" and a unique slug,
    so that two evals of the same detector stay apart in tables and file names."""
    used = set()
    for run in runs:
        folder = os.path.basename(os.path.normpath(run.path)) or "eval"
        base = f"{run.detector} ({folder})"
        name, i = base, 2
        while name in used:
            name, i = f"{base} #{i}", i + 1
        used.add(name)
        run.name = name
        slug = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{run.detector}_{folder}").strip("_") or "model"
        s, i = slug, 2
        while s in {r.slug for r in runs if r is not run}:
            s, i = f"{slug}_{i}", i + 1
        run.slug = s
