"""The extraction's own filters equal scipy.ndimage's with mode="nearest"; its compiled window
tests equal their numpy form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.ndimage import convolve1d, median_filter, uniform_filter1d

from cylfric._filters import (
    convolve_nearest,
    median,
    median_and_deviation,
    median_deviation,
    rolling_mean,
    rolling_median,
    stroke_window,
)


@pytest.mark.parametrize("n", [1, 2, 5, 17, 1000, 10001])
@pytest.mark.parametrize("size", [1, 3, 9, 10, 101])
def test_filters_equal_scipy_ndimage_nearest(n, size):
    rng = np.random.default_rng(n * 1000 + size)
    x = 150.0 + rng.normal(size=n).cumsum()  # a force-like level with drift [N]
    x[::7] = x[0]  # ties, as quantised load-cell readings have
    assert_allclose(rolling_mean(x, size), uniform_filter1d(x, size, mode="nearest"), rtol=1e-12)
    if size % 2:
        kernel = np.arange(size // 2, -(size // 2) - 1, -1, dtype=float)
        expected = convolve1d(x, kernel, mode="nearest")
        assert_allclose(convolve_nearest(x, kernel), expected, rtol=1e-12, atol=1e-9)
        assert np.array_equal(rolling_median(x, size), median_filter(x, size, mode="nearest"))
    else:
        with pytest.raises(ValueError, match="odd size"):
            rolling_median(x, size)


def test_rolling_median_of_nine_is_right_for_every_input():
    """The size-9 rolling median (a compare-exchange network) equals scipy's on every window
    of zeros and ones: by the 0-1 principle of comparator networks (Knuth, TAOCP vol. 3,
    5.3.4), then on every input."""
    bits = (np.arange(512)[:, None] >> np.arange(9)) & 1  # the 512 windows of 9 samples
    x = np.concatenate([np.r_[row, 5 * [0.5]] for row in bits.astype(float)])
    assert np.array_equal(rolling_median(x, 9), median_filter(x, 9, mode="nearest"))


@pytest.mark.parametrize(
    "shape", ["noise", "quantised", "constant", "sorted", "reversed", "three values", "drift"]
)
def test_median_and_deviation_equal_numpy_exactly(shape):
    """median and median_and_deviation (a selection by sampling from 256 values on) return
    np.median's values, bit for bit, for short and long arrays of forces [N] with ties, runs
    and trends; NaN for an empty array or one holding a NaN."""
    rng = np.random.default_rng(len(shape))
    for n in [1, 2, 3, 10, 255, 256, 257, 600, 1001, 1558, 4830, 9000]:
        x = 150.0 + rng.normal(size=n)
        x = {
            "noise": x,
            "quantised": np.round(x, 1),
            "constant": np.full(n, 150.0),
            "sorted": np.sort(x),
            "reversed": np.sort(x)[::-1],
            "three values": rng.integers(0, 3, n).astype(float),
            "drift": np.cumsum(x - 150.0),
        }[shape]
        centre = np.median(x)
        assert median(x) == centre
        assert median_and_deviation(x) == (centre, np.median(np.abs(x - centre)))
        assert median(x[::3]) == np.median(x[::3])  # a strided view
    assert math.isnan(median(np.array([1.0, np.nan, 2.0])))
    assert all(math.isnan(v) for v in median_and_deviation(np.zeros(0)))


def _settling_reference(force, median_window, sigma, tolerance, min_samples, spike_sigma):
    """The settling test as numpy expressions (its form before it was compiled)."""
    n = len(force)
    if n < 4 * max(min_samples, 1) or sigma <= 0:
        return 0
    w = max(median_window, n // 20) | 1
    rolling = rolling_median(force, min(median_window, max(1, n // 3)) | 1)
    residual = force - rolling
    noise = 1.4826 * median_deviation(residual)
    clean = np.where(np.abs(residual) > spike_sigma * noise, rolling, force) if noise > 0 else force
    mean = rolling_mean(clean, w)
    half = n // 2
    final = median(clean[half:])
    spread = max(1.4826 * median_deviation(mean[half:]), noise / math.sqrt(w))
    band = max(sigma * spread, tolerance * abs(final))
    outside = np.flatnonzero(np.abs(mean[:half] - final) > band)
    return min(int(outside[-1]) + 1 + w // 2, half) if outside.size else 0


def _trim_reference(force, trim_sigma, trim_floor, w, spike_sigma):
    """The cushion trimming as numpy expressions (its form before it was compiled)."""
    n = len(force)
    rolling = rolling_median(force, w)
    level = median(rolling[n // 4 : n - n // 4] if n >= 8 else rolling)
    sigma = 1.4826 * median_deviation(force)
    outside = np.abs(rolling - level) > max(trim_sigma * (sigma / math.sqrt(w)), trim_floor)
    w_long = max(w, n // 10)
    if w_long > w:
        residual = force - rolling
        noise = 1.4826 * median_deviation(residual)
        spikes = np.abs(residual) > spike_sigma * noise if noise > 0 else residual != 0
        mean = rolling_mean(np.where(spikes, rolling, force), w_long)
        outside |= np.abs(mean - level) > trim_sigma * sigma / math.sqrt(w_long)
    outside = np.flatnonzero(outside)
    before, after = outside[outside < n // 2], outside[outside >= n // 2]
    return (int(before[-1]) + 1 if before.size else 0, int(after[0]) if after.size else n)


def _longest_run(mask):
    """(start, stop) of the longest run of True (the first of equal ones), (0, 0) for none."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    if not edges.size:
        return 0, 0
    i = int(np.argmax(edges[1::2] - edges[::2]))
    return int(edges[::2][i]), int(edges[1::2][i])


@pytest.mark.parametrize("seed", range(4))
def test_compiled_window_tests_equal_their_numpy_form(seed):
    """stroke_window finds the samples the numpy expressions find (velocity settled, force
    settled, cushions trimmed), exactly, on strokes with noise, drift, settling transients,
    cushioning ramps, spikes, quantised and constant force readings [N], for several median
    sizes and sample minima."""
    rng = np.random.default_rng(seed)
    for _ in range(150):
        n = int(rng.integers(3, 2500))
        speed = 0.01 * (1.0 - np.exp(-np.arange(n) / rng.uniform(1.0, 200.0)))  # [m/s]
        velocity = speed * (1.0 + rng.normal(size=n) * rng.choice([0.001, 0.01, 0.05]))
        force = 150.0 + rng.normal(size=n) * rng.choice([0.0, 0.1, 1.0, 10.0])
        if rng.random() < 0.5:  # a settling transient or a cushion: a ramp at one end
            ramp = np.linspace(rng.choice([-1, 0]), rng.choice([0, 1]), n) ** 3
            force += rng.normal() * 20 * ramp
        if rng.random() < 0.3:
            force[rng.integers(0, n, 3)] += 150.0
        if rng.random() < 0.3:
            force = np.round(force, 1)
        size, floor = int(rng.choice([1, 3, 9, 21])), float(rng.choice([0.0, 1.0]))
        least = int(rng.choice([0, 10, 50]))
        settled = np.abs(velocity - median(velocity)) <= 0.02 * abs(median(velocity))
        start, stop = _longest_run(settled)
        cut = None
        if stop - start >= least:
            window = force[start:stop]
            first = _settling_reference(window, size, 3.0, 0.005, least, 5.0)
            kept = window[first:]
            w = min(size, max(1, len(kept) // 3) | 1)
            cut = (first, *_trim_reference(kept, 4.0, floor, w, 5.0))
        found = stroke_window(
            velocity,
            force,
            velocity_tolerance=0.02,
            min_samples=least,
            median_window=size,
            settle_sigma=3.0,
            settle_tolerance=0.005,
            trim_sigma=4.0,
            trim_floor=floor,
            spike_sigma=5.0,
        )
        assert np.array_equal(found[0], settled)
        assert found[1:] == (start, stop, cut)


def test_stroke_window_refuses_an_even_median_size():
    """An even median size reaches the trimming's rolling median: refused as that filter
    refuses it."""
    with pytest.raises(ValueError, match="odd size"):
        stroke_window(
            np.full(200, 0.01),
            np.full(200, 150.0),
            velocity_tolerance=0.02,
            min_samples=10,
            median_window=10,
            settle_sigma=3.0,
            settle_tolerance=0.005,
            trim_sigma=4.0,
            trim_floor=1.0,
            spike_sigma=5.0,
        )
