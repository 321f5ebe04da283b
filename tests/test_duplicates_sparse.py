"""Issue 22, deliverable 8: a file present twice (same bytes) counts once, with a warning
naming both; a sparse grid (2 speeds x 3 pressures) loses no valid run to the quality gate."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest
from fit_helpers import copy_campaign, excluded_table, fit_no_report  # tests/fit_helpers.py

from cylfric.io.campaign import Campaign, find_duplicates
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
    header = lines[0].strip().split(",")  # file, pressure_bar, velocity_mm_s, and the
    row = lines[1].strip().split(",")  # rough bench's session and truth columns
    source = folder / row[header.index("file")]
    shutil.move(source, folder / "run_x.txt")
    text = (folder / "run_x.txt").read_text().replace("Pressure: 20 bar\n", "")
    (folder / "run_x.txt").write_text(text)
    row[header.index("file")], row[header.index("pressure_bar")] = "run_x.txt", "0"
    lines[1] = ",".join(row) + "\n"
    manifest.write_text("".join(lines))
    excluded = assess(extract_campaign(folder, workers=1)).excluded
    assert list(excluded["file"]) == ["run_x.txt"]
    assert list(excluded["check"]) == ["metadata"]
    assert "no 0-bar level it belongs to" in excluded["reason"].iloc[0]


def _with_copy(folder, tmp_path):
    """A copy of the campaign with one run present twice (the same bytes under another
    name, listed in manifest.csv); returns (folder, original name, copy name)."""
    folder = copy_campaign(folder, tmp_path)
    manifest = folder / "manifest.csv"
    lines = manifest.read_text().splitlines(keepends=True)
    original = lines[3].split(",")[0]
    copy = "zz_again_" + original
    shutil.copy(folder / original, folder / copy)
    manifest.write_text("".join(lines) + lines[3].replace(original, copy, 1))
    return folder, original, copy


def test_a_file_present_twice_counts_once(sparse, tmp_path):
    folder, original, copy = _with_copy(sparse["loaded"], tmp_path)
    result, out = fit_no_report(folder, tmp_path)
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert f"{copy}: duplicate of {original} (the same bytes, SHA-256)" in text  # both named
    excluded = excluded_table(out)
    assert list(excluded["file"]) == [copy] and list(excluded["check"]) == ["duplicate"]
    assert excluded["reason"].iloc[0].startswith(f"duplicate of {original}")
    sheet = json.loads((out / "datasheet.json").read_text())
    files = [Path(f["name"]).name for f in sheet["fit"]["source"]["files"]]
    assert len(files) == 6 and copy not in files  # the six runs, each once
    points = pd.read_csv(out / "points.csv")
    assert not points["file"].str.endswith(copy).any()
    assert any("1 by duplicate" in note for note in sheet["notes"])


def test_campaign_open_lists_duplicates_and_reads_each_file_once(sparse, tmp_path):
    folder, original, copy = _with_copy(sparse["loaded"], tmp_path)
    campaign = Campaign.open(folder)
    assert [info.path.name for info in campaign.runs].count(original) == 1
    assert copy not in {info.path.name for info in campaign.runs}
    assert [(d.file, d.original) for d in campaign.duplicates] == [(copy, original)]
    extraction = extract_campaign(campaign, workers=1)
    assert len(extraction.runs) == 6
    # files of the same size but other bytes are not duplicates
    different = folder / "zz_other.txt"
    data = bytearray((folder / original).read_bytes())
    data[-2] = ord("7") if data[-2] != ord("7") else ord("8")
    different.write_bytes(bytes(data))
    found = find_duplicates([folder / original, different, folder / copy])
    assert found == {folder / copy: folder / original}
