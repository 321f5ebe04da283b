"""MATLAB / GNU Octave export of the friction model: functions and a parameter struct (lossless).

``export_matlab(model, out)`` writes four function files into ``out`` (prefix ``cylfric`` by
default):

``cylfric_params.m``
    ``P = cylfric_params()``: the parameter struct, every value in SI with its unit in a
    comment: the operating-pressure rule ``P.reference``, and for each friction parameter its
    pressure law ``P.F_c.law`` with the coefficients (``P.F_c.intercept`` [N],
    ``P.F_c.slope`` [N/Pa], ...); parameters the data did not identify are ``[]``; the
    scatter record ``P.scatter`` (``repeatability_percent`` [%], ``run_N`` [N], ...,
    ``reproducibility_percent``, ``session_source``, ``session_prior_basis``) and the
    lack-of-fit test ``P.lack_of_fit`` (``p_value``, ``significant``, ``action``), each with
    ``computed = false`` when the datasheet has none (:mod:`cylfric.export.scatter`).
``cylfric_params_at.m``
    ``q = cylfric_params_at(p_a, p_b, P)``: the friction parameters at the operating pressure
    of the chamber pressures [Pa].
``cylfric_friction.m``
    ``F = cylfric_friction(v, p_a, p_b, P)``: the steady-state friction [N] (thesis eq. 2.7)
    at velocity ``v`` [m/s], vectorised with implicit expansion (MATLAB R2016b+, Octave).
``cylfric_lugre_step.m``
    ``[z, F] = cylfric_lugre_step(z, v, p_a, p_b, h, P)``: the exact LuGre bristle update over a
    step ``h`` [s] at constant velocity (eq. 2.5) and the dynamic friction force [N].

The values are written with 17 significant digits, so MATLAB reads back the same doubles:
nothing is lost. The files are written atomically and are deterministic (no dates).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import TYPE_CHECKING

from ..escape import matlab_comment, matlab_string
from .fmu import FRICTION_PARAMETERS, REFERENCE_TEXT, _as_model, _check_name
from .scatter import NOT_COMPUTED, band_text, scatter_records

if TYPE_CHECKING:
    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = ["export_matlab", "MATLAB_FUNCTIONS", "scatter_struct_lines"]

MATLAB_FUNCTIONS = ("params", "params_at", "friction", "lugre_step")
"""The functions written, as ``<name>_<function>.m``."""

_MEANING = {
    "F_c": "Coulomb friction level",
    "F_s": "stiction (breakaway) level",
    "sigma_2": "viscous coefficient",
    "v_r": "Stribeck velocity parameter",
    "alpha": "Stribeck exponent",
    "sigma_0": "bristle stiffness",
    "sigma_1": "bristle damping",
}
_MISSING_VALUE = {"F_s": "q.F_c", "sigma_2": "0 .* q.F_c", "v_r": "1", "alpha": "1"}


def _number(value: float) -> str:
    """A double as text MATLAB reads back exactly (shortest round-trip, 17 digits at most)."""
    text = repr(float(value))
    return text if text not in ("inf", "-inf", "nan") else text.capitalize()


def _params_file(model, name) -> str:
    from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS

    lines = [
        f"function P = {name}_params()",
        f"%{name.upper()}_PARAMS Parameters of the cylfric friction model (SI units).",
        f"%   P = {name}_params() returns the struct that {name}_friction and",
        f"%   {name}_lugre_step use. Written by cylfric (cylfric.export.matlab); the values are",
        "%   the model's own, to the last bit (17 significant digits).",
        "%",
        f"%   Steady-state law: {model.friction_law}.",
        f"%   Operating pressure: {REFERENCE_TEXT[model.reference]} [Pa].",
        "%   Each friction parameter X has a pressure law X.law of the operating pressure p:",
        "%     constant     X = intercept",
        "%     linear       X = intercept + slope p",
        "%     quadratic    X = intercept + slope p + curvature p^2",
        "%     exponential  X = intercept + amplitude (exp(rate p) - 1)",
        "%   A parameter the data did not identify is [] (F_s = F_c, sigma_2 = 0).",
    ]
    method = model.provenance.get("method")
    if method:
        lines.append(f"%   Identified by: {matlab_comment(method)}.")
    lines.append(
        "%   P.scatter: the scatter components (repeatability, run, session: *_percent [%],"
    )
    lines.append(
        "%   *_N [N]), reproducibility s_R; P.lack_of_fit: the lack-of-fit test (computed ="
    )
    lines.append("%   false when the datasheet has none).")
    lines += [f"%   {line}" for line in textwrap.wrap(band_text(model), 86)]
    lines += [
        "",
        f"P.reference = {matlab_string(model.reference)};  % operating-pressure rule: a, b, sum, "
        "mean, max",
        f"P.friction_law = {matlab_string(model.friction_law)};",
    ]
    for parameter in FRICTION_PARAMETERS:
        law = model.laws[parameter]
        meaning = _MEANING[parameter]
        if law is None:
            reason = model.not_identified.get(parameter, "not identified")
            lines.append(
                f"P.{parameter} = [];  % {meaning}: not identified ({matlab_comment(reason)})"
            )
            continue
        status = model.dynamic_status.get(parameter)
        note = f", {matlab_comment(status[0])}: {matlab_comment(status[1])}" if status else ""
        lines.append(f"P.{parameter}.law = {matlab_string(law)};  % {meaning}{note}")
        for coefficient in PRESSURE_LAW_COEFFICIENTS[law]:
            key = parameter if law == "constant" else f"{parameter}.{coefficient}"
            p = model.parameters[key]
            lines.append(
                f"P.{parameter}.{coefficient} = {_number(p.value)};  % [{matlab_comment(p.unit)}]"
            )
    if model.validity is not None:
        lines.append("% range the data covered (outside it the model is extrapolated)")
        units = {"pressure_min": "Pa", "pressure_max": "Pa"}
        for key in ("pressure_min", "pressure_max", "velocity_min", "velocity_max"):
            value = model.validity[key]
            lines.append(f"P.validity.{key} = {_number(value)};  % [{units.get(key, 'm/s')}]")
    lines += scatter_struct_lines(model, "P")
    lines += ["end", ""]
    return "\n".join(lines)


def scatter_struct_lines(model, prefix: str) -> list[str]:
    """MATLAB lines setting ``<prefix>.scatter`` and ``<prefix>.lack_of_fit`` (SI, % and N).

    ``<prefix>.scatter.computed`` is false, with a ``note``, when the datasheet has no
    ``fit.scatter`` record (an older cylfric); likewise ``lack_of_fit``. User text goes
    through :func:`cylfric.escape.matlab_string` and :func:`~cylfric.escape.matlab_comment`.
    """
    lines = [
        "% scatter about the law (datasheet fit.scatter; relative values in % of the friction",
        "% level, forces in N at reference_force_N; docs/uncertainty.md)",
    ]
    records = scatter_records(model)
    for field, key, numbers, texts, table in records:
        struct = f"{prefix}.{field}"
        if numbers is None or texts is None:
            note = NOT_COMPUTED.format(key=key)
            lines.append(f"{struct}.computed = false;  % {note}")
            lines.append(f"{struct}.note = {matlab_string(note)};")
            continue
        lines.append(f"{struct}.computed = true;")
        for name, value in numbers.items():
            unit, meaning = table[name]
            if name == "significant":
                text = "true" if value else "false"
            elif unit == "1" and float(value).is_integer():
                text = str(int(value))
            else:
                text = _number(value)
            lines.append(f"{struct}.{name} = {text};  % [{unit}] {meaning}")
        for name, words in texts.items():
            lines.append(f"{struct}.{name} = {matlab_string(words)};")
    lines.append(f"% {band_text(model)}")
    return lines


def _params_at_file(model, name) -> str:
    lines = [
        f"function q = {name}_params_at(p_a, p_b, P)",
        f"%{name.upper()}_PARAMS_AT Friction parameters at the operating pressure (SI).",
        f"%   q = {name}_params_at(p_a, p_b, P) with chamber pressures p_a, p_b [Pa] (p_b",
        "%   defaults to p_a) returns q.F_c, q.F_s [N], q.sigma_2 [N*s/m], q.v_r [m/s],",
        "%   q.alpha [-], q.sigma_0 [N/m], q.sigma_1 [N*s/m] (arrays of the pressures' size).",
        f"%   P defaults to {name}_params().",
        "if nargin < 2 || isempty(p_b), p_b = p_a; end",
        f"if nargin < 3, P = {name}_params(); end",
        "switch P.reference",
        "  case 'a', p = p_a;",
        "  case 'b', p = p_b;",
        "  case 'sum', p = p_a + p_b;",
        "  case 'mean', p = 0.5 .* (p_a + p_b);",
        "  case 'max', p = max(p_a, p_b);",
        "  otherwise, error('cylfric:reference', 'unknown pressure reference %s', P.reference);",
        "end",
        "q.F_c = pressure_law(P.F_c, p);",
    ]
    for parameter in FRICTION_PARAMETERS[1:]:
        if parameter in _MISSING_VALUE:
            lines += [
                f"if isempty(P.{parameter})",
                f"  q.{parameter} = {_MISSING_VALUE[parameter]};",
                "else",
                f"  q.{parameter} = pressure_law(P.{parameter}, p);",
                "end",
            ]
        else:
            lines.append(f"q.{parameter} = pressure_law(P.{parameter}, p);")
    lines += [
        "end",
        "",
        "function value = pressure_law(spec, p)",
        "% a pressure law of the operating pressure p [Pa] (cylfric.friction.pressure)",
        "switch spec.law",
        "  case 'constant'",
        "    value = spec.intercept + 0 .* p;",
        "  case 'linear'",
        "    value = spec.intercept + spec.slope .* p;",
        "  case 'quadratic'",
        "    value = spec.intercept + spec.slope .* p + spec.curvature .* p .* p;",
        "  case 'exponential'",
        "    % by its initial slope amplitude*rate, as cylfric: well posed as rate -> 0",
        "    c = spec.rate;",
        "    if abs(c) < 1e-14, c = 1e-14; end",
        "    value = spec.intercept + spec.amplitude .* spec.rate .* expm1(c .* p) ./ c;",
        "  otherwise",
        "    error('cylfric:law', 'unknown pressure law %s', spec.law);",
        "end",
        "end",
        "",
    ]
    return "\n".join(lines)


def _friction_file(model, name) -> str:
    return "\n".join(
        [
            f"function F = {name}_friction(v, p_a, p_b, P)",
            f"%{name.upper()}_FRICTION Steady-state friction force [N] of the cylfric model.",
            f"%   F = {name}_friction(v, p_a, p_b) at velocity v [m/s] (> 0 extends) and chamber",
            "%   pressures p_a, p_b [Pa] (p_b defaults to p_a); arrays broadcast (implicit",
            "%   expansion). F is positive in the direction of motion, 0 at v = 0.",
            "%     F = sign(v) (F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha) + sigma_2 |v|)   eq. 2.7",
            f"%   with the parameters at the operating pressure {REFERENCE_TEXT[model.reference]}.",
            f"%   P defaults to {name}_params().",
            "if nargin < 3, p_b = []; end",
            f"if nargin < 4, P = {name}_params(); end",
            f"q = {name}_params_at(p_a, p_b, P);",
            "speed = abs(v);",
            "g = q.F_c + (q.F_s - q.F_c) .* exp(-((speed ./ q.v_r) .^ q.alpha));  % eq. 2.5, g(v)",
            "F = sign(v) .* (g + q.sigma_2 .* speed);  % eq. 2.7",
            "end",
            "",
        ]
    )


def _lugre_file(model, name) -> str:
    return "\n".join(
        [
            f"function [z, F] = {name}_lugre_step(z, v, p_a, p_b, h, P)",
            f"%{name.upper()}_LUGRE_STEP Exact LuGre bristle update over a step, and the force.",
            f"%   [z, F] = {name}_lugre_step(z, v, p_a, p_b, h) advances the bristle deflection",
            "%   z [m] over a step h [s] at constant velocity v [m/s] and chamber pressures",
            "%   p_a, p_b [Pa] with the exact solution of eq. 2.5 (stable for any sigma_0 and h):",
            "%     z(h) = z_ss + (z(0) - z_ss) exp(-sigma_0 |v| h / g(v)),",
            "%     z_ss = sign(v) g(v) / sigma_0,",
            "%   and returns the LuGre force at the end of the step [N]:",
            "%     F = sigma_0 z + sigma_1 dz/dt + sigma_2 v,  dz/dt = v - sigma_0 |v| z / g(v).",
            "%   Hold v over short steps (or use the mid-step velocity) to follow a motion.",
            f"%   P defaults to {name}_params().",
            f"if nargin < 6, P = {name}_params(); end",
            f"q = {name}_params_at(p_a, p_b, P);",
            "speed = abs(v);",
            "g = q.F_c + (q.F_s - q.F_c) .* exp(-((speed ./ q.v_r) .^ q.alpha));  % eq. 2.5, g(v)",
            "z_ss = sign(v) .* g ./ q.sigma_0;",
            "z = z_ss + (z - z_ss) .* exp(-q.sigma_0 .* speed .* h ./ g);",
            "dz = v - q.sigma_0 .* speed .* z ./ g;  % eq. 2.5",
            "F = q.sigma_0 .* z + q.sigma_1 .* dz + q.sigma_2 .* v;  % eq. 2.5",
            "end",
            "",
        ]
    )


def export_matlab(model: FrictionModel, out: StrPath, *, name: str | None = None) -> list[Path]:
    """Write the model as MATLAB/Octave functions and a parameter struct (lossless).

    Parameters
    ----------
    model : FrictionModel, path or dict
        The friction model, or a datasheet (JSON path or dict).
    out : path
        Output folder (created if needed).
    name : str, optional
        Prefix of the function names (a MATLAB identifier); default ``"cylfric"``, which gives
        ``cylfric_friction(v, p_a, p_b)`` [N] at velocity [m/s] and pressures [Pa].

    Returns
    -------
    list of Path
        The files written: ``<name>_params.m``, ``<name>_params_at.m``,
        ``<name>_friction.m``, ``<name>_lugre_step.m``.
    """
    model = _as_model(model)
    name = _check_name(name, "cylfric")
    if not name[0].isalpha() or len(name) > 63 - len("_lugre_step"):
        raise ValueError(
            f"name {name!r} does not make MATLAB function names; expected a letter first and "
            f"at most {63 - len('_lugre_step')} characters"
        )
    from ..io.writers import atomic_write_text

    writers = {
        "params": _params_file,
        "params_at": _params_at_file,
        "friction": _friction_file,
        "lugre_step": _lugre_file,
    }
    texts = {f"{name}_{kind}.m": writer(model, name) for kind, writer in writers.items()}
    return [atomic_write_text(Path(out) / filename, text) for filename, text in texts.items()]
