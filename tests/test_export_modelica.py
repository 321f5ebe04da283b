"""Modelica export: the package parses (modparc), and its equations reproduce cylfric.

No Modelica simulator is installable from the package index here (the ``modelica`` package
on the index is a 0.0.2 placeholder without its parser or simulator), so the element is not
simulated: the test parses the package and evaluates its steady-state equations (der(z) = 0,
z = g sign(v) / sigma_0) with the parameter values and pressure-law functions read from the
.mo text, against ``model.friction``.
"""

from __future__ import annotations

import re

import modparc
import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.export import export
from cylfric.export.modelica import modelica_package
from cylfric.model import FrictionModel

VALIDITY = {"pressure_min": 1e4, "pressure_max": 159e5, "velocity_min": 1e-3, "velocity_max": 0.135}

MODELS = {
    "thesis": FrictionModel(validity=VALIDITY),
    "quadratic_sum": FrictionModel(
        {
            "F_c": {"intercept": 60.0, "slope": 4e-6, "curvature": 1e-14},
            "F_s": {"intercept": 100.0, "slope": 5e-6, "curvature": 2e-14},
            "sigma_2": {"intercept": 300.0, "slope": 0.0, "curvature": 0.0},
            "v_r": 0.008,
            "alpha": 1.3,
        },
        pressure_law="quadratic",
        reference="sum",
    ),
    "exponential_max": FrictionModel(
        {
            "F_c": {"intercept": 60.0, "amplitude": 40.0, "rate": 1e-7},
            "F_s": {"intercept": 100.0, "amplitude": 50.0, "rate": 1e-7},
            "sigma_2": 320.0,
            "v_r": 0.01,
            "alpha": 1.0,
        },
        pressure_law="exponential",
        reference="max",
    ),
    "coulomb_viscous": FrictionModel(
        {"F_c": {"intercept": 80.0, "slope": 3e-6}, "sigma_2": {"intercept": 350.0, "slope": 0.0}},
        friction_law="coulomb_viscous",
    ),
}


def _steady_state_from_text(text, velocity, pressure_a, pressure_b):
    """Evaluate the .mo's own equations in steady state (a tiny reader for this package)."""

    def python(expr):
        expr = expr.replace("^", "**").replace("PressureLaws.", "")
        return re.sub(r"\babs\(", "np.abs(", re.sub(r"\bexp\(", "np.exp(", expr))

    env = {"np": np, "max": np.maximum}
    for _kind, name, value in re.findall(
        r'parameter (\S+?) (\w+)(?:\(unit="[^"]*"\))? = ([-+0-9.eE]+)', text
    ):
        env[name] = float(value)
    for name, inputs, body in re.findall(
        r"function (\w+) .*?((?:input Real \w+.*?;\s*)+)output Real y;\s*algorithm\s*y := (.*?);",
        text,
        flags=re.S,
    ):
        args = re.findall(r"input Real (\w+)", inputs)
        env[name] = eval(f"lambda {', '.join(args)}: {python(body)}", env)  # noqa: S307
    env.update(v_rel=velocity, p_a=pressure_a, p_b=pressure_b)
    equations = text.split("  equation\n", 1)[1].split("der(z)")[0]
    for line in equations.strip().splitlines():
        left, _, right = line.strip().rstrip(";").partition(" = ")
        if left in ("s_rel", "v_rel"):
            continue
        env[left] = eval(python(right), env)  # noqa: S307
    return env["g"] * np.sign(velocity) + env["sigma_2"] * velocity  # der(z) = 0


@pytest.mark.parametrize("key", sorted(MODELS))
def test_package_parses_and_reproduces_the_model_in_steady_state(key, tmp_path):
    model = MODELS[key]
    result = export(model, "modelica", tmp_path, name=key)
    assert result.lossless and len(result.files) == 1
    text = result.files[0].read_text()
    tree = modparc.parse(text)
    declared = {str(c) for c in tree.search("Declaration")}
    assert any("flange_a" in d for d in declared) and any("p_b" in d for d in declared)
    v = np.array([-0.12, -0.01, -0.001, 0.002, 0.02, 0.135])
    pa = np.array([5e5, 20e5, 80e5, 100e5, 150e5, 1e4])
    pb = np.array([5e5, 30e5, 80e5, 60e5, 150e5, 1e4])
    expected = model.friction(v, model.operating_pressure(pa, pb))
    assert_allclose(_steady_state_from_text(text, v, pa, pb), expected, rtol=1e-12)


def test_parameters_carry_si_units_and_the_interfaces():
    _, text = modelica_package(MODELS["thesis"], name="thesis")
    assert "Modelica.Mechanics.Translational.Interfaces.Flange_a flange_a" in text
    assert "Modelica.Mechanics.Translational.Interfaces.Flange_b flange_b" in text
    assert 'Modelica.Blocks.Interfaces.RealInput p_a(unit="Pa"' in text
    assert "parameter SI.Force F_c_intercept = 70.2" in text
    assert 'parameter Real F_c_slope(unit="N/Pa") = 5.0000000000000004e-06' in text
    assert 'parameter Real sigma_2_slope(unit="N.s/(m.Pa)")' in text
    assert "parameter SI.TranslationalSpringConstant sigma_0 = 1000000.0" in text
    assert "SI.Position z(start=0, fixed=true)" in text
    assert "p = (p_a + p_b)/2;" in text  # the thesis rule: mean of the chamber pressures


def test_parser_rejects_a_broken_package():
    # the check above means something only if the parser refuses broken text
    _, text = modelica_package(MODELS["thesis"], name="thesis")
    with pytest.raises(Exception):  # noqa: B017 - modparc raises funcparserlib's NoParseError
        modparc.parse(text.replace("  equation\n", "  equation\n    f = ;\n", 1))


def test_export_is_deterministic(tmp_path):
    a = export(MODELS["thesis"], "modelica", tmp_path / "a", name="x").files[0]
    b = export(MODELS["thesis"], "modelica", tmp_path / "b", name="x").files[0]
    assert a.read_bytes() == b.read_bytes()
    assert a.name == "X.mo"
