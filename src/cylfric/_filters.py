"""Three 1-D filters of the steady-state extraction, with edge values repeated ("nearest").

They equal :func:`scipy.ndimage.convolve1d`, :func:`~scipy.ndimage.median_filter` (odd
sizes) and :func:`~scipy.ndimage.uniform_filter1d` with ``mode="nearest"`` to rounding
(``tests/test_filters.py``), without importing scipy.ndimage (about 0.2 s) before the
extraction can start: scipy is imported while the second extraction worker reads files.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba
import numpy as np

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "convolve_nearest",
    "median",
    "median_deviation",
    "median_and_deviation",
    "rolling_median",
    "rolling_mean",
]


def _padded(x, before, after):
    """``x`` with its first value repeated ``before`` times and its last ``after`` times."""
    x = np.asarray(x, dtype=float)
    n = x.size
    out = np.empty(before + n + after)
    out[:before] = x[0]
    out[before : before + n] = x
    out[before + n :] = x[-1]
    return out


def convolve_nearest(x: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Convolution of ``x`` with an odd-length ``kernel``, centred, edges repeated."""
    m = len(kernel) // 2
    return np.convolve(_padded(x, m, len(kernel) - 1 - m), kernel, mode="valid")


def rolling_mean(x: np.ndarray, size: int) -> np.ndarray:
    """Mean of ``size`` samples around each sample (for even sizes, one more before)."""
    padded = _padded(x, size // 2, size - 1 - size // 2)
    base = padded[0]  # summing differences from one value keeps the rounding small
    sums = np.concatenate(([0.0], np.cumsum(padded - base)))
    return (sums[size:] - sums[:-size]) / size + base


@numba.njit(cache=True, nogil=True)
def _rolling_median(padded, size, out):
    window = np.sort(padded[:size])  # the current window, kept sorted
    half = size // 2
    out[0] = window[half]
    for i in range(1, out.size):
        leaving, entering = padded[i - 1], padded[i + size - 1]
        j = 0
        while window[j] != leaving:  # remove the value that leaves ...
            j += 1
        while j > 0 and window[j - 1] > entering:  # ... and shift in the new one, in order
            window[j] = window[j - 1]
            j -= 1
        while j < size - 1 and window[j + 1] < entering:
            window[j] = window[j + 1]
            j += 1
        window[j] = entering
        out[i] = window[half]
    return out


def rolling_median(x: np.ndarray, size: int) -> np.ndarray:
    """Median of ``size`` (odd) samples around each sample, edges repeated."""
    if size % 2 == 0:
        raise ValueError(f"rolling_median needs an odd size; got {size}")
    x = np.asarray(x, dtype=float)
    out = np.empty(x.size)
    if x.size:
        _rolling_median(_padded(x, size // 2, size // 2), size, out)
    return out


@numba.njit(cache=True, nogil=True)
def _median(x):
    for value in x:
        if np.isnan(value):
            return np.nan
    return np.median(x)  # quickselect; an even count: (a + b) / 2, as numpy's


@numba.njit(cache=True, nogil=True)
def _median_deviation(x):
    for value in x:
        if np.isnan(value):
            return np.nan, np.nan
    centre = np.median(x)
    return centre, np.median(np.abs(x - centre))


def median(x: np.ndarray) -> float:
    """``np.median(x)`` of a 1-D float array (the same value, without numpy's per-call cost:
    the extraction takes about 30 medians of short arrays per run file); NaN if ``x`` holds
    a NaN or is empty."""
    x = np.asarray(x, dtype=float)
    return float(_median(x)) if x.size else np.nan


def median_deviation(x: np.ndarray) -> float:
    """``np.median(np.abs(x - np.median(x)))`` [units of x] (the median absolute deviation,
    unscaled) of a 1-D float array; NaN if ``x`` holds a NaN or is empty."""
    return median_and_deviation(x)[1]


def median_and_deviation(x: np.ndarray) -> tuple[float, float]:
    """``(median(x), median_deviation(x))`` [units of x] in one pass (the median is computed
    once); (NaN, NaN) if ``x`` holds a NaN or is empty."""
    x = np.asarray(x, dtype=float)
    if not x.size:
        return np.nan, np.nan
    centre, deviation = _median_deviation(x)
    return float(centre), float(deviation)
