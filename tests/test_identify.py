"""Identification and datasheet: the whole chain raw files -> points -> datasheet (ch. 4)."""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

from cylfric.datasheet import (
    DatasheetError,
    build_datasheet,
    evaluate,
    read_datasheet,
    validate,
    write_datasheet,
)
from cylfric.friction import params_at_pressure, stribeck
from cylfric.friction.literature import THESIS_2016
from cylfric.identify import IdentificationWarning, fit_stribeck, identify, pressure_levels
from cylfric.model import FrictionModel
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SPEEDS = (1, 2, 3, 5, 7, 10, 15, 20, 30, 45, 60, 80, 100, 135)
PRESSURES = (0.1, 20.7, 55.0, 83.0, 124.0, 159.0)


def _linear(intercept, slope_per_bar):
    return {"intercept": intercept, "slope": slope_per_bar / 1e5}


PARAMETER_SETS = {
    # thesis eq. 4.1-4.3, alpha = 1, v_r = 10 mm/s
    "thesis": (dict(THESIS_2016.coefficients), 35.67 / 2),
    # high-friction seals, gentle Stribeck exponent
    "stiff": (
        {
            "F_c": _linear(150.0, 0.8),
            "F_s": _linear(260.0, 1.1),
            "sigma_2": _linear(1200.0, 2.0),
            "v_r": 0.020,
            "alpha": 0.7,
        },
        30.0,
    ),
    # low-friction PTFE-like seals, sharp Stribeck dip
    "ptfe": (
        {
            "F_c": _linear(30.0, 0.25),
            "F_s": _linear(55.0, 0.35),
            "sigma_2": _linear(150.0, 0.4),
            "v_r": 0.005,
            "alpha": 1.5,
        },
        -12.0,
    ),
}


@pytest.fixture(scope="module", params=sorted(PARAMETER_SETS))
def chain(request, tmp_path_factory):
    coefficients, weight = PARAMETER_SETS[request.param]
    settings = BenchSettings.clean(
        friction=FrictionModel(coefficients=coefficients),
        pressures_bar=PRESSURES,
        speeds_mm_s=SPEEDS,
        weight_offset=weight,
        seed=7,
    )
    folder = tmp_path_factory.mktemp(request.param)
    generate_campaign(folder, settings)
    extraction = extract_campaign(folder)
    ident = identify(extraction.points)
    sheet = build_datasheet(ident, extraction=extraction, campaign=str(folder))
    return request.param, coefficients, weight, extraction, ident, sheet, folder


def test_chain_recovers_the_true_parameters(chain):
    name, truth, weight, extraction, ident, sheet, _ = chain
    got = sheet["parameters"]
    for par in ("F_c", "F_s"):
        assert_allclose(got[par]["intercept"], truth[par]["intercept"], rtol=0.02, err_msg=name)
        assert_allclose(got[par]["slope"], truth[par]["slope"], rtol=0.05, err_msg=name)
    assert_allclose(got["sigma_2"]["intercept"], truth["sigma_2"]["intercept"], rtol=0.05)
    assert_allclose(got["sigma_2"]["slope"], truth["sigma_2"]["slope"], rtol=0.05)
    assert_allclose(got["v_r"], truth["v_r"], rtol=0.10)
    assert_allclose(got["alpha"], truth["alpha"], rtol=0.10)
    assert abs(sheet["offset"] - weight) < 0.5


def test_sensitivity_minimum_at_true_alpha_and_v_r(chain):
    name, truth, *_, ident, _, _ = chain
    assert_allclose(ident.recommended["alpha"], truth["alpha"], rtol=0.05, err_msg=name)
    assert_allclose(ident.recommended["v_r"], truth["v_r"], rtol=0.05, err_msg=name)
    table = ident.sensitivity
    if name == "thesis":  # Tables 4.2-4.4: alpha = 1, v_r = 10 mm/s is the minimum
        assert table.loc[table["rmse [N]"].idxmin(), "alpha [-]"] == 1.0
        t44 = table[table["table"] == "4.4"]
        assert t44.loc[t44["rmse [N]"].idxmin(), "v_r [m/s]"] == 0.010


def test_per_pressure_table_follows_the_laws(chain):
    name, truth, *_, ident, _, _ = chain
    table = ident.per_pressure
    assert len(table) == len(PRESSURES)
    expected = params_at_pressure(table["pressure [Pa]"].to_numpy(), truth)
    assert_allclose(table["F_c [N]"], expected["F_c"], rtol=0.03)
    assert_allclose(table["F_s [N]"], expected["F_s"], rtol=0.03)
    assert np.all(table["F_c_stderr [N]"] > 0)


def test_datasheet_round_trip_evaluates_the_same_forces(chain, tmp_path):
    *_, sheet, _ = chain
    path = write_datasheet(tmp_path / "datasheet.json", sheet)
    again = read_datasheet(path)
    v = np.concatenate([-np.geomspace(0.135, 0.0011, 15), np.geomspace(0.0011, 0.135, 16)])
    p = np.full_like(v, 80e5)
    assert_allclose(evaluate(again, v, p), evaluate(sheet, v, p), rtol=1e-15)
    model = FrictionModel.from_datasheet(path)
    assert np.array_equal(model.friction(v, p), evaluate(sheet, v, p))
    assert json.dumps(model.to_datasheet(), sort_keys=True) == json.dumps(sheet, sort_keys=True)
    assert len(again["fit"]["source"]["files"]) == len(PRESSURES) * len(SPEEDS)


def test_laws_compared_by_information_criteria(chain):
    *_, ident, _, _ = chain
    assert set(ident.comparison["law"]) == {"linear", "quadratic", "exponential"}
    assert (ident.comparison["aic"].notna()).all()


def test_fixed_alpha_and_v_r_are_held(chain):
    # as the thesis chose alpha = 1, v_r = 10 mm/s for its cylinder; here each set's own values
    _, truth, _, extraction, *_ = chain
    fixed = {"alpha": truth["alpha"], "v_r": truth["v_r"]}
    ident = identify(extraction.points, fixed=fixed, sensitivity=False)
    assert ident.model.coefficients()["alpha"] == truth["alpha"]
    assert all(f.params["v_r"] == truth["v_r"] for f in ident.per_pressure_fits)
    for par in ("F_c", "F_s"):
        assert_allclose(
            ident.model.coefficients()[par]["intercept"], truth[par]["intercept"], rtol=0.01
        )


def test_per_direction_fits(chain):
    _, truth, _, extraction, *_ = chain
    ident = identify(extraction.points, per_direction=True, sensitivity=False)
    assert set(ident.directions) == {"extension", "retraction"}
    for result in ident.directions.values():
        assert_allclose(
            result.model.coefficients()["F_c"]["intercept"], truth["F_c"]["intercept"], rtol=0.03
        )


# ---------------------------------------------------------------------------- unit level


def test_fit_stribeck_recovers_thesis_table_row():
    rng = np.random.default_rng(0)
    v = np.geomspace(1e-3, 0.135, 27)
    truth = {"F_c": 99.5, "F_s": 146.0, "sigma_2": 386.0, "v_r": 0.010, "alpha": 1.0}
    f = stribeck(v, **truth) + rng.normal(0, 0.5, v.size)
    fit = fit_stribeck(v, f, fixed={"alpha": 1.0})
    assert_allclose(fit.params["F_c"], 99.5, rtol=0.02)
    assert fit.stderr["alpha"] == 0.0 and "alpha" not in fit.free
    assert fit.ci95["F_s"][0] < fit.params["F_s"] < fit.ci95["F_s"][1]
    assert "RMSE" in fit.report() and "(fixed)" in fit.report()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"velocity": [0.01] * 3, "friction": [1.0] * 3}, "3 points are too few"),
        ({"velocity": [0.01, np.nan] * 4, "friction": [1.0] * 8}, "contains NaN"),
        (
            {"velocity": [0.01] * 8, "friction": [1.0] * 8, "fixed": {"mu": 1}},
            r"unknown fixed parameters \['mu'\]",
        ),
    ],
)
def test_fit_stribeck_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        fit_stribeck(**kwargs)


def test_identify_errors():
    points = pd.DataFrame(
        {"velocity [m/s]": [0.01] * 3, "pressure [Pa]": [0.0] * 3, "friction [N]": [1.0] * 3}
    )
    with pytest.raises(ValueError, match="3 usable points are too few"):
        identify(points)
    with pytest.raises(ValueError, match=r"unknown pressure law 'cubic'"):
        identify(points, pressure_law="cubic")
    with pytest.raises(ValueError, match=r"lacks columns \['friction \[N\]'\]"):
        identify(points.drop(columns="friction [N]"))
    with pytest.raises(ValueError, match="contain NaN"):
        identify(points.assign(**{"friction [N]": np.nan}))


def test_pressure_levels_cluster_measured_pressures():
    labels, means = pressure_levels([0.1e5, 0.12e5, 55e5, 55.3e5, 54.8e5, 159e5])
    assert list(labels) == [0, 0, 1, 1, 1, 2]
    assert_allclose(means, [0.11e5, 55.033e5, 159e5], rtol=1e-3)


def test_one_speed_per_pressure_gives_level_with_warning(shared_data, tmp_path):
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    points = extract_campaign(folder).points
    oring = points[points["seal"] == "O-ring"]
    with pytest.warns(IdentificationWarning, match="Stribeck shape .* cannot be identified"):
        ident = identify(oring)
    assert not ident.stribeck_identifiable
    slope = ident.model.coefficients()["F_c"]["slope"] * 1e5  # N/bar
    assert 0.3 < slope < 1.0  # the O-ring half-range rises about 0.65 N/bar
    sheet = build_datasheet(ident)
    assert sheet["model"]["stribeck_identifiable"] is False
    assert sheet["model"]["friction_law"] == "coulomb"
    # not identified: null with a reason, never a copied or zero value
    for name in ("F_s", "sigma_2", "v_r", "alpha"):
        assert sheet["parameters"][name] is None
        assert "one speed per direction" in sheet["not_identified"][name]
    assert all(row["F_s"] is None and row["sigma_2"] is None for row in sheet["per_pressure"])
    assert sheet["fit"]["covariance"]["names"] == ["F_c.intercept", "F_c.slope"]
    validate(sheet)


def test_datasheet_validation_names_the_key(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rng = np.random.default_rng(1)
        v = np.tile(np.geomspace(1e-3, 0.1, 12), 3)
        p = np.repeat([1e5, 50e5, 100e5], 12)
        f = stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients)) + rng.normal(0, 0.3, 36)
        ident = identify(
            pd.DataFrame({"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": f}),
            sensitivity=False,
        )
    sheet = build_datasheet(ident)
    bad = json.loads(json.dumps(sheet))
    del bad["parameters"]["v_r"]
    with pytest.raises(DatasheetError, match=r"parameters: 'v_r' is a required property"):
        validate(bad)
    bad = json.loads(json.dumps(sheet))
    bad["parameters"]["alpha"] = -1
    with pytest.raises(DatasheetError, match="parameters/alpha"):
        write_datasheet(tmp_path / "x.json", bad)
    assert not (tmp_path / "x.json").exists()
    (tmp_path / "broken.json").write_text("{not json")
    with pytest.raises(DatasheetError, match="broken.json: not valid JSON"):
        read_datasheet(tmp_path / "broken.json")


def test_non_monotonic_pressure_level_is_warned_not_hidden():
    # the thesis saw an odd 20.7 bar curve (ch. 6): a level that falls gets a warning
    rng = np.random.default_rng(3)
    v = np.tile(np.geomspace(1e-3, 0.13, 14), 4)
    p = np.repeat([1e5, 20e5, 55e5, 100e5], 14)
    f = stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients)) + rng.normal(0, 0.2, 56)
    f[14:28] -= 25.0  # the 20 bar level far below the 1 bar one
    points = pd.DataFrame({"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": f})
    with pytest.warns(IdentificationWarning) as record:
        ident = identify(points, sensitivity=False)
    messages = [str(w.message) for w in record]
    assert any(m.startswith("F_c is not monotonic in pressure: it falls") for m in messages)
    assert any(m.startswith("F_s is not monotonic in pressure: it falls") for m in messages)
    assert sum("not monotonic" in note for note in ident.notes) == 2
