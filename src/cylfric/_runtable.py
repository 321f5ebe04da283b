"""The run summaries of an extraction as columns (issue 27: flat memory).

A run summary (:attr:`cylfric.steady_state.Extraction.runs`) is a small nested dict of
about 30 Python objects (file, nominal values from every source with where they were
found, SHA-256, ...): some 2.5 kB a run, 51 MB at 20,000 runs, unpickled from the readers
and held to the end of a fit. :class:`RunTable` keeps the same summaries as one numpy
array per leaf (floats, integers, booleans) or per string leaf an object array whose
repeated strings are one object, plus each run's *shape* (its leaves' paths in order), so
that ``table[i]`` is the same dict, key order and value types included. It is a
read-only :class:`~collections.abc.Sequence` of dicts; :meth:`RunTable.column` gives one
leaf for every run without building the dicts (the gate and the datasheet read columns).
Standard library and numpy only.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

_DICT, _TUPLE = 0, 1
_MISSING = object()


def _flatten(value: Any, path: tuple, out: dict) -> None:
    if type(value) in (dict, tuple) and not value:  # an empty one is a leaf
        out[path] = value
    elif type(value) is dict:
        for key, item in value.items():
            _flatten(item, (*path, (_DICT, key)), out)
    elif type(value) is tuple:
        for index, item in enumerate(value):
            _flatten(item, (*path, (_TUPLE, index)), out)
    else:
        out[path] = value


def _template(paths: list, start: int = 0, depth: int = 0):
    """The nesting of leaf ``paths`` (in order) as (kind, [(key, sub)]) with leaves as their
    index in ``paths``."""
    groups: dict = {}
    for index, path in enumerate(paths):
        groups.setdefault(path[0], []).append((path[1:], start + index))
    kind = next(iter(groups))[0] if groups else _DICT
    subs = []
    for step, inner in groups.items():
        if not inner[0][0]:  # a leaf
            subs.append((step[1], inner[0][1]))
        else:
            rests = [rest for rest, _ in inner]
            subs.append((step[1], _template(rests, inner[0][1], depth + 1)))
    return kind, subs


def _build(template, values: list):
    kind, subs = template
    items = [(key, values[sub] if type(sub) is int else _build(sub, values)) for key, sub in subs]
    return tuple(v for _, v in items) if kind == _TUPLE else dict(items)


def _array(values: list) -> np.ndarray:
    """One leaf's values as a compact array (exact types kept; see :meth:`RunTable.column`)."""
    kinds = {type(v) for v in values if v is not _MISSING}
    filler = {float: np.nan, bool: False, int: 0}
    if len(kinds) == 1 and (kind := next(iter(kinds))) in filler:
        dtype = {float: np.float64, bool: np.bool_, int: np.int64}[kind]
        try:
            return np.array([filler[kind] if v is _MISSING else v for v in values], dtype=dtype)
        except OverflowError:  # an int beyond 64 bits: kept as the object
            pass
    out = np.empty(len(values), dtype=object)
    same: dict = {}  # repeated strings (units, sources, header lines) as one object
    out[:] = [
        None if v is _MISSING else (same.setdefault(v, v) if type(v) is str else v) for v in values
    ]
    return out


class RunTable(Sequence):
    """Run summaries as columns; ``table[i]`` is run i's dict (None where a file failed).

    Build with :meth:`from_dicts` (in a reader, per chunk of files), join chunks with
    :meth:`join`, keep the runs read with :meth:`select`.
    """

    __slots__ = ("_shapes", "_codes", "_columns", "_builders")

    def __init__(self, shapes: list, codes: np.ndarray, columns: dict) -> None:
        self._shapes = shapes  # tuple of leaf paths per shape; None: no summary
        self._codes = codes  # shape index per run
        self._columns = columns  # leaf path -> array over the runs
        self._builders: dict = {}  # shape index -> its row builder, made on first use

    @classmethod
    def from_dicts(cls, summaries: Sequence[dict | None]) -> RunTable:
        """The summaries (dicts of dicts, tuples and scalars; None) as a table."""
        flat = []
        for summary in summaries:
            leaves: dict = {}
            if summary is not None:
                _flatten(summary, (), leaves)
            flat.append(None if summary is None else leaves)
        index: dict = {}
        codes = np.array(
            [index.setdefault(None if f is None else tuple(f), len(index)) for f in flat],
            dtype=np.int64,
        )
        paths = dict.fromkeys(p for shape in index if shape for p in shape)
        columns = {
            p: _array([_MISSING if f is None else f.get(p, _MISSING) for f in flat]) for p in paths
        }
        return cls(list(index), codes, columns)

    @classmethod
    def join(cls, tables: Sequence[RunTable]) -> RunTable:
        """The tables' runs one after another."""
        shapes: dict = {}
        codes = []
        for table in tables:
            remap = np.array(
                [shapes.setdefault(s, len(shapes)) for s in table._shapes] or [0], dtype=np.int64
            )
            codes.append(remap[table._codes])
        paths = dict.fromkeys(p for t in tables for p in t._columns)
        columns: dict = {}
        for path in paths:
            parts: list = [t._columns.get(path) for t in tables]
            dtypes = {p.dtype for p in parts if p is not None}
            if len(dtypes) == 1 and all(p is not None for p in parts):
                columns[path] = np.concatenate(parts)
                continue
            values: list = []
            for table, part in zip(tables, parts, strict=True):
                n = len(table)
                values += [_MISSING] * n if part is None else part.tolist()
            columns[path] = _array(values)
        joined = np.concatenate(codes) if codes else np.zeros(0, dtype=np.int64)
        return cls(list(shapes), joined, columns)

    def select(self, keep) -> RunTable:
        """The runs where the boolean sequence ``keep`` is true."""
        mask = np.asarray(keep, dtype=bool)
        return RunTable(
            self._shapes, self._codes[mask], {p: c[mask] for p, c in self._columns.items()}
        )

    def __len__(self) -> int:
        return len(self._codes)

    def _row(self, i: int) -> dict | None:
        code = self._codes[i]
        builder = self._builders.get(code)
        if builder is None:
            builder = self._builders[code] = self._builder(self._shapes[code])
        return builder(i)

    def _builder(self, shape):
        """A function run index -> the dict of one shape (its leaves read from the columns)."""
        if shape is None:
            return lambda i: None
        columns = self._columns
        # numeric leaves come back as Python numbers (.item())
        getters = [(p, columns[p], columns[p].dtype != object) for p in shape]
        template = _template(list(shape))
        return lambda i: _build(template, [c[i].item() if n else c[i] for _, c, n in getters])

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self._row(j) for j in range(*i.indices(len(self)))]
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"run {i} of {n}")
        return self._row(i % n if n else i)

    def __iter__(self) -> Iterator[dict | None]:
        block = 1024  # the columns' values as Python objects a block at a time
        templates: dict = {}
        for a in range(0, len(self), block):
            codes = self._codes[a : a + block].tolist()
            values = {p: c[a : a + block].tolist() for p, c in self._columns.items()}
            for j, code in enumerate(codes):
                shape = self._shapes[code]
                if shape is None:
                    yield None
                    continue
                if code not in templates:
                    templates[code] = _template(list(shape))
                yield _build(templates[code], [values[p][j] for p in shape])

    def __eq__(self, other) -> bool:
        if isinstance(other, (RunTable, list, tuple)):
            return len(self) == len(other) and list(self) == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"RunTable({len(self)} runs)"

    def __reduce__(self):
        return (RunTable, (self._shapes, self._codes, self._columns))

    def column(self, *keys: str, default: Any = None) -> list:
        """The leaf ``keys`` (a path of dict keys, e.g. ``"nominal", "pressure"`` would be a
        dict: give the leaf, ``"file"``) of every run as a list of Python values, ``default``
        where a run lacks it."""
        return self._column(tuple((_DICT, k) for k in keys), default)

    def leaves(self, *keys: str, index: int) -> list:
        """Item ``index`` of every tuple one dict level below ``keys`` (e.g. the value of
        each source in ``"nominal", "pressure"``), one list per such leaf over the runs
        (NaN where a run lacks it)."""
        head = tuple((_DICT, k) for k in keys)
        found = []
        for path in self._columns:
            if len(path) == len(head) + 2 and path[: len(head)] == head:
                if path[-2][0] == _DICT and path[-1] == (_TUPLE, index):
                    found.append(path)
        return [self._column(path, math.nan) for path in found]

    def _column(self, path: tuple, default: Any) -> list:
        values = self._columns.get(path)
        if values is None:
            return [default] * len(self)
        present = np.array([path in (s or ()) for s in self._shapes], dtype=bool)[self._codes]
        listed = values.tolist()
        if present.all():
            return listed
        return [v if ok else default for v, ok in zip(listed, present.tolist(), strict=True)]


def run_column(runs: Sequence, *keys: str, default: Any = None) -> list:
    """:meth:`RunTable.column` of ``runs``, or the same from a list of dicts."""
    if isinstance(runs, RunTable):
        return runs.column(*keys, default=default)
    out = []
    for info in runs:
        value: Any = info
        for key in keys:
            value = value.get(key, _MISSING) if isinstance(value, dict) else _MISSING
            if value is _MISSING:
                break
        out.append(default if value is _MISSING else value)
    return out
