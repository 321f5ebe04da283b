"""The extraction's chunked tasks (issue 27): files per task, the points packed as columns,
and the points table built from columns equal to the one built from rows."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pandas as pd
import pytest

from cylfric.steady_state import (
    CHUNK_FILES,
    _file_bytes,
    _finish_columns,
    _finish_rows,
    _join,
    _offset_rows,
    _pack,
    chunk_size,
)


@pytest.mark.parametrize("n", [1, 15, 16, 100, 1000, 20000])
@pytest.mark.parametrize("workers", [1, 2, 4])
def test_chunks_give_each_worker_several_tasks_of_at_most_chunk_files(n, workers):
    size = chunk_size(n, workers)
    tasks = math.ceil(n / size)
    assert 1 <= size <= CHUNK_FILES
    assert tasks >= min(n, 8 * workers) // 2  # several tasks a worker: the load balances
    assert (tasks - 1) * size < n  # no empty task


def _run_rows(run, directions, label=None):
    """Rows of one run as _point_rows gives them: one per stroke (a direction each)."""
    rows = []
    for stroke, d in enumerate(directions):
        row = {
            "run": run,
            "file": f"run_{run}.txt",
            "stroke": stroke,
            "direction [-]": d,
            "pressure [Pa]": 5e6 + run,
            "pressure_std [Pa]": 0.0,
            "velocity [m/s]": 0.01 * d,
            "velocity_std [m/s]": 1e-5,
            "force [N]": 17.8 + d * (100.0 + run + stroke),
            "friction [N]": math.nan,
            "friction_std [N]": 0.8,
            "n [-]": 100 + stroke,
            "window_start [s]": 1.0,
            "window_end [s]": 2.0,
            "spikes [-]": 0,
            "offset [N]": math.nan,
            "flag": "ok",
        }
        if label is not None:
            row["seal"] = label
        rows.append(row)
    return _offset_rows(rows)


CAMPAIGN = SimpleNamespace(unlisted=(), folder="campaign")


def _copy(rows):
    return [dict(r) for r in rows]


def test_points_from_packed_columns_equal_the_points_from_rows():
    # three runs; the middle one ran in one direction only: no offset of its own, so the
    # campaign offset (median of the others) is applied when the table is built
    runs = [_run_rows(0, (1, -1)), _run_rows(1, (1, 1)), _run_rows(2, (1, -1, 1, -1))]
    assert runs[1][0]["flag"] == "no_offset"
    packs = [_pack([(r, {}, None) for r in runs[:2]]), _pack([(runs[2], {}, None)])]
    assert all(isinstance(points, dict) for points, *_ in packs)  # columns, not rows
    from_columns = _finish_columns(CAMPAIGN, _join([p[0] for p in packs]), [], [], 0)
    from_rows = _finish_rows(CAMPAIGN, [r for rows in _copy_all(runs) for r in rows], [], [], 0)
    pd.testing.assert_frame_equal(from_columns.points, from_rows.points, check_exact=True)
    assert from_columns.points["flag"].eq("ok").all()
    assert from_columns.offset == from_rows.offset == pytest.approx(17.3)  # median of runs 0, 2


def _copy_all(runs):
    return [_copy(rows) for rows in runs]


def test_runs_with_labels_the_others_lack_are_joined_as_rows():
    runs = [_run_rows(0, (1, -1)), _run_rows(1, (1, -1), label="PK")]
    packs = [_pack([(runs[0], {}, None)]), _pack([(runs[1], {}, None)])]
    assert _join([p[0] for p in packs]) is None  # different columns: not joined as columns
    rows = [r for rows in _copy_all(runs) for r in rows]
    expected = pd.DataFrame(rows, columns=[*rows[0], "seal"])
    built = _finish_rows(CAMPAIGN, rows, [], [], 0).points
    pd.testing.assert_frame_equal(built.drop(columns="session"), expected)
    assert built["seal"].isna().sum() == 2


def test_bytes_read_counts_regular_files_only(tmp_path):
    """The extraction's ``bytes_read``: a file's size; a folder or a file gone counts 0."""
    run = tmp_path / "run.txt"
    run.write_bytes(b"t,x\n0,1\n")
    assert _file_bytes(run) == 8
    assert _file_bytes(tmp_path) == 0
    assert _file_bytes(tmp_path / "gone.txt") == 0
