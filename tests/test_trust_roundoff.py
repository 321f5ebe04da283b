"""cylfric reads back every datasheet it writes (issue 11, F9 of the hostile check).

A bounded linear law converted to intercept and slope left sigma_2 = -2.2e-16 N*s/m at
10 bar; the model then refused its own datasheet (report, export, drift: exit 2 with
``np.float64(...)``), and the confidence band's difference quotients stepped across the
bound (sigma_2 = -0.017 N*s/m) even on a datasheet that was exactly physical.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cylfric.datasheet import validate
from cylfric.friction import params_at_pressure, stribeck
from cylfric.friction._checks import ROUNDOFF, clamp_roundoff
from cylfric.identify import identify
from cylfric.identify.linear_fit import _onto_bounds
from cylfric.model import FrictionModel
from cylfric.model.serialize import DatasheetError

SPEEDS = np.array([1, 2, 5, 10, 20, 50, 100]) * 1e-3  # the F9 campaign's speeds [m/s]
PRESSURES = np.array([10, 55, 103, 159]) * 1e5  # and pressures [Pa]


def _noise_model(seed):
    """Pure noise around 100 N (no speed or pressure trend), as the F9 campaign."""
    rng = np.random.default_rng(seed)
    v, p = (a.ravel() for a in np.meshgrid(SPEEDS, PRESSURES))
    points = pd.DataFrame(
        {"velocity [m/s]": v, "pressure [Pa]": p, "friction [N]": rng.uniform(80, 120, v.size)}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(points, sensitivity=False).model


def test_a_law_a_rounding_error_below_its_bound_is_put_exactly_onto_it():
    # sigma_2 fitted to 0 at 10 bar and 50 N*s/m at 159 bar; the intercept one float step
    # too low, as the two-point -> intercept/slope conversion can leave it
    slope = 50.0 / 149e5
    intercept = float(np.nextafter(-slope * 10e5, -math.inf))
    ends = (10e5, 159e5)
    coefficients = {
        "F_c": {"intercept": 100.0, "slope": 0.0},
        "sigma_2": {"intercept": intercept, "slope": slope},
    }
    before = params_at_pressure(np.array(ends), coefficients, law="linear")["sigma_2"]
    assert before[0] < 0  # the fault: a negative viscous coefficient at 10 bar
    _onto_bounds(coefficients, ends)
    after = params_at_pressure(np.array(ends), coefficients, law="linear")["sigma_2"]
    assert after[0] >= 0.0
    moved = abs(coefficients["sigma_2"]["intercept"] - intercept)
    assert moved < 1e-14  # moved by rounding only
    assert after[1] == pytest.approx(50.0, rel=1e-12)


def test_a_real_violation_is_not_hidden_by_the_rounding_clamp():
    coefficients = {"F_c": 100.0, "sigma_2": {"intercept": -1.0, "slope": 1e-6}}
    _onto_bounds(coefficients, (0.5e5, 10e5))  # sigma_2(0.5 bar) = -0.95 N*s/m: real
    assert coefficients["sigma_2"]["intercept"] == -1.0
    clamped = clamp_roundoff({"F_c": 10.0, "F_s": 9.0, "sigma_2": -1e-3})
    assert clamped == {"F_c": 10.0, "F_s": 9.0, "sigma_2": -1e-3}


def test_validation_and_the_model_agree_on_the_rounding_tolerance(tmp_path):
    """What the datasheet validation accepts, the model evaluates (same ROUNDOFF); what
    it refuses names the file."""
    base = FrictionModel.from_datasheet(_noise_model(5).to_datasheet())
    p_min = base.validity["pressure_min"]
    for below, accepted in ((0.5 * ROUNDOFF, True), (1e-6, False)):
        sheet = base.to_datasheet()
        s2 = sheet["parameters"]["sigma_2"]
        s2["intercept"] -= below + (s2["intercept"] + s2["slope"] * p_min)  # -below at p_min
        path = tmp_path / f"sheet_{below:g}.json"
        import json

        path.write_text(json.dumps(sheet))
        if accepted:
            model = FrictionModel.from_datasheet(path)
            assert model.params_at(p_min)["sigma_2"] == 0.0  # clamped onto the bound
            assert model.friction(0.05, p_min) > 0
            lower, upper = model.band(np.array([0.01, 0.05]), p_min)
            assert np.all(np.isfinite(lower)) and np.all(lower < upper)
        else:
            with pytest.raises(
                DatasheetError, match=rf"{path.name}: parameters/sigma_2: unphysical"
            ):
                FrictionModel.from_datasheet(path)


def test_the_band_of_a_model_with_a_coefficient_on_its_bound_evaluates():
    """Seed 5 fits sigma_2 = 0 exactly at 10 bar: the band's difference quotients step
    across that bound and used to raise (sigma_2 = np.float64(-0.017...) out of range)."""
    model = _noise_model(5)
    assert model.friction_law == "coulomb_viscous"
    p_min = model.validity["pressure_min"]
    assert model.params_at(p_min)["sigma_2"] == 0.0
    grid = np.geomspace(1e-3, 0.1, 9)
    for p in PRESSURES:
        lower, upper = model.band(grid, np.full_like(grid, p))
        f = model.friction(grid, np.full_like(grid, p))
        assert np.all(lower < f) and np.all(f < upper)
    validate(model.to_datasheet())


@pytest.mark.parametrize("seed", range(6))
def test_pure_noise_datasheets_are_exactly_physical_at_the_ends(seed):
    """No tolerance here: the written law itself holds the bounds at both ends."""
    model = _noise_model(seed)
    ends = np.array([model.validity["pressure_min"], model.validity["pressure_max"]])
    given = {k: v for k, v in model.coefficients().items() if v is not None}
    k = params_at_pressure(ends, given, law="linear")
    assert np.all(k["F_c"] >= 0.0)
    if "sigma_2" in k:
        assert np.all(k["sigma_2"] >= 0.0)
    if "F_s" in k:
        assert np.all(k["F_s"] >= k["F_c"])


def test_out_of_range_messages_print_plain_numbers():
    with pytest.raises(ValueError, match=r"parameter sigma_2 = -0\.017 is out of range; expected"):
        stribeck(0.01, F_c=10.0, F_s=12.0, v_r=0.01, sigma_2=np.float64(-0.017))
    with pytest.raises(ValueError, match=r"parameter F_c = -2\.0 is out of range") as info:
        stribeck(np.array([0.01]), F_c=np.array([-2.0]), F_s=1.0, v_r=0.01, sigma_2=1.0)
    assert "np.float64" not in str(info.value)


_near_bound = st.one_of(
    st.floats(-1e-6, 1e3),
    st.sampled_from([0.0, -1e-16, -1e-12, -1e-10, -1e-9, -2e-9, -1e-7]),
)


@given(F_c=_near_bound, dF=_near_bound, sigma_2=_near_bound)
def test_scalar_clamp_is_the_array_clamp(F_c, dF, sigma_2):
    """The plain-number path of clamp_roundoff (no numpy, for the batch's set-up) puts exactly
    the values the array path puts onto their bounds, and leaves the rest alone."""
    params = {"F_c": F_c, "F_s": F_c + dF, "sigma_2": sigma_2}
    scalar = clamp_roundoff(params)
    array = clamp_roundoff({k: np.array([v]) for k, v in params.items()})
    for name in params:
        assert isinstance(scalar[name], float)
        assert scalar[name] == float(np.asarray(array[name])[0]), name


def test_a_datasheet_without_a_friction_level_is_refused_not_a_type_error():
    """The schema lets F_c be null (as F_s and sigma_2); a model needs its level (found by
    mypy in the type work of issue 24: validate raised a bare TypeError)."""
    import pytest

    from cylfric.model import DatasheetError, FrictionModel, validate

    sheet = FrictionModel().to_datasheet()
    sheet["parameters"].update(F_c=None, F_s=None, sigma_2=None)
    with pytest.raises(DatasheetError, match="parameters/F_c: null"):
        validate(sheet)
