"""FMI 2.0 FMU of the pressure-dependent LuGre friction element (model exchange + co-simulation).

``export_fmu(model, out)`` writes ``<out>/<name>.fmu``: the model description with every
coefficient of the datasheet as a tunable parameter with its SI unit, the C sources (the
generic FMU code in ``templates/cylfric_fmu.c`` plus two generated headers: value references
and default values, and the pressure law of each friction parameter), the binary for this
platform compiled with the system C compiler (``$CC``, ``cc``, ``gcc`` or ``clang``), and the
datasheet itself under ``resources/``.

The element (thesis eq. 2.5, 2.7; SI throughout):

* element ``"friction"``: inputs ``velocity`` [m/s], ``pressure_a`` [Pa], ``pressure_b`` [Pa];
* output ``friction_force`` [N] (positive in the direction of motion);
* state ``z`` [m] (bristle deflection), ``der(z)`` [m/s];
* parameters: the coefficients of the pressure laws (``F_c.intercept`` [N],
  ``F_c.slope`` [N/Pa], ...), ``sigma_0`` [N/m], ``sigma_1`` [N*s/m], and ``max_substep`` [s]
  (longest internal step of the co-simulation ``doStep``);
* fixed parameters ``scatter.*`` and ``lack_of_fit.*``: the datasheet's scatter components
  (``scatter.session_percent`` [%], ``scatter.session_N`` [N], ``scatter.reproducibility_percent``,
  ...) and lack-of-fit test, with the record's texts in their descriptions; how to form a
  band for a new session in ``documentation/index.html``;
* the operating-pressure rule (a, b, sum, mean, max) and the pressure law of each parameter
  are fixed at export (structural); their coefficients are tunable;
* element ``"cylinder"``: the moving mass driven by the input ``force`` [N] and the pressure
  force (eq. 3.1), or by a position servo (inputs ``position_reference`` [m],
  ``velocity_reference`` [m/s], gains ``kp`` [N/m], ``kd`` [N*s/m]), outputs ``position``
  [m], ``velocity`` [m/s], ``friction_force`` [N], parameters ``mass`` [kg], ``area_a``,
  ``area_b`` [m^2]; its co-simulation step is cylfric's fixed-step impulse scheme
  (``cylfric.simulate(method="fixed")``).

Co-simulation integrates z with the exact solution of eq. 2.5 for a velocity held over each
substep (inputs at the middle of the substep, linear in time when the master sets input
derivatives): unconditionally stable for any bristle stiffness, exact for held inputs.

The export is deterministic: the same model gives byte-identical files (fixed zip timestamps
and order, no dates, a GUID derived from the content).
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import warnings
import zipfile
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from ..escape import c_comment, c_string, html_text
from ..escape import xml_attr as quoteattr

if TYPE_CHECKING:
    from collections.abc import Mapping

    from cylfric._typing import StrPath

    from ..model import FrictionModel

__all__ = ["export_fmu", "ELEMENTS", "FMU_INPUTS", "FMU_OUTPUTS", "compiler", "fmi_platform"]

ELEMENTS = ("friction", "cylinder")
"""Elements :func:`export_fmu` can write."""

FMU_INPUTS = {"velocity": "m/s", "pressure_a": "Pa", "pressure_b": "Pa"}
"""Inputs of the friction element and their units."""
FMU_OUTPUTS = {"friction_force": "N"}
"""Outputs of the friction element and their units."""

REFERENCE_CODES = {"a": 0, "b": 1, "sum": 2, "mean": 3, "max": 4}
"""Operating-pressure rules as the C code numbers them (``CYLFRIC_REFERENCE``)."""

REFERENCE_TEXT = {
    "a": "p = pressure_a",
    "b": "p = pressure_b",
    "sum": "p = pressure_a + pressure_b",
    "mean": "p = 0.5 (pressure_a + pressure_b)",
    "max": "p = max(pressure_a, pressure_b)",
}

FRICTION_PARAMETERS = ("F_c", "F_s", "sigma_2", "v_r", "alpha", "sigma_0", "sigma_1")
"""The parameters of eq. 2.5 in the order of the C code's ``prm`` array."""

_DESCRIPTION = {
    "F_c": "Coulomb friction level",
    "F_s": "stiction (breakaway) level",
    "sigma_2": "viscous coefficient",
    "v_r": "Stribeck velocity parameter",
    "alpha": "Stribeck exponent",
    "sigma_0": "bristle stiffness",
    "sigma_1": "bristle damping",
}
_COEFFICIENT_TEXT = {
    "intercept": "value at p = 0",
    "slope": "rise per Pa of operating pressure",
    "curvature": "curvature per Pa^2 of operating pressure",
    "amplitude": "amplitude of the exponential law",
    "rate": "rate of the exponential law",
}
_LAW_TEXT = {
    "constant": "{n} = {n}",
    "linear": "{n}(p) = {n}.intercept + {n}.slope p",
    "quadratic": "{n}(p) = {n}.intercept + {n}.slope p + {n}.curvature p^2",
    "exponential": "{n}(p) = {n}.intercept + {n}.amplitude (exp({n}.rate p) - 1)",
}
_MISSING = {
    "F_s": "F_c",
    "sigma_2": "0.0",
    "v_r": "1.0",
    "alpha": "1.0",
}
"""What a reduced law uses for the parameters it lacks (as ``FrictionModel.params_at``)."""

# SI base-unit exponents (kg, m, s) of the units the description uses
_BASE = {
    "N": (1, 1, -2),
    "Pa": (1, -1, -2),
    "m/s": (0, 1, -1),
    "m": (0, 1, 0),
    "s": (0, 0, 1),
    "N/m": (1, 0, -2),
    "N*s/m": (1, 0, -1),
    "-": (0, 0, 0),
    "kg": (1, 0, 0),
    "m2": (0, 2, 0),
    "m/s2": (0, 1, -2),
    "%": (0, 0, 0),
}

_FIXED_DATE = (1980, 1, 1, 0, 0, 0)
_TEMPLATE_FILES = ("cylfric_fmu.c", "fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,62}")  # with fullmatch: no trailing newline
_CFLAGS = ("-shared", "-fPIC", "-O2", "-ffp-contract=off", "-std=c99")


def _as_model(model: object) -> FrictionModel:
    """A FrictionModel from a model, a datasheet path or a datasheet dict."""
    from ..model import FrictionModel

    if isinstance(model, FrictionModel):
        return model
    if isinstance(model, str | os.PathLike | dict):
        return FrictionModel.from_datasheet(model)
    raise ValueError(
        f"model is a {type(model).__name__}; expected a cylfric.model.FrictionModel, "
        "a datasheet path or a datasheet dict"
    )


def datasheet_text(model: FrictionModel) -> str:
    """The model's datasheet as JSON text, without a creation date the model does not carry.

    ``to_datasheet`` stamps the current time when the model has none (a model built in Python
    rather than read from a datasheet); an export leaves it out, so that the same model gives
    the same files.
    """
    sheet = model.to_datasheet()
    if "created" not in model.record:
        sheet.pop("created", None)
    return json.dumps(sheet, indent=2, allow_nan=False) + "\n"


def _check_name(name, default):
    name = default if name is None else name
    if not isinstance(name, str) or not _IDENTIFIER.fullmatch(name):
        raise ValueError(
            f"name {name!r} is not a valid model identifier; expected a C identifier "
            "(letters, digits, underscores, not starting with a digit, at most 63 characters)"
        )
    return name


def fmi_platform() -> tuple[str, str] | None:
    """(FMI 2.0 platform folder, shared-library suffix) of this machine, or None."""
    machine = platform.machine().lower()
    if machine not in ("x86_64", "amd64"):
        return None
    if sys.platform.startswith("linux"):
        return "linux64", ".so"
    if sys.platform == "darwin":
        return "darwin64", ".dylib"
    return None


def compiler() -> str | None:
    """The C compiler export uses: ``$CC``, else ``cc``, ``gcc`` or ``clang`` on the PATH."""
    if os.environ.get("CC"):
        return shutil.which(os.environ["CC"])
    for candidate in ("cc", "gcc", "clang"):
        found = shutil.which(candidate)
        if found:
            return found
    return None


# ---------------------------------------------------------------------------- variables
def _unit_of(parameter: str, coefficient: str | None) -> tuple[str, tuple[int, ...]]:
    """(FMI unit name, SI exponents) of a coefficient of ``parameter``."""
    from ..model.core import PARAMETER_UNITS

    base = PARAMETER_UNITS[parameter]
    exponents: tuple[int, ...] = _BASE[base]
    powers: dict[str | None, int] = {"slope": 1, "curvature": 2}
    power = powers.get(coefficient, 0)
    name = base.replace("*", ".")
    if coefficient == "rate":
        return "1/Pa", tuple(-e for e in _BASE["Pa"])
    if power:
        name = ("1" if base == "-" else name) + ("/Pa" if power == 1 else "/Pa2")
        exponents = tuple(e - power * q for e, q in zip(exponents, _BASE["Pa"], strict=True))
    return ("" if name == "-" else name), exponents


def _coefficients(model):
    """Coefficient rows (name, value, unit, exponents, description) and C law lines."""
    from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS

    rows, lines = [], []
    for index, parameter in enumerate(FRICTION_PARAMETERS):
        law = model.laws[parameter]
        if law is None:
            expression = _MISSING[parameter]
            if expression == "F_c":
                expression = "prm[P_F_C]"
            reason = model.not_identified.get(parameter, "not identified")
            lines.append(f"    prm[{index}] = {expression}; /* {parameter}: {c_comment(reason)} */")
            continue
        status = model.dynamic_status.get(parameter)
        note = f" ({status[0]}: {status[1]})" if status else ""
        args = []
        for coefficient in PRESSURE_LAW_COEFFICIENTS[law]:
            key = parameter if law == "constant" else f"{parameter}.{coefficient}"
            unit, exponents = _unit_of(parameter, None if law == "constant" else coefficient)
            text = _DESCRIPTION[parameter]
            if law != "constant":
                text += f", {law} pressure law: {_COEFFICIENT_TEXT[coefficient]}"
            rows.append((key, model.parameters[key].value, unit, exponents, text + note))
            args.append(key)
        refs = ", ".join(
            f"r[VR_FIRST_PARAMETER + {len(rows) - len(args) + i}]" for i in range(len(args))
        )
        lines.append(f"    prm[{index}] = law_{law}(p, {refs}); /* {parameter} */")
    return rows, lines


def _start_pressure(model) -> float:
    if model.validity is None:
        return 0.0
    return 0.5 * (model.validity["pressure_min"] + model.validity["pressure_max"])


def _nominal_z(model, pressure) -> float:
    params = model.params_at(model.operating_pressure(pressure, pressure))
    if params["sigma_0"] > 0:
        value = max(abs(params["F_c"]), abs(params["F_s"])) / params["sigma_0"]
        if value > 0 and value == value:
            return float(value)
    return 1e-4


_COMMON_ROWS = {
    "pressure_a": ("input", "continuous", None, "Pa", "pressure in chamber A (cap side)"),
    "pressure_b": ("input", "continuous", None, "Pa", "pressure in chamber B (rod side)"),
    "friction_force": (
        "output",
        "continuous",
        None,
        "N",
        "friction force, positive in the direction of motion (eq. 2.5)",
    ),
    "z": ("local", "continuous", "exact", "m", "mean bristle deflection"),
    "der(z)": ("local", "continuous", None, "m/s", "bristle rate (eq. 2.5)"),
    "operating_pressure": ("local", "continuous", None, "Pa", "pressure the laws see"),
    "max_substep": (
        "parameter",
        "tunable",
        None,
        "s",
        "longest internal step of co-simulation doStep",
    ),
}
_ELEMENT_ROWS: dict[str, dict[str, tuple[str, str, str | None, str, str]]] = {
    "friction": {
        "velocity": ("input", "continuous", None, "m/s", "rod velocity, > 0 extends"),
    },
    "cylinder": {
        "force": ("input", "continuous", None, "N", "drive force on the rod, > 0 extends"),
        "position": ("output", "continuous", "exact", "m", "rod position"),
        "velocity": ("output", "continuous", "exact", "m/s", "rod velocity, > 0 extends"),
        "der(velocity)": ("local", "continuous", None, "m/s2", "rod acceleration (eq. 3.1)"),
        "mass": ("parameter", "tunable", None, "kg", "moving mass (rod, piston, load)"),
        "area_a": (
            "parameter",
            "tunable",
            None,
            "m2",
            "piston area of chamber A; 0: the pressures only set the friction",
        ),
        "area_b": (
            "parameter",
            "tunable",
            None,
            "m2",
            "piston area of chamber B; 0: the pressures only set the friction",
        ),
        "position_reference": (
            "input",
            "continuous",
            None,
            "m",
            "position drive: reference position of the servo (acts with kp)",
        ),
        "velocity_reference": (
            "input",
            "continuous",
            None,
            "m/s",
            "position drive: reference velocity of the servo (acts with kd)",
        ),
        "kp": ("parameter", "tunable", None, "N/m", "position drive: servo stiffness; 0: off"),
        "kd": ("parameter", "tunable", None, "N.s/m", "position drive: servo damping; 0: off"),
    },
}
_LAYOUT = {
    "friction": (
        "velocity",
        "pressure_a",
        "pressure_b",
        "friction_force",
        "z",
        "der(z)",
        "operating_pressure",
        "max_substep",
    ),
    "cylinder": (
        "force",
        "pressure_a",
        "pressure_b",
        "friction_force",
        "z",
        "der(z)",
        "operating_pressure",
        "max_substep",
        "position",
        "velocity",
        "der(velocity)",
        "mass",
        "area_a",
        "area_b",
        "position_reference",
        "velocity_reference",
        "kp",
        "kd",
    ),
}
"""Value references (the position in the tuple) of each element's variables."""
_STATES = {
    "friction": (("z", "der(z)"),),
    "cylinder": (("position", "velocity"), ("velocity", "der(velocity)"), ("z", "der(z)")),
}
"""(state, derivative) pairs of each element, in the order of the state vector."""
_DEFAULT_MASS = 2.5
"""Default moving mass [kg]: the thesis rig's assumed 2.5 kg (cylfric.simulate.THESIS_CYLINDER)."""


def _variables(model, element):
    """Variable rows (name, vr, causality, variability, initial, unit, start, description)."""
    from .loss import chamber_pressures

    # both chambers at the start pressure, or a single-acting cylinder's working chamber
    pressure = _start_pressure(model)
    pressure_a, pressure_b = (float(p) for p in chamber_pressures(model, pressure))
    starts = {
        "velocity": 0.0,
        "force": 0.0,
        "pressure_a": pressure_a,
        "pressure_b": pressure_b,
        "z": 0.0,
        "max_substep": 1e-4,
        "position": 0.0,
        "mass": _DEFAULT_MASS,
        "area_a": 0.0,
        "area_b": 0.0,
        "position_reference": 0.0,
        "velocity_reference": 0.0,
        "kp": 0.0,
        "kd": 0.0,
    }
    table = {**_COMMON_ROWS, **_ELEMENT_ROWS[element]}
    rows = []
    for vr, var in enumerate(_LAYOUT[element]):
        causality, variability, initial, unit, text = table[var]
        if var == "operating_pressure":
            text = f"{text}, {REFERENCE_TEXT[model.reference]}"
        rows.append((var, vr, causality, variability, initial, unit, starts.get(var), text))
    coefficient_rows, law_lines = _coefficients(model)
    units = {row[5]: _BASE[row[5].replace(".", "*")] for row in rows}
    first = len(rows)
    for offset, (key, value, unit, exponents, text) in enumerate(coefficient_rows):
        rows.append((key, first + offset, "parameter", "tunable", None, unit, value, text))
        if unit:
            units[unit] = exponents
    for key, value, unit, text in _scatter_rows(model):
        rows.append((key, len(rows), "parameter", "fixed", None, unit, value, text))
        if unit:
            units[unit] = _BASE.get(unit, (0, 0, 0))
    return rows, law_lines, units, pressure


def _scatter_rows(model) -> list[tuple[str, float, str, str]]:
    """(name, value, unit, description) of the fixed parameters ``scatter.*`` and
    ``lack_of_fit.*``: the datasheet's fit.scatter and quality.lack_of_fit records as data
    (``*.computed`` = 0 with a "not computed" description when a record is missing)."""
    from .scatter import NOT_COMPUTED, scatter_records

    out = []
    records = scatter_records(model)
    for prefix, key, numbers, texts, table in records:
        if numbers is None or texts is None:
            out.append((f"{prefix}.computed", 0.0, "", NOT_COMPUTED.format(key=key)))
            continue
        out.append((f"{prefix}.computed", 1.0, "", f"1: the datasheet carries {key}"))
        notes = {  # the record's texts, in the description of the number they qualify
            "repeatability_percent": f"; method: {texts.get('method', '')}",
            "session_percent": f"; source: {texts.get('session_source', '')}",
            "session_prior_percent": f"; basis: {texts.get('session_prior_basis', '')}",
            "significant": f"; test: {texts.get('test', '')}; action: {texts.get('action', '')}",
        }
        for name, value in numbers.items():
            unit, meaning = table[name]
            unit = "" if unit == "1" else unit
            out.append((f"{prefix}.{name}", value, unit, f"{meaning}{notes.get(name, '')}"))
    return out


def _unit_xml(units) -> list[str]:
    out = ["  <UnitDefinitions>"]
    for name in sorted(units):
        kg, m, s = units[name]
        attrs = "".join(f' {k}="{v}"' for k, v in (("kg", kg), ("m", m), ("s", s)) if v)
        if name == "%":
            attrs += ' factor="0.01"'
        out.append(f"    <Unit name={quoteattr(name)}><BaseUnit{attrs}/></Unit>")
    out.append("  </UnitDefinitions>")
    return out


def _law_summary(model) -> str:
    parts = []
    for parameter in FRICTION_PARAMETERS:
        law = model.laws[parameter]
        if law is not None and law != "constant":
            parts.append(_LAW_TEXT[law].format(n=parameter))
    return "; ".join(parts)


def _nominals(element, nominal_z):
    """Nominal value of each state [m], [m/s] (tolerances scale with them)."""
    return {"position": 0.1, "velocity": 0.1, "z": nominal_z}


def _model_description(model, name, guid, rows, units, nominals, element) -> str:
    from .._version import __version__

    what = (
        "moving mass of a hydraulic cylinder driven by a force, with its"
        if element == "cylinder"
        else "hydraulic cylinder:"
    )
    description = (
        f"Pressure-dependent LuGre friction of a {what} (cylfric, thesis eq. 2.5/2.7),"
        f" {model.friction_law} steady-state law; {REFERENCE_TEXT[model.reference]}; "
        f"{_law_summary(model)}"
    )
    method = model.provenance.get("method")
    if method:
        description += f"; identified by {method}"
    description += (
        "; scatter about the law: fixed parameters scatter.* (fit.scatter) and lack_of_fit.* "
        "(quality.lack_of_fit), bands in documentation/index.html"
    )
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        "<fmiModelDescription",
        '  fmiVersion="2.0"',
        f"  modelName={quoteattr(name)}",
        f"  guid={quoteattr(guid)}",
        f"  description={quoteattr(description)}",
        f"  generationTool={quoteattr('cylfric ' + __version__)}",
        '  variableNamingConvention="structured"',
        '  numberOfEventIndicators="0">',
        f'  <ModelExchange modelIdentifier="{name}" completedIntegratorStepNotNeeded="true">',
        "    <SourceFiles>",
        '      <File name="cylfric_fmu.c"/>',
        "    </SourceFiles>",
        "  </ModelExchange>",
        f'  <CoSimulation modelIdentifier="{name}" canHandleVariableCommunicationStepSize="true"'
        ' canInterpolateInputs="true">',
        "    <SourceFiles>",
        '      <File name="cylfric_fmu.c"/>',
        "    </SourceFiles>",
        "  </CoSimulation>",
        *_unit_xml(units),
        '  <DefaultExperiment startTime="0.0" stopTime="1.0" stepSize="0.001"/>',
        "  <ModelVariables>",
    ]
    index = {}
    for i, (var, vr, causality, variability, initial, unit, start, text) in enumerate(rows, 1):
        index[var] = i
        attrs = f'name={quoteattr(var)} valueReference="{vr}" description={quoteattr(text)}'
        attrs += f' causality="{causality}" variability="{variability}"'
        if initial:
            attrs += f' initial="{initial}"'
        real = []
        if unit:
            real.append(f"unit={quoteattr(unit)}")
        derivative_of = {d: state for state, d in _STATES[element]}
        if var in derivative_of:
            real.append(f'derivative="{index[derivative_of[var]]}"')
        if var in derivative_of.values():
            real.append(f'nominal="{nominals[var]!r}"')
        if start is not None:
            real.append(f'start="{float(start)!r}"')
        out.append(f"    <!-- index {i} -->")
        out.append(f"    <ScalarVariable {attrs}>")
        out.append(f"      <Real {' '.join(real)}/>" if real else "      <Real/>")
        out.append("    </ScalarVariable>")
    outputs = [index[r[0]] for r in rows if r[2] == "output"]
    derivatives = [index[d] for _, d in _STATES[element]]
    initial = sorted(
        {index[r[0]] for r in rows if r[2] == "output" and r[4] is None}
        | {i for i in derivatives if rows[i - 1][4] is None}
    )

    def unknowns(indices):
        return [f'      <Unknown index="{i}"/>' for i in indices]

    out += [
        "  </ModelVariables>",
        "  <ModelStructure>",
        "    <Outputs>",
        *unknowns(sorted(outputs)),
        "    </Outputs>",
        "    <Derivatives>",
        *unknowns(derivatives),
        "    </Derivatives>",
        "    <InitialUnknowns>",
        *unknowns(initial),
        "    </InitialUnknowns>",
        "  </ModelStructure>",
        "</fmiModelDescription>",
        "",
    ]
    return "\n".join(out)


def _flags(rows, test):
    return "{" + ", ".join("1" if test(r) else "0" for r in rows) + "}"


def _model_header(model, name, guid, rows, nominals, element) -> str:
    values = ",\n".join(
        f"    {float(r[6] if r[6] is not None else 0.0)!r} /* {r[0]} */" for r in rows
    )
    states = _STATES[element]
    vr = {r[0]: r[1] for r in rows}
    defines = [
        f"#define VR_{var.replace('der(', 'der_').rstrip(')').upper()} {vr[var]}"
        for var in _LAYOUT[element]
    ]
    return "\n".join(
        [
            "/* Generated by cylfric.export.fmu: value references and defaults of this model. */",
            "#ifndef CYLFRIC_MODEL_H",
            "#define CYLFRIC_MODEL_H",
            f"#define MODEL_IDENTIFIER_STRING {c_string(name)}",
            f'#define MODEL_GUID "{guid}"',
            f"#define CYLFRIC_REFERENCE {REFERENCE_CODES[model.reference]} "
            f"/* {REFERENCE_TEXT[model.reference]} */",
            f"#define CYLFRIC_CYLINDER {int(element == 'cylinder')}",
            f"#define N_REALS {len(rows)}",
            f"#define N_STATES {len(states)}",
            *defines,
            f"#define VR_FIRST_PARAMETER {len(_LAYOUT[element])}",
            "static const fmi2ValueReference STATE_VRS[N_STATES] = {"
            + ", ".join(str(vr[st]) for st, _ in states)
            + "};",
            "static const fmi2ValueReference DERIVATIVE_VRS[N_STATES] = {"
            + ", ".join(str(vr[d]) for _, d in states)
            + "};",
            "static const fmi2Real STATE_NOMINALS[N_STATES] = {"
            + ", ".join(repr(nominals[st]) for st, _ in states)
            + "};",
            "static const unsigned char IS_INPUT[N_REALS] = "
            + _flags(rows, lambda r: r[2] == "input")
            + ";",
            "static const unsigned char IS_SETTABLE[N_REALS] = "
            + _flags(rows, lambda r: r[2] in ("input", "parameter") or r[4] == "exact")
            + ";",
            "static const fmi2Real DEFAULT_REALS[N_REALS] = {",
            values,
            "};",
            "#endif",
            "",
        ]
    )


def _params_header(model, law_lines) -> str:
    return "\n".join(
        [
            "/* Generated by cylfric.export.fmu: friction parameters of eq. 2.5 at the operating",
            f" * pressure p [Pa] ({model.friction_law} law; {REFERENCE_TEXT[model.reference]}). */",
            "static void cylfric_params_at(const fmi2Real *r, fmi2Real p, fmi2Real prm[N_PRM]) {",
            *law_lines,
            "}",
            "",
        ]
    )


def _documentation(model, name) -> str:
    """``documentation/index.html``: the element, its scatter record and how to form a band
    for a new session (user text through :func:`cylfric.escape.html_text`)."""
    from .scatter import summary_lines

    paragraphs = "\n".join(f"<p>{line}</p>" for line in summary_lines(model, html_text))
    label = html_text(model.record.get("name", "cylfric model"))
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html><head><meta charset="utf-8"><title>' + html_text(name) + "</title></head>",
            "<body>",
            f"<h1>{html_text(name)}: LuGre friction of the cylfric datasheet {label}</h1>",
            "<p>Inputs velocity [m/s], pressure_a, pressure_b [Pa]; output friction_force [N]. "
            "The datasheet is in resources/datasheet.json.</p>",
            "<h2>Scatter about the law</h2>",
            "<p>Fixed parameters scatter.* (datasheet fit.scatter; *_percent in % of the "
            "friction level, *_N in N) and lack_of_fit.* (quality.lack_of_fit).</p>",
            paragraphs,
            "</body></html>",
            "",
        ]
    )


def _build_description(name, source: str = "cylfric_fmu.c") -> str:
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            '<fmiBuildDescription fmiVersion="3.0">',
            f'  <BuildConfiguration modelIdentifier="{name}">',
            '    <SourceFileSet language="C99">',
            f"      <SourceFile name={quoteattr(source)}/>",
            "    </SourceFileSet>",
            "  </BuildConfiguration>",
            "</fmiBuildDescription>",
            "",
        ]
    )


def _template(filename: str) -> bytes:
    return resources.files(__package__).joinpath("templates", filename).read_bytes()


def _compile(sources: dict, name: str, suffix: str, cc: str, main: str = "cylfric_fmu.c") -> bytes:
    """Compile the sources (``main``, the one translation unit) with ``cc`` in a scratch
    folder; returns the shared library. Also used by :mod:`cylfric.control.export`."""
    with tempfile.TemporaryDirectory(prefix="cylfric-fmu-") as tmp:
        folder = Path(tmp) / "sources"
        folder.mkdir()
        for filename, data in sources.items():
            (folder / filename).write_bytes(data)
        target = f"{name}{suffix}"
        command = [cc, *_CFLAGS, "-Isources", f"sources/{main}", "-o", target, "-lm"]
        done = subprocess.run(command, cwd=tmp, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            raise RuntimeError(
                f"compiling the FMU with {' '.join(command)} failed:\n{done.stderr.strip()}"
            )
        return (Path(tmp) / target).read_bytes()


def _zip(entries: dict) -> bytes:
    import io

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for arcname in sorted(entries, key=lambda a: (a != "modelDescription.xml", a)):
            info = zipfile.ZipInfo(arcname, date_time=_FIXED_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3
            mode = 0o755 if arcname.startswith("binaries/") else 0o644
            info.external_attr = (0o100000 | mode) << 16
            archive.writestr(info, entries[arcname])
    return buffer.getvalue()


def export_fmu(
    model: FrictionModel | StrPath | Mapping[str, Any],
    out: StrPath,
    *,
    element: Literal["friction", "cylinder"] = "friction",
    name: str | None = None,
) -> list[Path]:
    """Write an FMI 2.0 FMU (model exchange and co-simulation) of the friction element.

    Parameters
    ----------
    model : FrictionModel, path or dict
        The friction model, or a datasheet (JSON path or dict) read with
        :meth:`cylfric.model.FrictionModel.from_datasheet`.
    out : path
        Output folder (created if needed); the FMU is ``<out>/<name>.fmu``.
    element : {"friction", "cylinder"}
        ``"friction"``: inputs ``velocity`` [m/s], ``pressure_a``, ``pressure_b`` [Pa];
        output ``friction_force`` [N]; state ``z`` [m].
        ``"cylinder"``: the moving mass with the friction, ``m dv/dt = force + area_a
        pressure_a - area_b pressure_b - friction_force + drive`` (thesis eq. 3.1): inputs
        ``force`` [N], ``pressure_a``, ``pressure_b`` [Pa]; outputs ``friction_force`` [N],
        ``position`` [m], ``velocity`` [m/s]; states position, velocity, z; parameters
        ``mass`` [kg] (default 2.5, the thesis rig's assumption), ``area_a``, ``area_b``
        [m^2] (default 0). Position drive: ``drive = kp (position_reference - position) +
        kd (velocity_reference - velocity)`` with inputs ``position_reference`` [m],
        ``velocity_reference`` [m/s] and parameters ``kp`` [N/m], ``kd`` [N*s/m] (default 0:
        force drive only), as :class:`cylfric.simulate.PositionServo` without integral gain.
    name : str, optional
        Model identifier (a C identifier); default ``"cylfric_<element>"``.

    Returns
    -------
    list of Path
        The files written (the ``.fmu``).

    Notes
    -----
    The binary for this platform (``binaries/linux64/<name>.so`` on x86-64 Linux) is compiled
    with the system C compiler at export; the sources are inside (``sources/``) so that other
    platforms can build it (e.g. ``fmpy.util.compile_platform_binary``). Without a C compiler
    the FMU carries the sources only, with a warning. Writing is atomic and deterministic.
    """
    if element not in ELEMENTS:
        raise ValueError(f"unknown FMU element {element!r}; valid: {list(ELEMENTS)}")
    model = _as_model(model)
    name = _check_name(name, f"cylfric_{element}")
    rows, law_lines, units, pressure = _variables(model, element)
    nominals = _nominals(element, _nominal_z(model, pressure))
    datasheet = datasheet_text(model)
    params_h = _params_header(model, law_lines)
    # the GUID is a hash of everything the binary depends on: same model, same GUID
    digest = hashlib.sha256()
    for part in (name, element, params_h, datasheet, *(_template(f) for f in _TEMPLATE_FILES)):
        digest.update(part if isinstance(part, bytes) else part.encode())
        digest.update(b"\0")
    h = digest.hexdigest()
    guid = f"{{{h[:8]}-{h[8:12]}-{h[12:16]}-{h[16:20]}-{h[20:32]}}}"
    sources = {f: _template(f) for f in _TEMPLATE_FILES}
    sources["cylfric_model.h"] = _model_header(model, name, guid, rows, nominals, element).encode()
    sources["cylfric_params.h"] = params_h.encode()
    entries = {f"sources/{f}": data for f, data in sources.items()}
    entries["sources/buildDescription.xml"] = _build_description(name).encode()
    entries["modelDescription.xml"] = _model_description(
        model, name, guid, rows, units, nominals, element
    ).encode()
    entries["resources/datasheet.json"] = datasheet.encode()
    entries["documentation/index.html"] = _documentation(model, name).encode()
    target = fmi_platform()
    cc = compiler()
    if target is None or cc is None:
        why = (
            "no C compiler ($CC, cc, gcc, clang)"
            if cc is None
            else (f"no FMI 2.0 platform name for {sys.platform}/{platform.machine()}")
        )
        warnings.warn(
            f"{why}: the FMU carries its C sources only; compile them on the target "
            "(fmpy.util.compile_platform_binary) before simulating",
            RuntimeWarning,
            stacklevel=2,
        )
    else:
        folder, suffix = target
        entries[f"binaries/{folder}/{name}{suffix}"] = _compile(sources, name, suffix, cc)
    from ..io.writers import atomic_write_bytes

    path = atomic_write_bytes(Path(out) / f"{name}.fmu", _zip(entries))
    return [path]
