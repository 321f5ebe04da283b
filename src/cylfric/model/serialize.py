"""A friction model as a datasheet (JSON, SI) and back; the schema and its validation.

The datasheet is the serialised :class:`~cylfric.model.FrictionModel`: the model owns the
keys ``model``, ``parameters``, ``stderr``, ``not_identified``, ``dynamic``, ``validity`` and,
under ``fit``, ``method``, ``rmse``, ``n_points``, ``fixed``, ``bounds``, ``covariance``,
``influence``, ``covariance_nonrobust``, ``correlations``, ``statistics`` and ``source``.
Every other key (the per-pressure table, the offset, notes, ...) is kept verbatim in
:attr:`FrictionModel.record`, so that datasheet -> model -> datasheet is the identity.
"""

from __future__ import annotations

import functools
import json
import math
import os
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .names import (
    DYNAMIC_PARAMETERS,
    FRICTION_LAWS,
    PARAMETER_UNITS,
    STEADY_PARAMETERS,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping
    from typing import TypeVar

    from .._typing import StrPath
    from .core import FrictionModel

    _M = TypeVar("_M", bound=FrictionModel)

__all__ = [
    "SCHEMA",
    "SCHEMA_ID",
    "DatasheetError",
    "validate",
    "read_datasheet",
    "to_datasheet",
    "from_datasheet",
    "clean",
    "compile_schema",
]

SCHEMA_ID = "cylfric-datasheet/1"
SCHEMA = json.loads(resources.files("cylfric.model").joinpath("datasheet.schema.json").read_text())
"""The JSON Schema of a datasheet (draft 2020-12)."""

UNITS = {
    "force": "N",
    "pressure": "Pa",
    "velocity": "m/s",
    "sigma_2": "N*s/m",
    "sigma_0": "N/m",
    "sigma_1": "N*s/m",
    "slope": "unit per Pa",
    "curvature": "unit per Pa^2",
    "rate": "1/Pa",
}
"""Units of a datasheet's values (SI)."""

_MODEL_FIT_KEYS = (
    "influence",
    "covariance_nonrobust",
    "method",
    "rmse",
    "n_points",
    "fixed",
    "bounds",
    "covariance",
    "correlations",
    "statistics",
    "source",
)
_MODEL_KEYS = ("model", "parameters", "stderr", "not_identified", "dynamic", "validity", "fit")

MAX_FORCE = 1e8
"""Largest friction force a datasheet may promise [N] (10x the largest presses' force)."""


class DatasheetError(ValueError):
    """A datasheet does not follow the schema; the message names the file and the key."""


def clean(value: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars and arrays -> Python, tuples -> lists."""
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "biu" or (value.dtype.kind == "f" and np.isfinite(value).all()):
            return value.tolist()  # already Python numbers in lists: nothing to replace
        return clean(value.tolist())
    if isinstance(value, list | tuple):
        return [clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _matrix(pair):
    if pair is None:
        return None
    names, matrix = pair
    # the array itself: clean() makes its lists once (a 20,000-run influence matrix, 6 MB)
    return {"names": list(names), "matrix": np.asarray(matrix, dtype=float)}


def _bound(x):
    return None if not math.isfinite(x) else float(x)


def to_datasheet(model: FrictionModel) -> dict[str, Any]:
    """The datasheet dict of ``model`` (see the module docstring for who owns which key)."""
    from .._version import __version__

    record = dict(model.record)
    record_fit = dict(record.pop("fit", {}))
    stats = dict(model.statistics)
    rmse = stats.pop("rmse", None)
    n_points = stats.pop("n_points", None)
    coefficients = model.coefficients()
    dynamic = {}
    for name in DYNAMIC_PARAMETERS:
        status, reason = model.dynamic_status[name]
        dynamic[name] = {
            "value": coefficients[name],
            "unit": PARAMETER_UNITS[name],
            "status": status,
            "reason": reason,
        }
    identified = [p for p in model.parameters.values() if p.value is not None]
    fit = {
        "method": model.provenance.get("method", "given (not fitted)"),
        "rmse": rmse,
        "n_points": n_points,
        "fixed": {
            p.name: p.value for p in identified if not p.vary and p.parameter in STEADY_PARAMETERS
        },
        "bounds": {p.name: [_bound(p.bounds[0]), _bound(p.bounds[1])] for p in identified},
        "covariance": _matrix(model.covariance),
        "correlations": _matrix(model.correlations()),
        "influence": _matrix(model.influence),
        "covariance_nonrobust": _matrix(model.covariance_nonrobust),
        "statistics": stats,
        "source": dict(model.provenance.get("source", {"campaign": "", "files": []})),
        **record_fit,
    }
    if n_points is None:
        del fit["n_points"]
    sheet = {
        "schema": SCHEMA_ID,
        "cylfric_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "name": "cylinder",
        "units": dict(UNITS),
        "offset": None,
        "per_pressure": [],
        "notes": [],
        **record,
        "model": {
            "friction_law": model.friction_law,
            "equation": FRICTION_LAWS[model.friction_law][1],
            "pressure_law": model.pressure_law,
            "pressure_reference": model.reference,
            "stribeck_identifiable": model.friction_law == "stribeck",
            **(
                {"pressure_reference_basis": dict(model.pressure_reference_basis)}
                if model.pressure_reference_basis is not None
                else {}
            ),
        },
        "parameters": model.coefficients(include_dynamic=False),
        "stderr": model.stderr(),
        "not_identified": dict(model.not_identified),
        "dynamic": dynamic,
        "validity": None if model.validity is None else dict(model.validity),
        "fit": fit,
    }
    return clean(sheet)


def from_datasheet(cls: type[_M], source: StrPath | Mapping[str, Any]) -> _M:
    """Build ``cls`` (a FrictionModel) from a datasheet path or dict, after validation."""
    if isinstance(source, str | os.PathLike):
        sheet, where = read_datasheet(source), os.fspath(source)
    else:
        sheet, where = validate(dict(source)), "datasheet"
    model_part = sheet["model"]
    fit = dict(sheet["fit"])
    stats = dict(fit.get("statistics") or {})
    if fit.get("rmse") is not None:
        stats["rmse"] = fit["rmse"]
    if fit.get("n_points") is not None:
        stats["n_points"] = fit["n_points"]
    dynamic = sheet.get("dynamic") or {}
    covariance = fit.get("covariance")
    influence = fit.get("influence")
    nonrobust = fit.get("covariance_nonrobust")
    bounds = {
        name: (-math.inf if lo is None else lo, math.inf if hi is None else hi)
        for name, (lo, hi) in (fit.get("bounds") or {}).items()
    }
    record = {k: v for k, v in sheet.items() if k not in _MODEL_KEYS}
    record_fit = {k: v for k, v in fit.items() if k not in _MODEL_FIT_KEYS}
    if record_fit:
        record["fit"] = record_fit
    parameters = dict(sheet["parameters"])
    friction_law = model_part.get("friction_law", "stribeck")
    names = _coefficient_names(parameters, model_part["pressure_law"])
    fixed = [name for name in (fit.get("fixed") or {}) if name in names]
    try:
        model = cls(
            {k: parameters.get(k) for k in STEADY_PARAMETERS},
            pressure_law=model_part["pressure_law"],
            friction_law=friction_law,
            sigma_0=dynamic.get("sigma_0", {}).get("value"),
            sigma_1=dynamic.get("sigma_1", {}).get("value"),
            dynamic_status={k: (v["status"], v.get("reason", "")) for k, v in dynamic.items()}
            or None,
            reference=model_part["pressure_reference"],
            pressure_reference_basis=model_part.get("pressure_reference_basis"),
            stderr={k: v for k, v in (sheet.get("stderr") or {}).items() if v is not None},
            fixed=fixed,
            bounds=bounds,
            covariance=None if covariance is None else (covariance["names"], covariance["matrix"]),
            influence=None if influence is None else (influence["names"], influence["matrix"]),
            covariance_nonrobust=None
            if nonrobust is None
            else (nonrobust["names"], nonrobust["matrix"]),
            statistics=stats,
            validity=sheet.get("validity"),
            provenance={"method": fit["method"], "source": fit["source"]},
            not_identified=sheet.get("not_identified") or {},
            record=record,
        )
    except (ValueError, TypeError) as exc:
        raise DatasheetError(f"{where}: {exc}") from None
    if isinstance(source, str | os.PathLike):
        model.source = os.fspath(source)  # evaluation errors name the file
    return model


def _coefficient_names(parameters, default_law):
    from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS

    names: set[str] = set()
    for name, spec in parameters.items():
        if isinstance(spec, dict):
            law = spec.get("law", default_law)
            names.update(f"{name}.{c}" for c in PRESSURE_LAW_COEFFICIENTS.get(law, ()))
            names.add(name)
        elif spec is not None:
            names.add(name)
    return names


_LARGEST_INT = 2**1023
"""Largest integer a datasheet may hold (about 9e307, below the largest float)."""


def _first_nonfinite(value: Any) -> tuple[list[str], float] | None:
    """(keys, number) of the first NaN or infinity in a nested JSON value, or None.

    A list of plain numbers (an influence matrix of runs x coefficients) is checked at once
    with numpy; anything else element by element. The keys come back innermost first.
    """
    if isinstance(value, dict):
        for key, item in value.items():
            found = _first_nonfinite(item)
            if found is not None:
                found[0].append(str(key))
                return found
    elif isinstance(value, list):
        try:
            if np.isfinite(np.asarray(value, dtype=float)).all():
                return None  # every element a finite number (or a nested list of them)
        except (TypeError, ValueError, OverflowError):
            pass  # strings, objects, None or ragged rows: look at each element
        for index, item in enumerate(value):
            found = _first_nonfinite(item)
            if found is not None:
                found[0].append(str(index))
                return found
    elif isinstance(value, int) and not isinstance(value, bool):
        if abs(value) > _LARGEST_INT:  # JSON allows 400 digits; a float does not
            return [], value
    elif isinstance(value, float) and not math.isfinite(value):
        return [], value
    return None


def _physical(sheet):
    """The first physical violation of a datasheet's model, or None.

    F_c >= 0, F_s >= F_c, sigma_2 >= 0 and forces below :data:`MAX_FORCE` over the
    validity pressure range (0-200 bar when the sheet has none).
    """
    from ..friction import params_at_pressure
    from ..friction._checks import roundoff_tolerance

    val = sheet.get("validity") or {}
    p = np.linspace(val.get("pressure_min", 0.0), val.get("pressure_max", 200e5), 41)
    v_max = val.get("velocity_max", 1.0)
    given = {k: v for k, v in sheet["parameters"].items() if v is not None}
    try:
        params = params_at_pressure(p, given, law=sheet["model"]["pressure_law"])
    except (ValueError, TypeError) as exc:
        return f"parameters: {exc}"
    F_c = params.get("F_c")
    if F_c is None:  # the schema allows null for every law; a friction model needs its level
        return "parameters/F_c: null; a datasheet needs at least the Coulomb level F_c"
    F_s = params.get("F_s", F_c)
    sigma_2 = params.get("sigma_2", 0.0 * p)
    span = f"{p[0] / 1e5:.4g}-{p[-1] / 1e5:.4g} bar"
    # rounding of a value fitted onto a bound: the model's own tolerance (it evaluates these)
    tol, tol_2 = roundoff_tolerance(F_c, F_s, sigma_2)
    checks = (
        (np.any(F_c < -tol), "parameters/F_c", f"F_c < 0 N within {span}"),
        (np.any(F_s < F_c - tol), "parameters/F_s", f"F_s < F_c within {span}"),
        (np.any(sigma_2 < -tol_2), "parameters/sigma_2", f"sigma_2 < 0 N*s/m within {span}"),
        (
            np.max(np.maximum(F_s, F_c) + sigma_2 * v_max) > MAX_FORCE,
            "parameters",
            f"friction above {MAX_FORCE:.0e} N within {span}: not a cylinder's friction",
        ),
    )
    for bad, where, what in checks:
        if bad:
            return f"{where}: unphysical: {what}"
    return None


@functools.cache
def _compiled_schema() -> Callable[[Any], Any]:
    """The schema compiled to Python by fastjsonschema (once per process, about 0.1 s)."""
    import fastjsonschema

    return fastjsonschema.compile(SCHEMA)


def _compiled_failures() -> tuple[type[Exception], ...]:
    """What the compiled schema may raise where jsonschema is left to decide: a violation, or
    a schema or value fastjsonschema cannot handle."""
    import fastjsonschema

    return (fastjsonschema.JsonSchemaException, TypeError, ValueError)


def compile_schema() -> None:
    """Compile the datasheet schema now rather than at the first :func:`validate`.

    Once per process: about 0.1 s and some 15 MB of memory while fastjsonschema builds and
    compiles the validator's code (0.6 MB kept). ``cylfric fit`` does it while its pool
    reads the files, so neither falls in the fit's tail (where the second core is mostly
    idle and its forked helpers share this process's pages). A fastjsonschema that cannot
    compile the schema is no error here: :func:`validate` then lets jsonschema decide.
    """
    try:
        _compiled_schema()
    except _compiled_failures():
        pass


def _schema_problem(sheet: Any) -> str | None:
    """``"path: message"`` of the first schema violation of ``sheet``, or None.

    The compiled schema answers quickly for a valid sheet (a 20,000-run datasheet in about
    0.1 s, where jsonschema takes 2 s); when it objects, jsonschema (the reference
    implementation of draft 2020-12) decides and words the message, so a sheet is refused
    only if jsonschema refuses it, with jsonschema's path and expectation (of the first
    error by path; inside a ``oneOf``, of the alternative that came closest:
    :func:`jsonschema.exceptions.best_match`).
    """
    try:
        _compiled_schema()(sheet)
    except _compiled_failures():
        pass  # jsonschema decides and names the problem
    else:
        return None
    import jsonschema
    from jsonschema.exceptions import best_match

    validator = jsonschema.Draft202012Validator(SCHEMA)
    errors = sorted(validator.iter_errors(sheet), key=lambda e: list(e.path))
    if not errors:
        return None
    # of a "oneOf" (a matrix or null, ...) the alternative that came closest: its path and
    # expectation, not the whole value (a 20,000-run influence matrix is megabytes of repr)
    first = best_match(errors[:1])
    where = "/".join(str(p) for p in first.absolute_path) or "(top level)"
    return f"{where}: {first.message}"


def _si_unit(declared: Any, expected: str) -> bool:
    """Whether a declared unit names the SI unit ``expected`` (the same spelling up to
    spaces and ``*``/``·``, or a unit of :mod:`cylfric.units` of the same dimension and
    factor 1: ``"N s/m"`` is ``"N*s/m"``, ``"kN"`` is not ``"N"``)."""
    from ..units import UnitError, _lookup

    if not isinstance(declared, str):
        return False

    def spelled(unit: str) -> str:
        return unit.replace(" ", "").replace("·", "*")

    if spelled(declared) == spelled(expected):
        return True
    try:
        found, wanted = _lookup(declared), _lookup(expected)
    except (KeyError, UnitError):
        return False
    return found[0] == wanted[0] and found[1] == 1.0 == wanted[1]


def _not_si(declared: Any) -> bool:
    """Whether ``declared`` is a unit cylfric knows with a factor to SI other than 1 (an
    engineering unit: kN, bar, mm/s, N/mm)."""
    from ..units import UnitError, _lookup

    if not isinstance(declared, str):
        return True
    try:
        return _lookup(declared)[1] != 1.0
    except (KeyError, UnitError):
        return False


def _unit_problem(sheet: dict) -> str | None:
    """``"path: message"`` of the first declared unit that is not the SI unit the values are
    read in, or None. A datasheet holds SI values (:data:`UNITS`); one that declares
    ``"force": "kN"`` or ``dynamic.sigma_0.unit = "N/mm"`` is refused rather than read
    1000x off."""
    tables = [("units", sheet.get("units"))]
    dynamic_fit = sheet.get("dynamic_fit")
    if isinstance(dynamic_fit, dict):
        tables.append(("dynamic_fit/units", dynamic_fit.get("units")))
    for where, table in tables:
        if table is None:
            continue
        if not isinstance(table, dict):
            return f'{where}: expected an object of SI units, e.g. {{"force": "N"}}'
        for key, declared in table.items():
            expected = UNITS.get(key) or PARAMETER_UNITS.get(key)
            wrong = not _si_unit(declared, expected) if expected else _not_si(declared)
            if wrong:
                shown = f"the SI unit {expected!r}" if expected else "an SI unit"
                return (
                    f"{where}/{key}: {declared!r} is not {shown}; cylfric reads a datasheet's "
                    "values in SI (N, Pa, m/s, N/m, N*s/m) and does not convert them: "
                    "convert the values to SI and declare the SI unit"
                )
    for name, entry in (sheet.get("dynamic") or {}).items():
        expected = PARAMETER_UNITS.get(name)
        if isinstance(entry, dict) and expected and not _si_unit(entry.get("unit"), expected):
            return (
                f"dynamic/{name}/unit: {entry.get('unit')!r} is not the SI unit {expected!r}; "
                f"cylfric reads {name} in {expected} and does not convert it: convert the "
                "value to SI and declare the SI unit"
            )
    return None


def validate(sheet: dict, *, source: str = "datasheet") -> dict:
    """Raise :class:`DatasheetError` naming the first problem; return ``sheet``.

    Checks the schema, that every number is finite (no NaN, no infinity), and the physics
    of the model over its validity range (F_c >= 0, F_s >= F_c, sigma_2 >= 0, forces below
    1e8 N).
    """
    try:
        problem = _schema_problem(sheet)
    except RecursionError:
        problem = "(top level): arrays or objects nested too deeply to read"
    if problem:
        raise DatasheetError(f"{source}: {problem}")
    problem = _unit_problem(sheet)
    if problem:
        raise DatasheetError(f"{source}: {problem}")
    found = _first_nonfinite(sheet)
    if found is not None:
        keys, number = found
        where = "/".join(reversed(keys))
        shown: object = number
        if isinstance(number, int):
            shown = f"an integer of {len(str(abs(number)))} digits"
        raise DatasheetError(
            f"{source}: {where}: {shown} is not finite; expected a finite number "
            f"(at most {float(_LARGEST_INT):.3g} in magnitude)"
        )
    val = sheet.get("validity")
    if val:
        for quantity, unit, scale in (("pressure", "bar", 1e5), ("velocity", "mm/s", 1e-3)):
            low, high = val[f"{quantity}_min"], val[f"{quantity}_max"]
            if low > high or low < 0:
                raise DatasheetError(
                    f"{source}: validity/{quantity}_min: {low / scale:.6g}-{high / scale:.6g} "
                    f"{unit} is not a range; expected 0 <= {quantity}_min <= {quantity}_max"
                )
    problem = _physical(sheet)
    if problem:
        raise DatasheetError(f"{source}: {problem}")
    return sheet


def read_datasheet(path: StrPath) -> dict[str, Any]:
    """Read and validate a datasheet JSON file (errors name the file)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise DatasheetError(f"{path}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise DatasheetError(f"{path}: not UTF-8 text ({exc})") from None
    return validate(load_json(text, str(path), DatasheetError), source=str(path))


def load_json(text: str, source: str, error: type[ValueError] = ValueError) -> Any:
    """JSON text parsed, or ``error`` naming ``source``: invalid JSON, arrays or objects
    nested too deeply for the parser (100,000 levels), or a number with more digits than
    Python converts (``int_max_str_digits``)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{source}: not valid JSON ({exc})") from None
    except RecursionError:
        raise error(
            f"{source}: not a datasheet: arrays or objects nested too deeply to read"
        ) from None
    except ValueError as exc:  # 'Exceeds the limit (4300 digits) for integer string ...'
        raise error(f"{source}: not valid JSON here ({exc})") from None
