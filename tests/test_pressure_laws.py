"""Pressure laws (operating point -> parameter dict), thesis eq. 2.10 and 4.1-4.3."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric import friction as fr
from cylfric.friction import pressure as pl
from cylfric.friction.literature import LITERATURE, THESIS_2016, THESIS_2016_REVISED


def test_linear_thesis_law_composes_with_stribeck():
    p = np.array([0.1, 55.0, 159.0]) * 1e5
    params = fr.params_at_pressure(p, THESIS_2016.coefficients)
    assert_allclose(params["F_c"], 70.2 + 0.5 * p / 1e5)
    force = fr.stribeck(0.05, **params)
    assert force.shape == (3,) and np.all(np.diff(force) > 0)


def test_revised_thesis_intercepts():
    params = fr.params_at_pressure(0.0, THESIS_2016_REVISED.coefficients)
    assert_allclose([params["F_c"], params["F_s"]], [73.5, 117.0])


def test_quadratic_and_exponential_reduce_to_linear():
    p = np.linspace(0, 2e7, 5)
    assert_allclose(pl.quadratic(p, 1.0, 2e-6, 0.0), pl.linear(p, 1.0, 2e-6))
    assert_allclose(pl.exponential(p, 1.0, 2e-6 / 1e-12, 1e-12), pl.linear(p, 1.0, 2e-6), rtol=1e-4)


def test_mixed_laws_in_one_coefficient_set():
    coeffs = {
        "F_c": {"law": "exponential", "intercept": 50.0, "amplitude": 10.0, "rate": 1e-7},
        "F_s": {"intercept": 80.0, "slope": 1e-5},
        "sigma_2": 300.0,
        "v_r": 0.01,
    }
    out = fr.params_at_pressure(1e7, coeffs)
    assert_allclose(out["F_c"], 50.0 + 10.0 * np.expm1(1.0))
    assert_allclose(out["F_s"], 180.0)


@pytest.mark.parametrize(
    ("reference", "expected"),
    [("a", 10.0), ("b", 30.0), ("sum", 40.0), ("mean", 20.0), ("max", 30.0)],
)
def test_operating_pressure_references(reference, expected):
    assert fr.operating_pressure(10.0, 30.0, reference=reference) == expected


def test_operating_pressure_unknown_reference_lists_valid():
    with pytest.raises(ValueError, match=r"unknown pressure reference 'avg'; valid: \['a', 'b'"):
        fr.operating_pressure(1.0, reference="avg")


def test_unknown_pressure_law_and_wrong_coefficients():
    with pytest.raises(
        ValueError, match=r"unknown pressure law 'cubic'; valid: \['constant', 'exponential'"
    ):
        fr.params_at_pressure(1.0, {"F_c": {"law": "cubic", "intercept": 1.0}})
    with pytest.raises(ValueError, match="coefficients of F_c do not fit the linear pressure law"):
        fr.params_at_pressure(1.0, {"F_c": {"intercept": 1.0, "rate": 2.0}})


def test_simscape_cylinder_friction_form():
    out = fr.simscape_cylinder_friction(
        50e5,
        30e5,
        preload_force=20.0,
        coulomb_friction_coefficient=1e-6,
        breakaway_ratio=1.5,
        viscous_coefficient=300.0,
        transition_coefficient=100.0,
    )
    assert_allclose(out["F_c"], 20.0 + 1e-6 * 80e5)
    assert_allclose(out["F_s"], 1.5 * out["F_c"])
    assert out["v_r"] == 0.01 and out["alpha"] == 1.0
    with pytest.raises(ValueError, match="breakaway_ratio = 0.5 is out of range; expected >= 1"):
        fr.simscape_cylinder_friction(
            0,
            0,
            preload_force=1,
            coulomb_friction_coefficient=0,
            breakaway_ratio=0.5,
            viscous_coefficient=0,
            transition_coefficient=1,
        )
    with pytest.raises(ValueError, match="transition_coefficient = 0 is out of range"):
        fr.simscape_cylinder_friction(
            0,
            0,
            preload_force=1,
            coulomb_friction_coefficient=0,
            breakaway_ratio=1,
            viscous_coefficient=0,
            transition_coefficient=0,
        )


def test_every_literature_set_has_a_citation():
    for s in LITERATURE.values():
        assert len(s.citation) > 20 and s.name
