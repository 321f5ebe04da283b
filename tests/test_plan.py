"""The standard test plan (issue 15): D-optimal design, predicted uncertainty, test sheet.

The acceptance test runs the plan's points on the virtual bench over 40 seeds and compares
the spread of the refitted coefficients with the plan's predicted standard errors.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.identify.stribeck_fit import design_columns
from cylfric.model import FrictionModel
from cylfric.plan import (
    WindowNoise,
    compare,
    d_optimal,
    grid_uncertainty,
    make_plan,
    predicted_uncertainty,
)
from cylfric.simulate.bench import BenchSettings, generate_campaign, run_plan
from cylfric.simulate.plant import Cylinder

# a flat noise model: every window's mean friction known to 0.05 N [N]
FLAT = WindowNoise((1e-3, 0.2), (0.05, 0.05), "flat")


def test_d_optimal_puts_a_straight_line_at_the_ends():
    """Textbook result: for y = a + b x on [-1, 1] the D-optimal exact design of 2m runs
    puts m runs at each end (Atkinson, Donev & Tobias, Optimum Experimental Designs, ch. 9)."""
    x = np.linspace(-1, 1, 21)
    rows = np.column_stack([np.ones_like(x), x])
    design = d_optimal(rows, 6, max_repeats=3)
    assert sorted(x[design]) == [-1, -1, -1, 1, 1, 1]
    quadratic = np.column_stack([np.ones_like(x), x, x**2])
    design = d_optimal(quadratic, 3)  # y = a + b x + c x^2: -1, 0, 1
    assert_allclose(sorted(x[design]), [-1, 0, 1], atol=1e-12)


def test_exchange_improves_on_the_greedy_start_and_respects_repeats():
    rng = np.random.default_rng(3)
    rows = rng.normal(size=(60, 4))
    greedy_only = d_optimal(rows, 10, max_sweeps=0)
    exchanged = d_optimal(rows, 10)
    logdet = [np.linalg.slogdet(rows[d].T @ rows[d])[1] for d in (greedy_only, exchanged)]
    assert logdet[1] >= logdet[0] - 1e-12
    assert len(set(exchanged.tolist())) == 10  # max_repeats=1: no candidate twice
    with pytest.raises(ValueError, match="cannot identify 4 coefficients"):
        d_optimal(rows, 3)
    with pytest.raises(ValueError, match="exceed the 60 candidates"):
        d_optimal(rows, 61)


def test_predicted_covariance_is_the_weighted_least_squares_formula():
    """With v_r and alpha held the law is linear in its six coefficients
    (identify.stribeck_fit.design_columns): cov = (X^T W X)^-1, W = 2 / sem^2 per run."""
    model = FrictionModel()
    v = np.array([1, 3, 10, 30, 100, 2, 8, 25, 70, 135]) * 1e-3
    p = np.array([0.1, 0.1, 0.1, 0.1, 0.1, 159, 159, 159, 159, 80]) * 1e5
    noise = WindowNoise((1e-3, 0.135), (0.02, 0.09))
    u = predicted_uncertainty(model, v, p, noise, fixed=("v_r", "alpha"))
    x = design_columns(v, p, 0.010, 1.0)
    w = 2.0 / noise(v) ** 2
    expected = np.linalg.inv(x.T @ (w[:, None] * x))
    assert u.names == (
        "F_c.intercept",
        "F_c.slope",
        "F_s.intercept",
        "F_s.slope",
        "sigma_2.intercept",
        "sigma_2.slope",
    )
    assert_allclose(u.covariance, expected, rtol=1e-6)
    # the band at the operating points is the propagated covariance (model.standard_error)
    fitted = model.replace(covariance=(u.names, u.covariance))
    v_op, p_op = u.band["velocity [m/s]"], u.band["pressure [Pa]"]
    assert_allclose(u.band["stderr [N]"], fitted.standard_error(v_op, p_op), rtol=1e-5)
    assert_allclose(u.band["half_width [N]"], 1.959964 * u.band["stderr [N]"], rtol=1e-6)


def test_one_pressure_cannot_identify_the_pressure_laws():
    v = np.geomspace(1e-3, 0.1, 12)
    with pytest.raises(ValueError, match="cannot identify the 8 coefficients"):
        predicted_uncertainty(FrictionModel(), v, np.full(v.size, 50e5), FLAT)


def test_jacobian_is_exact_for_the_linear_coefficients_and_matches_the_band_one():
    """Linear coefficients: the derivative is the design column (exact); v_r and alpha:
    the central differences of the band's jacobian (FrictionModel._jacobian)."""
    model = FrictionModel()
    v, p = np.array([0.002, 0.03, 0.12]), np.array([1e5, 80e5, 159e5])
    jac = model.jacobian(v, p)
    exact = design_columns(v, p, 0.010, 1.0)
    # rounding of the central difference: about 1e-16 * F / h, h = 1e-2 |coefficient|
    for k in range(6):
        assert_allclose(jac[:, k], exact[:, k], rtol=1e-7, atol=1e-9 * np.abs(exact[:, k]).max())
    names = list(model.varying[:8])
    variances = [1e-2, 1e-16, 1e-2, 1e-16, 1.0, 1e-12, 1e-10, 1e-6]  # [SI^2], a fit's size
    with_cov = model.replace(covariance=(names, np.diag(variances)))
    assert_allclose(jac[:, 6:], with_cov._jacobian(v, p)[:, 6:], rtol=1e-4)
    with pytest.raises(ValueError, match="no value for"):
        FrictionModel(friction_law="coulomb", coefficients={"F_c": 70.0}).jacobian(
            v, p, ["F_s.intercept"]
        )


def test_window_noise_interpolates_log_log_and_calibrates_from_points():
    noise = WindowNoise((1e-3, 1e-1), (0.01, 0.1))
    assert_allclose(
        noise([1e-3, 1e-2, 1e-1, 1.0, 1e-4]), [0.01, 0.0316228, 0.1, 0.1, 0.01], rtol=1e-5
    )
    assert_allclose(noise.run_std(1e-3), 0.01 / np.sqrt(2))
    points = pd.DataFrame(
        {
            "velocity [m/s]": [0.001, -0.00101, 0.01, -0.0099],
            "friction_std [N]": [0.8, 0.8, 0.8, 0.8],
            "n [-]": [1600, 400, 100, 100],
            "flag": ["ok", "ok", "ok", "short_window"],
        }
    )
    calibrated = WindowNoise.from_points(points)
    assert len(calibrated.speeds) == 2  # 1 and 1.01 mm/s are one speed group
    assert_allclose(calibrated.sem, [np.sqrt((0.02**2 + 0.04**2) / 2), 0.08])
    with pytest.raises(ValueError, match="lacks"):
        WindowNoise.from_points(points.drop(columns="n [-]"))
    with pytest.raises(ValueError, match="increasing"):
        WindowNoise((0.1, 0.01), (1, 1))


def test_bench_runs_an_explicit_list_of_points(tmp_path):
    assert BenchSettings.clean(pressures_bar=(1, 2), speeds_mm_s=(5, 9)).runs() == (
        (1, 5),
        (1, 9),
        (2, 5),
        (2, 9),
    )
    settings = BenchSettings.clean(points=((100, 20), (0.1, 3), (100, 20)), seed=1)
    info = generate_campaign(tmp_path, settings)
    names = [p.name for p in info["files"]]
    assert names == [
        "run_000_p100bar_v20mms.txt",
        "run_001_p0.1bar_v3mms.txt",
        "run_002_p100bar_v20mms.txt",
    ]
    manifest = pd.read_csv(tmp_path / "manifest.csv")
    assert manifest.iloc[:, 1:].to_numpy().tolist() == [[100, 20], [0.1, 3], [100, 20]]
    assert settings.slow_speeds() == {3.0, 20.0}  # the two slowest distinct speeds
    with pytest.raises(ValueError, match="does not fit the stroke"):
        run_plan(0.5, BenchSettings.clean())


def test_plan_for_the_thesis_ranges_beats_a_third_of_the_grid():
    """A 90-run plan against the thesis' 27 x 10 grid (270 runs): a grid a third the size
    has standard errors sqrt(3) = 1.73x larger; the D-optimal plan stays below that for
    every coefficient (measured: 1.01-1.59 with the bench-calibrated noise)."""
    s = BenchSettings.clean()
    noise = WindowNoise((1e-3, 2e-3, 1e-2, 0.135), (0.054, 0.022, 0.024, 0.08))
    plan = make_plan((0.1e5, 159e5), (1e-3, 0.135), 90, noise=noise)
    grid = grid_uncertainty(
        FrictionModel(), np.array(s.pressures_bar) * 1e5, np.array(s.speeds_mm_s) * 1e-3, noise
    )
    table = compare(grid, plan.uncertainty)
    assert len(plan.runs) == 90 and table["plan / grid"].between(0.9, np.sqrt(3)).all()
    assert plan.runs["velocity [m/s]"].between(1e-3, 0.135).all()
    assert plan.runs["pressure [Pa]"].between(0.1e5, 159e5).all()
    # run order: pressure levels ascending, a note where the pressure is set
    assert plan.runs["pressure [Pa]"].is_monotonic_increasing
    first = plan.runs.groupby("pressure [Pa]")["run"].min()
    noted = plan.runs.loc[plan.runs["notes"] != "", "run"]
    assert sorted(noted) == sorted(first)


@pytest.mark.slow
def test_predicted_uncertainty_matches_monte_carlo_refits(tmp_path):
    """The issue's acceptance: a 16-run plan run 40 times on the virtual bench (raw files
    -> extraction -> identification); the spread of each refitted coefficient against the
    plan's predicted standard error.

    Noise calibration: pilot runs of the same bench (other seeds) at 7 speeds through the
    extraction give each window's standard error friction_std / sqrt(n) against speed
    (WindowNoise.from_bench); a run's friction, the mean of its two directions, has
    sem / sqrt(2). Short strokes (60 mm) keep each campaign at about 0.3 s.

    The standard deviation of 40 draws has a sampling error of 1/sqrt(78) = 11 %, so the
    test asks the geometric mean of the eight ratios to lie within 20 % of 1 and each ratio
    within 35 % (3 sampling sigmas). Measured when written: ratios 0.88-1.08 over 100 seeds
    (geometric mean 0.98); over these 40 seeds see the assertion message.
    """
    cylinder = Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060)
    base = BenchSettings.clean(cylinder=cylinder)
    noise = WindowNoise.from_bench(base, speeds=np.geomspace(2e-3, 0.1, 7))
    plan = make_plan(
        (0.1e5, 159e5), (2e-3, 0.1), 16, settings=base, noise=noise, n_pressures=5, n_speeds=15
    )
    from cylfric.identify import identify
    from cylfric.steady_state import extract_campaign

    fits = []
    for seed in range(40):
        folder = tmp_path / f"c{seed}"
        generate_campaign(folder, replace(base, points=plan.points, seed=seed))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = identify(extract_campaign(folder).points, sensitivity=False).model
        assert model.friction_law == "stribeck"
        fits.append({n: model.parameters[n].value for n in plan.uncertainty.names})
    empirical = pd.DataFrame(fits).std(ddof=1)
    predicted = pd.Series(plan.uncertainty.stderr)
    ratio = empirical / predicted
    assert 0.8 <= np.exp(np.log(ratio).mean()) <= 1.2, ratio
    assert ratio.between(0.65, 1.35).all(), ratio


def test_cli_plan_writes_the_test_sheet(tmp_path):
    out = tmp_path / "plan"
    points = pd.DataFrame(
        {
            "velocity [m/s]": [0.001, 0.01, 0.15],
            "friction_std [N]": [0.8, 0.8, 0.8],
            "n [-]": [200, 1000, 60],
        }
    )
    points.to_csv(tmp_path / "points.csv", index=False)
    done = CliRunner().invoke(
        app,
        [
            "plan",
            "--pressures",
            "0-160bar",
            "--speeds",
            "1-150mm/s",
            "--runs",
            "20",
            "--noise-from",
            str(tmp_path / "points.csv"),
            "--out",
            str(out),
            "--compare-thesis-grid",
        ],
    )
    assert done.exit_code == 0, done.output
    sheet = pd.read_csv(out / "plan.csv")
    assert list(sheet.columns) == [
        "run",
        "pressure [bar]",
        "speed [mm/s]",
        "stroke [mm]",
        "sample interval [ms]",
        "notes",
    ]
    assert len(sheet) == 20 and sheet["run"].tolist() == list(range(1, 21))
    assert sheet["speed [mm/s]"].between(1, 150).all()
    assert sheet["pressure [bar]"].between(0, 160).all()
    page = (out / "plan.html").read_text()
    assert "data:image/png;base64," in page and page.count("<tr>") > 20
    comparison = pd.read_csv(out / "comparison.csv")
    assert len(comparison) == 8 and (comparison["27 x 10 grid"] > 0).all()
    assert "F_c.intercept" in done.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--speeds", "1-400mm/s"], "does not fit the stroke"),
        (["--pressures", "160-0bar"], "low end must be below"),
        (["--pressures", "abc"], "expected LOW-HIGH"),
        (["--speeds", "0-150mm/s"], "the lowest speed must be > 0"),
        (["--runs", "5"], "5 runs cannot identify 8 coefficients"),
        (["--fix", "alpha=1"], "no values"),
    ],
)
def test_cli_plan_bad_input(tmp_path, args, message):
    points = pd.DataFrame(
        {"velocity [m/s]": [0.001, 0.1], "friction_std [N]": [0.8, 0.8], "n [-]": [200, 60]}
    )
    points.to_csv(tmp_path / "points.csv", index=False)
    base = ["plan", "--out", str(tmp_path / "o"), "--noise-from", str(tmp_path / "points.csv")]
    done = CliRunner().invoke(app, base + args)
    assert done.exit_code == 2, done.output
    assert message in done.output


def _coulomb_viscous():
    return FrictionModel(
        coefficients={
            "F_c": {"intercept": 70.0, "slope": 5e-6},
            "F_s": None,
            "sigma_2": {"intercept": 340.0, "slope": 8e-6},
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb_viscous",
    )


def test_a_bilinear_model_is_planned_at_the_corners():
    """F = F_c(p) + sigma_2(p) v is bilinear in (v, p): with equal noise the D-optimal design
    is the 2^2 factorial at the corners of the (v, p) box (Atkinson et al., ch. 11)."""
    plan = make_plan(
        (0.0, 150e5), (1e-3, 0.1), 8, model=_coulomb_viscous(), noise=FLAT, max_repeats=2
    )
    assert plan.uncertainty.names == (
        "F_c.intercept",
        "F_c.slope",
        "sigma_2.intercept",
        "sigma_2.slope",
    )
    corners = sorted(plan.points)
    assert corners == [
        (0, 1),
        (0, 1),
        (0, 100),
        (0, 100),
        (150, 1),
        (150, 1),
        (150, 100),
        (150, 100),
    ]


def test_cli_plan_for_a_datasheet(tmp_path):
    import json

    (tmp_path / "sheet.json").write_text(json.dumps(_coulomb_viscous().to_datasheet()))
    flat_points = pd.DataFrame(
        {"velocity [m/s]": [0.001, 0.1], "friction_std [N]": [0.5, 0.5], "n [-]": [100, 100]}
    )
    flat_points.to_csv(tmp_path / "points.csv", index=False)
    done = CliRunner().invoke(
        app,
        [
            "plan",
            "--model",
            str(tmp_path / "sheet.json"),
            "--runs",
            "4",
            "--pressures",
            "0-150",
            "--speeds",
            "1-100",
            "--noise-from",
            str(tmp_path / "points.csv"),
            "--out",
            str(tmp_path / "o"),
        ],
    )
    assert done.exit_code == 0, done.output
    sheet = pd.read_csv(tmp_path / "o" / "plan.csv")
    assert sorted(zip(sheet["pressure [bar]"], sheet["speed [mm/s]"], strict=True)) == [
        (0, 1),
        (0, 100),
        (150, 1),
        (150, 100),
    ]
    assert len(pd.read_csv(tmp_path / "o" / "uncertainty.csv")) == 4
