"""``cylfric export`` and ``cylfric fit --export``: outputs, exit codes, report section."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
VALIDITY = {"pressure_min": 1e4, "pressure_max": 159e5, "velocity_min": 1e-3, "velocity_max": 0.135}


@pytest.fixture(scope="module")
def datasheet(tmp_path_factory):
    path = tmp_path_factory.mktemp("sheet") / "datasheet.json"
    path.write_text(json.dumps(FrictionModel(validity=VALIDITY).to_datasheet()))
    return path


def test_export_hopsan_writes_files_and_summary(datasheet, tmp_path):
    result = runner.invoke(
        app, ["export", str(datasheet), "--to", "hopsan", "--out", str(tmp_path), "--name", "rig"]
    )
    assert result.exit_code == 0, result.output
    assert "RMS difference" in result.output
    for name in (
        "rig_hopsan.hcom",
        "rig_hopsan_parameters.csv",
        "README_hopsan.md",
        "loss_hopsan.csv",
        "loss_hopsan.txt",
        "loss_hopsan.png",
        "loss_hopsan_pressure_signal.csv",
    ):
        assert (tmp_path / name).is_file(), name


def test_export_modelica_from_the_command_line(datasheet, tmp_path):
    result = runner.invoke(
        app, ["export", str(datasheet), "--to", "modelica", "--out", str(tmp_path), "--name", "rig"]
    )
    assert result.exit_code == 0, result.output
    assert "lossless" in result.output and (tmp_path / "Rig.mo").is_file()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--to", "stl"], "--to 'stl': unknown export target; valid: ['fmu', 'hopsan'"),
        (["--to", "hopsan"], "no such datasheet file"),
    ],
)
def test_export_bad_input_exits_2_naming_the_problem(datasheet, tmp_path, args, message):
    sheet = str(datasheet) if "stl" in args else str(tmp_path / "missing.json")
    result = runner.invoke(app, ["export", sheet, *args, "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert message in result.output.replace("\n", " ")


def test_export_unreadable_datasheet_exits_2(tmp_path):
    bad = tmp_path / "datasheet.json"
    bad.write_text("{not json")
    result = runner.invoke(app, ["export", str(bad), "--to", "simscape", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert str(bad) in result.output.replace("\n", "")


def test_fit_export_bad_target_stops_before_fitting(tmp_path):
    (tmp_path / "camp").mkdir()
    result = runner.invoke(
        app,
        ["fit", str(tmp_path / "camp"), "--out", str(tmp_path / "o"), "--export", "simscape,stl"],
    )
    assert result.exit_code == 2
    assert "unknown export target 'stl'" in result.output
    assert not (tmp_path / "o").exists()


def test_fit_with_export_writes_exports_and_report_section(tmp_path):
    campaign = tmp_path / "camp"
    generate_campaign(
        campaign, BenchSettings.clean(pressures_bar=(0.1, 159.0), speeds_mm_s=(1, 4, 15, 60, 135))
    )
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["fit", str(campaign), "--out", str(out), "--export", "hopsan,modelica"]
    )
    assert result.exit_code == 0, result.output
    assert (out / "export" / "hopsan" / "loss_hopsan.csv").is_file()
    assert list((out / "export" / "modelica").glob("*.mo"))
    report = (out / "report.html").read_text()
    assert "<h2>Simulator exports</h2>" in report
    assert "lossless, the full pressure-dependent LuGre model" in report
    assert "rms [N]" in report


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if ".staging-" in p.name or p.suffix == ".lock")


def test_fit_export_failure_names_campaign_and_target_and_writes_nothing(tmp_path):
    """One pressure level: the lossy exports have no pressure range to report the loss over.
    The error said only 'pressure_range = (5500000.0, 5500000.0) Pa is not a range'."""
    campaign = tmp_path / "camp"
    generate_campaign(
        campaign, BenchSettings.clean(pressures_bar=(55.0,), speeds_mm_s=(1, 4, 15, 60, 135))
    )
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["fit", str(campaign), "--out", str(out), "--no-report", "--export", "modelica,hopsan"]
    )
    assert result.exit_code == 2
    assert " ".join(result.output.split()) == (
        f"error: {campaign}: --export hopsan failed: pressure_range = (5500000.0, 5500000.0) "
        "Pa is not a range; expected 0 <= min < max. Nothing was written (--out "
        f"{out} was not created); fit without --export hopsan to get the datasheet and the "
        "other outputs"
    )
    assert not out.exists() and _leftovers(tmp_path) == []


def test_fit_export_failure_keeps_the_earlier_output(tmp_path, monkeypatch):
    """A C compiler that fails (here $CC=false): the FMU export raised 'unexpected
    RuntimeError' (exit 1) and never said that the earlier --out was left as it was."""
    campaign = tmp_path / "camp"
    generate_campaign(
        campaign, BenchSettings.clean(pressures_bar=(0.1, 159.0), speeds_mm_s=(1, 4, 15, 60, 135))
    )
    out = tmp_path / "out"
    args = ["fit", str(campaign), "--out", str(out), "--no-report"]
    assert runner.invoke(app, args).exit_code == 0
    before = (out / "datasheet.json").read_bytes()
    monkeypatch.setenv("CC", "false")
    from cylfric.export.fmu import fmi_platform

    if fmi_platform() is None:
        pytest.skip("no FMI platform name for this machine: the FMU is not compiled")
    result = runner.invoke(app, [*args, "--export", "fmu"])
    assert result.exit_code == 2
    flat = " ".join(result.output.split())
    assert flat.startswith(f"error: {campaign}: --export fmu failed: compiling the FMU with ")
    assert flat.endswith(
        f"failed. Nothing was written (--out {out} keeps its earlier contents); fit without "
        "--export fmu to get the datasheet and the other outputs"
    )
    assert (out / "datasheet.json").read_bytes() == before
    assert not (out / "export").exists() and _leftovers(tmp_path) == []
