"""The friction datasheet: the JSON form (SI) of a :class:`~cylfric.model.FrictionModel`.

:func:`build_datasheet` turns an identification into a datasheet dict (its model plus the
campaign's record: per-pressure table, offset, law comparison, notes, source files);
:func:`write_datasheet` validates and writes it atomically; :func:`read_datasheet` reads and
validates; :func:`evaluate` uses a datasheet as a friction law. Schema and validation live
with the model (:mod:`cylfric.model.serialize`, ``datasheet.schema.json``).
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from ._atomic import atomic_write_chunks
from ._runtable import run_column
from ._version import __version__
from .io.campaign import file_sha256
from .model import SCHEMA, SCHEMA_ID, DatasheetError, FrictionModel, read_datasheet, validate
from .model.serialize import clean

if TYPE_CHECKING:
    from collections.abc import Iterator, Mapping, Sequence

    import numpy as np
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.identify.steady import Identification
    from cylfric.steady_state import Extraction

__all__ = [
    "DatasheetError",
    "SCHEMA",
    "build_datasheet",
    "datasheet_model",
    "write_datasheet",
    "read_datasheet",
    "validate",
    "evaluate",
    "file_digest",
    "SCHEMA_ID",
]

_PARAM_UNITS = {"F_c": "N", "F_s": "N", "sigma_2": "N*s/m", "v_r": "m/s", "alpha": "-"}


file_digest = file_sha256
"""SHA-256 of a file's bytes (hex): :func:`cylfric.io.campaign.file_sha256`, which finds a
campaign's duplicate files with the same digest."""


def build_datasheet(
    identification: Identification,
    *,
    extraction: Extraction | None = None,
    files: Sequence[StrPath] | None = None,
    campaign: str | None = None,
    name: str | None = None,
    pressure_reference: str | None = None,
    pressure_reference_basis: Mapping[str, Any] | None = None,
    recipe: str | None = None,
) -> dict[str, Any]:
    """Datasheet dict from an :class:`~cylfric.identify.Identification`.

    The datasheet of :func:`datasheet_model` (same parameters).
    """
    return datasheet_model(
        identification,
        extraction=extraction,
        files=files,
        campaign=campaign,
        name=name,
        pressure_reference=pressure_reference,
        pressure_reference_basis=pressure_reference_basis,
        recipe=recipe,
    ).to_datasheet()


def datasheet_model(
    identification: Identification,
    *,
    extraction: Extraction | None = None,
    files: Sequence[StrPath] | None = None,
    campaign: str | None = None,
    name: str | None = None,
    pressure_reference: str | None = None,
    pressure_reference_basis: Mapping[str, Any] | None = None,
    recipe: str | None = None,
    cylinder: Mapping[str, Any] | None = None,
) -> FrictionModel:
    """The identified model with the campaign's record: what the datasheet holds.

    ``datasheet_model(...).to_datasheet()`` is :func:`build_datasheet`; the model itself
    goes to the exports without a detour through the dict.

    Parameters
    ----------
    identification : Identification
        The identified model and the campaign's tables.
    extraction : Extraction, optional
        Supplies the offset [N] and its spread, and the source files.
    files : list of path, optional
        Source files to hash (default: the files of ``extraction``).
    campaign : str, optional
        Campaign folder, recorded in ``fit.source``.
    name : str, optional
        A name for the cylinder or campaign.
    pressure_reference : str, optional
        Which chamber pressure the laws see (default: the model's rule, ``"mean"``).
    pressure_reference_basis : mapping, optional
        Why (``kind``, ``rule``, ``chamber``, ``stated_by``;
        :func:`cylfric.friction.pressure.pressure_reference_basis`); its ``rule`` is the
        reference when ``pressure_reference`` is not given. Default: the model's.
    cylinder : mapping, optional
        The cylinder as campaign.toml states it (``kind``, ``bore`` [m], ``rod`` [m]) and
        its chamber areas (``area_a``, ``area_b`` [m^2]): the datasheet's ``cylinder``.
    """
    ident = identification
    model = ident.model
    digests = {}
    if files is None and extraction is not None:
        files = run_column(extraction.runs, "file")
        # the reader hashed the bytes it read (io.text); other files are hashed here
        hashed = zip(files, run_column(extraction.runs, "sha256"), strict=True)
        digests = {file: digest for file, digest in hashed if digest}
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
    from datetime import UTC, datetime

    fit_record: dict[str, Any] = {
        "law_comparison": ident.comparison.to_dict("records"),
        "sensitivity": {"recommended": ident.recommended},
    }
    if getattr(ident, "confounding", None) is not None:  # pressure tied to direction/speed
        fit_record["confounding"] = ident.confounding
    record = {
        "schema": SCHEMA_ID,
        "cylfric_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "name": name or (Path(campaign).name if campaign else "cylinder"),
        "offset": extraction.offset if extraction is not None else None,
        "offset_std": extraction.offset_std if extraction is not None else None,
        "per_pressure": per_pressure,
        "notes": list(ident.notes),
        "fit": fit_record,
    }
    if cylinder is not None:
        record["cylinder"] = dict(cylinder)
    earlier = dict(model.record)  # what the identification recorded: scatter, lack of fit
    if "scatter" in earlier.get("fit", {}):
        fit_record = cast("dict[str, Any]", record["fit"])
        fit_record["scatter"] = earlier["fit"]["scatter"]
    if "quality" in earlier:
        record["quality"] = earlier["quality"]
    source = {
        "campaign": str(campaign or ""),
        "files": [
            {"name": Path(f).name, "sha256": digests.get(f) or file_digest(f)} for f in files
        ],
    }
    if recipe is not None:  # a campaign.toml from outside the folder (--config)
        source["recipe"] = str(recipe)
    changes = {
        "record": clean(record),
        "provenance": {**model.provenance, "source": source},
    }
    if pressure_reference_basis is not None:
        changes["pressure_reference_basis"] = dict(pressure_reference_basis)
        changes["reference"] = pressure_reference or pressure_reference_basis["rule"]
    elif pressure_reference is not None:
        changes["reference"] = pressure_reference
    return model.replace(**changes)


def write_datasheet(path: StrPath, sheet: dict[str, Any]) -> Path:
    """Validate ``sheet`` and write it as JSON, atomically."""
    validate(sheet, source=str(path))
    # json.dumps with indent encodes in Python and joins every piece at once (some 30 MB of
    # small strings at 20,000 runs): the same pieces streamed to the file instead
    pieces = json.JSONEncoder(indent=2, allow_nan=False).iterencode(sheet)
    return atomic_write_chunks(path, _batched(itertools.chain(pieces, ["\n"])))


def _batched(pieces: Iterator[str], size: int = 1 << 14) -> Iterator[bytes]:
    """Text pieces joined ``size`` at a time, as UTF-8."""
    while batch := list(itertools.islice(pieces, size)):
        yield "".join(batch).encode()


def evaluate(
    sheet: Mapping[str, Any], velocity: ArrayLike, pressure: ArrayLike, *, strict: bool = False
) -> np.ndarray | float:
    """Friction force [N] of a datasheet at ``velocity`` [m/s] and operating ``pressure`` [Pa].

    The datasheet's model (:meth:`FrictionModel.from_datasheet`) evaluated; warns outside the
    validity ranges (raises with ``strict=True``).
    """
    return FrictionModel.from_datasheet(sheet).friction(velocity, pressure, strict=strict)
