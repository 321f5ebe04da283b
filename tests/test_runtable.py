"""The run summaries as columns (cylfric._runtable): the same dicts back, compactly."""

import math
import pickle
import sys

import numpy as np
import pytest

from cylfric._runtable import RunTable, run_column


def summary(i, source="manifest", extra=False):
    run = {
        "file": f"/c/run_{i:05d}.txt",
        "run": i,
        "pressure [Pa]": 1e5 * (1 + i % 3),
        "velocity [m/s]": 0.001 * (1 + i % 7),
        "rows": 9000 + i,
        "source": {"pressure": source, "velocity": "manifest"},
        "nominal": {
            "pressure": {
                "manifest": (1e5 * (1 + i % 3), f"manifest.csv line {i + 2}"),
                "header": (1e5 * (1 + i % 3), "Pressure: 1 bar"),
            },
            "velocity": {"manifest": (0.001 * (1 + i % 7), f"manifest.csv line {i + 2}")},
        },
        "pressure measured": i % 2 == 0,
        "events": 3,
        "sha256": f"{i:064x}",
    }
    if extra:  # another shape: a key the others lack, an empty dict, a None, a big int
        run["seal"] = None
        run["source"] = {}
        run["rows"] = 2**70
    return run


def test_rows_equal_the_dicts_key_order_and_types_included():
    dicts = [summary(i) for i in range(40)] + [summary(40, "header", extra=True), None]
    table = RunTable.from_dicts(dicts)
    assert len(table) == len(dicts)
    assert table == dicts and list(table) == dicts
    for got, want in zip(table, dicts, strict=True):
        assert repr(got) == repr(want)  # key order and Python types (no numpy scalars)
    assert [table[i] for i in range(len(table))] == dicts
    assert table[-1] is None and table[1:3] == dicts[1:3]
    with pytest.raises(IndexError):
        table[len(dicts)]


def test_join_select_and_pickle_keep_the_runs():
    dicts = [summary(i) for i in range(10)] + [summary(10, extra=True)] + [None]
    parts = [RunTable.from_dicts(dicts[:5]), RunTable.from_dicts(dicts[5:])]
    joined = RunTable.join(parts)
    assert joined == dicts
    keep = [d is not None and d["run"] % 2 == 0 for d in dicts]
    chosen = joined.select(keep)
    assert chosen == [d for d, k in zip(dicts, keep, strict=True) if k]
    assert pickle.loads(pickle.dumps(chosen)) == chosen
    assert RunTable.join([]) == []


def test_columns_without_building_dicts():
    dicts = [summary(i) for i in range(6)] + [summary(6, extra=True)]
    table = RunTable.from_dicts(dicts)
    assert table.column("file") == [d["file"] for d in dicts]
    assert table.column("seal", default="-") == ["-"] * 6 + [None]
    assert table.column("absent", default=0) == [0] * 7
    values = table.leaves("nominal", "pressure", index=0)
    assert len(values) == 2  # manifest, header
    assert values[0] == [d["nominal"]["pressure"]["manifest"][0] for d in dicts]
    assert run_column(dicts, "source", "pressure") == run_column(table, "source", "pressure")
    assert all(math.isnan(v) for v in run_column(dicts, "seal", default=math.nan)[:6])


def test_smaller_than_the_dicts():
    """The point of it: 2,000 summaries take a fraction of their dicts' memory."""
    dicts = [summary(i) for i in range(2000)]

    def size(obj, seen):
        if id(obj) in seen:
            return 0
        seen.add(id(obj))
        total = sys.getsizeof(obj)
        if isinstance(obj, dict):
            total += sum(size(k, seen) + size(v, seen) for k, v in obj.items())
        elif isinstance(obj, (list, tuple)):
            total += sum(size(v, seen) for v in obj)
        elif isinstance(obj, np.ndarray) and obj.dtype == object:
            total += sum(size(v, seen) for v in obj)
        return total

    table = RunTable.from_dicts(dicts)
    columns = size(table._columns, set()) + table._codes.nbytes
    assert columns < size(dicts, set()) / 3
