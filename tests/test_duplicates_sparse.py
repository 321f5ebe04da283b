"""Issue 22, deliverable 8: a file present twice (same bytes) counts once, with a warning
naming both; a sparse grid (2 speeds x 3 pressures) loses no valid run to the quality gate."""

from __future__ import annotations

import shutil

import pytest
from fit_helpers import copy_campaign, excluded_table, fit_no_report  # tests/fit_helpers.py

from cylfric.quality import assess
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign

SPARSE = dict(speeds_mm_s=(2, 50), seed=3)
"""Two speeds per pressure: fewer than the outlier check's neighbours (``min_speeds``)."""


@pytest.fixture(scope="module")
def sparse(tmp_path_factory):
    """2 speeds x 3 pressures on the virtual bench, one grid with a 0-bar level."""
    folders = {}
    for name, pressures in (("loaded", (20.0, 80.0, 150.0)), ("zero", (0.0, 80.0, 150.0))):
        folder = tmp_path_factory.mktemp(f"sparse-{name}")
        generate_campaign(folder, BenchSettings(pressures_bar=pressures, **SPARSE))
        folders[name] = folder
    return folders


@pytest.mark.parametrize("grid", ["loaded", "zero"])
def test_a_sparse_grid_loses_no_valid_run(sparse, grid):
    """The 0-bar level of two runs (as many as every other level) was a 'metadata
    conflict' of both runs: a level needed 3 runs however few the other levels had."""
    extraction = extract_campaign(sparse[grid], workers=1)
    assert len(extraction.runs) == 6
    report = assess(extraction)
    assert report.excluded.empty, report.excluded.to_dict("records")
    assert report.points["flag"].eq("ok").all()


def test_a_sparse_grid_fits_with_every_run(sparse, tmp_path):
    result, out = fit_no_report(sparse["zero"], tmp_path)
    assert result.exit_code == 0, result.output
    assert excluded_table(out).empty
    assert "excluded" not in result.output


def test_a_lone_0_bar_run_on_a_sparse_grid_is_still_a_conflict(sparse, tmp_path):
    """One run at 0 bar where every level has two: not a level, a typo (issue 11, F3)."""
    folder = copy_campaign(sparse["loaded"], tmp_path)
    manifest = folder / "manifest.csv"
    lines = manifest.read_text().splitlines(keepends=True)
    name, _, speed = lines[1].strip().split(",")
    source = folder / name
    shutil.move(source, folder / "run_x.txt")
    text = (folder / "run_x.txt").read_text().replace("Pressure: 20 bar\n", "")
    (folder / "run_x.txt").write_text(text)
    lines[1] = f"run_x.txt,0,{speed}\n"
    manifest.write_text("".join(lines))
    excluded = assess(extract_campaign(folder, workers=1)).excluded
    assert list(excluded["file"]) == ["run_x.txt"]
    assert list(excluded["check"]) == ["metadata"]
    assert "no 0-bar level it belongs to" in excluded["reason"].iloc[0]
