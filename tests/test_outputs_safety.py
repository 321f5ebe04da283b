"""Outputs are safe (issue 11): staged and swapped in whole, locked, never inside or around
the campaign, never over a folder that is not cylfric's; generate never overwrites silently."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cylfric.report.figures
from cylfric import _outfolder
from cylfric.cli import app
from cylfric.pipeline import MARKER, fit_campaign
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
SMALL = BenchSettings.clean(
    pressures_bar=(0.1, 80.0, 159.0), speeds_mm_s=(1, 3, 8, 15, 30, 60, 135)
)


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
    with (out / MARKER).open("a") as marker:  # as if an earlier fit had written it
        marker.write("skipped.csv\n")
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


def test_fit_dot_inside_the_campaign_says_which_out_to_give(campaign, monkeypatch):
    """'cylfric fit .' in the campaign folder: the default --out cylfric-out lies inside it.
    The message said only 'choose an output folder outside the campaign' about a folder
    named '.'; it now names the folder and an --out to type, and that --out works. (The
    default stays cylfric-out here: a folder written beside the one the user stands in,
    unasked, would surprise.)"""
    monkeypatch.chdir(campaign)
    result = runner.invoke(app, ["fit", ".", "--no-report"])
    assert result.exit_code == 2
    assert " ".join(result.output.split()) == (
        f"error: --out cylfric-out is inside the campaign folder . ({campaign.resolve()}): its "
        "files would be read back as runs; choose an output folder outside the campaign, "
        f"e.g. --out ../{campaign.name}-fit"
    )
    assert not (campaign / "cylfric-out").exists()
    result = runner.invoke(app, ["fit", ".", "--no-report", "--out", f"../{campaign.name}-fit"])
    assert result.exit_code == 0, result.output
    assert (campaign.parent / f"{campaign.name}-fit" / "datasheet.json").is_file()


def test_an_absolute_campaign_gets_an_absolute_out_to_give(campaign):
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(campaign.parent)])
    assert result.exit_code == 2
    assert " ".join(result.output.split()).endswith(
        f"contains the campaign folder {campaign}; the output folder is replaced whole, so "
        "choose one that does not hold the raw files, e.g. --out "
        f"{campaign.parent / (campaign.name + '-fit')}"
    )


def test_a_folder_that_is_not_cylfric_output_is_not_replaced(campaign, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("my own file\n")
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2 and "is not a cylfric output folder" in result.output
    assert (out / "notes.txt").read_text() == "my own file\n"


def test_a_folder_with_only_a_datasheet_and_no_marker_is_refused(campaign, tmp_path):
    """F8 of the issue-11 check: a user folder holding a datasheet.json beside documents
    was wiped (exit 0, no message). Without the marker it is not cylfric's: exit 2."""
    out = tmp_path / "mydocs"
    (out / "photos").mkdir(parents=True)
    (out / "datasheet.json").write_text("{}")
    (out / "thesis.docx").write_text("thesis draft\n")
    (out / "photos" / "rig.jpg").write_text("img\n")
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2
    assert "is not a cylfric output folder (no .cylfric-output marker)" in result.output
    assert "datasheet.json, photos/, thesis.docx" in " ".join(result.output.split())
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == [
        "datasheet.json",
        "photos",
        "photos/rig.jpg",
        "thesis.docx",
    ]


def test_files_added_to_an_earlier_output_folder_are_never_deleted(campaign, tmp_path):
    """The marker lists what cylfric wrote; anything else in --out refuses the re-use
    (exit 2 naming the files) and the folder is left exactly as it was."""
    out = tmp_path / "out"
    fit_campaign(campaign, out, report=False)
    listed = (out / MARKER).read_text().splitlines()
    assert "datasheet.json" in listed and "points.csv" in listed and MARKER not in listed
    (out / "my notes.txt").write_text("keep me\n")
    (out / "photos").mkdir()
    (out / "photos" / "rig.jpg").write_text("img\n")
    before = sorted(p.relative_to(out).as_posix() for p in out.rglob("*"))
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2
    message = " ".join(result.output.split())
    assert "holds files cylfric did not write (my notes.txt, photos/;" in message
    assert "choose another --out, or move them out of it" in message
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == before
    (out / "my notes.txt").unlink()
    (out / "photos" / "rig.jpg").unlink()
    (out / "photos").rmdir()
    assert (
        runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"]).exit_code == 0
    )


def test_more_than_four_foreign_files_are_counted(tmp_path):
    from cylfric._outfolder import check_reusable as _check_reusable

    out = tmp_path / "out"
    out.mkdir()
    (out / MARKER).write_text("# header\ndatasheet.json\nexport/\nexport/a.txt\n")
    (out / "datasheet.json").write_text("{}")
    (out / "export").mkdir()
    (out / "export" / "a.txt").write_text("")
    _check_reusable(out)  # only listed files: re-usable
    for name in "abcdef":
        (out / "export" / f"{name}.mine").write_text("")
    with pytest.raises(
        ValueError,
        match=r"\(export/a\.mine, export/b\.mine, export/c\.mine, "
        r"export/d\.mine and 2 more; not listed",
    ):
        _check_reusable(out)


def test_a_file_added_during_the_fit_stops_the_swap(campaign, tmp_path, monkeypatch):
    import cylfric.pipeline as pipeline

    out = tmp_path / "out"
    fit_campaign(campaign, out, report=False)
    real_fit = pipeline._fit

    def fit_and_meanwhile_a_user_saves_a_file(*args, **kwargs):
        result = real_fit(*args, **kwargs)
        (out / "late.txt").write_text("saved during the fit\n")
        return result

    monkeypatch.setattr(pipeline, "_fit", fit_and_meanwhile_a_user_saves_a_file)
    with pytest.raises(ValueError, match=r"holds files cylfric did not write \(late\.txt;"):
        fit_campaign(campaign, out, report=False)
    assert (out / "late.txt").read_text() == "saved during the fit\n"
    assert not [p for p in tmp_path.iterdir() if ".staging-" in p.name]


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
            _outfolder.swap_in(staging, out)
    assert (out / "datasheet.json").read_bytes() == before


@pytest.mark.parametrize("kind", ["old", "staging"])
def test_a_folder_named_like_a_leftover_but_not_made_by_cylfric_is_kept(campaign, tmp_path, kind):
    """Issue 43 (data loss; main deleted it with exit 0): `.OUT.old-*` / `.OUT.staging-*`
    beside OUT is removed only when cylfric's marker says it made it."""
    out = tmp_path / "res"
    theirs = tmp_path / f".res.{kind}-2024"
    theirs.mkdir()
    (theirs / "thesis.docx").write_text("four years of work\n")
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--no-report"])
    assert result.exit_code == 2, result.output
    assert ".res." in result.output and "cylfric did not make it" in result.output
    assert (theirs / "thesis.docx").read_text() == "four years of work\n"
    assert not out.exists()


def test_leftovers_cylfric_made_are_removed(campaign, tmp_path):
    out = tmp_path / "res"
    fit_campaign(campaign, out, report=False)
    killed = tmp_path / ".res.staging-killed"  # a writer killed before its output marker
    killed.mkdir()
    (killed / _outfolder.STAGING_MARKER).write_text("12345\n")
    (killed / "points.csv").write_text("half written")
    old = tmp_path / ".res.old-777"  # a previous output moved aside, then the writer died
    old.mkdir()
    (old / "datasheet.json").write_text("{}")
    (old / MARKER).write_text("# header\ndatasheet.json\n")
    fit_campaign(campaign, out, report=False)
    assert not killed.exists() and not old.exists()
    assert (out / MARKER).is_file() and not (out / _outfolder.STAGING_MARKER).exists()


def test_a_full_disk_while_writing_the_lock_names_the_lock_file(tmp_path, monkeypatch):
    """The lock's process id not written (ENOSPC): the error names the lock file and the
    action, and no lock is left behind."""
    import errno

    out = tmp_path / "res"
    real_write = os.write

    def full(handle, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "write", full)
    with pytest.raises(OSError) as caught, _outfolder.lock(out):
        pass
    monkeypatch.setattr(os, "write", real_write)
    from cylfric._paths import os_error_message

    said = os_error_message(caught.value)  # what the command line prints
    assert said.startswith(f"writing --out {out}: writing the lock file {tmp_path / '.res.lock'}")
    assert said.endswith("No space left on device")
    assert not (tmp_path / ".res.lock").exists()
