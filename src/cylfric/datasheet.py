"""The friction datasheet: a JSON file (SI) that other tools read, with its JSON Schema.

:func:`build_datasheet` turns an identification into a datasheet dict; :func:`write_datasheet`
validates and writes it atomically; :func:`read_datasheet` reads and validates;
:func:`evaluate` uses a datasheet as a friction law. The schema ships with the package
(``datasheet.schema.json``).
"""

from __future__ import annotations

import hashlib
import json
import math
from datetime import UTC, datetime
from importlib import resources
from pathlib import Path

import jsonschema
import numpy as np

from . import __version__
from .friction import params_at_pressure, stribeck
from .io.writers import atomic_write_text

__all__ = [
    "DatasheetError",
    "SCHEMA",
    "build_datasheet",
    "write_datasheet",
    "read_datasheet",
    "validate",
    "evaluate",
    "file_digest",
    "SCHEMA_ID",
]

SCHEMA_ID = "cylfric-datasheet/1"
SCHEMA = json.loads(resources.files("cylfric").joinpath("datasheet.schema.json").read_text())
"""The JSON Schema of a datasheet (draft 2020-12)."""

_PARAM_UNITS = {"F_c": "N", "F_s": "N", "sigma_2": "N*s/m", "v_r": "m/s", "alpha": "-"}


class DatasheetError(ValueError):
    """A datasheet does not follow the schema; the message names the file and the key."""


def _clean(value):
    """JSON-safe: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def file_digest(path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def build_datasheet(
    identification,
    *,
    extraction=None,
    files=None,
    campaign=None,
    name=None,
    pressure_reference="mean",
) -> dict:
    """Datasheet dict from an :class:`~cylfric.identify.Identification`.

    Parameters
    ----------
    identification : Identification
        The identified model.
    extraction : Extraction, optional
        Supplies the offset [N] and its spread, and the source files.
    files : list of path, optional
        Source files to hash (default: the files of ``extraction``).
    campaign : str, optional
        Campaign folder, recorded in ``fit.source``.
    name : str, optional
        A name for the cylinder or campaign.
    pressure_reference : str
        Which chamber pressure the laws see (the thesis rig: ``"mean"`` of equal pressures).
    """
    ident = identification
    surface = ident.surface
    if files is None and extraction is not None:
        files = [r["file"] for r in extraction.runs]
    files = files or []
    per_pressure = []
    for _, row in ident.per_pressure.iterrows():
        item = {
            "pressure": row["pressure [Pa]"],
            "n_points": int(row["n_points [-]"]),
            "rmse": row["rmse [N]"],
            "stribeck_velocity": row["stribeck_velocity [m/s]"],
        }
        for par, unit in _PARAM_UNITS.items():
            item[par] = row.get(f"{par} [{unit}]", math.nan)
            item[f"{par}_stderr"] = row.get(f"{par}_stderr [{unit}]", math.nan)
        per_pressure.append(item)
    pts = ident.points
    speed = pts["velocity [m/s]"].abs()
    sheet = {
        "schema": SCHEMA_ID,
        "cylfric_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "name": name or (Path(campaign).name if campaign else "cylinder"),
        "units": {
            "force": "N",
            "pressure": "Pa",
            "velocity": "m/s",
            "sigma_2": "N*s/m",
            "slope": "unit per Pa",
            "curvature": "unit per Pa^2",
            "rate": "1/Pa",
        },
        "model": {
            "friction_law": "stribeck",
            "equation": "F = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha) + sigma_2 |v| "
            "(thesis eq. 2.7), times sign(v)",
            "pressure_law": surface.law,
            "pressure_reference": pressure_reference,
            "stribeck_identifiable": bool(ident.stribeck_identifiable),
        },
        "parameters": surface.coefficients,
        "stderr": surface.stderr,
        "offset": extraction.offset if extraction is not None else None,
        "offset_std": extraction.offset_std if extraction is not None else None,
        "per_pressure": per_pressure,
        "validity": {
            "pressure_min": float(pts["pressure [Pa]"].min()),
            "pressure_max": float(pts["pressure [Pa]"].max()),
            "velocity_min": float(speed.min()),
            "velocity_max": float(speed.max()),
        },
        "fit": {
            "method": (
                f"global surface fit, bounded soft-L1 least squares ({surface.law} pressure laws)"
                if ident.stribeck_identifiable
                else "friction level versus pressure (Stribeck shape not identifiable)"
            ),
            "rmse": surface.rmse,
            "n_points": surface.n_points,
            "fixed": ident.fixed,
            "law_comparison": ident.comparison.to_dict("records"),
            "sensitivity": {"recommended": ident.recommended},
            "source": {
                "campaign": str(campaign or ""),
                "files": [{"name": Path(f).name, "sha256": file_digest(f)} for f in files],
            },
        },
        "notes": list(ident.notes),
    }
    return _clean(sheet)


def validate(sheet: dict, *, source="datasheet") -> dict:
    """Raise :class:`DatasheetError` naming the first schema violation; return ``sheet``."""
    validator = jsonschema.Draft202012Validator(SCHEMA)
    errors = sorted(validator.iter_errors(sheet), key=lambda e: list(e.path))
    if errors:
        first = errors[0]
        where = "/".join(str(p) for p in first.path) or "(top level)"
        raise DatasheetError(f"{source}: {where}: {first.message}")
    return sheet


def write_datasheet(path, sheet: dict) -> Path:
    """Validate ``sheet`` and write it as JSON, atomically."""
    validate(sheet, source=str(path))
    return atomic_write_text(path, json.dumps(sheet, indent=2, allow_nan=False) + "\n")


def read_datasheet(path) -> dict:
    """Read and validate a datasheet JSON file."""
    path = Path(path)
    try:
        sheet = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise DatasheetError(f"{path}: cannot read ({exc.strerror})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DatasheetError(f"{path}: not valid JSON ({exc})") from None
    return validate(sheet, source=str(path))


def evaluate(sheet: dict, velocity, pressure):
    """Friction force [N] of a datasheet at ``velocity`` [m/s] and ``pressure`` [Pa]."""
    params = params_at_pressure(pressure, sheet["parameters"], law=sheet["model"]["pressure_law"])
    return stribeck(velocity, **params)
