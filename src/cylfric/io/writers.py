"""Writers of bench files: the MTS-export-like text dialect and ``manifest.csv``.

All writes are atomic: the text goes to a temporary file in the target folder, which is then
renamed over the target, so a reader never sees half a file.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._atomic import atomic_write_bytes, atomic_write_text

if TYPE_CHECKING:
    from .._typing import StrPath

__all__ = ["atomic_write_bytes", "atomic_write_text", "write_mts_text", "write_manifest"]


def _block(columns: dict, decimals: dict) -> bytes:
    """Tab-separated numeric rows via pyarrow (fast), values rounded to ``decimals``."""
    import pyarrow as pa  # here: reading a campaign (which imports this module) needs no pyarrow
    import pyarrow.csv as pacsv

    arrays = [pa.array(np.round(values, decimals[name])) for name, values in columns.items()]
    table = pa.table(arrays, names=list(columns))
    sink = io.BytesIO()
    pacsv.write_csv(table, sink, pacsv.WriteOptions(include_header=False, delimiter="\t"))
    return sink.getvalue()


def write_mts_text(
    path: StrPath,
    segments: list[dict],
    *,
    header: dict,
    units: dict,
    decimals: dict,
    decimal_comma: bool = False,
    newline: str = "\n",
) -> Path:
    """Write one run in the testing-machine export dialect.

    Layout: a first line ``MTS793|MPT|...``, ``key: value`` header lines, then for each
    segment a status line ``Segment N started``, the column-name row, the units row and
    tab-separated numbers; a final ``Test run ended``.

    Parameters
    ----------
    path : path-like
        Target file.
    segments : list of dict
        One dict per segment: column name -> values (already in the file units).
    header : dict
        ``key: value`` lines (e.g. ``{"Pressure": "55 bar"}``).
    units : dict
        Column name -> unit text for the units row.
    decimals : dict
        Column name -> decimals written.
    decimal_comma : bool
        Write ``0,0172`` instead of ``0.0172``.
    newline : str
        ``"\\n"`` or ``"\\r\\n"``.
    """
    names = list(units)
    lines = ["MTS793|MPT|ENU|1|2|.|/|:|1|0|0|A"]
    lines += [f"{key}: {value}" for key, value in header.items()]
    lines.append("")
    out = io.BytesIO()
    out.write((newline.join(lines) + newline).encode())
    for number, segment in enumerate(segments, start=1):
        head = [f"Segment {number} started", "\t".join(names), "\t".join(units[n] for n in names)]
        out.write((newline.join(head) + newline).encode())
        body = _block({n: segment[n] for n in names}, decimals)
        if decimal_comma:
            body = body.replace(b".", b",")
        if newline != "\n":
            body = body.replace(b"\n", newline.encode())
        out.write(body)
    out.write(f"Test run ended{newline}".encode())
    return atomic_write_bytes(path, out.getvalue())


def write_manifest(path: StrPath, rows: list[tuple[str, float, float]]) -> Path:
    """Write ``manifest.csv`` with columns ``file,pressure_bar,velocity_mm_s``."""
    text = "file,pressure_bar,velocity_mm_s\n" + "".join(
        f"{name},{p:g},{v:g}\n" for name, p, v in rows
    )
    return atomic_write_text(path, text)
