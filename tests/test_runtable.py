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


def test_the_gates_prefilter_keeps_every_run_with_a_metadata_conflict():
    """quality._metadata_suspects reads columns; every run _conflicts flags is among them."""
    from cylfric.quality import _conflicts, _metadata_suspects

    rng = np.random.default_rng(7)
    dicts = []
    for i in range(300):
        run = summary(i)
        run["pressure measured"] = False
        nominal = run["nominal"]["pressure"]
        if i % 5 == 0:  # a header that says something else (sometimes only slightly)
            nominal["header"] = (nominal["header"][0] * rng.choice([1.001, 1.5, 0.1]), "h")
        if i % 11 == 0:  # a source the others lack
            run["nominal"]["velocity"]["file name"] = (0.002, "v2mms")
        if i % 13 == 0:
            del nominal["header"]
        dicts.append(run)
    table = RunTable.from_dicts(dicts)
    runs = [d["run"] for d in dicts]
    suspects = set(_metadata_suspects(table, [False] * 300, runs, {3, 4}))
    floors = {"pressure": 0.5e5, "velocity": 1e-4}
    flagged = {i for i, d in enumerate(dicts) if _conflicts(d, 0.05, floors)}
    assert flagged and flagged <= suspects and {3, 4} <= suspects
    assert len(suspects) < 300  # the point: most runs are not read in full


def test_tables_and_datasheet_streamed_are_the_same_bytes(tmp_path):
    """pipeline._csv writes row blocks, write_datasheet the encoder's pieces: same bytes."""
    import json

    import pandas as pd

    from cylfric.datasheet import _batched
    from cylfric.pipeline import _csv

    frame = pd.DataFrame(
        {"a [m]": [0.1, 1e-17, np.nan, 3.0, 2.5e10], "b": ["x", "y,z", None, "", "q"]}
    )
    _csv(tmp_path / "t.csv", frame, rows=2)
    assert (tmp_path / "t.csv").read_text() == frame.to_csv(index=False)
    _csv(tmp_path / "e.csv", frame.iloc[:0], rows=2)
    assert (tmp_path / "e.csv").read_text() == frame.iloc[:0].to_csv(index=False)
    sheet = {"x": [1.5, {"y": None, "z": "ü"}], "w": list(range(50))}
    pieces = json.JSONEncoder(indent=2, allow_nan=False).iterencode(sheet)
    streamed = b"".join(_batched(iter(pieces), size=3)).decode()
    assert streamed == json.dumps(sheet, indent=2, allow_nan=False)
