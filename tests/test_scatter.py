"""Scatter components, lack of fit and band scopes (issue 22) on synthetic tables with known
components; the real-data acceptance is tests/test_scatter_real.py."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from cylfric.identify import identify
from cylfric.identify.lack_of_fit import lack_of_fit
from cylfric.identify.scatter import residual_function, scatter_components
from cylfric.model import FrictionModel, validate


def _table(seed, sessions=8, runs=6, points=12, s_session=0.10, s_run=0.05, s_r=0.02):
    """Friction points of level 100 N with relative session, run and point scatter [-]."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(sessions):
        b = rng.normal(0, s_session)
        for k in range(runs):
            c = rng.normal(0, s_run)
            for _ in range(points):
                f = 100.0 * (1 + b + c + rng.normal(0, s_r))
                rows.append({"session": str(s), "run": s * runs + k, "friction [N]": f})
    return pd.DataFrame(rows)


def test_mixed_model_recovers_known_components():
    table = _table(seed=3, sessions=12)
    record = scatter_components(
        table, np.full(len(table), 100.0), prior={"std_percent": 10.0, "dof": 1, "basis": "test"}
    )
    c = record["components"]
    assert c["repeatability"]["std_percent"] == pytest.approx(2.0, rel=0.1)
    assert c["run"]["std_percent"] == pytest.approx(5.0, rel=0.3)
    assert c["session"]["estimated_percent"] == pytest.approx(10.0, rel=0.4)
    assert c["session"]["source"] == "estimated+prior"
    assert record["reproducibility"]["std_N"] == pytest.approx(
        np.sqrt(2**2 + 5**2 + 10**2), rel=0.3
    )


def test_one_session_takes_the_prior():
    table = _table(seed=1, sessions=1)
    record = scatter_components(table, np.full(len(table), 100.0))
    session = record["components"]["session"]
    assert session["source"] == "prior"
    assert session["prior_percent"] > 0 and session["prior_basis"]


def _points(seed, curved=False, sessions=1, runs_per_level=1):
    """Points of a one-speed campaign: level 20 + 4 p/bar N (or curved), 4 pressures."""
    rng = np.random.default_rng(seed)
    rows, run = [], 0
    for s in range(sessions):
        for bar in (10, 30, 50, 70, 90):
            for _ in range(runs_per_level):
                level = 20 + 0.4 * bar + (0.004 * (bar - 50) ** 2 if curved else 0.0)
                level *= 1 + rng.normal(0, 0.01)
                for d in (1, -1):
                    for _ in range(8):
                        rows.append(
                            {
                                "velocity [m/s]": 0.01 * d,
                                "pressure [Pa]": bar * 1e5,
                                "friction [N]": level * (1 + rng.normal(0, 0.02)),
                                "direction [-]": d,
                                "flag": "ok",
                                "run": run,
                                "session": str(s),
                            }
                        )
                run += 1
    return pd.DataFrame(rows)


def _identify(points):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(points, sensitivity=False)


def test_lack_of_fit_sees_a_curve_and_rarely_a_line():
    curved = [_identify(_points(seed, curved=True)).model.lack_of_fit for seed in range(3)]
    assert all(t["significant"] and t["test"] == "pure-error F" for t in curved)
    alarms = [
        lack_of_fit(p, rng.normal(0, 1, len(p)), 2)["significant"]
        for p, rng in ((_points(seed), np.random.default_rng(seed)) for seed in range(20))
    ]
    assert sum(alarms) <= 4  # 5 % expected; 4 of 20 has probability < 2 %


def test_runs_test_without_replicates():
    x = np.arange(1.0, 41.0) * 1e5  # 40 pressure levels, one point each [Pa]
    curve = 1e-12 * (x - 20e5) ** 2 - 1.3  # residuals of a straight law to a parabola [N]
    points = pd.DataFrame(
        {"pressure [Pa]": x, "velocity [m/s]": 0.01, "friction [N]": 10 + x / 1e5 + curve}
    )
    result = lack_of_fit(points, curve, 2)
    assert result["test"].startswith("Wald-Wolfowitz") and result["significant"]


def test_scopes_ordered_and_round_trip_through_the_datasheet():
    model = _identify(_points(0, sessions=2, runs_per_level=2)).model
    v, p = np.full(5, 0.01), np.linspace(10e5, 90e5, 5)
    widths = [
        np.subtract(*model.prediction_band(v, p, scope=s)[::-1])
        for s in ("point", "run", "session")
    ]
    assert np.all(widths[0] <= widths[1] + 1e-12) and np.all(widths[1] <= widths[2] + 1e-12)
    sheet = model.to_datasheet()
    validate(sheet)
    assert sheet["fit"]["scatter"]["components"]["session"]["source"] == "estimated+prior"
    assert "lack_of_fit" in sheet["quality"]
    back = FrictionModel.from_datasheet(sheet)
    assert back.scatter == model.scatter and back.lack_of_fit == model.lack_of_fit
    np.testing.assert_allclose(
        back.prediction_band(v, p, scope="session"), model.prediction_band(v, p, scope="session")
    )


def test_old_datasheet_loads_and_refuses_the_wider_scopes():
    model = _identify(_points(1)).model
    sheet = model.to_datasheet()
    del sheet["fit"]["scatter"], sheet["quality"]  # a datasheet of an older cylfric
    old = FrictionModel.from_datasheet(validate(sheet))
    assert old.scatter is None and old.lack_of_fit is None
    old.prediction_band(0.01, 5e6)  # scope "point" as before
    with pytest.raises(ValueError, match="needs the scatter components"):
        old.prediction_band(0.01, 5e6, scope="session")
    with pytest.raises(ValueError, match="unknown band scope"):
        old.prediction_band(0.01, 5e6, scope="day")


def test_the_runs_test_equals_statsmodels():
    """lack_of_fit.runs_test: the textbook Wald-Wolfowitz test (imports no statsmodels into a
    fit) gives statsmodels' runstest_1samp(x, cutoff=0, correction=True) to rounding."""
    from statsmodels.sandbox.stats.runs import runstest_1samp

    from cylfric.identify.lack_of_fit import runs_test

    rng = np.random.default_rng(0)
    for n in (10, 11, 49, 50, 51, 200):
        for curved in (False, True):
            x = rng.normal(size=n) + (3 * np.linspace(-1, 1, n) ** 2 - 1 if curved else 0)
            expected = runstest_1samp(x, cutoff=0.0, correction=True)
            assert runs_test(x) == pytest.approx(expected, rel=1e-12, abs=1e-15)
    assert runs_test(np.ones(12)) == pytest.approx(runstest_1samp(np.ones(12), cutoff=0.0))


def test_one_session_anova_equals_reml_on_balanced_runs():
    """One session: the ISO 5725-2 one-way analysis of variance of the runs gives what
    statsmodels' REML gives on balanced runs (and needs neither statsmodels nor iterations)."""
    from statsmodels.regression.mixed_linear_model import MixedLM

    from cylfric.identify.scatter import _one_way

    rng = np.random.default_rng(4)
    runs = np.repeat(np.arange(12), 8)
    r = rng.normal(0, 0.05, 12)[runs] + rng.normal(0, 0.02, runs.size)
    table = pd.DataFrame({"r": r, "run": runs.astype(str), "session": "s"})
    _, run_var, repeat_var = _one_way(table)
    fit = MixedLM(r, np.ones((r.size, 1)), groups=runs).fit(reml=True)
    assert run_var == pytest.approx(float(np.asarray(fit.cov_re)[0, 0]), rel=1e-3)  # REML iterates
    assert repeat_var == pytest.approx(float(fit.scale), rel=1e-3)


def test_same_mount_bands_use_the_model_based_covariance_and_their_own_dof():
    """Scopes point and run: the mean's term is the model-based covariance (new data of the
    same mount share its effects) and the quantile the residual variance's (both scales come
    from the same residuals), not the session prior's; session: the cluster-robust one."""
    rng = np.random.default_rng(2)
    rows = []
    for run, (bar, mm_s) in enumerate(
        (b, v) for b in (10, 40, 70, 100) for v in (1, 3, 10, 30, 100)
    ):
        scale = 1 + rng.normal(0, 0.05)  # the run's level
        level = (30 + 0.4 * bar) * (1 + 0.5 * np.exp(-mm_s / 10)) + 2.0 * mm_s
        for d in (1, -1):
            rows.append(
                {
                    "velocity [m/s]": d * mm_s * 1e-3,
                    "pressure [Pa]": bar * 1e5,
                    "friction [N]": level * scale * (1 + rng.normal(0, 0.01)),
                    "direction [-]": d,
                    "flag": "ok",
                    "run": run,
                    "session": "1",
                }
            )
    model = _identify(pd.DataFrame(rows)).model
    assert model.covariance_nonrobust is not None
    assert model.covariance_nonrobust[0] == model.covariance[0]
    v, p = np.full(3, 0.01), np.array([20e5, 50e5, 80e5])
    robust = model.standard_error(v, p)
    nonrobust = model.standard_error(v, p, robust=False)
    assert not np.allclose(robust, nonrobust)
    # the point band by hand: the internally studentised residual's 95 % quantile with
    # the residual variance's dof nu, sqrt(nu B^-1(0.95; 1/2, (nu-1)/2)), x sqrt(se_model^2 +
    # s_res^2); nu the Satterthwaite dof of the nested strata (the runs share their levels)
    from scipy import stats

    n_dof = model.scatter["residual_variance"]["dof"]
    assert 4 < n_dof < model.statistics["n_points"] - model.statistics["n_variables"]
    # s(F): the residual variance function at each level (its mean over the points: s_res^2)
    shape = model.scatter["residual_function"]
    f = model.friction(v, p)
    s_f = np.sqrt(shape["absolute_std_N"] ** 2 + (shape["relative_std_percent"] / 100 * f) ** 2)
    np.testing.assert_allclose(model.residual_scale(v, p), s_f, rtol=1e-12)
    low, high = model.prediction_band(v, p, scope="point")
    quantile = np.sqrt(n_dof * stats.beta.ppf(0.95, 0.5, (n_dof - 1) / 2))
    assert 1.9 < quantile < stats.norm.ppf(0.975) < stats.t.ppf(0.975, n_dof)
    expected = quantile * np.sqrt(nonrobust**2 + s_f**2)
    np.testing.assert_allclose(0.5 * (high - low), expected, rtol=1e-9)
    # the session band: Student-t with the cluster-robust se (a new mount shares nothing)
    assert np.all(np.subtract(*model.prediction_band(v, p, scope="session")[::-1]) > (high - low))
    # without the model-based covariance (an older datasheet) the robust one serves
    sheet = model.to_datasheet()
    assert validate(sheet)["fit"]["covariance_nonrobust"]["names"] == list(model.covariance[0])
    back = FrictionModel.from_datasheet(sheet)
    np.testing.assert_allclose(
        back.prediction_band(v, p, scope="run"), model.prediction_band(v, p, scope="run")
    )
    del sheet["fit"]["covariance_nonrobust"]
    old = FrictionModel.from_datasheet(validate(sheet))
    assert old.covariance_nonrobust is None
    np.testing.assert_allclose(old.standard_error(v, p, robust=False), robust)
    # the run band: the same quantile on sqrt(se_model^2 + max(s(F)^2, F^2 (s_r^2 + s_run^2)))
    from cylfric.model.core import _band_parts

    part = _band_parts(model.scatter, "run")
    assert part["between_dof"] == model.scatter["components"]["run"]["dof"]
    relative = f**2 * (part["repeat"] ** 2 + part["between"] ** 2)
    low_run, high_run = model.prediction_band(v, p, scope="run")
    np.testing.assert_allclose(
        0.5 * (high_run - low_run),
        quantile * np.sqrt(nonrobust**2 + np.maximum(s_f**2, relative)),
        rtol=1e-9,
    )
    session = _band_parts(model.scatter, "session")
    assert session["between_dof"] == model.scatter["components"]["session"]["dof"]
    # one session: s_L^2 + (s_L^2 - s_run^2) / 1 (the fitted curve carries the session's
    # shared offset, not its run-to-run scatter)
    s_l = model.scatter["components"]["session"]["between_percent"] / 100
    s_run = model.scatter["components"]["run"]["std_percent"] / 100
    assert model.scatter["sessions"] == 1
    assert session["between"] == pytest.approx(np.sqrt(2 * s_l**2 - s_run**2), rel=1e-12)
    # replacing the covariance drops the model-based one (it belongs to the fit)
    assert model.replace(covariance=model.covariance).covariance_nonrobust is None


def test_a_model_based_covariance_that_does_not_match_is_refused():
    names = ("F_c",)
    with pytest.raises(ValueError, match="covariance_nonrobust needs a covariance with the same"):
        FrictionModel(
            {"F_c": 50.0, "F_s": 60.0, "sigma_2": 0.0, "v_r": 0.01, "alpha": 1.0},
            pressure_law="constant",
            covariance_nonrobust=(names, np.eye(1)),
        )
    with pytest.raises(ValueError, match="covariance_nonrobust has non-finite values"):
        FrictionModel(
            {"F_c": 50.0, "F_s": 60.0, "sigma_2": 0.0, "v_r": 0.01, "alpha": 1.0},
            pressure_law="constant",
            covariance=(names, np.eye(1)),
            covariance_nonrobust=(names, np.full((1, 1), np.nan)),
        )


def _strata_design(seed, sessions=2, levels=4, runs=3, points=4):
    """A nested design (session > pressure level > run > point) with a weighted straight line
    in pressure fitted to it: (points table, residuals [N], jacobian, sigma [N])."""
    rng = np.random.default_rng(seed)
    rows = []
    for s in range(sessions):
        for level in range(levels):
            for k in range(runs):
                for _ in range(points):
                    rows.append({"session": str(s), "level": level, "run": f"{level}-{k}"})
    table = pd.DataFrame(rows)
    bar = 10.0 + 30.0 * table["level"].to_numpy(float)
    jacobian = np.column_stack([np.ones(len(table)), bar])
    sigma = rng.uniform(0.5, 2.0, len(table))
    y = rng.normal(0.0, 1.0, len(table))
    w = 1.0 / sigma**2
    coef = np.linalg.solve(jacobian.T @ (jacobian * w[:, None]), jacobian.T @ (w * y))
    return table, y - jacobian @ coef, jacobian, sigma


def test_residual_strata_match_the_projectors_and_split_the_residual_sum_of_squares():
    """Each stratum's SS and dof against dense projectors: P the nested group means, H the
    weighted hat matrix, d_s = tr(P_s (I - H)); the SS add up to the RSS and the dof to
    N - p (a run named alike in two levels is two runs)."""
    from cylfric.identify.scatter import residual_strata

    table, r, jac, sigma = _strata_design(5)
    record = residual_strata(table, r, jac, sigma)
    n = len(r)
    w = np.diag(1.0 / sigma**2)
    hat = jac @ np.linalg.solve(jac.T @ w @ jac, jac.T @ w)

    def means(keys):
        _, index = np.unique(keys, return_inverse=True)
        z = np.eye(index.max() + 1)[index]
        return z @ np.diag(1.0 / z.sum(0)) @ z.T

    session = table["session"].to_numpy(str)
    block = np.char.add(session, table["level"].to_numpy(str))
    run = np.char.add(np.char.add(block, "/"), table["run"].to_numpy(str))
    nested = [means(session), means(block), means(run), np.eye(n)]
    parts = [nested[0]] + [b - a for a, b in zip(nested, nested[1:], strict=False)]
    names = [s["name"] for s in record["strata"]]
    assert names == ["session", "pressure block", "run", "point"]
    for stratum, projector in zip(record["strata"], parts, strict=True):
        assert stratum["sum_of_squares_N2"] == pytest.approx(r @ projector @ r, rel=1e-9)
        assert stratum["dof"] == pytest.approx(np.trace(projector @ (np.eye(n) - hat)), abs=1e-9)
    assert sum(s["sum_of_squares_N2"] for s in record["strata"]) == pytest.approx(r @ r)
    assert sum(s["dof"] for s in record["strata"]) == pytest.approx(n - 2)
    # Satterthwaite's dof of the strata that have dof
    used = [(s["sum_of_squares_N2"], s["dof"]) for s in record["strata"] if s["dof"] > 0.5]
    expected = sum(a for a, _ in used) ** 2 / sum(a**2 / d for a, d in used)
    assert record["dof"] == pytest.approx(expected, rel=1e-12)


def test_residual_dof_is_the_dominant_stratum_s_when_one_carries_the_scatter():
    """Residuals that are pressure-block offsets alone (every run of a level off by the same
    amount) have the block stratum's dof, not N - p: 2 sessions x 4 levels - 2 = 6."""
    from cylfric.identify.scatter import residual_strata

    table, _, jac, _ = _strata_design(6)
    offsets = np.random.default_rng(1).normal(0, 5.0, 8)
    block = table["session"].astype(int).to_numpy() * 4 + table["level"].to_numpy()
    y = offsets[block]
    coef, *_ = np.linalg.lstsq(jac, y, rcond=None)
    record = residual_strata(table, y - jac @ coef, jac)
    d = {s["name"]: s["dof"] for s in record["strata"]}
    assert d["session"] + d["pressure block"] == pytest.approx(8 - 2)
    ss = {s["name"]: s["sum_of_squares_N2"] for s in record["strata"]}
    assert ss["run"] == pytest.approx(0.0, abs=1e-9) and ss["point"] == pytest.approx(0, abs=1e-9)
    assert 1.0 < record["dof"] <= 6.0 + 1e-9
    assert record["dof"] < len(y) - 2


def test_residual_strata_of_a_campaign_without_sessions_are_one_session():
    """No session said (None in every row, or no column): one session, as a label would."""
    from cylfric.identify.scatter import residual_strata

    table, r, jac, sigma = _strata_design(7, sessions=1)
    said = residual_strata(table, r, jac, sigma)
    for unsaid in (table.assign(session=None), table.drop(columns="session")):
        record = residual_strata(unsaid, r, jac, sigma)
        assert record["dof"] == pytest.approx(said["dof"], rel=1e-12)
        assert [s["dof"] for s in record["strata"]] == pytest.approx(
            [s["dof"] for s in said["strata"]]
        )


@pytest.mark.parametrize(("absolute", "relative"), [(2.0, 0.05), (0.0, 0.08), (3.0, 0.0)])
def test_residual_function_recovers_two_components_and_keeps_the_mean_square(absolute, relative):
    """s(F)^2 = s_a^2 + (s_b F)^2 by moments: both components recovered from residuals drawn
    with them (and one drawn at 0 found near 0); the function's mean over the points is the
    residual variance RSS / (N - p) whatever the case."""
    rng = np.random.default_rng(7)
    force = rng.uniform(10.0, 200.0, 40_000)  # fitted friction [N]
    e = rng.normal(0.0, np.sqrt(absolute**2 + (relative * force) ** 2))
    shape = residual_function(force, e, n_parameters=6)
    a, b = shape["absolute_std_N"], shape["relative_std_percent"] / 100
    assert a == pytest.approx(absolute, abs=0.06 * max(absolute, 1.0))
    assert b == pytest.approx(relative, abs=0.005)
    np.testing.assert_allclose(np.mean(a**2 + (b * force) ** 2), e @ e / (e.size - 6), rtol=1e-9)


def test_residual_function_clips_a_negative_component_and_keeps_the_mean_square():
    """Scatter growing faster than the level (e ~ F^1.5) gives a negative absolute part:
    relative only; scatter shrinking with it (e ~ F^-0.5) a negative relative part: absolute
    only; the mean over the points stays RSS / (N - p)."""
    force = np.linspace(10.0, 200.0, 400)
    sign = np.where(np.arange(400) % 2, 1.0, -1.0)
    for power, components in ((1.5, "relative only"), (-0.5, "absolute only")):
        e = sign * 0.01 * force**power
        shape = residual_function(force, e, n_parameters=3)
        a, b = shape["absolute_std_N"], shape["relative_std_percent"] / 100
        assert (
            shape["components"] == components
            and (a == 0.0) == (power > 0)
            and (b == 0.0) == (power < 0)
        )
        np.testing.assert_allclose(np.mean(a**2 + (b * force) ** 2), e @ e / 397, rtol=1e-12)


def test_residual_function_of_one_level_is_the_residual_std():
    e = np.random.default_rng(3).normal(0, 1.5, 50)
    shape = residual_function(np.full(50, 80.0), e, n_parameters=2)
    assert shape["components"] == "absolute only" and shape["relative_std_percent"] == 0.0
    assert shape["absolute_std_N"] == pytest.approx(np.sqrt(e @ e / 48), rel=1e-12)
    assert residual_function(np.ones(2), np.ones(2), n_parameters=2) is None


def test_point_band_follows_the_level_of_relative_scatter():
    """Relative scatter: the point band at the lowest pressure is narrower than at the
    highest, by about the levels' ratio; an older datasheet without the record keeps one
    s_res for every level."""
    model = _identify(_points(4, sessions=1, runs_per_level=3)).model
    assert model.scatter["residual_function"]["relative_std_percent"] > 0
    v, p = np.full(2, 0.01), np.array([10e5, 90e5])
    scale = model.residual_scale(v, p)
    level = model.friction(v, p)
    assert scale[0] < scale[1] and scale[1] / scale[0] <= level[1] / level[0] + 1e-9
    sheet = model.to_datasheet()
    validate(sheet)
    assert (
        FrictionModel.from_datasheet(sheet).scatter["residual_function"]
        == (model.scatter["residual_function"])
    )
    del sheet["fit"]["scatter"]["residual_function"]  # an earlier cylfric's datasheet
    old = FrictionModel.from_datasheet(validate(sheet))
    np.testing.assert_allclose(old.residual_scale(v, p), model.statistics["residual_std"])
    half = np.subtract(*model.prediction_band(v, p)[::-1])
    half_old = np.subtract(*old.prediction_band(v, p)[::-1])
    assert half[0] < half_old[0] and half[1] > half_old[1]


def test_a_scaled_model_scales_its_residual_scatter_at_every_level():
    """catalog.scale_model multiplies the forces by k: the residual scatter s(F) at every
    operating point is k times the tested model's (its absolute part in N scaled, its
    relative part kept)."""
    from cylfric.catalog import scale_model

    model = _identify(_points(5, sessions=1, runs_per_level=3)).model
    v, p = np.full(3, 0.01), np.array([10e5, 50e5, 90e5])
    scaled = scale_model(model, 1.7)
    np.testing.assert_allclose(scaled.friction(v, p), 1.7 * model.friction(v, p), rtol=1e-12)
    np.testing.assert_allclose(
        scaled.residual_scale(v, p), 1.7 * model.residual_scale(v, p), rtol=1e-12
    )
    shape = scaled.scatter["residual_function"]
    assert (
        shape["relative_std_percent"] == model.scatter["residual_function"]["relative_std_percent"]
    )


def test_strata_groups_are_those_of_the_labels_text():
    """The points are grouped by their labels' text (as str(v)), the integer columns by value
    without a string per point: the same groups, numbered as first seen."""
    import pandas as pd

    from cylfric.identify.scatter import _label_codes, _nested

    big = 2**53
    points = pd.DataFrame(
        {
            "run": pd.array([big, big + 1, None, big + 1, 3], dtype="Int64"),  # NA: "<NA>"
            "level": np.array([0, 0, 1, 1, 0]),
            "session": [None, float("nan"), "A", "A", 1],  # "None", "nan", "A", "A", "1"
        }
    )
    assert list(_label_codes(points, "run")) == [0, 1, 2, 1, 3]  # not merged as floats
    assert list(_label_codes(points, "level")) == [0, 0, 1, 1, 0]
    assert list(_label_codes(points, "session")) == [0, 1, 2, 2, 3]
    assert list(_label_codes(points, "missing")) == [0] * 5
    block = _nested(_label_codes(points, "session"), _label_codes(points, "level"))
    assert list(block) == [0, 1, 2, 2, 3]
