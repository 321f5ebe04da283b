"""Near-duplicates (issue 43, item 5): a copy of a run with a header line changed (here its
pressure) is found and reported like a byte-for-byte copy, comparing the numbers only.
The tests of finding them fail on the code before (it compared whole files)."""

from __future__ import annotations

import shutil

import pytest

from cylfric.io.campaign import Campaign, _data_offset, find_near_duplicates

SMALL = {"pressures_bar": (10.0, 80.0), "speeds_mm_s": (2, 10, 50)}


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path_factory.mktemp("bench") / "c"
    generate_campaign(folder, BenchSettings.clean(**SMALL))
    return folder


def _relabelled_copy(bench, tmp_path):
    folder = tmp_path / "campaign"
    shutil.copytree(bench, folder)
    original = sorted(folder.glob("run_001_*.txt"))[0]
    text = original.read_text()
    assert "Pressure: 10 bar" in text
    copy = folder / "run_001b_p55bar_v10mms.txt"
    copy.write_text(text.replace("Pressure: 10 bar", "Pressure: 55 bar"))
    with open(folder / "manifest.csv", "a") as manifest:
        manifest.write(f"{copy.name},55,10\n")
    return folder, original, copy


def test_a_copy_with_a_header_line_changed_is_a_duplicate(bench, tmp_path):
    folder, original, copy = _relabelled_copy(bench, tmp_path)
    campaign = Campaign.open(folder)
    assert [(d.file, d.original) for d in campaign.duplicates] == [(copy.name, original.name)]
    assert copy not in {info.path for info in campaign.runs}
    (reason,) = [d.reason for d in campaign.duplicates]
    assert reason.startswith(f"duplicate of {original.name} (the same samples")
    assert "only the header lines differ" in reason


def test_fit_reports_the_near_duplicate_in_excluded_csv(bench, tmp_path):
    import pandas as pd
    from typer.testing import CliRunner

    from cylfric.cli import app

    folder, original, copy = _relabelled_copy(bench, tmp_path)
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["fit", str(folder), "--out", str(out), "--no-report"])
    assert result.exit_code == 0, result.output
    assert f"{copy.name}: duplicate of {original.name}" in " ".join(result.output.split())
    excluded = pd.read_csv(out / "excluded.csv")
    row = excluded[excluded["file"].astype(str).str.endswith(copy.name)]
    assert list(row["check"]) == ["duplicate"]


def test_runs_with_other_numbers_are_not_near_duplicates(bench, tmp_path):
    folder = tmp_path / "campaign"
    shutil.copytree(bench, folder)
    runs = sorted(folder.glob("run_*.txt"))
    assert find_near_duplicates(runs) == {}
    # the same header, one sample changed near the end: not a copy
    data = bytearray(runs[0].read_bytes())
    position = data.rindex(b"\t") + 2
    data[position] = ord("7") if data[position] != ord("7") else ord("8")
    changed = folder / "zz_changed.txt"
    changed.write_bytes(bytes(data))
    assert find_near_duplicates([runs[0], changed]) == {}


@pytest.mark.parametrize(
    ("text", "offset"),
    [
        (b"Time\tForce\ns\tN\n0\t1.5\n0.1\t1.6\n", 15),
        (b"a\r\n1\t2\r\nNaN 3\r\n", 3),
        (b"1 2\n3 4\n", 0),
        (b"header only\nmore\n", None),
        (b"x\n1e-3;+2,5\n", 2),
    ],
)
def test_the_numeric_block_starts_at_the_first_row_of_numbers(text, offset):
    assert _data_offset(text, whole=True) == offset


def test_a_segment_marker_after_the_first_rows_is_compared_not_skipped(tmp_path):
    """Two runs whose first segments differ are not duplicates even when everything after
    a later header line agrees (the block starts at the first row of numbers)."""
    rest = b"Segment 2\nTime\tForce\n" + b"".join(b"%d\t2.0\n" % i for i in range(50))
    a = tmp_path / "a.txt"
    b = tmp_path / "b.txt"
    a.write_bytes(b"Time\tForce\n0\t1.0\n" + rest)
    b.write_bytes(b"Time\tForce\n0\t9.0\n" + rest)
    assert find_near_duplicates([a, b]) == {}
