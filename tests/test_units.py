"""Unit conversion at the edges."""

import pytest
from numpy.testing import assert_allclose

from cylfric.units import UnitError, from_si, parse_quantity, to_si


@pytest.mark.parametrize(
    ("text", "dimension", "expected"),
    [
        ("10mm/s", "velocity", 0.01),
        ("55bar", "pressure", 55e5),
        ("5MPa", "pressure", 5e6),
        ("5 MPa", "pressure", 5e6),
        ("0,5 kN", "force", 500.0),
        ("20 ms", "time", 0.02),
        ("1e3 Pa", "pressure", 1e3),
        ("0.34 N*s/mm", "damping", 340.0),
    ],
)
def test_parse_quantity(text, dimension, expected):
    assert_allclose(parse_quantity(text, dimension), expected)


def test_bare_number_uses_default_unit():
    assert parse_quantity("159", "pressure", default_unit="bar") == 159e5


def test_round_trip():
    assert_allclose(from_si(to_si(12.5, "psi"), "psi"), 12.5)


def test_errors_name_the_problem():
    with pytest.raises(UnitError, match="unit 'mm' is a length unit, expected a pressure unit"):
        parse_quantity("5mm", "pressure")
    with pytest.raises(UnitError, match="unknown unit 'furlong'; known units:"):
        to_si(1.0, "furlong")
    with pytest.raises(UnitError, match="cannot read 'fast' as a velocity"):
        parse_quantity("fast", "velocity")
