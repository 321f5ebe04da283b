"""``motion.toml``: which signals of a motion record are time, position, force and pressures.

A motion record is a ``.mat`` file (its variables) or a bench text file (its columns, read by
:func:`cylfric.io.read_bench_text`). ``motion.toml`` names the signals and the settings of
the identification from the record (:func:`cylfric.identify.motion.fit_motion`)::

    [signals]
    time = "t"                 # [s]
    position = "qm"            # [m] (or the unit in [units])
    force = "vir"              # times force_scale gives the driving force [N]
    force_scale = "gtau"       # a number or a scalar variable of the file (EMPS: N/V)
    pressure_a = "pA"          # optional chamber pressures: the refinement to the
    pressure_b = "pB"          #   pressure-dependent Stribeck model

    [units]                    # units of .mat variables (text records carry their own)
    position = "mm"

    [filter]                   # IDIM-LS settings (defaults: the EMPS benchmark procedure)
    cutoff = 100.0             # zero-phase Butterworth low-pass of the position [Hz]
    order = 4                  # its order [-]
    decimation = 10            # decimation factor of the regression [-]
    border = 50                # samples dropped at each end (filter edge effects) [-]

    [refinement]               # only with pressures
    friction_law = "stribeck"  # or "coulomb_viscous"
    reference = "mean"         # chamber pressure the laws see: a, b, sum, mean, max
    alpha = 1.0                # Stribeck exponent, held fixed [-]
    v_r = "10 mm/s"            # starting value of the Stribeck velocity
    min_speed = "5 mm/s"       # slower samples left out (sticking, presliding)

    [validation]               # closed-loop replay of a second record (EMPS procedure)
    reference = "qg"           # position reference [m]
    kp = "kp"                  # position gain [1/s] (number or scalar variable)
    kv = "kv"                  # velocity gain [force-signal unit per m/s]
    saturation = 10.0          # limit of the controller output (force-signal unit)
    disturbance = "pulses_N"   # optional signal added to the controller output

The file is checked against :data:`MOTION_SCHEMA`: an unknown key, a wrong type or a missing
signal raises :class:`~cylfric.io.BenchFileError` naming the key and its line.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..units import UnitError, parse_quantity, unit_dimension
from .text import BenchFileError

if TYPE_CHECKING:
    from cylfric._typing import StrPath

__all__ = [
    "MotionConfig",
    "MotionRecord",
    "load_motion_config",
    "read_motion_record",
    "MOTION_SCHEMA",
    "SIGNAL_DIMENSIONS",
]

SIGNAL_DIMENSIONS = {
    "time": "time",
    "position": "length",
    "force": "force",
    "pressure_a": "pressure",
    "pressure_b": "pressure",
}
"""Signals of ``[signals]`` (besides ``force_scale``) and the dimension of each."""

_NAME = {"type": "string", "minLength": 1}
_NAME_OR_NUMBER = {"anyOf": [_NAME, {"type": "number"}]}
MOTION_SCHEMA = {
    "type": "object",
    "additionalProperties": False,
    "required": ["signals"],
    "properties": {
        "signals": {
            "type": "object",
            "additionalProperties": False,
            "required": ["time", "position", "force"],
            "properties": {**{k: _NAME for k in SIGNAL_DIMENSIONS}, "force_scale": _NAME_OR_NUMBER},
        },
        "units": {
            "type": "object",
            "additionalProperties": False,
            "properties": {k: _NAME for k in SIGNAL_DIMENSIONS},
        },
        "filter": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "cutoff": {"type": "number", "exclusiveMinimum": 0},
                "order": {"type": "integer", "minimum": 1, "maximum": 12},
                "decimation": {"type": "integer", "minimum": 1, "maximum": 100},
                "border": {"type": "integer", "minimum": 0},
            },
        },
        "refinement": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "friction_law": {"enum": ["stribeck", "coulomb_viscous"]},
                "reference": {"enum": ["a", "b", "sum", "mean", "max"]},
                "alpha": {"type": "number", "exclusiveMinimum": 0},
                "v_r": _NAME,
                "min_speed": _NAME,
            },
        },
        "validation": {
            "type": "object",
            "additionalProperties": False,
            "required": ["reference", "kp", "kv"],
            "properties": {
                "reference": _NAME,
                "kp": _NAME_OR_NUMBER,
                "kv": _NAME_OR_NUMBER,
                "saturation": {"type": "number", "exclusiveMinimum": 0},
                "disturbance": _NAME,
            },
        },
    },
}
"""JSON Schema of motion.toml."""


@dataclass(frozen=True)
class MotionConfig:
    """Signals and settings of a motion identification (``motion.toml``).

    Attributes
    ----------
    signals : dict
        Role (``time``, ``position``, ``force``, ``pressure_a``, ``pressure_b``) -> variable or
        column name in the record.
    force_scale : float or str
        Factor from the force signal to newtons [N per signal unit], or the name of a
        scalar variable of the record holding it (EMPS: ``"gtau"`` [N/V]).
    units : dict
        Role -> unit of a ``.mat`` variable (default: SI, ``s``, ``m``, ``N``, ``Pa``).
    cutoff : float
        Cut-off frequency of the zero-phase Butterworth low-pass of the position [Hz].
    order : int
        Order of that filter [-] (applied forward and backward: twice the order).
    decimation : int
        Decimation factor of the regression (``scipy.signal.decimate``) [-].
    border : int
        Samples dropped at each end of the record (filter and difference edges) [-].
    friction_law, reference : str
        Steady-state law and pressure reference of the refinement.
    alpha : float
        Stribeck exponent of the refinement, held fixed [-].
    v_r : float
        Starting value of the Stribeck velocity of the refinement [m/s].
    min_speed : float
        Samples slower than this are left out of the refinement [m/s].
    validation : dict or None
        ``reference``, ``kp``, ``kv``, ``saturation``, ``disturbance`` of the closed-loop replay.
    source : str or None
        The file read (None for defaults).
    """

    signals: dict
    force_scale: float | str = 1.0
    units: dict = field(default_factory=dict)
    cutoff: float = 100.0
    order: int = 4
    decimation: int = 10
    border: int = 50
    friction_law: str = "stribeck"
    reference: str = "mean"
    alpha: float = 1.0
    v_r: float = 0.01
    min_speed: float = 0.005
    validation: dict | None = None
    source: str | None = None

    def line_of(self, key: str, table: str | None = None) -> int | None:
        """Line of ``key = ...`` (in ``[table]``) in the file (None without a file)."""
        return _line_of(self.source, key, table) if self.source else None

    def error(self, table: str | None, key: str, message: str) -> BenchFileError:
        """A :class:`BenchFileError` naming this file, the line of ``table.key``, ``message``."""
        return BenchFileError(
            self.source or "motion config", message, line=self.line_of(key, table)
        )


def load_motion_config(path: StrPath) -> MotionConfig:
    """Read and check ``motion.toml``.

    Parameters
    ----------
    path : path-like
        The file (see the module docstring for its tables and keys).

    Returns
    -------
    MotionConfig

    Raises
    ------
    BenchFileError
        Invalid TOML, an unknown key, a wrong type, a missing signal or a unit of the wrong
        dimension; the message names the file, the key and its line.
    """
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BenchFileError(path, f"invalid TOML ({exc})") from None
    except RecursionError:
        raise BenchFileError(path, "invalid TOML (arrays or tables nested too deeply)") from None
    except OSError as exc:
        raise BenchFileError(path, f"cannot read the file ({exc.strerror})") from None
    _validate(doc, path)
    signals = dict(doc["signals"])
    force_scale = signals.pop("force_scale", 1.0)
    if isinstance(force_scale, float | int) and not (
        math.isfinite(force_scale) and force_scale != 0
    ):
        raise BenchFileError(
            path,
            f"signals.force_scale = {force_scale}; expected a finite non-zero number",
            line=_line_of(path, "force_scale", "signals"),
        )
    units = dict(doc.get("units", {}))
    for role, unit in units.items():
        try:
            dimension = unit_dimension(unit)
        except UnitError as exc:
            raise BenchFileError(
                path, f"units.{role}: {exc}", line=_line_of(path, role, "units")
            ) from None
        if dimension != SIGNAL_DIMENSIONS[role]:
            raise BenchFileError(
                path,
                f"units.{role} = {unit!r} is a {dimension} unit; expected a "
                f"{SIGNAL_DIMENSIONS[role]} unit",
                line=_line_of(path, role, "units"),
            )
    if ("pressure_a" in units or "pressure_b" in units) and not (
        "pressure_a" in signals or "pressure_b" in signals
    ):
        raise BenchFileError(path, "[units] gives a pressure unit but [signals] no pressure")
    filt, refine = doc.get("filter", {}), doc.get("refinement", {})
    speeds = {}
    for key, default in (("v_r", 0.01), ("min_speed", 0.005)):
        speeds[key] = default
        if key in refine:
            try:
                speeds[key] = parse_quantity(refine[key], "velocity", default_unit="mm/s")
            except UnitError as exc:
                raise BenchFileError(
                    path, f"refinement.{key}: {exc}", line=_line_of(path, key, "refinement")
                ) from None
    if not speeds["v_r"] > 0 or not speeds["min_speed"] >= 0:
        raise BenchFileError(
            path,
            "refinement.v_r must be > 0 and refinement.min_speed >= 0",
            line=_line_of(path, "v_r" if not speeds["v_r"] > 0 else "min_speed", "refinement"),
        )
    if refine and not ("pressure_a" in signals or "pressure_b" in signals):
        raise BenchFileError(
            path,
            "[refinement] needs a recorded pressure: name signals.pressure_a (and pressure_b)",
            line=_line_of(path, "refinement"),
        )
    return MotionConfig(
        signals=signals,
        force_scale=force_scale,
        units=units,
        cutoff=float(filt.get("cutoff", 100.0)),
        order=int(filt.get("order", 4)),
        decimation=int(filt.get("decimation", 10)),
        border=int(filt.get("border", 50)),
        friction_law=refine.get("friction_law", "stribeck"),
        reference=refine.get("reference", "mean"),
        alpha=float(refine.get("alpha", 1.0)),
        v_r=speeds["v_r"],
        min_speed=speeds["min_speed"],
        validation=dict(doc["validation"]) if "validation" in doc else None,
        source=str(path),
    )


def _line_of(path, key, table=None) -> int | None:
    """1-based line of ``key = ...`` (or of the table ``[key]``), inside ``[table]`` if given."""
    pattern = re.compile(rf"^\s*(\[\s*{re.escape(key)}\s*\]|\"?{re.escape(key)}\"?\s*=)")
    current = None
    for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
        header = re.match(r"^\s*\[\s*([^\]]+?)\s*\]", line)
        if header and not pattern.match(line):
            current = header.group(1)
            continue
        if pattern.match(line) and (table is None or current == table):
            return number
    return None


def _validate(doc, path) -> None:
    """Raise BenchFileError naming the key (and its line) of the first schema violation."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(MOTION_SCHEMA)
    errors = sorted(validator.iter_errors(doc), key=lambda e: (len(e.path), list(e.path)))
    if not errors:
        return
    error = errors[0]
    where = ".".join(str(p) for p in error.path)
    table = f"[{where}]" if where else "the top level"
    if error.validator == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        valid = sorted(error.schema.get("properties", {}))
        raise BenchFileError(
            path,
            f"unknown key {extra[0]!r} in {table} (valid: {valid})",
            line=_line_of(path, extra[0], where or None),
        )
    if error.validator == "required":
        missing = [k for k in error.validator_value if k not in error.instance]
        name = f"{where}.{missing[0]}" if where else missing[0]
        what = "signal" if where == "signals" else "key"
        raise BenchFileError(
            path,
            f'missing {what} {name!r} in {table}; expected e.g. {missing[0]} = "name"',
            line=_line_of(path, where) if where else None,
        )
    key = str(error.path[-1]) if error.path else ""
    table_of_key = ".".join(str(p) for p in list(error.path)[:-1]) or None
    message = error.message
    if error.validator in ("type", "anyOf"):
        expected = {
            "anyOf": "a variable name (text) or a number",
        }.get(error.validator, f"a value of type {error.validator_value}")
        message = f"{error.instance!r} has the wrong type; expected {expected}"
    raise BenchFileError(
        path, f"{where}: {message}", line=_line_of(path, key, table_of_key) if key else None
    )


@dataclass(frozen=True)
class MotionRecord:
    """The signals of a motion record, in SI.

    Attributes
    ----------
    time : ndarray
        [s], strictly increasing, uniformly sampled (within 5 %).
    position : ndarray
        [m].
    force : ndarray
        Driving force (signal times ``force_scale``) [N].
    pressure_a, pressure_b : ndarray or None
        Chamber pressures [Pa] when recorded.
    variables : dict
        Every vector of the record by name (raw values, e.g. for the validation signals).
    scalars : dict
        Scalar variables of a ``.mat`` record (gains such as EMPS's ``gtau``, ``kp``, ``kv``).
    force_scale : float
        The factor applied to the force signal [N per signal unit].
    file : str
        The record read.
    """

    time: np.ndarray
    position: np.ndarray
    force: np.ndarray
    pressure_a: np.ndarray | None
    pressure_b: np.ndarray | None
    variables: dict
    scalars: dict
    force_scale: float
    file: str


MAX_MAGNITUDE = {"position": 1e3, "force": 1e9, "pressure_a": 1e10, "pressure_b": 1e10}
"""Largest magnitude [SI: m, N, Pa] of a sample of a motion record: beyond any physical rig
(a stroke of 1 km, 1 GN, 100 kbar); a larger sample is a spike or a corrupt value and is
refused like a non-finite one (it would swamp the least squares)."""

VARYING = ("position", "force")
"""Signals refused when constant: the regression needs their variation."""


def _check_samples(path, name, role, values, is_mat, unit):
    """Refuse absurd magnitudes (:data:`MAX_MAGNITUDE`, in SI) and a constant position or
    force, naming the file, the channel and the first bad sample."""
    from .text import data_row_line

    limit = MAX_MAGNITUDE.get(role)
    if limit is not None:
        bad = np.flatnonzero(np.abs(values) > limit)
        if bad.size:
            first = int(bad[0])
            where = f"sample {first}" + ("" if is_mat else f" (data row {first + 1})")
            raise BenchFileError(
                path,
                f"{name} ({role}) holds {values[first]:.6g} {unit} at {where}"
                + (f" and {bad.size - 1} more such samples" if bad.size > 1 else "")
                + f"; beyond any physical rig (|{role}| above {limit:g} {unit}): a spike or "
                "a corrupt value; remove or interpolate it (or cut the record) before the "
                "identification",
                line=None if is_mat else data_row_line(path, first),
            )
    if role in VARYING and values.size and np.ptp(values) == 0:
        raise BenchFileError(
            path,
            f"{name} ({role}) does not change ({values[0]:.6g} {unit} in all {values.size} "
            "samples); the identification needs a recorded signal that varies: check that "
            "motion.toml names the right channel",
        )


def _non_finite(path, name, role, values, bad, is_mat) -> BenchFileError:
    """The error for non-finite samples: file, channel, first sample index (and its line in
    a text record), how many there are, and what to do."""
    from .text import data_row_line

    first = int(bad[0])
    where = f"sample {first}" + ("" if is_mat else f" (data row {first + 1})")
    return BenchFileError(
        path,
        f"{name} ({role}) holds {values[first]} at {where}"
        + (f" and {bad.size - 1} more non-finite samples" if bad.size > 1 else "")
        + "; expected finite numbers in every sample: remove or interpolate the gap (or "
        "cut the record) before the identification",
        line=None if is_mat else data_row_line(path, first),
    )


def _strip_unit(name: str) -> str:
    return name.rsplit(" [", 1)[0] if name.endswith("]") and " [" in name else name


def read_motion_record(path: StrPath, config: MotionConfig) -> MotionRecord:
    """Read the signals that ``config`` names from a ``.mat`` or bench text record.

    Parameters
    ----------
    path : path-like
        The record (never modified): ``.mat`` (variables) or a bench text file (columns).
    config : MotionConfig
        The signal names and units (:func:`load_motion_config`).

    Returns
    -------
    MotionRecord

    Raises
    ------
    BenchFileError
        A named variable missing from the record (naming the key and its line in
        motion.toml and listing the variables found), signals of different lengths, non-finite
        samples (NaN, inf: naming the channel, the first sample index and, in a text record,
        its line), time not increasing or not uniformly sampled.
    """
    from .matfile import read_mat
    from .text import read_bench_text

    path = Path(path)
    is_mat = path.suffix.lower() == ".mat"
    if is_mat:
        data, meta = read_mat(path)
        scalars = dict(meta["scalars"])
    else:
        if config.units:
            role = sorted(config.units)[0]
            raise config.error(
                "units",
                role,
                f"units.{role}: a text record carries its units in its header; [units] is only "
                f"for .mat records ({path} is text)",
            )
        data, meta = read_bench_text(path)
        scalars = {}
    variables = {_strip_unit(str(c)): np.asarray(data[c], dtype=float) for c in data.columns}
    found = sorted(variables)

    def vector(role, name, table="signals"):
        if name not in variables:
            extra = f"; scalars {sorted(scalars)}" if scalars else ""
            raise config.error(
                table,
                role,
                f"{table}.{role} = {name!r} is not a variable of {path.name}; found {found}{extra}",
            )
        values = variables[name]
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise _non_finite(path, name, role, values, bad, is_mat)
        return values

    def scale(role, value, table):
        if isinstance(value, str):
            if value not in scalars:
                raise config.error(
                    table,
                    role,
                    f"{table}.{role} = {value!r} is not a scalar variable of {path.name}; "
                    f"scalars: {sorted(scalars)} (or give a number)",
                )
            value = scalars[value]
        if not (math.isfinite(value) and value != 0):
            raise config.error(table, role, f"{table}.{role} = {value}; expected non-zero")
        return float(value)

    si = {}
    for role in SIGNAL_DIMENSIONS:
        if role not in config.signals:
            continue
        values = vector(role, config.signals[role])
        unit = config.units.get(role)
        if is_mat and unit is not None:
            from ..units import to_si

            values = to_si(values, unit, SIGNAL_DIMENSIONS[role])
        si_unit = {"position": "m", "force": "", "time": "s"}.get(role, "Pa")
        _check_samples(path, config.signals[role], role, values, is_mat, si_unit)
        si[role] = values
    force_scale = scale("force_scale", config.force_scale, "signals")
    time = si["time"]
    if time.size < 10:
        raise BenchFileError(path, f"only {time.size} samples; expected a motion record")
    step = np.diff(time)
    if not np.all(step > 0):
        raise BenchFileError(path, f"{config.signals['time']} (time) is not strictly increasing")
    median = float(np.median(step))
    if np.max(np.abs(step - median)) > 0.05 * median:
        raise BenchFileError(
            path,
            f"{config.signals['time']} (time) is not uniformly sampled (steps "
            f"{step.min():.4g}-{step.max():.4g} s); resample it before the identification",
        )
    return MotionRecord(
        time=time,
        position=si["position"],
        force=si["force"] * force_scale,
        pressure_a=si.get("pressure_a"),
        pressure_b=si.get("pressure_b"),
        variables=variables,
        scalars=scalars,
        force_scale=force_scale,
        file=str(path),
    )
