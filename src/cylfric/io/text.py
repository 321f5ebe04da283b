"""Reader of test-bench text files: testing-machine exports and plain delimited files.

One reader covers the family the thesis met ("text files mixed with string characters"):
a free-text / ``key: value`` preamble (``MTS793|MPT|...``, ``Pressure: 55 bar``); a header row
with units in the cell (``Force [kN]``, ``Force (N)``) or on the next row (``Sec  mm  kN``);
tab, semicolon, comma or whitespace separators; decimal point or comma; repeated header
blocks, status lines and blank lines between segments; CRLF or LF; UTF-8 or latin-1.
Headerless files take their column names and units from the caller (``campaign.toml``).

Speed: a compiled byte-level scanner (:mod:`cylfric.io._scan`) classifies the lines and
parses every numeric block in one pass each; only the few text lines are looked at in
Python.
"""

from __future__ import annotations

import codecs
import hashlib
import re
from collections import Counter
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..units import UnitError, to_si, unit_dimension

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import pandas as pd
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath

__all__ = [
    "BenchFileError",
    "COLUMN_KEYWORDS",
    "QUANTITY_DIMENSIONS",
    "read_bench_text",
    "read_bench_arrays",
    "read_mts_text",
    "read_delimited",
    "canonical_name",
]


_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def escape_control(text: str) -> str:
    """``text`` with control characters written as escapes (``\\x00``, ``\\t``): a message
    must stay one readable line whatever bytes a file holds."""
    named = {"\t": "\\t", "\n": "\\n", "\r": "\\r"}
    return _CONTROL.sub(lambda m: named.get(m.group(), f"\\x{ord(m.group()):02x}"), text)


class BenchFileError(ValueError):
    """A bench file cannot be read; the message names the file, the line and what was expected."""

    def __init__(self, path: StrPath, message: str, line: int | None = None) -> None:
        self.path = str(path)
        self.line = line
        self.message = message
        where = f"{self.path}" + (f", line {line}" if line is not None else "")
        super().__init__(escape_control(f"{where}: {message}"))

    def __reduce__(
        self,
    ) -> tuple[
        type[BenchFileError], tuple[str, str, int | None]
    ]:  # pickled whole (extraction sends errors between processes)
        return (type(self), (self.path, self.message, self.line))


# Canonical quantity -> keywords found in column names (English, German, Swedish).
COLUMN_KEYWORDS: dict[str, tuple[str, ...]] = {
    "time": ("time", "zeit", "tid", "sec"),
    "position": ("displacement", "position", "weg", "stroke", "läge", "lage", "extension"),
    "force": ("force", "load", "kraft", "last"),
    "pressure_a": ("pressure a", "pressure_a", "p_a", "pressure 1", "p1", "druck a", "tryck a"),
    "pressure_b": ("pressure b", "pressure_b", "p_b", "pressure 2", "p2", "druck b", "tryck b"),
    "pressure": ("pressure", "druck", "tryck"),
    "velocity": ("velocity", "speed", "geschwindigkeit", "hastighet"),
    "temperature": ("temperature", "temp"),
}

QUANTITY_DIMENSIONS = {
    "time": "time",
    "position": "length",
    "force": "force",
    "pressure": "pressure",
    "pressure_a": "pressure",
    "pressure_b": "pressure",
    "velocity": "velocity",
}
SI_UNITS = {"time": "s", "length": "m", "force": "N", "pressure": "Pa", "velocity": "m/s"}

_DEMAND_WORDS = (
    "setpoint",
    "set point",
    "command",
    "cmd",
    "target",
    "demand",
    "reference",
    "soll",
    "börvärde",
    "borvarde",
    "desired",
)
"""Words of a column that holds a demanded value, never the measured quantity."""

_CELL_UNIT = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")
_KEY_VALUE = re.compile(r"^\s*([A-Za-zÀ-ÿ][^:=|]{0,60}?)\s*[:=]\s*(.*?)\s*$")
_MAX_TEXT_LINES = 5000


@lru_cache(maxsize=1024)
def canonical_name(name: str) -> str | None:
    """Map a column name such as ``Axial Force`` or ``Zeit`` to a canonical quantity.

    Memoised per name (every run file of a campaign repeats the same few columns)."""
    low = " ".join(name.lower().replace("_", " ").replace("-", " ").split())
    if any(word in low.split() for word in ("raw", "volt", "voltage", "signal")):
        return None  # raw sensor channels are kept as read, never taken for a quantity
    if any(word in low for word in _DEMAND_WORDS):
        return None  # what was asked for, not what was measured
    if low in {"t", "s", "sec"}:
        return "time"
    if low in {"x", "pos"}:
        return "position"
    if low in {"f", "fl"}:
        return "force"
    if low in {"p", "pa", "pb"}:
        return {"p": "pressure", "pa": "pressure_a", "pb": "pressure_b"}[low]
    if low in {"v", "vel"}:
        return "velocity"
    for quantity, words in COLUMN_KEYWORDS.items():
        if any(word in low for word in words):
            return quantity
    return None


def _is_unit(token: str) -> bool:
    try:
        unit_dimension(token)
    except UnitError as exc:  # an ambiguous prefix is still a unit (and an error later)
        return "ambiguous" in str(exc)
    return True


@dataclass
class _Header:
    names: list
    units: list
    line: int
    rows: tuple = ()  # 1-based numbers of the names (and units) rows in the file


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return [cell.strip() for cell in line.split(delimiter)]


def _detect_delimiter(sample: str) -> str | None:
    """Delimiter of a data line: tab, semicolon, whitespace (None) or comma."""
    if "\t" in sample:
        return "\t"
    if ";" in sample:
        return ";"
    if " " in sample.strip():
        return None
    if "," in sample:
        return ","
    return None


def _decode(raw: bytes, path, encoding=None, line=None) -> str:
    """Text of a preamble/header line: ``encoding`` if given, else UTF-8, else latin-1."""
    if encoding is not None:
        try:
            return raw.decode(encoding)
        except UnicodeDecodeError as exc:
            raise BenchFileError(
                path,
                f"not valid {encoding} text ({exc.reason}); expected "
                "the encoding given, or none for UTF-8/latin-1",
                line=line,
            ) from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def read_bench_text(
    path: StrPath,
    *,
    columns: Sequence[str] | None = None,
    units: Sequence[str] | None = None,
    delimiter: str = "auto",
    decimal: str = "auto",
    encoding: str | None = None,
    roles: Mapping[str, str] | None = None,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a bench text file into a DataFrame in SI; see :func:`read_bench_arrays`.

    Returns ``(data, metadata)`` with ``data`` a pandas DataFrame whose column names carry
    their units (``"time [s]"``, ``"position [m]"``, ``"force [N]"``, ``"pressure_a [Pa]"``,
    ``"segment [-]"``).
    """
    arrays, metadata = read_bench_arrays(
        path,
        columns=columns,
        units=units,
        delimiter=delimiter,
        decimal=decimal,
        encoding=encoding,
        roles=roles,
    )
    import pandas as pd  # here, not at the top: the reader runs without pandas

    return pd.DataFrame(arrays, copy=False), metadata


def read_bench_arrays(
    path: StrPath,
    *,
    columns: Sequence[str] | None = None,
    units: Sequence[str] | None = None,
    delimiter: str = "auto",
    decimal: str = "auto",
    encoding: str | None = None,
    roles: Mapping[str, Any] | None = None,
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read a bench text file into SI arrays.

    Parameters
    ----------
    path : path-like
        The file (never modified).
    columns : list of str, optional
        Column names for a headerless file (``campaign.toml``); overrides a header row.
    units : list of str, optional
        Units of ``columns`` (e.g. ``["ms", "mm", "N"]``).
    delimiter : {"auto", "tab", "semicolon", "comma", "whitespace"}
        Column separator.
    decimal : {"auto", ".", ","}
        Decimal separator.
    encoding : str, optional
        Text encoding of the preamble (default: UTF-8, falling back to latin-1).
    roles : dict, optional
        Quantity -> column name (``{"force": "Axial Force"}``, campaign.toml ``[columns]``):
        that column is the quantity, other candidates are kept as read (a name that two
        columns share is told apart by its place: ``"Axial Force#2"``). Without it, two
        measured candidates for one quantity are an error listing them; setpoint, command,
        target or demand columns are never taken for a measured quantity.

    Returns
    -------
    data : dict of ndarray
        One column per recognised quantity, in SI with the unit in the name
        (``"time [s]"``, ``"position [m]"``, ``"force [N]"``, ``"pressure_a [Pa]"`` ...),
        other columns as read (``"name [unit]"``), and ``"segment [-]"`` (0, 1, ...: the
        blocks of data between header or status lines).
    metadata : dict
        ``file``, ``header`` (``key: value`` lines), ``columns`` (original names),
        ``units`` (original units), ``delimiter``, ``decimal``, ``events`` (status lines
        with line numbers), ``rows``, ``segments`` and ``sha256`` (of the bytes read, for the
        datasheet's provenance: hashed here, on the core that reads the file).

    Raises
    ------
    BenchFileError
        Empty, binary, truncated or corrupt files, unknown units, missing columns; the
        message names the file, the line when known, and what was expected.
    """
    path = path if isinstance(path, Path) else Path(path)
    if encoding is not None:
        try:
            codecs.lookup(encoding)
        except LookupError:
            raise ValueError(
                f"unknown encoding {encoding!r}; expected a Python codec name "
                "such as 'utf-8' or 'latin-1'"
            ) from None
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise BenchFileError(path, f"cannot read the file ({exc.strerror})") from None
    if not raw or raw.isspace():
        raise BenchFileError(path, "the file is empty; expected a bench record")
    nul = raw.find(b"\x00")
    if nul >= 0:
        line = raw.count(b"\n", 0, nul) + 1  # on line 1: a binary or UTF-16 file, no line
        raise BenchFileError(
            path,
            "binary content (NUL bytes); expected a text export "
            "(UTF-8 or latin-1), not UTF-16 or a binary file"
            + ("" if nul < 65536 else " (a corrupt stretch in an otherwise text file?)"),
            line=line if line > 1 else None,
        )
    # the compiled scanner (numba) loads with the first file read, in the process that reads
    # it: cylfric fit forks its extraction child before numba is imported
    from ._scan import NUMERIC, TEXT, parse_block, scan_lines

    sha256 = hashlib.sha256(raw).hexdigest()
    buf = np.frombuffer(raw, dtype=np.uint8)
    starts, ends, kinds = scan_lines(buf)
    text_idx = np.flatnonzero(kinds == TEXT)
    data_idx: np.ndarray = np.flatnonzero(kinds == NUMERIC)
    del kinds
    if buf.size < 2**31:  # line offsets and indices in 32 bits: half the index of a big file
        starts, ends, data_idx = (a.astype(np.int32) for a in (starts, ends, data_idx))
    if text_idx.size > _MAX_TEXT_LINES and text_idx.size > data_idx.size:
        raise BenchFileError(
            path,
            f"{text_idx.size} of {text_idx.size + data_idx.size} lines are not numeric; "
            "expected a numeric table (is this a bench file?)",
        )
    if data_idx.size == 0:
        raise BenchFileError(
            path, "no numeric data rows; expected rows of numbers after the header"
        )

    if data_idx[-1] == starts.size - 1 and not raw.endswith(b"\n"):
        raise BenchFileError(
            path,
            "the last data row has no line end: the file looks truncated "
            "(a row cut mid-number would read as a wrong value); "
            "expected every row to end with a newline",
            line=int(data_idx[-1]) + 1,
        )

    def line_text(i):
        return _decode(raw[starts[i] : ends[i]], path, encoding, int(i) + 1).rstrip("\r")

    # Data runs: consecutive data lines, blank lines allowed inside, broken by text lines.
    breaks = np.searchsorted(data_idx, text_idx)
    cut = sorted(set(breaks[(breaks > 0) & (breaks < data_idx.size)].tolist()))
    bounds = [0, *cut, data_idx.size]
    runs = [data_idx[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]

    sample = line_text(data_idx[0])
    delim = {
        "auto": _detect_delimiter(sample),
        "tab": "\t",
        "semicolon": ";",
        "comma": ",",
        "whitespace": None,
    }.get(delimiter, "?")
    if delim == "?":
        raise ValueError(
            f"unknown delimiter {delimiter!r}; valid: auto, tab, semicolon, comma, whitespace"
        )
    # MTS 793 / TestSuite exports begin every data row with a separator (an empty first
    # cell): read such rows from the byte after it
    if delim is not None and sample.startswith(delim):
        firsts = buf[starts[data_idx]]
        if not np.all(firsts == ord(delim)):
            bad = int(data_idx[np.flatnonzero(firsts != ord(delim))[0]])
            raise BenchFileError(
                path,
                "some data rows begin with a separator (an empty first cell) and others "
                "do not; expected one layout in the whole file",
                line=bad + 1,
            )
        starts = starts.copy()
        starts[data_idx] += 1
    if decimal == "auto":
        first = data_idx[:50]
        probe = b"".join(
            raw[a:b] for a, b in zip(starts[first].tolist(), ends[first].tolist(), strict=True)
        )
        decimal = "," if delim != "," and b"," in probe else "."
    if decimal not in (".", ","):
        raise ValueError(f"unknown decimal separator {decimal!r}; valid: '.', ','")

    header_meta: dict[str, str] = {}
    events: list[tuple[int, str]] = []
    text_lines = {int(i): line_text(i) for i in text_idx}
    for i, text in text_lines.items():
        match = _KEY_VALUE.match(text)
        if match and match.group(2) and not text.startswith("MTS"):
            header_meta.setdefault(match.group(1).strip(), match.group(2))
        elif text.strip() and i != (text_idx[0] if text_idx.size else -1):
            events.append((i + 1, text.strip()))

    explicit = None
    if columns is not None:
        if units is None or len(units) != len(columns):
            raise ValueError("give one unit per column in `units` (same length as `columns`)")
        explicit = _Header(list(columns), list(units), 0)

    blocks: list[tuple[int | np.ndarray, np.ndarray, _Header]] = []
    header = explicit
    for seg, run in enumerate(runs):
        previous = text_idx[: np.searchsorted(text_idx, run[0])][-3:].tolist()
        if explicit is None:
            ncols = len(_split(line_text(run[0]), delim))
            found = _header_before(previous, text_lines, delim, ncols)
            header = found or header
        if header is None:
            raise BenchFileError(
                path,
                "no header row with column names before the data; "
                "expected e.g. 'Time  Displacement  Force' or a column "
                "map in campaign.toml",
                line=int(run[0]) + 1,
            )
        blocks.append((seg, run, header))
    header_rows = {row for _, _, hdr in blocks for row in hdr.rows}
    events = [(number, text) for number, text in events if number not in header_rows]

    segments = len(blocks)
    first_header = blocks[0][2]
    if segments > 1 and all(
        hdr.names == first_header.names and hdr.units == first_header.units for _, _, hdr in blocks
    ):
        # one layout in every block (a header repeated per segment): all the data rows
        # parsed at once, with their segment numbers (the same values, nothing joined)
        counts = [len(run) for _, run, _ in blocks]
        segment = np.repeat(np.arange(segments, dtype=np.int32), counts)
        blocks = [(segment, data_idx, first_header)]

    frames = []
    sep = 0 if delim is None else ord(delim)
    for number, run, hdr in blocks:
        values, bad, code, field = parse_block(
            buf, starts, ends, run, len(hdr.names), sep, ord(decimal)
        )
        if bad >= 0:
            text = line_text(bad)[:60]
            if code == 1:
                message = (
                    f"expected {len(hdr.names)} numeric columns, found {field} ({text!r}); "
                    "truncated or corrupt row"
                )
            else:
                cells = _split(text, delim)
                cell = cells[field] if field < len(cells) else ""
                message = (
                    f"expected a number in column {field + 1}, found {cell[:30]!r} "
                    f"(decimal separator {decimal!r})"
                )
            raise BenchFileError(path, message, line=int(bad) + 1)
        frames.append((number, hdr, values, int(run[0]) + 1))

    names = first_header.names
    # the bytes and the line index are done with: let them go before the columns are
    # assembled (peak memory about the file plus its numbers, not twice that)
    # (None only to release them: none is read again, so no Optional in their types)
    raw = buf = starts = ends = data_idx = text_idx = runs = run = blocks = None  # type: ignore[assignment]
    data, col_units = _assemble(frames, path, roles or {}, own=True)
    metadata = {
        "file": str(path),
        "header": header_meta,
        "columns": names,
        "units": col_units,
        "delimiter": cast("dict[str | None, str]", {None: "whitespace"}).get(delim, delim),
        "decimal": decimal,
        "events": events,
        "rows": int(len(data["segment [-]"])),
        "segments": segments,
        "sha256": sha256,
    }
    return data, metadata


def data_row_line(path: StrPath, row: int) -> int | None:
    """1-based line of the file holding data row ``row`` (0-based, over all segments).

    The rows of :func:`read_bench_arrays` are the file's numeric lines in order; this maps a
    sample index back to its line for an error message (None when out of range).
    """
    from ._scan import NUMERIC, scan_lines

    raw = Path(path).read_bytes()
    _, _, kinds = scan_lines(np.frombuffer(raw, dtype=np.uint8))
    numeric = np.flatnonzero(kinds == NUMERIC)
    return int(numeric[row]) + 1 if 0 <= row < numeric.size else None


def _split_header(line: str, delim, ncols: int) -> list[str]:
    """Cells of a header row; whitespace rows may hold names with spaces or ``[unit]``."""
    cells = _split(line, delim)
    if delim is not None and len(cells) == ncols + 1 and cells[0] == "":
        return cells[1:]  # MTS/TestSuite: the names and units rows begin with a separator too
    if delim is not None or len(cells) == ncols:
        return cells
    wide = [c for c in re.split(r"\s{2,}|\t", line.strip()) if c]
    if len(wide) == ncols:
        return wide
    merged: list[str] = []
    for token in cells:
        if merged and re.fullmatch(r"[\[(].*[\])]", token):
            merged[-1] = f"{merged[-1]} {token}"
        else:
            merged.append(token)
    return merged


def _header_before(previous, text_lines, delim, ncols):
    """Names (and units) row among the text lines just before a data block, or None.

    A candidate counts only if it has as many cells as the block has columns, so a status
    line such as ``*** Interlock 1 ***`` is never taken for a header.
    """
    if not previous:
        return None
    last = text_lines[previous[-1]]
    cells = _split_header(last, delim, ncols)
    if len(cells) != ncols:
        return None
    if all(_is_unit(c) for c in cells if c) and len(previous) >= 2:
        names_line = previous[-2]
        names = _split_header(text_lines[names_line], delim, ncols)
        if len(names) == len(cells):
            return _Header(names, cells, names_line + 1, (names_line + 1, previous[-1] + 1))
    if len(cells) >= 2 and not _KEY_VALUE.match(last):
        names, units = [], []
        for cell in cells:
            match = _CELL_UNIT.match(cell)
            names.append(match.group(1) if match else cell)
            units.append(match.group(2) if match else "")
        return _Header(names, units, previous[-1] + 1, (previous[-1] + 1,))
    return None


MAX_COLUMNS = 10_000
"""Most columns a run file may have (a bench records tens; 30,000 took 4 s to read)."""


def _column_roles(names, roles, path, line):
    """Quantity of each column: the ``roles`` map first, else :func:`canonical_name`.

    Raises BenchFileError when a role names no column, when two columns are measured
    candidates for one quantity and no role chooses, or for more than :data:`MAX_COLUMNS`
    columns.
    """
    if len(names) > MAX_COLUMNS:
        raise BenchFileError(
            path,
            f"{len(names):,} columns; a run file has at most {MAX_COLUMNS:,} (time, position, "
            "force, pressures and a few more): export the channels of the test only",
            line=line,
        )
    labels = _column_labels(names)
    counts = Counter(names)  # one pass: names.count per column was quadratic (30,000: 25 s)
    repeated = {n for n, k in counts.items() if k > 1}
    for quantity, column in roles.items():
        if column in repeated:
            options = " or ".join(
                f'"{label}"' for label, n in zip(labels, names, strict=True) if n == column
            )
            raise BenchFileError(
                path,
                f"campaign.toml [columns] {quantity} = {column!r} names {counts[column]} "
                f"columns of that name; choose one by its place: {quantity} = {options}",
                line=line,
            )
    unknown = {q: c for q, c in roles.items() if c not in names and c not in labels}
    if unknown:
        quantity, column = next(iter(unknown.items()))
        raise BenchFileError(
            path,
            f"campaign.toml [columns] {quantity} = {column!r} names no column; the file has "
            f"{labels}",
            line=line,
        )
    chosen = {c: q for q, c in roles.items()}
    quantities = []
    for name, label in zip(names, labels, strict=True):
        quantity = chosen.get(label) or chosen.get(name) or canonical_name(name)
        if label not in chosen and name not in chosen and quantity in roles:
            quantity = None  # another column was chosen for this quantity
        quantities.append(quantity)
    for quantity in set(q for q in quantities if q in QUANTITY_DIMENSIONS):
        candidates = [n for n, q in zip(labels, quantities, strict=True) if q == quantity]
        if len(candidates) > 1:
            raise BenchFileError(
                path,
                f"columns {candidates} all look like the measured {quantity}; choose one in "
                f'campaign.toml: [columns] {quantity} = "{candidates[0]}"',
                line=line,
            )
    return quantities


def _column_labels(names):
    """Names that tell every column apart: a name used more than once gets ``#1``, ``#2``
    ... by its place (``Axial Force#2``, as campaign.toml ``[columns]`` may name it)."""
    seen: dict[str, int] = {}
    labels = []
    counts = Counter(names)
    for name in names:
        if counts[name] > 1:
            seen[name] = seen.get(name, 0) + 1
            labels.append(f"{name}#{seen[name]}")
        else:
            labels.append(name)
    return labels


def si_columns(
    path: StrPath,
    names: Sequence[str],
    units: Sequence[str],
    values: ArrayLike,
    roles: Mapping[str, Any] | None = None,
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Named columns with their units as the readers' SI dict (``"time [s]"``, ...).

    ``values`` is an (n, len(names)) array; quantities are recognised by name (or chosen by
    ``roles``, as ``[columns] force = "F"``) and converted to SI; the result has the
    columns of :func:`read_bench_arrays` and ``units`` (the original unit per quantity).
    Used for records whose format carries no header, such as ``.mat`` runs.
    """
    hdr = _Header(list(names), list(units), 0)
    return _assemble([(0, hdr, np.asarray(values, dtype=float), 1)], Path(path), roles or {})


def _assemble(frames, path, roles, own: bool = False):
    """Convert blocks to SI, name columns canonically, concatenate with a segment column.

    ``frames`` are (segment number, or one per row as an int32 array; header; values; first
    line) per block. ``own``: the blocks are the reader's own arrays, converted in place (no
    copy); else the caller's values are left alone.
    """
    parts = []
    col_units = {}
    lines = []
    for seg, hdr, values, first in frames:
        lines.append(hdr.line or first)
        cols = {}
        quantities = _column_roles(hdr.names, roles, path, hdr.line or None)
        unit_line = (hdr.rows[-1] if hdr.rows else hdr.line) or None  # a units row, if any
        for j, (name, unit) in enumerate(zip(hdr.names, hdr.units, strict=True)):
            quantity = quantities[j]
            if quantity in QUANTITY_DIMENSIONS:
                dim = QUANTITY_DIMENSIONS[quantity]
                if not unit:
                    raise BenchFileError(
                        path,
                        f"column {name!r} has no unit; expected a {dim} "
                        f"unit in the header ('{name} [unit]') or on a "
                        "units row",
                        line=hdr.line or None,
                    )
                try:
                    udim = unit_dimension(unit)
                except UnitError as exc:
                    raise BenchFileError(path, f"column {name!r}: {exc}", line=unit_line) from None
                if udim != dim:
                    raise BenchFileError(
                        path,
                        f"column {name!r} has unit {unit!r} ({udim}); expected a {dim} unit",
                        line=unit_line,
                    )
                key = f"{quantity} [{SI_UNITS[dim]}]"
                if key in cols:
                    key = f"{name} [{SI_UNITS[dim]}]"
                if own:
                    column = values[:, j]
                    column *= to_si(1.0, unit, dim)  # a unit is a factor (units.to_si)
                    cols[key] = column
                else:
                    cols[key] = to_si(values[:, j], unit, dim)
                col_units[quantity] = unit
            else:
                cols[f"{name} [{unit or '-'}]"] = values[:, j]
        cols["segment [-]"] = (
            seg if isinstance(seg, np.ndarray) else np.full(values.shape[0], seg, dtype=np.int32)
        )
        parts.append(cols)
    keys = list(parts[0])
    for cols, line in zip(parts[1:], lines[1:], strict=True):
        if list(cols) != keys:
            raise BenchFileError(
                path,
                "the columns change between segments; expected the same "
                f"columns in every block ({keys} vs {list(cols)})",
                line=line,
            )
    if len(parts) == 1:
        return parts[0], col_units
    return {k: np.concatenate([p[k] for p in parts]) for k in keys}, col_units


def read_mts_text(path: StrPath, **kwargs: Any) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a testing-machine text export (MTS-like). See :func:`read_bench_text`."""
    return read_bench_text(path, **kwargs)


def read_delimited(
    path: StrPath,
    columns: Sequence[str] | None = None,
    units: Sequence[str] | None = None,
    **kwargs: Any,
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read a plain delimited file, with or without a header row. See :func:`read_bench_text`."""
    return read_bench_text(path, columns=columns, units=units, **kwargs)
