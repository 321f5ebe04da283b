"""Three 1-D filters of the steady-state extraction, with edge values repeated ("nearest"),
and the compiled window tests built on them.

The filters equal :func:`scipy.ndimage.convolve1d`, :func:`~scipy.ndimage.median_filter` (odd
sizes) and :func:`~scipy.ndimage.uniform_filter1d` with ``mode="nearest"`` to rounding
(``tests/test_filters.py``), without importing scipy.ndimage (about 0.2 s) before the
extraction can start: scipy is imported while the second extraction worker reads files.

:func:`stroke_window` is the window tests of each stroke (velocity settled, then the force
settled and the cushions trimmed; :func:`cylfric.steady_state.find_windows`) in one compiled
call: the same operations as the numpy expressions they replaced (no sum is reordered: the
rolling mean is a sequential cumulative sum, as ``np.cumsum``), without some fifty small numpy
calls per stroke, and the trimming reuses the settling test's rolling median.
"""

from __future__ import annotations

import math
import operator
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
    "stroke_window",
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
    if size == 9:  # the extraction's default: a selection network, no branches
        for i in range(out.size):
            out[i] = _median9(padded, i)
        return out
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


@numba.njit(cache=True, nogil=True, inline="always")
def _median9(x, i):
    """The median of ``x[i : i + 9]`` by the 19 compare-exchanges of Paeth's median-of-9
    network (A. W. Paeth, "Median finding on a 3x3 grid", Graphics Gems, 1990; the order of
    N. Devillard's ``opt_med9``): the same value as sorting them, about ten times faster than
    the sorted window on noisy forces (its searches branch unpredictably)."""
    p0, p1, p2, p3, p4 = x[i], x[i + 1], x[i + 2], x[i + 3], x[i + 4]
    p5, p6, p7, p8 = x[i + 5], x[i + 6], x[i + 7], x[i + 8]
    p1, p2 = min(p1, p2), max(p1, p2)
    p4, p5 = min(p4, p5), max(p4, p5)
    p7, p8 = min(p7, p8), max(p7, p8)
    p0, p1 = min(p0, p1), max(p0, p1)
    p3, p4 = min(p3, p4), max(p3, p4)
    p6, p7 = min(p6, p7), max(p6, p7)
    p1, p2 = min(p1, p2), max(p1, p2)
    p4, p5 = min(p4, p5), max(p4, p5)
    p7, p8 = min(p7, p8), max(p7, p8)
    p3 = max(p0, p3)
    p5 = min(p5, p8)
    p4, p7 = min(p4, p7), max(p4, p7)
    p6 = max(p3, p6)
    p4 = max(p1, p4)
    p2 = min(p2, p5)
    p4 = min(p4, p7)
    p4, p2 = min(p4, p2), max(p4, p2)
    p4 = max(p6, p4)
    return min(p4, p2)


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
def _order_pair(x, k):
    """The ``k``-th and ``k + 1``-th smallest values of ``x`` (without NaN; the ``k``-th
    twice when it is the last), ``x`` unchanged.

    Selection by sampling (Floyd and Rivest 1975): two values of a sorted sample of about
    32 bracket the wanted ones, one pass keeps the values between them (and counts those
    below), and the search goes on in them; a bracket that misses, or keeps most values, ends
    in a quickselect of the values left. About twice as fast as the quickselect of
    ``np.median`` on the extraction's strokes (its branches are hard to predict); the values
    are the same: an order statistic is a value of ``x``, whichever way it is found. (No
    ``np.sort`` or ``np.partition``: their compiled code would triple the size of every
    cached function that takes a median, and the time to load it in each new process.)
    """
    n = x.size
    work = np.empty(2 * n)
    src = x
    base = 0  # the half of ``work`` written next
    while n >= 256:
        step = n // 32
        sample = np.empty((n - step // 2 + step - 1) // step)  # src[step // 2 : n : step]
        for i in range(sample.size):  # sorted by insertion (about 32 values)
            value = src[step // 2 + i * step]
            j = i
            while j > 0 and sample[j - 1] > value:
                sample[j] = sample[j - 1]
                j -= 1
            sample[j] = value
        at = (k * sample.size) // n
        lo = sample[max(at - 4, 0)]
        hi = sample[min(at + 5, sample.size - 1)]
        dst = work[base : base + n]
        below = 0
        kept = 0
        for i in range(n):
            value = src[i]
            below += value < lo
            dst[kept] = value
            kept += (value >= lo) & (value <= hi)
        if k < below or k + 1 >= below + kept or 4 * kept > 3 * n:
            break  # missed (or little gained): select in what is left
        src, n, k = dst[:kept], kept, k - below
        base = 0 if base else x.size  # the other half of ``work``
    a = work[base : base + n]
    for i in range(n):
        a[i] = src[i]
    first = _select(a, k)
    second = first
    if k + 1 < n:  # the smallest of those after the k-th (none is smaller than it)
        second = a[k + 1]
        for i in range(k + 2, n):
            if a[i] < second:
                second = a[i]
    return first, second


@numba.njit(cache=True, nogil=True)
def _select(a, k):
    """``a[k]`` once ``a`` is rearranged so that no value before ``k`` is larger and none
    after it smaller (quickselect, Hoare's partition around a median of three; in place)."""
    lo, hi = 0, a.size - 1
    while hi > lo:
        mid = (lo + hi) // 2
        if a[mid] < a[lo]:
            a[mid], a[lo] = a[lo], a[mid]
        if a[hi] < a[mid]:
            a[hi], a[mid] = a[mid], a[hi]
            if a[mid] < a[lo]:
                a[mid], a[lo] = a[lo], a[mid]
        pivot = a[mid]
        i, j = lo, hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while pivot < a[j]:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            break  # a[j + 1 : i] all equal the pivot
    return a[k]


@numba.njit(cache=True, nogil=True)
def _median_of(x):
    """``np.median(x)`` of a non-empty ``x`` without NaN (an even count: (a + b) / 2, as
    numpy's)."""
    n = x.size
    a, b = _order_pair(x, (n - 1) // 2)
    return a if n % 2 else (a + b) / 2


@numba.njit(cache=True, nogil=True)
def _median(x):
    for value in x:
        if np.isnan(value):
            return np.nan
    return _median_of(x)


@numba.njit(cache=True, nogil=True)
def _median_deviation(x):
    for value in x:
        if np.isnan(value):
            return np.nan, np.nan
    centre = _median_of(x)
    return centre, _median_of(np.abs(x - centre))


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


@numba.njit(cache=True, nogil=True)
def _padded_nb(x, before, after):
    n = x.size
    out = np.empty(before + n + after)
    out[:before] = x[0]
    out[before : before + n] = x
    out[before + n :] = x[-1]
    return out


@numba.njit(cache=True, nogil=True)
def _rolling_median_nb(x, size):
    """:func:`rolling_median` (``size`` odd) of a non-empty ``x``."""
    return _rolling_median(_padded_nb(x, size // 2, size // 2), size, np.empty(x.size))


@numba.njit(cache=True, nogil=True)
def _rolling_mean_nb(x, size):
    """:func:`rolling_mean` of a non-empty ``x``: the same sequential sums as ``np.cumsum``."""
    padded = _padded_nb(x, size // 2, size - 1 - size // 2)
    base = padded[0]
    sums = np.empty(padded.size + 1)
    sums[0] = 0.0
    total = 0.0
    for i in range(padded.size):
        total += padded[i] - base
        sums[i + 1] = total
    out = np.empty(x.size)  # (sums[size:] - sums[:-size]) / size + base, in one loop
    for i in range(x.size):
        out[i] = (sums[i + size] - sums[i]) / size + base
    return out


@numba.njit(cache=True, nogil=True)
def _median_nb(x):
    return _median(x) if x.size else np.nan


@numba.njit(cache=True, nogil=True)
def _deviation_nb(x):
    return _median_deviation(x)[1] if x.size else np.nan


@numba.njit(cache=True, nogil=True)
def _max(a, b):
    return b if b > a else a  # Python's max(a, b), NaN included


@numba.njit(cache=True, nogil=True, inline="always")
def _despiked(force, rolling, limit):
    """``np.where(np.abs(force - rolling) > limit, rolling, force)`` in one loop: samples
    farther than ``limit`` [N] from the rolling median replaced by it (0: every sample that
    differs from it)."""
    clean = np.empty(force.size)
    for i in range(force.size):
        clean[i] = rolling[i] if abs(force[i] - rolling[i]) > limit else force[i]
    return clean


@numba.njit(cache=True, nogil=True)
def _settled_from(force, rolling, noise, median_window, sigma, tolerance, spike_sigma):
    """Samples at the start of ``force`` before it has settled (see :func:`stroke_window`),
    given its rolling median and the robust sigma of its residual."""
    n = force.size
    w = max(median_window, n // 20) | 1
    clean = _despiked(force, rolling, spike_sigma * noise) if noise > 0 else force
    mean = _rolling_mean_nb(clean, w)
    half = n // 2
    final = _median_nb(clean[half:])
    spread = _max(1.4826 * _deviation_nb(mean[half:]), noise / math.sqrt(w))
    band = _max(sigma * spread, tolerance * abs(final))
    for i in range(half - 1, -1, -1):  # the last sample of the first half outside the band
        if abs(mean[i] - final) > band:
            return min(i + 1 + w // 2, half)
    return 0


@numba.njit(cache=True, nogil=True)
def _trimmed(force, rolling, noise, w, trim_sigma, trim_floor, spike_sigma):
    """(start, stop) of ``force`` kept by the cushion trimming (see :func:`stroke_window`),
    given its rolling median (size ``w``) and the robust sigma of its residual (NaN: not
    known yet)."""
    n = force.size
    level = _median_nb(rolling[n // 4 : n - n // 4] if n >= 8 else rolling)
    deviation = _deviation_nb(force)
    spread = 1.4826 * deviation / math.sqrt(w)
    limit = _max(trim_sigma * spread, trim_floor)
    # a slow drift (cushioning starting to engage) hides under the noise of a short median:
    # a rolling mean over a tenth of the window sees it, with its own 4-sigma limit
    w_long = max(w, n // 10)
    mean = rolling  # (unused unless w_long > w)
    long_limit = np.inf
    if w_long > w:
        sigma = 1.4826 * deviation
        # isolated spikes (a sample or a few, far from the rolling median) are replaced by
        # the rolling median first: one spike of 150 N in a mean over 370 samples moved it
        # beyond its limit in mid-stroke, and the whole stroke was trimmed away (issue 11, F4)
        if np.isnan(noise):
            noise = 1.4826 * _deviation_nb(force - rolling)
        clean = _despiked(force, rolling, spike_sigma * noise if noise > 0 else 0.0)
        mean = _rolling_mean_nb(clean, w_long)
        long_limit = trim_sigma * sigma / math.sqrt(w_long)
    # a sample is outside when |rolling - level| > limit or |mean - level| > long_limit
    # (never with w_long = w: long_limit is then infinite); tested only where the search looks
    mid = n // 2
    lo = 0
    for i in range(mid - 1, -1, -1):  # the last outside sample before the middle
        if abs(rolling[i] - level) > limit or abs(mean[i] - level) > long_limit:
            lo = i + 1
            break
    hi = n
    for i in range(mid, n):  # the first from the middle on
        if abs(rolling[i] - level) > limit or abs(mean[i] - level) > long_limit:
            hi = i
            break
    return lo, hi


@numba.njit(cache=True, nogil=True)
def _window_by_force(
    force,
    median_window,
    settle_sigma,
    settle_tolerance,
    min_samples,
    trim_sigma,
    trim_floor,
    spike_sigma,
):
    n = force.size
    first = 0
    w = min(median_window, max(1, n // 3)) | 1
    rolling = np.empty(0)
    noise = np.nan
    settled = not (n < 4 * max(min_samples, 1) or settle_sigma <= 0)
    if settled:
        rolling = _rolling_median_nb(force, w)
        noise = 1.4826 * _deviation_nb(force - rolling)
        first = _settled_from(
            force, rolling, noise, median_window, settle_sigma, settle_tolerance, spike_sigma
        )
    kept = force[first:]
    m = kept.size
    w_trim = min(median_window, max(1, m // 3) | 1)
    if m == 0 or w_trim % 2 == 0:  # nothing to trim, or no median of that size (refused)
        return first, 0, m, w_trim
    if settled and w_trim == w:
        # the settling test's rolling median, but for its first w // 2 values (their window
        # reached before the kept samples): the same medians, not computed again
        if first == 0:
            trim_rolling = rolling
        else:
            trim_rolling = rolling[first:].copy()
            noise = np.nan  # another residual
            h = w // 2
            if m >= w:
                trim_rolling[:h] = _rolling_median_nb(kept[:w], w)[:h]
            else:
                trim_rolling = _rolling_median_nb(kept, w)
    else:
        trim_rolling = _rolling_median_nb(kept, w_trim)
        noise = np.nan
    lo, hi = _trimmed(kept, trim_rolling, noise, w_trim, trim_sigma, trim_floor, spike_sigma)
    return first, lo, hi, w_trim


@numba.njit(cache=True, nogil=True)
def _stroke_window(
    velocity,
    force,
    velocity_tolerance,
    min_samples,
    median_window,
    settle_sigma,
    settle_tolerance,
    trim_sigma,
    trim_floor,
    spike_sigma,
):
    v_stroke = _median(velocity)
    settled = np.abs(velocity - v_stroke) <= velocity_tolerance * abs(v_stroke)
    start = stop = 0  # the longest run of settled samples (the first of equal ones)
    run = -1
    for i in range(settled.size + 1):
        if i < settled.size and settled[i]:
            if run < 0:
                run = i
        elif run >= 0:
            if i - run > stop - start:
                start, stop = run, i
            run = -1
    if stop - start < min_samples:
        return settled, start, stop, 0, 0, 0, 1
    first, lo, hi, w_trim = _window_by_force(
        force[start:stop],
        median_window,
        settle_sigma,
        settle_tolerance,
        min_samples,
        trim_sigma,
        trim_floor,
        spike_sigma,
    )
    return settled, start, stop, first, lo, hi, w_trim


def stroke_window(
    velocity: np.ndarray,
    force: np.ndarray,
    *,
    velocity_tolerance: float,
    min_samples: int,
    median_window: int,
    settle_sigma: float,
    settle_tolerance: float,
    trim_sigma: float,
    trim_floor: float,
    spike_sigma: float,
) -> tuple[np.ndarray, int, int, tuple[int, int, int] | None]:
    """The constant-velocity window of one stroke (``velocity`` [m/s] and ``force`` [N] of
    its samples), compiled: ``(settled, start, stop, cut)``.

    ``settled`` (bool per sample): |v - median v| <= ``velocity_tolerance`` * |median v|;
    ``start:stop`` its longest run (the first of equal ones). ``cut`` is None when that run
    is shorter than ``min_samples``, else ``(settled, lo, hi)``: the samples the force tests
    keep are ``force[start:stop][settled:][lo:hi]``.

    Force settling (a start-up transient: the pressures of a valve-driven axis build up after
    the speed has settled): the final level is the median of the run's second half; the force
    has settled from the first sample after which a rolling mean (a twentieth of the run)
    of the force, spikes (beyond ``spike_sigma`` robust sigmas of the rolling median's
    residual) replaced by the rolling median, stays within the band max(``settle_sigma`` *
    the rolling mean's robust spread over the second half, ``settle_tolerance`` * |final
    level|). Only the first half is ever cut; runs shorter than 4 * ``min_samples`` are
    not cut.

    Cushion trimming of the settled samples: the level is the median of the rolling median
    (``median_window`` samples) over the middle half; a sample is outside when its rolling
    median departs from the level by more than max(``trim_sigma`` * the force's robust
    sigma / sqrt(median size), ``trim_floor`` [N]), or (beyond ten median sizes) when a
    rolling mean over a tenth of the samples, spikes replaced by the rolling median, departs
    by more than ``trim_sigma`` robust sigmas of that mean. The samples between the last
    outside sample of the first half and the first of the second half are kept.

    The same operations as these rules written with numpy arrays (``tests/test_filters.py``
    compares them) in one call. Raises ValueError when the trimming's median size would be
    even (an even ``median_window``).
    """
    settled, start, stop, first, lo, hi, size = _stroke_window(
        np.ascontiguousarray(velocity, dtype=float),
        np.ascontiguousarray(force, dtype=float),
        float(velocity_tolerance),
        operator.index(min_samples),
        operator.index(median_window),
        float(settle_sigma),
        float(settle_tolerance),
        float(trim_sigma),
        float(trim_floor),
        float(spike_sigma),
    )
    if size % 2 == 0:
        raise ValueError(f"rolling_median needs an odd size; got {size}")
    cut = None if stop - start < min_samples else (int(first), int(lo), int(hi))
    return settled, int(start), int(stop), cut
