"""The report's cost stays bounded at thousands of runs (issue 27): above POINTS_DRAWN points
a figure draws bin means, not one marker per point."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from numpy.testing import assert_allclose

from cylfric.report.figures import POINTS_DRAWN, _plot_points, figure_directions, render


def _points(n, seed=0):
    """A points table of n windows: 4 pressures, speeds 1-135 mm/s, both directions."""
    rng = np.random.default_rng(seed)
    speed = rng.choice([1, 2, 5, 10, 20, 50, 135], n) * 1e-3
    direction = rng.choice([-1, 1], n)
    pressure = rng.choice([1e6, 5e6, 1e7, 1.5e7], n)
    force = direction * (100 + pressure * 1e-5 + rng.normal(0, 2, n)) + 17.8
    return pd.DataFrame(
        {
            "velocity [m/s]": direction * speed,
            "force [N]": force,
            "pressure [Pa]": pressure,
            "direction [-]": direction,
            "flag": "ok",
        }
    )


def test_binned_points_are_the_bin_means_with_their_spread():
    x = np.repeat([1.0, 10.0, 100.0], 50)
    y = np.arange(x.size, dtype=float)
    fig, ax = plt.subplots()
    _plot_points(ax, x, y, "o", binned=True)
    (line,) = ax.lines
    assert_allclose(line.get_xdata(), [1.0, 10.0, 100.0])
    assert_allclose(line.get_ydata(), [y[:50].mean(), y[50:100].mean(), y[100:].mean()])
    (bars,) = ax.collections  # the error bars: one segment per bin, +- the s.d.
    half = [(seg[1, 1] - seg[0, 1]) / 2 for seg in bars.get_segments()]
    assert_allclose(half, [y[:50].std()] * 3)
    plt.close(fig)


def test_a_large_campaign_draws_no_more_markers_than_a_small_one():
    small, large = _points(POINTS_DRAWN // 2), _points(20 * POINTS_DRAWN)

    def markers(points):
        fig = figure_directions(points, offset=17.8)
        n = sum(len(line.get_xdata()) for ax in fig.axes for line in ax.lines)
        svg = len(render(fig)[1])
        return n, svg

    n_small, svg_small = markers(small)
    n_large, svg_large = markers(large)
    assert n_small == len(small)  # small: every point drawn
    assert n_large <= n_small  # large: bin means only (7 speeds x 4 pressures x 2 directions)
    assert svg_large < 2 * svg_small
