"""Bands of a detector's evidence margin, shared by the report and by
ivoa_label_repeatability.py so that both count cells in the same bands.

The margin is the detector's worst evidence value minus its threshold, in
the evidence's own units (JPP-C: the per-pixel L1 DAISY window cost of its
worst ground sample, threshold 0.75); a cell is an obstacle iff the margin
is >= 0. The edges were chosen for JPP-C: in the simulator another draw of
the sensor noise moves a cell's worst cost by about 0.04 (median) to 0.13
(90th percentile), which ivoa_label_repeatability.py measures.
"""

from __future__ import annotations

from typing import Dict, List, Optional

import numpy as np

MARGIN_EDGES = (-0.3, -0.15, -0.08, -0.04, 0.0, 0.04, 0.08, 0.15, 0.3)
# Half-width of the band counted as "near the threshold".
NEAR_MARGIN = 0.08
# Share of cells whose margin must give the label's verdict for the evidence
# to be taken as that verdict's (a wrong threshold, or evidence recorded with
# other detector settings, fails it).
MARGIN_AGREEMENT_MIN = 0.99


def band_name(band: dict) -> str:
    """'< -0.3', '-0.08 … -0.04', '≥ 0.3' for a band dict (open ends: None)."""
    if band["low"] is None:
        return f"< {band['high']:g}"
    if band["high"] is None:
        return f"≥ {band['low']:g}"
    return f"{band['low']:g} … {band['high']:g}"


def share(hit: np.ndarray) -> Optional[float]:
    """Mean of a boolean array; None when it is empty."""
    return float(np.mean(hit)) if len(hit) else None


def margin_bands(margin: np.ndarray, said_obstacle: np.ndarray,
                 hits: Dict[str, Optional[np.ndarray]]) -> List[dict]:
    """Per non-empty band of MARGIN_EDGES (band i: edges[i] <= m < edges[i + 1],
    so a margin of exactly 0 is an obstacle's, as for JPP-C): its size, its
    share of the cells, how often the detector said obstacle, and the share
    of True of each hit array (None arrays give None)."""
    edges = (None,) + MARGIN_EDGES + (None,)
    band = np.digitize(margin, MARGIN_EDGES)
    out = []
    for i in range(len(edges) - 1):
        b = band == i
        if b.any():
            out.append(dict({"low": edges[i], "high": edges[i + 1], "n": int(b.sum()), "share": float(b.mean()),
                             "obstacle_share": float(np.mean(said_obstacle[b]))},
                            **{k: share(h[b]) if h is not None else None for k, h in hits.items()}))
    return out
