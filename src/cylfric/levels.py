"""Pressure levels of a campaign: measured pressures [Pa] grouped into the levels of a test.

Used by the data-quality gate (:mod:`cylfric.quality`) and the identification
(:mod:`cylfric.identify`, re-exported there); imports nothing of ours.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["pressure_levels"]


def pressure_levels(
    pressure: ArrayLike, *, gap: float = 0.5e5, relative: float = 0.02
) -> tuple[np.ndarray, np.ndarray]:
    """Group measured pressures [Pa] into levels; returns (level index per point, level means).

    A new level starts where sorted pressures jump by more than max(``gap`` [Pa],
    ``relative`` * pressure [-]). The defaults (0.5 bar, 2 %) keep campaigns with 7 bar steps
    up to 160 bar apart (5 % chained 147, 154 and 161 bar into one level) while the runs of
    one hand-pumped level, which scatter by well under 2 %, stay together.
    """
    p = np.asarray(pressure, dtype=float)
    order = np.argsort(p)
    sorted_p = p[order]
    jumps = np.diff(sorted_p) > np.maximum(gap, relative * np.abs(sorted_p[1:]))
    labels_sorted = np.concatenate(([0], np.cumsum(jumps)))
    labels = np.empty_like(labels_sorted)
    labels[order] = labels_sorted
    means = np.array([p[labels == k].mean() for k in range(labels_sorted[-1] + 1)])
    return labels, means
