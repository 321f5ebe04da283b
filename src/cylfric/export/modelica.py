"""Modelica export: a package with the pressure-dependent LuGre friction element (lossless).

The package ``<name>`` holds

* ``Friction``: LuGre friction (thesis eq. 2.5-2.7) between the translational flanges
  ``flange_a`` (rod) and ``flange_b`` (housing) of
  ``Modelica.Mechanics.Translational.Interfaces``, with the chamber pressures as
  ``Modelica.Blocks.Interfaces.RealInput`` ``p_a`` and ``p_b`` [Pa], the datasheet's
  operating-pressure rule, the bristle state ``z``, and every coefficient of the datasheet as
  a parameter with its SI unit (``Modelica.Units.SI`` types where they exist);
* ``Scatter`` and ``LackOfFit``: the datasheet's scatter components (``fit.scatter``:
  ``Scatter.session_percent`` [%], ``Scatter.session_N`` [N], ``Scatter.reproducibility_percent``,
  sources and the prior's basis) and lack-of-fit test (``quality.lack_of_fit``) as constants
  with units and descriptions, ``computed = false`` when the datasheet has none;
* ``PressureLaws``: the linear, quadratic and exponential laws as Modelica functions;
* ``Examples.ConstantVelocity``: the element pulled at constant speed and pressure.

The equations are written once, in the template ``templates/modelica.mo.tmpl``; this module
only fills in names and numbers. It carries the full model: no loss report.
"""

from __future__ import annotations

from pathlib import Path
from string import Template
from typing import TYPE_CHECKING

from ..escape import html_text, identifier, modelica_string
from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS
from ..io.writers import atomic_write_text
from ..model.core import DYNAMIC_PARAMETERS, STEADY_PARAMETERS
from .result import ExportResult
from .scatter import (
    LACK_OF_FIT_NUMBERS,
    NOT_COMPUTED,
    SCATTER_NUMBERS,
    band_text,
    lack_of_fit_numbers,
    lack_of_fit_texts,
    scatter_numbers,
    scatter_texts,
)

if TYPE_CHECKING:
    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = ["export_modelica", "modelica_package", "OPERATING_PRESSURE"]

OPERATING_PRESSURE = {
    "a": "p_a",
    "b": "p_b",
    "sum": "p_a + p_b",
    "mean": "(p_a + p_b)/2",
    "max": "max(p_a, p_b)",
}
"""The model's operating-pressure rule as a Modelica expression of ``p_a`` and ``p_b``."""

# Modelica type and unit (numerator, denominator) of each parameter
_TYPES = {
    "F_c": ("SI.Force", "N", ""),
    "F_s": ("SI.Force", "N", ""),
    "sigma_2": ("SI.TranslationalDampingConstant", "N.s", "m"),
    "v_r": ("SI.Velocity", "m", "s"),
    "alpha": ("Real", "1", ""),
    "sigma_0": ("SI.TranslationalSpringConstant", "N", "m"),
    "sigma_1": ("SI.TranslationalDampingConstant", "N.s", "m"),
}
_COMMENTS = {
    "F_c": "Coulomb friction [N]",
    "F_s": "Stiction (breakaway) friction [N]",
    "sigma_2": "Viscous coefficient [N.s/m]",
    "v_r": "Stribeck velocity parameter [m/s]",
    "alpha": "Stribeck exponent [1]",
    "sigma_0": "Bristle stiffness [N/m]",
    "sigma_1": "Bristle damping [N.s/m]",
}
_PER_PA = {"slope": 1, "curvature": 2, "rate": 1}


def _unit(parameter, coefficient=None) -> str:
    """Modelica unit string of a parameter or of one of its pressure-law coefficients."""
    _, numerator, denominator = _TYPES[parameter]
    if coefficient == "rate":
        return "1/Pa"
    power = _PER_PA.get(coefficient, 0)
    if not power:
        return numerator if not denominator else f"{numerator}/{denominator}"
    pa = "Pa" if power == 1 else "Pa2"
    return f"{numerator}/{pa}" if not denominator else f"{numerator}/({denominator}.{pa})"


def _num(x) -> str:
    text = format(float(x), ".17g")
    return text if any(c in text for c in ".en") else f"{text}.0"


def _specs(model):
    """(parameter, law, {coefficient: value}) of every parameter, as params_at evaluates it.

    Parameters a reduced law does not identify take the values ``FrictionModel.params_at``
    gives them (``F_s = F_c``, ``sigma_2 = 0``, ``v_r = 1``, ``alpha = 1``).
    """
    coefficients = model.coefficients()
    out: list[tuple[str, str, str | dict[str, float]]] = []
    for name in STEADY_PARAMETERS + DYNAMIC_PARAMETERS:
        law = model.laws[name]
        spec = coefficients[name]
        if spec is None:
            fallback = {"F_s": "F_c", "sigma_2": 0.0, "v_r": 1.0, "alpha": 1.0}[name]
            if isinstance(fallback, str):
                out.append((name, "same", fallback))
                continue
            law, spec = "constant", fallback
        if law == "constant":
            value = spec["intercept"] if isinstance(spec, dict) else spec
            out.append((name, "constant", {"intercept": float(value)}))
        else:
            names = PRESSURE_LAW_COEFFICIENTS[law]
            out.append((name, law, {c: float(spec[c]) for c in names}))
    return out


_COUNTS = ("sessions", "runs", "points", "dof_1", "dof_2")


def _constant(name: str, value: float, unit: str, meaning: str) -> str:
    """One Modelica constant declaration of a scatter number, with its unit."""
    if name == "significant":
        declaration = f"constant Boolean {name} = {'true' if value else 'false'}"
    elif name in _COUNTS and float(value).is_integer():
        declaration = f"constant Integer {name} = {int(value)}"
    elif unit == "N":
        declaration = f"constant SI.Force {name} = {_num(value)}"
    elif unit == "%":  # a percentage of the friction level: no SI unit, stated in the text
        declaration = f"constant Real {name} = {_num(value)}"
    else:
        declaration = f'constant Real {name}(unit="{unit}") = {_num(value)}'
    return f'    {declaration} "{modelica_string(f"{meaning} [{unit}]", quotes=False)}";'


def scatter_packages(model: FrictionModel) -> str:
    """Modelica source of the packages ``Scatter`` (fit.scatter) and ``LackOfFit``
    (quality.lack_of_fit): constants with units and descriptions, ``computed = false`` when
    the datasheet has no such record."""
    records = (
        (
            "Scatter",
            "fit.scatter",
            "Scatter about the law: repeatability, run and session components (datasheet "
            "fit.scatter; % of the friction level and N)",
            scatter_numbers(model),
            scatter_texts(model),
            SCATTER_NUMBERS,
        ),
        (
            "LackOfFit",
            "quality.lack_of_fit",
            "Lack-of-fit test of the law (datasheet quality.lack_of_fit)",
            lack_of_fit_numbers(model),
            lack_of_fit_texts(model),
            LACK_OF_FIT_NUMBERS,
        ),
    )
    out = []
    for package, key, title, numbers, texts, table in records:
        out += [f'  package {package} "{title}"', "    import SI = Modelica.Units.SI;"]
        if numbers is None or texts is None:
            note = modelica_string(NOT_COMPUTED.format(key=key), quotes=False)
            out.append(f'    constant Boolean computed = false "{note}";')
        else:
            out.append(f'    constant Boolean computed = true "the datasheet carries {key}";')
            for name, value in numbers.items():
                unit, meaning = table[name]
                out.append(_constant(name, value, unit, meaning))
            for name, text in texts.items():
                out.append(f"    constant String {name} = {modelica_string(text)};")
        if package == "Scatter":
            info = modelica_string(html_text(band_text(model)), quotes=False)
            out.append(f'    annotation (Documentation(info="<html><p>{info}</p></html>"));')
        out.append(f"  end {package};")
        out.append("")
    return "\n".join(out)


def modelica_package(model: FrictionModel, *, name: str | None = None) -> tuple[str, str]:
    """(package name, Modelica source text) of the model's friction package."""
    package = identifier(name or model.record.get("name") or "cylfric")
    package = package[0].upper() + package[1:]
    parameters, variables, laws = [], [], []
    for parameter, law, spec in _specs(model):
        kind = _TYPES[parameter][0]
        comment = _COMMENTS[parameter]
        status = model.dynamic_status.get(parameter)
        if status is not None and status[0] == "assumed":  # said where it is used
            why = modelica_string(status[1], quotes=False)
            comment += f", ASSUMED, not identified: {why}; see docs/dynamic_parameters.md"
        if law == "same":
            variables.append(f'    {kind} {parameter} "{comment} (= {spec}: not identified)";')
            laws.append(f"    {parameter} = {spec};")
        elif law == "constant":
            unit = "" if kind != "Real" else f'(unit="{_unit(parameter)}")'
            parameters.append(
                f'    parameter {kind} {parameter}{unit} = {_num(spec["intercept"])} "{comment}";'
            )
        else:
            for coefficient, value in spec.items():
                base = kind if coefficient in ("intercept", "amplitude") else "Real"
                unit = "" if base != "Real" else f'(unit="{_unit(parameter, coefficient)}")'
                parameters.append(
                    f"    parameter {base} {parameter}_{coefficient}{unit} = {_num(value)} "
                    f'"{comment}: {coefficient} of the {law} pressure law";'
                )
            variables.append(f'    {kind} {parameter} "{comment} at the operating pressure";')
            arguments = ", ".join(f"{parameter}_{c}" for c in spec)
            laws.append(f"    {parameter} = PressureLaws.{law}(p, {arguments});")
    validity = "the whole range (no validity given)"
    if model.validity is not None:
        val = model.validity
        validity = (
            f"{val['pressure_min'] / 1e5:.4g}-{val['pressure_max'] / 1e5:.4g} bar, "
            f"{val['velocity_min'] * 1e3:.4g}-{val['velocity_max'] * 1e3:.4g} mm/s"
        )
    label = str(model.record.get("name", "cylfric model"))
    example_p = (
        55e5
        if model.validity is None
        else 0.5 * (model.validity["pressure_min"] + model.validity["pressure_max"])
    )
    example_p = example_p / float(model.operating_pressure(1.0, 1.0))
    basis = model.pressure_reference_basis
    if basis is not None and basis["kind"] == "single-acting":
        # the working chamber at p, the other at atmosphere (0 gauge), as the cylinder runs
        working = "b" if basis.get("chamber") == "b" else "a"
        other = "a" if working == "b" else "b"
        example_comment = f"Pressure of the working chamber {working.upper()} (gauge)"
        example_connect = (
            f"      connect(pressure.y, friction.p_{working});\n"
            f'      friction.p_{other} = 0 "chamber {other.upper()} at atmosphere (gauge)";'
        )
    else:
        example_comment = "Chamber pressure (both chambers)"
        example_connect = (
            "      connect(pressure.y, friction.p_a);\n      connect(pressure.y, friction.p_b);"
        )
    template = Template(
        (Path(__file__).parent / "templates" / "modelica.mo.tmpl").read_text(encoding="utf-8")
    )
    text = template.substitute(
        package=package,
        name_string=modelica_string(label, quotes=False),
        name_html=modelica_string(html_text(label), quotes=False),
        reference=model.reference,
        operating=OPERATING_PRESSURE[model.reference],
        parameters="\n".join(parameters),
        variables="\n".join(variables),
        laws="\n".join(laws),
        validity=validity,
        example_velocity=_num(0.025),
        example_pressure=_num(example_p),
        example_pressure_comment=example_comment,
        example_connect=example_connect,
        scatter=scatter_packages(model),
        band_html=modelica_string(html_text(band_text(model)), quotes=False),
    )
    return package, text


def export_modelica(model: FrictionModel, out: StrPath, *, name: str | None = None) -> ExportResult:
    """Write the model's Modelica package ``<Name>.mo`` into ``out`` (lossless).

    Parameters
    ----------
    model : FrictionModel
        The cylfric model.
    out : path-like
        Output folder (created).
    name : str, optional
        Package name (made a Modelica identifier); default the datasheet's name.

    Returns
    -------
    ExportResult
        The file; ``loss`` None (the element carries the full model).
    """
    package, text = modelica_package(model, name=name)
    path = atomic_write_text(Path(out) / f"{package}.mo", text)
    return ExportResult("modelica", (path,), None)
