"""Session bands that respect how little a few sessions know (issue 39.8): the estimate of the
between-session scatter from n sessions counts n - 1 degrees of freedom against the prior's,
the datasheet says which kinds of session the band has seen, and the fitted curve carries
its runs' offsets where its covariance does not. Real data: tests/test_scatter_real.py
(leave sessions out) and test_session_band_real below."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

from cylfric.identify.scatter import scatter_components, session_kinds
from cylfric.model import FrictionModel
from cylfric.model.core import level_offset_covariance

PRIOR = {"std_percent": 14.0, "dof": 8, "basis": "test"}


def _sessions(n, *, spread=0.0, s_run=0.03, s_r=0.01, seed=0, kinds=None):
    """Points of ``n`` sessions x 4 pressure levels x 6 strokes at 100 N, each session's
    relative offset ``spread`` x (its index - the middle): sessions that agree (spread 0) or
    not; run offsets ``s_run``, stroke scatter ``s_r``; ``kinds`` a session_kind per session."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(n):
        b = spread * (s - (n - 1) / 2)
        for level in range(4):
            c = rng.normal(0, s_run)
            for _ in range(6):
                row = {
                    "session": f"day{s}",
                    "run": f"{s}-{level}",
                    "level": level,
                    "pressure [Pa]": 1e5 * (1 + 2 * level),
                    "friction [N]": 100.0 * (1 + b + c + rng.normal(0, s_r)),
                }
                if kinds is not None:
                    row["session_kind"] = kinds[s]
                rows.append(row)
    return pd.DataFrame(rows)


@pytest.mark.parametrize("n", [2, 3])
def test_agreeing_sessions_count_n_minus_1_dof_against_the_prior(n):
    # on main the estimate took the Satterthwaite dof of its run component too (12 runs:
    # about 9), and three agreeing sessions pulled s_L to 12.9 % on the real O-ring
    table = _sessions(n, seed=n)
    record = scatter_components(table, np.full(len(table), 100.0), prior=PRIOR)
    c = record["components"]
    estimate = (c["session"]["estimated_percent"] ** 2 + c["run"]["std_percent"] ** 2) / 1e4
    pooled = (8 * 0.14**2 + (n - 1) * estimate) / (8 + n - 1)  # scaled-inverse-chi-square
    assert c["session"]["dof"] == 8 + n - 1
    assert_allclose((c["session"]["between_percent"] / 100) ** 2, pooled, rtol=1e-9)
    # agreeing sessions (about 3 % apart) move the prior by their weight only
    assert c["session"]["between_percent"] >= 14.0 * np.sqrt(8 / (8 + n - 1)) - 1e-9
    assert record["session_names"] == [f"day{s}" for s in range(n)]


def test_many_sessions_let_the_estimate_decide():
    table = _sessions(40, spread=0.005, seed=5)  # 40 sessions 0.5 % apart in a row: s.d. 5.8 %
    record = scatter_components(table, np.full(len(table), 100.0), prior=PRIOR)
    session = record["components"]["session"]
    assert session["dof"] == 8 + 39
    assert session["between_percent"] < 9.0  # far below the 14 % prior


def test_the_datasheet_says_which_kinds_of_session_the_band_has_seen():
    table = _sessions(3, kinds=["rerun", "Re-run", "reconnected"])
    record = scatter_components(table, np.full(len(table), 100.0), prior=PRIOR)
    assert record["session_kinds"] == {
        "sessions": {"rerun": 2, "reconnect": 1},
        "seen": ["rerun", "reconnect"],
    }
    from cylfric.identify.scatter import scatter_note

    assert "seen sessions of kind rerun (2), reconnect (1)" in scatter_note(record)
    unstated = session_kinds(_sessions(2))
    assert unstated == {"sessions": {"unstated": 2}, "seen": []}
    with pytest.raises(
        ValueError, match="session 'day1': session_kind 'tuesday' is unknown; valid"
    ):
        session_kinds(_sessions(2, kinds=["rerun", "tuesday"]))
    mixed = _sessions(2, kinds=["rerun", "remount"])
    mixed.loc[mixed.index[-1], "session_kind"] = "rig"
    with pytest.raises(ValueError, match="session 'day1'.*one kind per session"):
        session_kinds(mixed)


def test_session_kind_column_of_the_manifest_reaches_the_datasheet(tmp_path):
    from cylfric.identify import identify
    from cylfric.identify.steady import with_uncertainty
    from cylfric.simulate.bench import BenchSettings, generate_campaign
    from cylfric.steady_state import extract_campaign

    settings = BenchSettings(pressures_bar=(20, 60), speeds_mm_s=(5.0, 20.0), seed=2, sessions=2)
    generate_campaign(tmp_path / "c", settings)
    manifest = pd.read_csv(tmp_path / "c" / "manifest.csv")
    manifest["session_kind"] = manifest["session"].map({"s1": "remount", "s2": "rig"})
    manifest.to_csv(tmp_path / "c" / "manifest.csv", index=False)
    points = extract_campaign(tmp_path / "c").points
    assert set(points["session_kind"].dropna()) == {"remount", "rig"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ident = with_uncertainty(identify(points[points["flag"].eq("ok")]))
    kinds = ident.model.scatter["session_kinds"]
    assert kinds == {"sessions": {"remount": 1, "rig": 1}, "seen": ["remount", "rig"]}


def _coulomb_model(levels_bar, runs, *, run=0.18, session=0.0, sessions=1):
    """F_c = 3.6 + 0.56 p/bar N (the O-ring257 session 1 law), a Coulomb law with a made-up
    model-based covariance (no runs' influence) and a scatter record of its levels."""
    base = FrictionModel(
        {
            "F_c": {"law": "linear", "intercept": 3.6, "slope": 0.56e-5},
            "F_s": None,
            "sigma_2": None,
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb",
        validity={
            "pressure_min": 1e5,
            "pressure_max": 7e5,
            "velocity_min": 0.007,
            "velocity_max": 0.016,
        },
    )
    names = ["F_c.intercept", "F_c.slope"]
    covariance = np.diag([0.05, 2.7e-13])
    scatter = {
        "sessions": sessions,
        "components": {
            "repeatability": {"std_percent": 6.0, "dof": 75},
            "run": {"std_percent": 100 * run, "dof": 2},
            "session": {"std_percent": 100 * session, "dof": 8, "between_percent": 100 * run},
        },
        "levels": {"pressure_Pa": [1e5 * b for b in levels_bar], "runs": runs},
    }
    return base.replace(
        covariance=(names, covariance),
        covariance_nonrobust=(names, covariance),
        statistics={"dof": 77, "residual_std": 1.0, "n_points": 79, "n_variables": 2},
        record={"fit": {"scatter": scatter}},
    )


def test_level_offsets_through_the_law_equal_least_squares_weights():
    # a second formulation: the straight line through the level means by ordinary least
    # squares, y_hat(p) = sum_i w_i(p) y_i with w = x(p)^T (X^T X)^-1 X^T; an offset b_i of
    # level i (s.d. run / sqrt(runs_i), a session's s shared by all) moves it by F_i b_i
    levels, runs = np.array([1.0, 3.0, 5.0, 7.0]), np.array([3, 3, 2, 3])
    model = _coulomb_model(levels, list(runs))
    run, session, sessions = 0.12, 0.07, 3
    covariance = level_offset_covariance(model, run=run, session=session, sessions=sessions)
    design = np.column_stack([np.ones(4), levels * 1e5])
    level_force = 3.6 + 0.56 * levels
    sigma = np.diag(run**2 / runs) + session**2 / sessions
    for bar in (0.5, 2.0, 4.0, 7.0):
        x = np.array([1.0, bar * 1e5])
        w = x @ np.linalg.solve(design.T @ design, design.T)
        expected = (w * level_force) @ sigma @ (w * level_force)
        jac = model._jacobian(np.array([0.01]), np.array([bar * 1e5]))[0]
        assert_allclose(jac @ covariance @ jac, expected, rtol=1e-6)


def test_a_covariance_without_the_runs_still_widens_the_session_band_by_their_offsets():
    # O-ring257 session 1: four files, one per pressure, 18 % run scatter; its covariance
    # treats the 79 points as independent (se 2-5 % of the level); on main the session band
    # was blind to the runs' share of the curve
    model = _coulomb_model([1, 3, 5, 7], [1, 1, 1, 1])
    p, v = np.array([1e5, 4e5, 7e5]), np.full(3, 0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        low, high = model.prediction_band(v, p, scope="session")
        bare = model.replace(record={"fit": {"scatter": {**model.scatter, "levels": None}}})
        low0, high0 = bare.prediction_band(v, p, scope="session")
    force = model.friction(v, p)
    runs_se = force * 0.18 * np.sqrt(np.array([0.7, 0.25, 0.7]))  # leverage of 4 levels
    assert np.all(high - low > high0 - low0)
    # the runs' share is the curve's standard error now: at least the quantile x that
    assert np.all(0.5 * (high - low) >= 1.96 * np.hypot(runs_se, force * 0.18))
