"""The command line: every exit code and error path, the report in a real browser."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from cylfric.cli import app
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


@pytest.fixture(scope="module")
def fitted(campaign, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    result = runner.invoke(app, ["fit", str(campaign), "--out", str(out), "--per-direction"])
    assert result.exit_code == 0, result.output
    return out, result


def test_fit_writes_every_output(fitted):
    out, result = fitted
    for name in (
        "datasheet.json",
        "points.csv",
        "per_pressure.csv",
        "sensitivity.csv",
        "law_comparison.csv",
        "per_direction.csv",
        "report.html",
    ):
        assert (out / name).is_file(), name
    for stem in (
        "fit",
        "parameters",
        "directions",
        "sensitivity",
        "sensitivity_curves",
        "residuals",
    ):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 1000
        assert (out / "figures" / f"{stem}.svg").read_text().lstrip().startswith("<?xml")
    assert "F_c(p)" in result.output and "N/bar" in result.output
    sheet = json.loads((out / "datasheet.json").read_text())
    assert abs(sheet["parameters"]["F_c"]["intercept"] - 70.2) < 1.5
    assert not any(p.name.endswith(".tmp") for p in out.rglob("*"))  # atomic writes


def test_fit_fix_and_no_report(campaign, tmp_path):
    result = runner.invoke(
        app,
        [
            "fit",
            str(campaign),
            "-o",
            str(tmp_path),
            "--fix",
            "alpha=1",
            "--fix",
            "v_r=10mm/s",
            "--no-report",
        ],
    )
    assert result.exit_code == 0, result.output
    sheet = json.loads((tmp_path / "datasheet.json").read_text())
    assert sheet["parameters"]["alpha"] == 1.0 and sheet["parameters"]["v_r"] == 0.01
    assert not (tmp_path / "report.html").exists()


def test_fit_skip_bad_writes_skipped_csv(campaign, tmp_path):
    copy = tmp_path / "c"
    shutil.copytree(campaign, copy)
    bad = sorted(copy.glob("*.txt"))[2]
    bad.write_bytes(b"\x00\x01binary")
    result = runner.invoke(app, ["fit", str(copy), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert f"{bad.name}: binary content" in result.output
    assert "Traceback" not in result.output
    result = runner.invoke(
        app, ["fit", str(copy), "-o", str(tmp_path / "o"), "--skip-bad", "--no-report"]
    )
    assert result.exit_code == 0, result.output
    assert "1 file(s) skipped" in result.output
    assert bad.name in (tmp_path / "o" / "skipped.csv").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fit", "/no/such/folder"], "not a folder; expected a campaign folder"),
        (["fit", "{campaign}", "--fix", "beta=2"], "--fix 'beta=2': expected NAME=VALUE"),
        (["fit", "{campaign}", "--fix", "v_r=10bar"], "unit 'bar' is a pressure unit"),
        (["fit", "{campaign}", "--law", "cubic", "--no-report"], "unknown pressure law 'cubic'"),
        (["show", "/no/such.json"], "cannot read"),
        (["generate", "{tmp}/g", "--speeds", "1,fast"], "cannot read 'fast' as a velocity"),
        (["generate", "{tmp}/g", "--speeds", "0"], "--speeds must be > 0"),
        (["simulate", "nope"], "not a datasheet file nor a literature set"),
        (["simulate", "thesis_2016", "--drive", "rocket"], "--drive 'rocket': expected one of"),
        (["simulate", "thesis_2016", "--mass", "0kg"], "must be > 0"),
    ],
)
def test_bad_input_exits_2_with_one_line(campaign, tmp_path, args, message):
    args = [a.format(campaign=campaign, tmp=tmp_path) for a in args]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output
    assert result.output.strip().startswith("error:")


def test_unexpected_error_exits_1_with_hint(campaign, tmp_path, monkeypatch):
    import cylfric.pipeline

    def boom(*args, **kwargs):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(cylfric.pipeline, "fit_campaign", boom)
    result = runner.invoke(app, ["fit", str(campaign), "-o", str(tmp_path)])
    assert result.exit_code == 1
    assert "unexpected RuntimeError: disk on fire" in result.output
    assert "rerun with --debug" in result.output


def test_show_and_version(fitted):
    out, _ = fitted
    result = runner.invoke(app, ["show", str(out / "datasheet.json")])
    assert result.exit_code == 0 and "Table 4.1" in result.output
    assert "[bar]" in result.output and "[N]" in result.output  # units are not rich markup
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output.startswith("cylfric ")


def test_generate_with_units(tmp_path):
    result = runner.invoke(
        app,
        [
            "generate",
            str(tmp_path),
            "--pressures",
            "10,5MPa",
            "--speeds",
            "5,0.1m/s",
            "--seed",
            "3",
            "--decimal-comma",
            "--clean",
        ],
    )
    assert result.exit_code == 0, result.output
    manifest = (tmp_path / "manifest.csv").read_text().splitlines()
    assert manifest[0] == "file,pressure_bar,velocity_mm_s"
    assert {line.split(",")[1] for line in manifest[1:]} == {"10", "50"}
    assert {line.split(",")[2] for line in manifest[1:]} == {"5", "100"}


def test_simulate_from_a_datasheet(fitted, tmp_path):
    out, _ = fitted
    result = runner.invoke(
        app,
        [
            "simulate",
            str(out / "datasheet.json"),
            "--drive",
            "sine",
            "--duration",
            "2s",
            "-o",
            str(tmp_path),
        ],
    )
    assert result.exit_code == 0, result.output
    lines = (tmp_path / "simulation.csv").read_text().splitlines()
    assert lines[0].startswith("time [s],position [m]") and len(lines) == 2002
    assert (tmp_path / "simulation.png").is_file()


def test_demo_prints_recovered_beside_thesis(tmp_path):
    result = runner.invoke(app, ["demo", "--clean", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Recovered against the truth" in result.output
    assert "the 95% band of a new run holds the true friction of" in " ".join(result.output.split())
    sheet = json.loads((tmp_path / "fit" / "datasheet.json").read_text())
    assert np.isclose(sheet["parameters"]["F_s"]["intercept"], 112.9, rtol=0.02)
    assert len(list((tmp_path / "campaign").glob("*.txt"))) == 270


# ----------------------------------------------------------------------------- browser

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _chromium(page: Path, shot: Path, profile: Path) -> str:
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        "--enable-logging=stderr",
        "--v=0",
        f"--screenshot={shot}",
        "--window-size=1200,2400",
        page.as_uri(),
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    return done.stderr


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)")
def test_report_renders_in_headless_chromium_without_console_errors(fitted, tmp_path):
    from matplotlib.image import imread

    out, _ = fitted
    # the console check really sees errors: a page that logs one is caught
    bad = tmp_path / "bad.html"
    bad.write_text("<html><body><script>console.error('boom')</script></body></html>")
    assert "boom" in _chromium(bad, tmp_path / "bad.png", tmp_path / "p1")
    log = _chromium(out / "report.html", tmp_path / "report.png", tmp_path / "p2")
    console = [line for line in log.splitlines() if "CONSOLE" in line]
    assert console == []
    image = imread(tmp_path / "report.png")
    assert image.shape[0] >= 2000 and image[..., :3].std() > 0.05  # not a blank page
    shutil.copy(tmp_path / "report.png", out / "report_screenshot.png")
