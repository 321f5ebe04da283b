"""Identification never writes an unphysical model; it falls back to what the data support
(issue 11: pure noise, no Stribeck dip, held F_c, flipped force-balance sign)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from cylfric.datasheet import build_datasheet, validate
from cylfric.friction import params_at_pressure, stribeck
from cylfric.friction.literature import THESIS_2016
from cylfric.identify import fit_stribeck, identify

SPEEDS = np.array([1, 2, 4, 7, 10, 15, 25, 40, 70, 135]) * 1e-3
PRESSURES = np.array([0.1, 55, 103, 159]) * 1e5


def _points(friction_of, noise=0.3, seed=0):
    rng = np.random.default_rng(seed)
    v, p = (a.ravel() for a in np.meshgrid(SPEEDS, PRESSURES))
    f = friction_of(v, p) + rng.normal(0, noise, v.size)
    return pd.DataFrame({"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": f})


def _identify(points, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(points, **kwargs)


def _physical(model):
    p = np.linspace(0.1e5, 159e5, 50)
    k = model.params_at(p)
    tol = 1e-9 * np.max(k["F_s"])  # a value at its bound, after rounding
    return (
        np.all(k["F_c"] >= -tol)
        and np.all(k["F_s"] >= k["F_c"] - tol)
        and np.all(k["sigma_2"] >= -1e-9)
    )


def test_pure_noise_gives_no_stribeck_dip_and_no_negative_coefficient():
    ident = _identify(_points(lambda v, p: 100.0 + 0 * v, noise=1.0))
    model = ident.model
    assert model.friction_law in ("coulomb_viscous", "coulomb")
    assert _physical(model)
    assert any("no identifiable Stribeck dip" in note for note in ident.notes)
    sheet = build_datasheet(ident)
    assert sheet["parameters"]["F_s"] is None and sheet["parameters"]["v_r"] is None
    assert "no identifiable Stribeck dip" in sheet["not_identified"]["F_s"]
    validate(sheet)
    assert ident.sensitivity is None  # no shape to study


def test_coulomb_plus_viscous_data_give_that_model_not_sigma_2_zero():
    ident = _identify(_points(lambda v, p: 80.0 + 0.3e-5 * p + 500.0 * v))
    model = ident.model
    assert model.friction_law == "coulomb_viscous"
    coefficients = model.coefficients()
    assert coefficients["F_c"]["intercept"] == pytest.approx(80.0, abs=0.5)
    assert coefficients["F_c"]["slope"] == pytest.approx(0.3e-5, rel=0.05)
    assert coefficients["sigma_2"]["intercept"] == pytest.approx(500.0, rel=0.02)
    assert model.parameters["sigma_2.intercept"].stderr > 0


def test_thesis_data_keep_the_stribeck_law():
    def thesis(v, p):
        return stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))

    ident = _identify(_points(thesis))
    assert ident.model.friction_law == "stribeck" and ident.stribeck_identifiable
    assert _physical(ident.model)


def test_held_F_c_is_held_in_the_datasheet():
    def thesis(v, p):
        return stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))

    ident = _identify(_points(thesis), fixed={"F_c": 70.0, "alpha": 1.0})
    sheet = build_datasheet(ident)
    assert sheet["parameters"]["F_c"] == {"law": "constant", "intercept": 70.0}
    assert sheet["fit"]["fixed"]["F_c"] == 70.0 and sheet["fit"]["fixed"]["alpha"] == 1.0
    assert all(row["F_c"] == 70.0 for row in sheet["per_pressure"])


def test_flipped_force_balance_sign_is_refused():
    def flipped(v, p):
        return -stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))

    with pytest.raises(ValueError, match="friction level is pushed to 0 N .* force-balance signs"):
        _identify(_points(flipped))


def test_single_pressure_stribeck_fit_keeps_F_s_above_F_c():
    # friction that rises towards zero speed less than noise: F_s must not fall below F_c
    rng = np.random.default_rng(2)
    v = np.geomspace(1e-3, 0.1, 14)
    f = 100.0 - 3.0 * np.exp(-v / 0.01) + 200.0 * v + rng.normal(0, 0.2, v.size)
    fit = fit_stribeck(v, f)
    assert fit.params["F_s"] >= fit.params["F_c"]
    assert fit.stderr["F_s"] >= 0
    held = fit_stribeck(v, f, fixed={"F_s": 99.0})
    assert held.params["F_c"] <= 99.0


def test_pressure_law_other_than_linear_is_refused_for_a_reduced_model():
    with pytest.raises(ValueError, match="quadratic pressure law cannot be used on these data"):
        _identify(_points(lambda v, p: 100.0 + 0 * v, noise=1.0), pressure_law="quadratic")


def test_each_warning_is_a_note_once():
    """Regression (issue 11 audit): --fix F_c=70N on the thesis data printed 'Covariance of
    the parameters could not be estimated' three times, once per pressure-law fit."""

    def thesis(v, p):
        return stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))

    ident = _identify(_points(thesis), fixed={"F_c": 70.0})
    assert ident.notes and len(ident.notes) == len(set(ident.notes))
