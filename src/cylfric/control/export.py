"""The compensator leaves cylfric: C source, an FMU and a MATLAB function of one sample.

``export_compensator(model, out, targets=("c", "fmu", "matlab"))`` writes the compensator step
of :func:`cylfric.control.kernel.compensator_step` (every exportable kind: ``none``,
``coulomb``, ``static``, ``lugre``; the ``oracle`` needs the plant's own friction and is not
a compensator one can deploy) with the datasheet's friction laws, the axis and the controller
constants fixed at export:

``c``
    ``cylfric_compensator.h`` (the interface: input, state and output structs of doubles),
    ``cylfric_compensator.c`` (the step, the same for every datasheet; C99, no allocation,
    no global written, a pure function of the measurements and the state) and the generated
    ``cylfric_compensator_params.h`` (the friction table, the operating-pressure rule, the
    axis constants, the sample time, sign smoothing, observer gain, Coulomb level; every
    number with 17 significant digits).
``fmu``
    ``<name>.fmu``: an FMI 2.0 co-simulation FMU of one kind (``compensator``, structural),
    inputs ``position`` [m], ``pressure_a``, ``pressure_b`` [Pa], ``position_reference`` [m],
    ``velocity_reference`` [m/s], outputs ``force`` [N] and ``command`` [-]; each ``doStep``
    is one controller sample (the step must equal the axis's sample time), built with the
    FMU machinery of :mod:`cylfric.export.fmu` (the same compiler, zip and build
    description; the sources inside for other platforms).
``matlab``
    ``<name>_step.m``: ``[force, command, state] = <name>_step(kind, position, pressure_a,
    pressure_b, position_reference, velocity_reference, state)`` with ``kind`` 0 none,
    1 coulomb, 2 static, 3 lugre and ``state`` a 4-vector (``zeros(4, 1)`` at the start):
    fixed sizes and subfunctions only, so that it serves as a Simulink MATLAB Function block.

The ``command`` output depends on the axis (areas, volumes, valve, supply, tank, bulk
modulus, leakage fixed at export), ``force`` does not: every target states the axis it bakes
in, with units (the comment of ``cylfric_compensator_params.h`` and its
``CYLFRIC_DEFAULT_AXIS``, the FMU's model description, the MATLAB help), and the interface
contract (one call per sample at the sample time, position absolute from the cap end, gauge
pressures, command > 0 = flow P->A = extension, command 0 at the first sample;
``templates/cylfric_compensator.h``, docs/control.md).

Every user string that reaches the generated code (the datasheet's source) goes through
:mod:`cylfric.escape`. The files are deterministic (no dates) and written atomically.
"""

from __future__ import annotations

import hashlib
import math
import textwrap
import warnings
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..escape import c_comment, c_string, matlab_comment
from ..escape import xml_attr as quoteattr
from .axis import DEFAULT_AXIS, Axis
from .kernel import COMPENSATOR_CODES, FRICTION_ROWS, REFERENCE_CODES, friction_table
from .loop import FORCE_FILTER, OBSERVER_GAIN, SMOOTHING_VELOCITY, compensator_constants

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "export_compensator",
    "EXPORT_TARGETS",
    "EXPORTABLE_COMPENSATORS",
    "C_FILES",
    "FMU_INPUTS",
    "FMU_OUTPUTS",
]

EXPORT_TARGETS = ("c", "fmu", "matlab")
"""What :func:`export_compensator` can write."""
EXPORTABLE_COMPENSATORS = ("none", "coulomb", "static", "lugre")
"""Compensator kinds the exports carry (codes of ``kernel.COMPENSATOR_CODES``)."""
C_FILES = ("cylfric_compensator.h", "cylfric_compensator.c", "cylfric_compensator_params.h")
"""The C target's files."""
FMU_INPUTS = {
    "position": (
        "m",
        "measured rod position, absolute from the cap end (0: chamber A's dead "
        "volume), > 0 extends",
    ),
    "pressure_a": ("Pa", "measured gauge pressure in chamber A (cap side)"),
    "pressure_b": ("Pa", "measured gauge pressure in chamber B (rod side)"),
    "position_reference": ("m", "reference position"),
    "velocity_reference": ("m/s", "reference velocity"),
    "velocity": (
        "m/s",
        "measured rod velocity, read only when the FMU was exported with the velocity "
        "input (else the velocity is the position's backward difference)",
    ),
}
"""Inputs of the compensator FMU (value references 0-5) with their units."""
FMU_OUTPUTS = {
    "force": ("N", "friction force estimate, positive in the direction of motion"),
    "command": (
        "",
        "valve command (> 0: flow P->A, extension) that changes the cylinder force by the "
        "estimate's change and holds it against the cross-piston leakage; for the axis "
        "baked in at export (see the model description)",
    ),
}
"""Outputs of the compensator FMU (value references 6, 7)."""

_AXIS_DEFINES = (
    ("CYLFRIC_AREA_A", "area_a", "piston area of chamber A [m^2]"),
    ("CYLFRIC_AREA_B", "area_b", "piston area of chamber B [m^2]"),
    ("CYLFRIC_STROKE", "stroke", "stroke [m]"),
    ("CYLFRIC_DEAD_VOLUME_A", "dead_volume_a", "volume of chamber A at x = 0 [m^3]"),
    ("CYLFRIC_DEAD_VOLUME_B", "dead_volume_b", "volume of chamber B at x = stroke [m^3]"),
    ("CYLFRIC_BULK_MODULUS", "bulk_modulus", "oil bulk modulus [Pa]"),
    ("CYLFRIC_SUPPLY", "supply_pressure", "supply pressure, gauge [Pa]"),
    ("CYLFRIC_TANK", "tank_pressure", "tank pressure, gauge [Pa]"),
    ("CYLFRIC_VALVE_K", "valve_coefficient", "valve flow coefficient [m^3/(s*sqrt(Pa))]"),
    ("CYLFRIC_LAMINAR_DROP", "valve_laminar_drop", "laminar transition of the orifices [Pa]"),
    ("CYLFRIC_LEAKAGE", "leakage", "cross-piston leakage coefficient C_i [m^3/(s*Pa)]"),
)
_ROW_UNITS = ("N", "N", "N*s/m", "m/s", "-", "N/m", "N*s/m")
_LAW_NAMES = {0: "constant", 1: "linear", 2: "quadratic", 3: "exponential"}
_REFERENCE_C = {
    "a": "p = pressure_a",
    "b": "p = pressure_b",
    "sum": "p = pressure_a + pressure_b",
    "mean": "p = 0.5 (pressure_a + pressure_b)",
    "max": "p = max(pressure_a, pressure_b)",
}


def _template(filename: str) -> bytes:
    return resources.files(__package__).joinpath("templates", filename).read_bytes()


def _number(value: float) -> str:
    """A double as C/MATLAB text that reads back to the same bits."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"cannot export the non-finite value {value!r}")
    return repr(value)


class _Constants:
    """Everything the exported step fixes: the friction table, rule, axis, controller."""

    def __init__(
        self,
        model,
        axis: Axis,
        smoothing_velocity: float,
        observer_gain: float,
        force_filter: float = 0.0,
        velocity_input: bool = False,
    ):
        self.model = model
        self.axis = axis
        self.table = friction_table(model)
        self.reference = model.reference
        ctrl = compensator_constants(
            model,
            axis,
            smoothing_velocity=smoothing_velocity,
            observer_gain=observer_gain,
            force_filter=force_filter,
            velocity_input=velocity_input,
        )
        self.velocity_input = bool(velocity_input)
        self.force_filter = float(force_filter)
        self.filter_gain = float(ctrl[10])
        self.sample_time = float(ctrl[9])
        self.smoothing = float(ctrl[5])
        self.observer_gain = float(ctrl[6])
        self.coulomb = float(ctrl[7])
        vector = dict(zip(_axis_names(), axis.vector(), strict=True))
        self.axis_values = {define: float(vector[key]) for define, key, _ in _AXIS_DEFINES}
        self.source = str(getattr(model, "source", None) or "a FrictionModel")

    def scalars(self):
        """(C name, value, description) of the controller constants."""
        return (
            ("CYLFRIC_SAMPLE_TIME", self.sample_time, "controller sample time T [s]"),
            ("CYLFRIC_SMOOTHING_VELOCITY", self.smoothing, "sign smoothing v_s [m/s]"),
            ("CYLFRIC_OBSERVER_GAIN", self.observer_gain, "LuGre observer gain k_o [1/s]"),
            (
                "CYLFRIC_FORCE_FILTER_GAIN",
                self.filter_gain,
                f"force filter a = 1 - exp(-T/tau_f), tau_f = {self.force_filter:g} s "
                "(1: no filter) [-]",
            ),
            (
                "CYLFRIC_VELOCITY_INPUT",
                float(self.velocity_input),
                "1: the step reads the input velocity; 0: (x - x_prev) / T [-]",
            ),
            (
                "CYLFRIC_COULOMB_FORCE",
                self.coulomb,
                "Coulomb level F_c at the rest operating pressure [N]",
            ),
        )


def _axis_facts(k: _Constants) -> tuple[str, list[str], str]:
    """The axis baked into the ``command`` output, with units: (heading, items, advice).

    ``command`` depends on these values; ``force`` does not depend on the hydraulics (areas,
    volumes, valve, supply, bulk modulus, leakage), only on the datasheet, the sample time
    and, for the ``coulomb`` kind, on F_c at the axis's rest pressures.
    """
    a = k.axis
    pa, pb = a.rest_pressures()
    which = (
        "cylfric's DEFAULT axis (no axis was given at export; see docs/control.md):"
        if a == DEFAULT_AXIS
        else "the axis given at export:"
    )
    items = [
        f"bore {a.bore * 1e3:.6g} mm, rod {a.rod * 1e3:.6g} mm (B side), rod_a "
        f"{a.rod_a * 1e3:.6g} mm (A side; 0 = single rod)",
        f"piston areas A_A = {a.area_a:.6g} m^2, A_B = {a.area_b:.6g} m^2",
        f"stroke {a.stroke * 1e3:.6g} mm; dead volumes {a.dead_volume_a * 1e3:.6g} L "
        f"(chamber A at x = 0), {a.dead_volume_b * 1e3:.6g} L (chamber B at x = stroke)",
        f"bulk modulus {a.bulk_modulus:.6g} Pa; cross-piston leakage C_i "
        f"{a.leakage:.6g} m^3/(s*Pa)",
        f"supply {a.supply_pressure / 1e5:.6g} bar, tank {a.tank_pressure / 1e5:.6g} bar (gauge)",
        f"valve {a.valve_nominal_flow * 6e4:.6g} L/min at {a.valve_nominal_drop / 1e5:.6g} "
        f"bar per landing (K = {a.valve_coefficient:.6g} m^3/(s*sqrt(Pa))), laminar below "
        f"{a.valve_laminar_drop / 1e5:.6g} bar",
        f"control rate {1.0 / k.sample_time:.6g} Hz (sample time T = {k.sample_time:.6g} s)",
        f"kind coulomb: F_c = {k.coulomb:.6g} N at the rest pressures p_A = "
        f"{pa / 1e5:.6g} bar, p_B = {pb / 1e5:.6g} bar",
    ]
    advice = (
        "On another axis `command` is wrong: export again with that axis (cylfric control "
        "--axis axis.toml), or use the output `force` [N] (independent of the hydraulics "
        "above) through your own force-to-valve path."
    )
    return f"The valve command (output `command`) is computed for {which}", items, advice


def _dynamic_note(k: _Constants) -> str:
    """sigma_0 and sigma_1 with their status (identified or assumed) and, when assumed, how to
    identify them. Numbers and fixed words only (no datasheet text)."""
    from .study import IDENTIFY_ADVICE, dynamic_parameters

    dynamic = dynamic_parameters(k.model)
    parts = [
        f"{name} = {d['value']:.6g} {d['unit']} "
        f"({'identified' if d['status'] == 'identified' else 'ASSUMED, not identified'})"
        for name, d in dynamic.items()
    ]
    text = "LuGre dynamic parameters of the datasheet: " + ", ".join(parts) + "."
    if any(d["status"] != "identified" for d in dynamic.values()):
        text += (
            " The lugre kind's force depends on sigma_0 (an assumed value a factor 10 off can"
            f" make it worthless; cylfric control's metrics.json 'sensitivity'): {IDENTIFY_ADVICE}."
        )
    return text


def _axis_lines(k: _Constants, width: int = 86) -> list[str]:
    """:func:`_axis_facts` and :func:`_dynamic_note` as comment lines (no prefix)."""
    heading, items, advice = _axis_facts(k)
    return [
        *textwrap.wrap(heading, width),
        *(f"  {item}" for item in items),
        *textwrap.wrap(advice, width),
        *textwrap.wrap(_dynamic_note(k), width),
    ]


def _axis_text(k: _Constants) -> str:
    """:func:`_axis_facts` and :func:`_dynamic_note` as one paragraph."""
    heading, items, advice = _axis_facts(k)
    return f"{heading} {'; '.join(items)}. {advice} {_dynamic_note(k)}"


def _axis_names() -> tuple[str, ...]:
    from .axis import _VECTOR

    return tuple(_VECTOR)


# ------------------------------------------------------------------------------- C
def _params_header(k: _Constants) -> str:
    rows = []
    for i, name in enumerate(FRICTION_ROWS):
        code = int(k.table[i, 0])
        values = ", ".join(_number(v) for v in k.table[i])
        rows.append(f"    {{{values}}}, /* {name} [{_ROW_UNITS[i]}]: {_LAW_NAMES[code]} */")
    lines = [
        "/* Generated by cylfric.control.export: the constants of the friction compensator (SI).",
        f" * Datasheet: {c_comment(k.source)}",
        f" * Friction law: {c_comment(k.model.friction_law)}; operating pressure "
        f"{_REFERENCE_C[k.reference]}.",
        " * FRICTION rows: F_c, F_s, sigma_2, v_r, alpha, sigma_0, sigma_1; columns: law code",
        " * (0 constant c0; 1 linear c0 + c1 p; 2 quadratic c0 + c1 p + c2 p^2; 3 exponential",
        " * c0 + c1 (exp(c2 p) - 1)), c0, c1, c2, with p the operating pressure [Pa].",
        " *",
        *(f" * {line}".rstrip() for line in _axis_lines(k)),
        " *",
        " * Call cylfric_compensator_step exactly once per sample, every CYLFRIC_SAMPLE_TIME:",
        " * the velocity is (x - x_prev) / CYLFRIC_SAMPLE_TIME unless CYLFRIC_VELOCITY_INPUT is 1",
        " * (then the input velocity; see cylfric_compensator.h). */",
        "#ifndef CYLFRIC_COMPENSATOR_PARAMS_H",
        "#define CYLFRIC_COMPENSATOR_PARAMS_H",
        f"#define CYLFRIC_DEFAULT_AXIS {int(k.axis == DEFAULT_AXIS)} "
        "/* 1: the command is for cylfric's default axis, not yours */",
        f"#define CYLFRIC_REFERENCE {REFERENCE_CODES[k.reference]} "
        f"/* {_REFERENCE_C[k.reference]} */",
        "static const double CYLFRIC_FRICTION[7][4] = {",
        *rows,
        "};",
    ]
    for define, value, text in k.scalars():
        lines.append(f"#define {define} ({_number(value)}) /* {text} */")
    for define, _, text in _AXIS_DEFINES:
        lines.append(f"#define {define} ({_number(k.axis_values[define])}) /* {text} */")
    lines += ["#endif", ""]
    return "\n".join(lines)


def _c_sources(k: _Constants) -> dict[str, bytes]:
    return {
        "cylfric_compensator.h": _template("cylfric_compensator.h"),
        "cylfric_compensator.c": _template("cylfric_compensator.c"),
        "cylfric_compensator_params.h": _params_header(k).encode(),
    }


# ------------------------------------------------------------------------------- FMU
def _fmu_description(k: _Constants, name: str, guid: str, kind: str) -> str:
    from .._version import __version__
    from ..export.fmu import _BASE, _unit_xml

    pa, pb = k.axis.rest_pressures()
    starts = [k.axis.start_position, pa, pb, k.axis.start_position, 0.0, 0.0]
    description = " ".join(
        [
            f"cylfric friction compensator ({kind}) of the datasheet {k.source}: exactly one",
            f"doStep per controller sample, every {k.sample_time!r} s (the velocity is the",
            "position difference over that step); position absolute from the cap end (x = 0 at",
            "chamber A's dead volume), gauge pressures, positive command = flow P->A =",
            f"extension; the first sample outputs command 0; {_REFERENCE_C[k.reference]}.",
            _axis_text(k),
        ]
    )
    every = (*FMU_INPUTS.values(), *FMU_OUTPUTS.values())
    units = {u: _BASE[u.replace(".", "*")] for u, _ in every if u}
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
        f"  <CoSimulation modelIdentifier={quoteattr(name)}"
        ' canHandleVariableCommunicationStepSize="false">',
        "    <SourceFiles>",
        '      <File name="cylfric_compensator_fmu.c"/>',
        "    </SourceFiles>",
        "  </CoSimulation>",
        *_unit_xml(units),
        f'  <DefaultExperiment startTime="0.0" stopTime="1.0" stepSize="{k.sample_time!r}"/>',
        "  <ModelVariables>",
    ]
    variables: list[tuple[str, str, str, str, float | None]] = [
        (var, unit, text, "input", start)
        for (var, (unit, text)), start in zip(FMU_INPUTS.items(), starts, strict=True)
    ]
    variables += [(var, unit, text, "output", None) for var, (unit, text) in FMU_OUTPUTS.items()]
    variables.append(("z_hat", "m", "observer's bristle deflection (lugre)", "local", None))
    for vr, (var, unit, text, causality, start) in enumerate(variables):
        variability = "continuous" if causality == "input" else "discrete"
        attrs = (
            f'name={quoteattr(var)} valueReference="{vr}" description={quoteattr(text)}'
            f' causality="{causality}" variability="{variability}"'
        )
        if causality != "input":
            attrs += ' initial="calculated"'
        real = [f"unit={quoteattr(unit)}"] if unit else []
        if start is not None:
            real.append(f'start="{float(start)!r}"')
        out += [
            f"    <!-- index {vr + 1} -->",
            f"    <ScalarVariable {attrs}>",
            f"      <Real {' '.join(real)}/>" if real else "      <Real/>",
            "    </ScalarVariable>",
        ]
    out += [
        "  </ModelVariables>",
        "  <ModelStructure>",
        "    <Outputs>",
        '      <Unknown index="7"/>',
        '      <Unknown index="8"/>',
        "    </Outputs>",
        "    <InitialUnknowns>",
        '      <Unknown index="7"/>',
        '      <Unknown index="8"/>',
        "    </InitialUnknowns>",
        "  </ModelStructure>",
        "</fmiModelDescription>",
        "",
    ]
    return "\n".join(out)


def _fmu_header(k: _Constants, name: str, guid: str, kind: str) -> str:
    pa, pb = k.axis.rest_pressures()
    starts = [k.axis.start_position, pa, pb, k.axis.start_position, 0.0, 0.0, 0.0, 0.0, 0.0]
    return "\n".join(
        [
            "/* Generated by cylfric.control.export: identifier, GUID, kind and start values. */",
            "#ifndef CYLFRIC_COMPENSATOR_FMU_H",
            "#define CYLFRIC_COMPENSATOR_FMU_H",
            f"#define MODEL_IDENTIFIER_STRING {c_string(name)}",
            f"#define MODEL_GUID {c_string(guid)}",
            f"#define CYLFRIC_FMU_KIND {COMPENSATOR_CODES[kind]} /* {kind} */",
            "#define CYLFRIC_FMU_STARTS {" + ", ".join(_number(s) for s in starts) + "}",
            "#endif",
            "",
        ]
    )


def _fmu_bytes(k: _Constants, name: str, kind: str) -> bytes:
    import platform
    import sys

    from ..export.fmu import (
        _build_description,
        _compile,
        _zip,
        compiler,
        datasheet_text,
        fmi_platform,
    )
    from ..export.fmu import _template as fmi_template

    fmi_headers = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
    sources = _c_sources(k)
    sources["cylfric_compensator_fmu.c"] = _template("cylfric_compensator_fmu.c")
    sources.update({f: fmi_template(f) for f in fmi_headers})
    datasheet = datasheet_text(k.model)
    digest = hashlib.sha256()
    parts = [name.encode(), kind.encode(), datasheet.encode()]
    for part in [*parts, *(sources[f] for f in sorted(sources))]:
        digest.update(part)
        digest.update(b"\0")
    h = digest.hexdigest()
    guid = f"{{{h[:8]}-{h[8:12]}-{h[12:16]}-{h[16:20]}-{h[20:32]}}}"
    sources["cylfric_compensator_fmu.h"] = _fmu_header(k, name, guid, kind).encode()
    entries = {f"sources/{f}": data for f, data in sources.items()}
    entries["sources/buildDescription.xml"] = _build_description(
        name, "cylfric_compensator_fmu.c"
    ).encode()
    entries["modelDescription.xml"] = _fmu_description(k, name, guid, kind).encode()
    entries["resources/datasheet.json"] = datasheet.encode()
    target, cc = fmi_platform(), compiler()
    if target is None or cc is None:
        why = (
            "no C compiler ($CC, cc, gcc, clang)"
            if cc is None
            else f"no FMI 2.0 platform name for {sys.platform}/{platform.machine()}"
        )
        warnings.warn(
            f"{why}: the compensator FMU carries its C sources only; compile them on the "
            "target (fmpy.util.compile_platform_binary) before simulating",
            RuntimeWarning,
            stacklevel=3,
        )
    else:
        folder, suffix = target
        entries[f"binaries/{folder}/{name}{suffix}"] = _compile(
            sources, name, suffix, cc, main="cylfric_compensator_fmu.c"
        )
    return _zip(entries)


# ------------------------------------------------------------------------------- MATLAB
def _matlab(k: _Constants, name: str) -> str:
    table = ";\n         ".join(" ".join(_number(v) for v in row) for row in k.table)
    rule = {
        "a": "p = pressure_a;",
        "b": "p = pressure_b;",
        "sum": "p = pressure_a + pressure_b;",
        "mean": "p = 0.5 * (pressure_a + pressure_b);",
        "max": "p = max(pressure_a, pressure_b);",
    }[k.reference]
    ax = {key: _number(v) for key, v in k.axis_values.items()}
    fn = f"{name}_step"
    signature = (
        f"function [force, command, state] = {fn}(kind, position, pressure_a, pressure_b, "
        "position_reference, velocity_reference, velocity, state)"
    )
    law = matlab_comment(k.model.friction_law)
    vs = _number(k.smoothing)
    axis_help = "\n".join(f"%   {line}".rstrip() for line in _axis_lines(k))
    return f"""{signature}
%{fn.upper()} One sample of the cylfric friction compensator (SI units).
%   [force, command, state] = {fn}(kind, position, pressure_a, pressure_b,
%       position_reference, velocity_reference, velocity, state)
%   kind: 0 none, 1 coulomb, 2 static, 3 lugre; position [m], pressure_a, pressure_b [Pa],
%   position_reference [m], velocity_reference [m/s], velocity: the measured velocity
%   [m/s], read only when exported with the velocity input (else pass 0); state:
%   4-vector [x_prev [m]; z_hat [m]; f_prev [N]; started [-]], zeros(4, 1) before the
%   first sample.
%   force: the friction force estimate [N]; command: the valve command [-] that changes the
%   cylinder force by the estimate's change and holds it against the cross-piston leakage
%   (add it to the position controller's command).
%   Call exactly once per controller sample, every T = {k.sample_time!r} s: without the
%   velocity input the velocity is (position - previous position) / T. position: absolute
%   from the cap end (x = 0 at chamber A's dead volume, > 0 extends), the reference in the
%   same frame; pressures gauge [Pa]; command > 0 opens P->A (extension); force > 0 in the
%   direction of motion. The first sample (state(4) = 0) outputs command 0 (no previous
%   sample) and the observer's z_hat = state(2) starts at 0. Fixed sizes and subfunctions
%   only: usable as a Simulink MATLAB Function block.
%
{axis_help}
%
%   Written by cylfric (cylfric.control.export; docs/control.md), the same step as
%   cylfric.control.kernel.compensator_step. Datasheet: {matlab_comment(k.source)}
%   Friction law: {law}; operating pressure {_REFERENCE_C[k.reference]}.
T = {_number(k.sample_time)};  % sample time [s]
started = state(4) > 0;
if {int(k.velocity_input)}
    v = velocity;
elseif started
    v = (position - state(1)) / T;
else
    v = 0;
end
state(1) = position;
comp = 0;
if kind == 1
    comp = {_number(k.coulomb)} * tanh(velocity_reference / {vs});
elseif kind == 2
    q = params_at(pressure_a, pressure_b);
    comp = g_of(abs(velocity_reference), q) * tanh(velocity_reference / {vs}) ...
        + q(3) * velocity_reference;
elseif kind == 3
    q = params_at(pressure_a, pressure_b);
    state(2) = z_step(state(2), v, T, q);
    state(2) = state(2) + {_number(k.observer_gain)} * (position_reference - position) * T;
    g = g_of(abs(v), q);
    dz = v - q(6) * abs(v) * state(2) / g;
    comp = q(6) * state(2) + q(7) * dz + q(3) * v;
elseif kind ~= 0
    error('cylfric:kind', 'kind = %g; expected 0 none, 1 coulomb, 2 static or 3 lugre', kind);
end
if started && kind ~= 0
    comp = state(3) + {_number(k.filter_gain)} * (comp - state(3));  % force filter
end
command = 0;
if started && kind ~= 0
    rate = (comp - state(3)) / T + leakage_force_rate(comp, position);
    if rate >= 0
        direction = 1;
    else
        direction = -1;
    end
    command = rate / force_rate_gain(direction, position, pressure_a, pressure_b);
end
state(3) = comp;
state(4) = 1;
force = comp;
end

function q = params_at(pressure_a, pressure_b)
% (F_c, F_s, sigma_2, v_r, alpha, sigma_0, sigma_1) at the operating pressure, kept physical
{rule}
F = [{table}];
q = zeros(1, 7);
for i = 1:7
    if F(i, 1) == 0
        q(i) = F(i, 2);
    elseif F(i, 1) == 1
        q(i) = F(i, 2) + F(i, 3) * p;
    elseif F(i, 1) == 2
        q(i) = F(i, 2) + p * (F(i, 3) + F(i, 4) * p);
    else
        q(i) = F(i, 2) + F(i, 3) * expm1(F(i, 4) * p);
    end
end
q = max(q, [1e-9 1e-9 0 1e-12 1e-3 1e-9 0]);
end

function y = exp_neg(x)
if x < 1e-3
    y = 1 - x * (1 - x * (0.5 - x * (1 / 6 - x * (1 / 24 - x * (1 / 120)))));
elseif x > 746
    y = 0;
else
    y = exp(-x);
end
end

function g = g_of(speed, q)
% g(|v|) of thesis eq. 2.5 [N]
u = speed * (1 / q(4));
if q(5) == 2
    d = exp_neg(u * u);
elseif q(5) == 1
    d = exp_neg(u);
else
    d = exp_neg(u ^ q(5));
end
g = q(1) + (q(2) - q(1)) * d;
end

function z = z_step(z0, v, h, q)
% exact bristle deflection after h at constant v (eq. 2.5)
if v == 0
    z = z0;
    return;
end
g = g_of(abs(v), q);
x = q(6) * abs(v) / g * h;
if v > 0
    z_ss = g / q(6);
else
    z_ss = -g / q(6);
end
if x < 1e-5
    one_minus_e = x * (1 - x * (0.5 - x / 6));
else
    one_minus_e = -expm1(-x);
end
z = z_ss + (z0 - z_ss) * (1 - one_minus_e);
end

function r = root_of(dp)
lam = {ax["CYLFRIC_LAMINAR_DROP"]};  % laminar transition [Pa]
if abs(dp) < lam
    r = dp / sqrt(lam);
elseif dp > 0
    r = sqrt(abs(dp));
else
    r = -sqrt(abs(dp));
end
end

function G = force_rate_gain(direction, x, pa, pb)
% d(A_A p_A - A_B p_B)/dt per unit valve opening [N/s]
aa = {ax["CYLFRIC_AREA_A"]};  % [m^2]
ab = {ax["CYLFRIC_AREA_B"]};  % [m^2]
va = {ax["CYLFRIC_DEAD_VOLUME_A"]} + aa * x;  % [m^3]
vb = {ax["CYLFRIC_DEAD_VOLUME_B"]} + ab * ({ax["CYLFRIC_STROKE"]} - x);  % [m^3]
ps = {ax["CYLFRIC_SUPPLY"]};  % [Pa]
pt = {ax["CYLFRIC_TANK"]};  % [Pa]
k = {ax["CYLFRIC_VALVE_K"]};  % [m^3/(s*sqrt(Pa))]
floor_ = sqrt({ax["CYLFRIC_LAMINAR_DROP"]});
if direction >= 0
    ka = k * max(root_of(ps - pa), floor_);
    kb = k * max(root_of(pb - pt), floor_);
else
    ka = k * max(root_of(pa - pt), floor_);
    kb = k * max(root_of(ps - pb), floor_);
end
G = {ax["CYLFRIC_BULK_MODULUS"]} * (aa * ka / va + ab * kb / vb);
end

function r = leakage_force_rate(force, x)
% force rate [N/s] that holds the cylinder force [N] against the cross-piston leakage
aa = {ax["CYLFRIC_AREA_A"]};  % [m^2]
ab = {ax["CYLFRIC_AREA_B"]};  % [m^2]
va = {ax["CYLFRIC_DEAD_VOLUME_A"]} + aa * x;  % [m^3]
vb = {ax["CYLFRIC_DEAD_VOLUME_B"]} + ab * ({ax["CYLFRIC_STROKE"]} - x);  % [m^3]
r = {ax["CYLFRIC_BULK_MODULUS"]} * {ax["CYLFRIC_LEAKAGE"]} * force / (0.5 * (aa + ab)) ...
    * (aa / va + ab / vb);
end
"""


# ------------------------------------------------------------------------------- API
def export_compensator(
    model: FrictionModel | StrPath | Mapping[str, Any],
    out: StrPath,
    *,
    targets: Iterable[str] = EXPORT_TARGETS,
    axis: Axis = DEFAULT_AXIS,
    compensator: str = "lugre",
    name: str = "cylfric_compensator",
    smoothing_velocity: float = SMOOTHING_VELOCITY,
    observer_gain: float = OBSERVER_GAIN,
    force_filter: float = FORCE_FILTER,
    velocity_input: bool = False,
) -> list[Path]:
    """Write the compensator step as C source, an FMU and/or a MATLAB function.

    Parameters
    ----------
    model : FrictionModel, path or dict
        The datasheet the compensator uses.
    out : path
        Output folder (created if needed).
    targets : iterable of {"c", "fmu", "matlab"}
        What to write (see the module notes).
    axis : Axis
        The axis (areas, volumes, valve, supply; its sample time is the compensator's).
    compensator : {"none", "coulomb", "static", "lugre"}
        The kind the FMU carries (structural); the C and MATLAB steps take it as an argument.
    name : str
        FMU model identifier and MATLAB function prefix (a C identifier).
    smoothing_velocity, observer_gain : float
        Sign smoothing v_s [m/s] and LuGre observer gain k_o [1/s], as in the loop.
    force_filter : float
        Time constant tau_f [s] of the first-order filter on the force estimate (0: none).
    velocity_input : bool
        The step reads the input ``velocity`` [m/s] (a velocity sensor or the user's own
        estimate) instead of differencing the position.

    Returns
    -------
    list of Path
        The files written.
    """
    from .._atomic import atomic_write_bytes, atomic_write_text
    from .._paths import make_folder
    from ..export.fmu import _as_model, _check_name

    targets = list(targets)
    unknown = [t for t in targets if t not in EXPORT_TARGETS]
    if unknown or not targets:
        raise ValueError(f"export targets {targets}: expected some of {list(EXPORT_TARGETS)}")
    if compensator not in EXPORTABLE_COMPENSATORS:
        raise ValueError(
            f"compensator {compensator!r} cannot be exported; valid: "
            f"{list(EXPORTABLE_COMPENSATORS)} (the oracle needs the plant's own friction)"
        )
    name = _check_name(name, "cylfric_compensator")
    model = _as_model(model)
    constants = _Constants(
        model, axis, smoothing_velocity, observer_gain, force_filter, velocity_input
    )
    out = Path(out)
    make_folder(out)
    written: list[Path] = []
    if "c" in targets:
        for filename, data in _c_sources(constants).items():
            written.append(atomic_write_bytes(out / filename, data))
    if "fmu" in targets:
        written.append(
            atomic_write_bytes(out / f"{name}.fmu", _fmu_bytes(constants, name, compensator))
        )
    if "matlab" in targets:
        written.append(atomic_write_text(out / f"{name}_step.m", _matlab(constants, name)))
    return written
