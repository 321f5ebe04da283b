"""The friction model object: one definition, serialisation, uncertainty, guards."""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

import cylfric
from cylfric.datasheet import DatasheetError, build_datasheet, evaluate
from cylfric.friction import lugre_g, lugre_z_update, params_at_pressure, stribeck
from cylfric.friction.literature import CANUDAS_DE_WIT_1995, THESIS_2016
from cylfric.identify import identify
from cylfric.model import FrictionModel, Parameter, ValidityWarning, engineering_unit
from cylfric.simulate import kernels

SRC = Path(cylfric.__file__).parent


@pytest.fixture(scope="module")
def fitted():
    """A model fitted to noisy points of the thesis law (3 pressures x 12 speeds)."""
    rng = np.random.default_rng(4)
    v = np.tile(np.geomspace(1e-3, 0.13, 12), 3)
    p = np.repeat([1e5, 80e5, 159e5], 12)
    f = stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients)) + rng.normal(0, 0.3, 36)
    points = pd.DataFrame({"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": f})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(points, sensitivity=False)


def test_default_is_the_thesis_law_and_matches_the_friction_functions():
    model = FrictionModel()
    v = np.linspace(-0.15, 0.15, 41)
    p = np.linspace(0, 160e5, 41)
    expected = stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))
    assert_allclose(model.friction(v, p), expected, rtol=1e-15)
    assert model.params_at(55e5)["F_c"] == pytest.approx(97.7)  # eq. 4.1 at 55 bar
    assert model.dynamic_status["sigma_0"][0] == "assumed"


def test_parameters_carry_value_unit_bounds_and_vary():
    model = FrictionModel(fixed=("alpha",))
    slope = model.parameters["F_c.slope"]
    assert slope == Parameter("F_c.slope", 5e-6, "N/Pa", None, True, (-math.inf, math.inf))
    assert model.parameters["v_r"].bounds == (1e-5, 10.0)
    assert not model.parameters["alpha"].vary
    assert engineering_unit("F_c.slope") == ("N/bar", 1e5)
    assert engineering_unit("sigma_2.intercept") == ("N*s/mm", 1e-3)
    assert engineering_unit("v_r") == ("mm/s", 1e3)
    value, _, unit = model.parameters["sigma_2.slope"].engineering()
    assert unit == "N*s/mm/bar" and value == pytest.approx(8e-4)  # eq. 4.3


def test_literature_set_keeps_its_dynamic_parameters():
    model = FrictionModel(dict(CANUDAS_DE_WIT_1995.params), pressure_law="constant")
    params = model.params_at(0.0)
    assert params["sigma_0"] == 1e5 and params["sigma_1"] == pytest.approx(math.sqrt(1e5))
    assert model.dynamic_status["sigma_0"][0] == "identified"
    assert model.replace(sigma_0=2e5).dynamic_status["sigma_0"][0] == "assumed"


def test_round_trip_is_identical_and_evaluate_is_the_model(fitted, tmp_path):
    sheet = build_datasheet(fitted, name="rig")
    again = FrictionModel.from_datasheet(sheet).to_datasheet()
    assert json.dumps(again, sort_keys=True) == json.dumps(sheet, sort_keys=True)
    path = tmp_path / "sheet.json"
    path.write_text(json.dumps(sheet))
    model = FrictionModel.from_datasheet(path)
    v = np.geomspace(1.1e-3, 0.13, 30)
    p = np.linspace(1e5, 159e5, 30)
    assert np.array_equal(model.friction(v, p), evaluate(sheet, v, p))
    assert np.array_equal(model.friction(v, p), fitted.model.friction(v, p))
    assert sheet["fit"]["covariance"]["names"] == list(model.covariance[0])
    assert_allclose(np.diag(sheet["fit"]["correlations"]["matrix"]), 1.0)


def test_band_widens_outside_the_data_and_prediction_band_adds_the_scatter(fitted):
    model = fitted.model
    v = np.array([0.01, 0.01])
    p = np.array([80e5, 400e5])  # inside, and far outside the measured pressures
    with pytest.warns(ValidityWarning, match="1 of 2 point"):
        lower, upper = model.band(v, p)
        model.check(v, p)
    assert np.all(lower < model._friction(v, p, model.coefficients()))
    assert (upper - lower)[1] > 3 * (upper - lower)[0]
    p_lo, p_hi = model.prediction_band(v[:1], p[:1])
    assert (p_hi - p_lo)[0] > (upper - lower)[0]
    scatter = model.statistics["residual_std"]
    assert 0.2 < scatter < 0.4  # the noise was 0.3 N
    wider = model.band(v[:1], p[:1], level=0.99)
    assert wider[1][0] - wider[0][0] > (upper - lower)[0]


def test_standard_error_is_the_first_order_propagation_of_the_covariance():
    # F = F_c (1 - e) + F_s e + sigma_2 v (alpha = 1): dF/dF_c = 1 - e, dF/dF_s = e
    model = FrictionModel(
        {"F_c": 70.0, "F_s": 110.0, "sigma_2": 300.0, "v_r": 0.01, "alpha": 1.0},
        pressure_law="constant",
        covariance=(["F_c", "F_s"], [[4.0, 1.0], [1.0, 9.0]]),
        statistics={"dof": 1000},
    )
    v = np.array([0.002, 0.01, 0.05])
    e = np.exp(-v / 0.01)
    jac = np.column_stack([1 - e, e])
    expected = np.sqrt(np.einsum("ni,ij,nj->n", jac, [[4.0, 1.0], [1.0, 9.0]], jac))
    assert_allclose(model.standard_error(v, 0.0), expected, rtol=1e-7)
    lower, upper = model.band(v, 0.0, level=0.95)
    assert_allclose((upper - lower) / 2, 1.9623 * expected, rtol=1e-4)  # t(0.975, 1000)


def test_effective_dof_counts_the_runs_that_carry_the_friction():
    """Satterthwaite's (sum a_g)^2 / sum a_g^2 over the runs' shares of the variance."""
    coefficients = {"F_c": 70.0, "F_s": 110.0, "sigma_2": 300.0, "v_r": 0.01, "alpha": 1.0}
    names = ["F_c", "F_s"]

    def model_with(influence):
        influence = np.asarray(influence, dtype=float)
        return FrictionModel(
            coefficients,
            pressure_law="constant",
            covariance=(names, influence.T @ influence),
            influence=(names, influence),
            statistics={"dof": 30},
        )

    one_run = model_with([[0.5, 0.2]] + [[0.0, 0.0]] * 9)
    assert_allclose(one_run.effective_dof([0.002, 0.05], 0.0), 1.0)
    equal = model_with([[0.3, 0.1], [-0.3, -0.1]] * 5)
    assert_allclose(equal.effective_dof([0.002, 0.05], 0.0), 10.0)
    # a band from one run is wider than one the same width of variance shared by ten runs
    lo1, up1 = one_run.band(0.002, 0.0)
    se1, se10 = one_run.standard_error(0.002, 0.0), equal.standard_error(0.002, 0.0)
    lo10, up10 = equal.band(0.002, 0.0)
    assert (up1 - lo1) / se1 == pytest.approx(2 * 12.706, rel=1e-3)  # t(0.975, 1)
    assert (up10 - lo10) / se10 == pytest.approx(2 * 2.228, rel=1e-3)  # t(0.975, 10)
    with pytest.raises(ValueError, match="influence needs a covariance"):
        FrictionModel(coefficients, pressure_law="constant", influence=(names, [[1.0, 0.0]]))


def test_fitted_influence_is_the_jackknife_behind_the_covariance():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = identify(_campaign_points(0, FrictionModel()), sensitivity=False).model
    names, influence = model.influence
    assert names == model.covariance[0]
    assert_allclose(influence.T @ influence, model.covariance[1], rtol=1e-10, atol=1e-30)
    dof = model.effective_dof(np.array([0.002, 0.13]), np.array([80e5, 159e5]))
    assert np.all((dof >= 1) & (dof <= model.statistics["dof"]))
    assert model.replace(coefficients=model.coefficients()).influence is None


def test_guards_warn_outside_validity_and_on_pressures_in_bar(fitted):
    model = fitted.model
    with pytest.warns(ValidityWarning, match="pressures are in Pa"):
        model.friction(0.01, 80.0)  # 80 bar typed as Pa
    with pytest.raises(ValueError, match=r"outside the validity ranges 1-159 bar"):
        model.friction(0.5, 80e5, strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.all(model.check(np.array([0.002, 0.1]), np.array([1e5, 159e5])))


def test_unidentified_parameters_are_none_with_a_reason():
    model = FrictionModel(
        {"F_c": {"intercept": 10.0, "slope": 1e-6}, "F_s": None, "sigma_2": None},
        friction_law="coulomb",
        not_identified={"F_s": "one speed per direction"},
    )
    assert model.coefficients()["F_s"] is None and model.parameters["F_s"].value is None
    assert model.not_identified["F_s"] == "one speed per direction"
    assert "v_r" in model.not_identified
    assert model.friction(0.05, 1e5) == pytest.approx(10.1)  # Coulomb only
    sheet = model.to_datasheet()
    assert sheet["parameters"]["sigma_2"] is None
    assert FrictionModel.from_datasheet(sheet).to_datasheet() == sheet
    with pytest.raises(ValueError, match="F_s is given but the coulomb law has no F_s"):
        FrictionModel({"F_c": 1.0, "F_s": 2.0}, friction_law="coulomb")


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda s: s["parameters"]["sigma_2"].update(intercept=-500.0), "sigma_2 < 0"),
        (lambda s: s["parameters"]["F_s"].update(intercept=1.0), "F_s < F_c"),
        (lambda s: s["parameters"]["sigma_2"].update(intercept=1e308), "friction above 1e\\+08 N"),
        (lambda s: s["parameters"]["F_c"].update(slope=math.nan), "F_c/slope: nan is not finite"),
        (lambda s: s["dynamic"]["sigma_0"].update(value=math.inf), "is not finite"),
    ],
)
def test_unphysical_or_non_finite_datasheets_are_refused(change, message):
    sheet = FrictionModel().to_datasheet()
    change(sheet)
    with pytest.raises(DatasheetError, match=message):
        FrictionModel.from_datasheet(sheet)


def test_fit_report_lists_values_errors_correlations_and_dynamics(fitted):
    text = fitted.model.fit_report()
    for section in ("[[Model]]", "[[Fit Statistics]]", "[[Variables]]", "[[Correlations]]"):
        assert section in text
    assert re.search(r"F_c\.slope\s*:\s+0\.\d+ \+/- [\d.e-]+ \(\d+\.\d+%\) N/bar", text)
    assert "sigma_0  = 1000 N/mm (assumed" in text
    lines = fitted.model.law_lines()
    assert lines[0].startswith("F_c(p) = (") and " ± " in lines[0] and "N/bar * p" in lines[0]


def test_compiled_kernels_agree_with_the_model_to_1e_12():
    rng = np.random.default_rng(11)
    for _ in range(300):
        coefficients = {
            "F_c": {"intercept": rng.uniform(1, 200), "slope": rng.uniform(0, 1e-5)},
            "F_s": {"intercept": rng.uniform(1, 300), "slope": rng.uniform(0, 1e-5)},
            "sigma_2": {"intercept": rng.uniform(0, 1e3), "slope": rng.uniform(0, 1e-5)},
            "v_r": 10 ** rng.uniform(-4, -1),
            "alpha": rng.choice([1.0, rng.uniform(0.3, 3)]),
        }
        model = FrictionModel(
            coefficients, sigma_0=10 ** rng.uniform(4, 9), sigma_1=10 ** rng.uniform(0, 4)
        )
        p = rng.uniform(0, 200e5)
        k = model.params_at(p)
        v = rng.choice([-1, 1]) * 10 ** rng.uniform(-6, 0)
        g = lugre_g(v, k["F_c"], k["F_s"], k["v_r"], alpha=k["alpha"])
        assert kernels.g_function(abs(v), k["F_c"], k["F_s"], k["v_r"], k["alpha"]) == (
            pytest.approx(g, rel=1e-12)
        )
        z = rng.uniform(-1, 1) * g / k["sigma_0"]
        force = model.dynamic_force(v, z, p)
        terms = abs(k["sigma_0"] * z) + abs(k["sigma_1"] * v) + abs(k["sigma_2"] * v)
        compiled = kernels.lugre_instant(
            v,
            z,
            *(k[n] for n in ("sigma_0", "sigma_1", "sigma_2", "F_c", "F_s", "v_r")),
            k["alpha"],
        )
        assert abs(compiled - force) <= 1e-12 * terms
        # the plant right-hand side of the Rosenbrock integrator (kernels._plant) inlines it
        sig = np.array([[0.0, 0.0, 0.0, k["F_c"], k["F_s"], k["sigma_2"]]] * 2)
        rhs = np.empty(4)
        plant_force = kernels._plant(
            0.0, np.array([0.0, v, z, 0.0]), rhs, sig, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
            k["sigma_0"], k["sigma_1"], 1.0 / k["v_r"], k["alpha"],
        )  # fmt: skip
        assert abs(plant_force - force) <= 1e-12 * terms
        h = 10 ** rng.uniform(-6, -2)
        z1 = lugre_z_update(z, v, h, k["sigma_0"], k["F_c"], k["F_s"], k["v_r"], alpha=k["alpha"])
        step = kernels.z_step(z, v, h, k["sigma_0"], k["F_c"], k["F_s"], k["v_r"], k["alpha"])
        assert abs(step[0] - z1) <= 1e-12 * max(abs(z1), g / k["sigma_0"])


_FORMULAS = {
    "g(v) or eq. 2.7": re.compile(
        r"\(\s*f_?s\s*-\s*f_?c\s*\)\s*\*|exp\(\s*-\s*[(\s]*(np\.)?(abs\()?\s*(speed|u|v)\b",
        re.IGNORECASE,
    ),
    "the LuGre force": re.compile(
        r"(sigma_?0|s0)\s*\*\s*\w+\s*\+\s*(sigma_?1|s1)\s*\*", re.IGNORECASE
    ),
    "a pressure law": re.compile(r"intercept\s*\+\s*slope\s*\*|\+\s*b\s*\*\s*p\b"),
}


def test_no_second_definition_of_the_model_outside_friction_and_model():
    allowed = {SRC / "friction", SRC / "model"}
    kernels_file = SRC / "simulate" / "kernels.py"  # tested against the model above
    # the independent loop that checks cylfric's: it must share no code with it (issue 40),
    # and tests/test_control_reference.py holds the two within 10 %
    independent = SRC / "control" / "reference_loop.py"
    found = []
    for path in SRC.rglob("*.py"):
        if path in (kernels_file, independent) or any(a in path.parents for a in allowed):
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#")[0]
            if code.strip().startswith(('"', "'")):
                continue
            for what, pattern in _FORMULAS.items():
                if pattern.search(code):
                    found.append(f"{path.relative_to(SRC)}:{number}: {what}: {line.strip()}")
    assert not found, "\n".join(found)


def _campaign_points(seed, truth, pressures_bar=(0.1, 55.0, 103.0, 159.0)):
    """Points shaped like a campaign: two directions per run sharing the run's error, whose
    spread grows with speed (short windows at high speed), with per-window std and n."""
    rng = np.random.default_rng(seed)
    speeds = np.array([1, 2, 4, 7, 10, 15, 25, 40, 70, 135]) * 1e-3
    rows = []
    for i, (p, v) in enumerate((p, v) for p in pressures_bar for v in speeds):
        spread = 0.015 + 0.4 * v  # [N]
        friction = truth.friction(v, p * 1e5) + rng.normal(0, spread)
        n = max(int((0.8 / spread) ** 2), 10)
        for sign in (1, -1):
            rows.append(
                {
                    "run": i,
                    "direction [-]": sign,
                    "velocity [m/s]": sign * v,
                    "pressure [Pa]": p * 1e5,
                    "friction [N]": friction,
                    "friction_std [N]": 0.8,
                    "n [-]": n,
                }
            )
    return pd.DataFrame(rows)


@pytest.mark.slow
def test_band_of_the_mean_is_calibrated_over_50_campaigns():
    truth = FrictionModel()
    v = np.array([0.002, 0.010, 0.025, 0.1, 0.005, 0.05, 0.13, 0.001])
    p = np.array([55e5, 103e5, 80e5, 159e5, 20e5, 5e5, 0.1e5, 159e5])
    true = truth.friction(v, p)
    inside = []
    for seed in range(50):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = identify(_campaign_points(seed, truth), sensitivity=False).model
        lower, upper = model.band(v, p, level=0.95)
        inside.append((lower <= true) & (true <= upper))
    inside = np.array(inside)
    assert 0.90 <= inside.mean() <= 0.99, inside.mean(axis=0)
    assert inside.mean(axis=0).min() >= 0.84, inside.mean(axis=0)


@pytest.mark.slow
def test_band_holds_the_truth_of_50_virtual_campaigns(tmp_path):
    """The issue's acceptance: raw files of the virtual bench -> extraction -> identification.

    Measured over 100 seeds (CR2 covariance, each point's effective degrees of freedom):
    coverage 0.93, 0.98, 0.99, 0.90, 0.95, 0.96, overall 0.952. The fastest point, 100 mm/s
    at 159 bar, is the weakest: a median of 2.6 effective runs carry sigma_2 there. (With
    the fit's 32 degrees of freedom everywhere it was 0.87 there; with CR3, 1.00 at 10 mm/s.)
    """
    from cylfric.simulate.bench import BenchSettings, generate_campaign
    from cylfric.steady_state import extract_campaign

    truth = FrictionModel()  # the bench's default friction: the thesis law
    v = np.array([0.002, 0.010, 0.025, 0.1, 0.005, 0.05])
    p = np.array([55e5, 103e5, 80e5, 159e5, 20e5, 5e5])
    true = truth.friction(v, p)
    inside = []
    for seed in range(50):
        folder = tmp_path / f"campaign{seed}"
        settings = BenchSettings.clean(
            pressures_bar=(0.1, 55, 103, 159),
            speeds_mm_s=(1, 2, 4, 7, 10, 15, 25, 40, 70, 135),
            seed=seed,
        )
        generate_campaign(folder, settings)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = identify(extract_campaign(folder).points, sensitivity=False).model
        lower, upper = model.band(v, p, level=0.95)
        inside.append((lower <= true) & (true <= upper))
    inside = np.array(inside)
    assert 0.90 <= inside.mean() <= 0.99, inside.mean(axis=0)
    assert inside.mean(axis=0).min() >= 0.84, inside.mean(axis=0)  # binomial sd 0.03 at 50


def test_pressure_only_check_for_simulations(fitted):
    model = fitted.model
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert model.check(None, np.array([1e5, 159e5])).all()
    with pytest.raises(ValueError, match="1 of 2 point"):
        model.check(None, np.array([1e5, 300e5]), strict=True)


def test_simulate_warns_outside_the_validity_pressures(fitted):
    from cylfric.simulate import Cylinder, SpringPull, simulate

    model = fitted.model
    with pytest.warns(ValidityWarning, match="outside the validity ranges"):
        simulate(Cylinder(10.0), model, SpringPull(2e4, 5e-3), 0.01, pressure_a=300e5)
    with pytest.warns(ValidityWarning, match="pressures are in Pa"):
        simulate(Cylinder(10.0), FrictionModel(), SpringPull(2e4, 5e-3), 0.01, pressure_a=50.0)
    with pytest.raises(ValueError, match="outside the validity ranges"):
        simulate(Cylinder(10.0), model, SpringPull(2e4, 5e-3), 0.01, pressure_a=300e5, strict=True)


def test_a_datasheet_is_read_from_any_path_like(tmp_path):
    """``from_datasheet`` takes what its type says (str, Path or any os.PathLike), as the
    FMU export and ``export()`` pass it on; a path-like object was taken for a dict."""
    path = tmp_path / "datasheet.json"
    path.write_text(json.dumps(FrictionModel().to_datasheet()))

    class Where:
        def __fspath__(self):
            return str(path)

    model = FrictionModel.from_datasheet(Where())
    assert model.source == str(path)
    assert model.friction(0.01, 1e5) == FrictionModel.from_datasheet(path).friction(0.01, 1e5)


def test_a_model_pickles_and_comes_back_the_same(fitted):
    """A FrictionModel goes through pickle (a forked or Dask worker sends models back: the
    sensitivity study's refits), its read-only mappings read-only again."""
    import pickle
    from types import MappingProxyType

    model = fitted.model
    back = pickle.loads(pickle.dumps(model))
    assert back.to_datasheet() == model.to_datasheet()
    assert back.friction(0.02, 50e5) == model.friction(0.02, 50e5)
    assert isinstance(back.parameters, MappingProxyType) and isinstance(
        back.record, MappingProxyType
    )
    with pytest.raises(TypeError):
        back.parameters["F_c"] = None  # type: ignore[index]


def test_effective_dof_in_blocks_is_the_same_as_at_once(monkeypatch):
    """The runs' shares are summed in blocks of points (SHARE_BLOCK entries: a report's band
    over 20,000 runs held 66 MB at once, 19 MB in blocks); each point's sums are the same to
    rounding (BLAS may take another kernel for a block's last rows)."""
    from cylfric.model import core

    rng = np.random.default_rng(7)
    jacobian = rng.normal(size=(50, 8))
    influence = rng.normal(size=(300, 8))
    whole = (jacobian @ influence.T) ** 2
    monkeypatch.setattr(core, "SHARE_BLOCK", 1000)  # 3 points a block
    total, squares = core._shares(jacobian, influence)
    assert_allclose(total, whole.sum(axis=-1), rtol=1e-13)
    assert_allclose(squares, (whole**2).sum(axis=-1), rtol=1e-13)
    grid, _ = core._shares(jacobian.reshape(5, 10, 8), influence)
    assert grid.shape == (5, 10) and np.array_equal(grid.ravel(), total)
    monkeypatch.setattr(core, "SHARE_BLOCK", 1 << 20)  # one block: the former sums exactly
    total, squares = core._shares(jacobian, influence)
    assert np.array_equal(total, whole.sum(axis=-1))
    assert np.array_equal(squares, (whole**2).sum(axis=-1))
