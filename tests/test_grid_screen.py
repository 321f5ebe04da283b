"""The (v_r, alpha) grids screened all at once (identify.stribeck_fit.grid_rss).

Identities: the screened residual sums of squares equal the node-by-node solve of
:func:`solve_linear` on :func:`design_columns` to rounding; the grid start of the surface
fits and the sensitivity study's minimum equal those of the node-by-node search bit for bit
(the nodes near the minimum are solved again); designs the projection cannot trust are
flagged, not guessed.
"""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose, assert_array_equal

from cylfric.friction import stribeck
from cylfric.identify.pressure_fit import _grid_start
from cylfric.identify.sensitivity import rmse_at, sensitivity_grid
from cylfric.identify.stribeck_fit import design_columns, grid_rss, solve_linear


def _points(seed=7, pressures=(10.0, 50.0, 100.0, 150.0)):
    """Speeds [m/s], pressures [bar], friction [N] of a Stribeck surface with noise."""
    rng = np.random.default_rng(seed)
    speed = np.tile(np.array([1, 2, 3, 5, 8, 12, 20, 40, 80]) * 1e-3, 2 * len(pressures))
    p_bar = np.repeat(np.asarray(pressures), speed.size // len(pressures))
    speed = speed * rng.uniform(0.97, 1.03, speed.size)
    force = stribeck(speed, 60 + 0.4 * p_bar, 95 + 0.6 * p_bar, 0.006, 900 + 2 * p_bar, alpha=1.3)
    return speed, p_bar, force + rng.normal(0, 1.5, speed.size)


def _exact_rss(speed, p_bar, force, v_r, alpha):
    a = design_columns(speed, p_bar, v_r, alpha)
    return float(np.sum((a @ solve_linear(a, force) - force) ** 2))


def _grid():
    v_rs = np.geomspace(5e-4, 0.08, 25)
    alphas = np.linspace(0.4, 3.0, 14)
    return [(v, a) for v in v_rs for a in alphas]


def test_screened_rss_equals_the_node_by_node_solve():
    speed, p_bar, force = _points()
    nodes = _grid()
    rss, trusted = grid_rss(speed, p_bar, force, [v for v, _ in nodes], [a for _, a in nodes])
    assert trusted.all()
    exact = [_exact_rss(speed, p_bar, force, v, a) for v, a in nodes]
    assert_allclose(rss, exact, rtol=1e-11)


def test_grid_start_is_the_node_by_node_search_bit_for_bit():
    speed, p_bar, force = _points()
    v_rs, alphas = np.geomspace(5e-4, 0.08, 25), np.linspace(0.4, 3.0, 14)
    best = (np.inf, None)
    for v_r in v_rs:  # the search as it was: every node solved, the first smallest kept
        for alpha in alphas:
            a = design_columns(speed, p_bar, v_r, alpha)
            coef = solve_linear(a, force)
            rss = float(np.sum((a @ coef - force) ** 2))
            if rss < best[0]:
                best = (rss, (coef, v_r, alpha))
    coef, v_r, alpha = _grid_start(speed, p_bar, force, v_rs, alphas)
    assert_array_equal(coef, best[1][0])
    assert (v_r, alpha) == best[1][1:]


def test_sensitivity_minimum_and_table_match_rmse_at():
    speed, p_bar, force = _points(seed=11)
    table, recommended = sensitivity_grid(speed, p_bar * 1e5, force)
    exact = [
        rmse_at(speed, p_bar * 1e5, force, v, a)
        for a, v in zip(table["alpha [-]"], table["v_r [m/s]"], strict=True)
    ]
    assert_allclose(table["rmse [N]"], exact, rtol=1e-11)
    best = int(np.argmin(exact))  # the node-by-node minimum, which starts the refinement
    assert table["rmse [N]"].iloc[best] == exact[best]
    assert int(table["rmse [N]"].idxmin()) == best
    assert recommended["rmse"] <= exact[best]


def test_designs_the_projection_cannot_trust_are_flagged():
    speed, p_bar, force = _points()
    one = np.full_like(p_bar, 50.0)  # a single pressure: the fixed columns are collinear
    rss, trusted = grid_rss(speed, one, force, [0.006, 0.01], [1.0, 1.3])
    assert not trusted.any() and np.isnan(rss).all()
    # v_r far below every speed: e underflows to 0, the node's columns vanish
    rss, trusted = grid_rss(speed, p_bar, force, [1e-9, 0.006], [3.0, 1.3])
    assert_array_equal(trusted, [False, True])
    assert_allclose(rss[1], _exact_rss(speed, p_bar, force, 0.006, 1.3), rtol=1e-11)
