"""Outputs are safe (issue 11): staged and swapped in whole, locked, never inside or around
the campaign, never over a folder that is not cylfric's; generate never overwrites silently."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cylfric.report.figures
from cylfric.cli import app
from cylfric.pipeline import MARKER, fit_campaign
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
SMALL = BenchSettings(pressures_bar=(0.1, 80.0, 159.0), speeds_mm_s=(1, 3, 8, 15, 30, 60, 135))


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("campaign")
    generate_campaign(folder, SMALL)
    return folder


def test_a_reused_out_keeps_no_stale_files(campaign, tmp_path):
    out = tmp_path / "out"
    fit_campaign(campaign, out, report=True)
    assert (out / "report.html").is_file() and (out / MARKER).is_file()
    (out / "skipped.csv").write_text("left from another campaign\n")
    fit_campaign(campaign, out, report=False)
    assert not (out / "report.html").exists() and not (out / "skipped.csv").exists()
    assert (out / "datasheet.json").is_file()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.")]  # no leftovers


def test_a_failing_figure_leaves_the_previous_out_untouched(campaign, tmp_path, monkeypatch):
    out = tmp_path / "out"
    fit_campaign(campaign, out, report=False)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}

    def broken(*args, **kwargs):
        raise RuntimeError("figure failed")

    monkeypatch.setattr(cylfric.report.figures, "figure_fit", broken)
    with pytest.raises(RuntimeError, match="figure failed"):
        fit_campaign(campaign, out, report=True)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    fresh = tmp_path / "fresh"
    with pytest.raises(RuntimeError):
        fit_campaign(campaign, fresh, report=True)
    assert not fresh.exists()  # no datasheet.json written before the report failed


def test_out_inside_or_around_the_campaign_is_refused(campaign):
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(campaign / "out")])
    assert result.exit_code == 2
    assert "is inside the campaign folder" in result.output
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(campaign.parent)])
    assert result.exit_code == 2 and "contains the campaign folder" in result.output


def test_a_folder_that_is_not_cylfric_output_is_not_replaced(campaign, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("my own file\n")
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2 and "is not a cylfric output folder" in result.output
    assert (out / "notes.txt").read_text() == "my own file\n"


def test_a_second_concurrent_fit_is_refused(campaign, tmp_path):
    out = tmp_path / "out"
    (tmp_path / ".out.lock").write_text(str(os.getppid()))  # a live process holds it
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2 and "another cylfric fit" in result.output
    (tmp_path / ".out.lock").write_text("999999999")  # a process that is gone: stale
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 0, result.output
    assert not (tmp_path / ".out.lock").exists()


def test_generate_refuses_a_non_empty_folder_without_force(tmp_path):
    (tmp_path / "run_000.txt").write_text("precious raw data\n")
    args = ["generate", str(tmp_path), "--pressures", "10", "--speeds", "5,50"]
    result = runner.invoke(app, args)
    assert result.exit_code == 2 and "is not empty" in result.output
    assert (tmp_path / "run_000.txt").read_text() == "precious raw data\n"
    assert runner.invoke(app, [*args, "--force"]).exit_code == 0


def test_fix_accepts_a_comma_separated_list_and_glob_selects_runs(campaign, tmp_path):
    out = tmp_path / "out"
    result = runner.invoke(
        app,
        [
            "fit",
            str(campaign),
            "--out",
            str(out),
            "--no-report",
            "--fix",
            "alpha=1,v_r=10mm/s",
            "--glob",
            "run_00*",
        ],
    )
    assert result.exit_code == 0, result.output
    import json

    sheet = json.loads((out / "datasheet.json").read_text())
    assert sheet["fit"]["fixed"] == {"v_r": 0.01, "alpha": 1.0}
    assert len(sheet["fit"]["source"]["files"]) == 10  # run_000 ... run_009 of 21


def test_leftovers_of_a_killed_fit_are_removed_and_a_failed_swap_restores(campaign, tmp_path):
    import cylfric.pipeline as pipeline

    out = tmp_path / "out"
    (tmp_path / ".out.staging-killed").mkdir()
    fit_campaign(campaign, out, report=False)
    assert not (tmp_path / ".out.staging-killed").exists()
    before = (out / "datasheet.json").read_bytes()
    staging = tmp_path / ".out.staging-x"
    staging.mkdir()
    real_rename = Path.rename

    def failing(self, target):
        if self == staging:
            raise OSError("disk full")
        return real_rename(self, target)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Path, "rename", failing)
        with pytest.raises(OSError, match="disk full"):
            pipeline._swap_in(staging, out)
    assert (out / "datasheet.json").read_bytes() == before
