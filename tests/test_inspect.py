"""``cylfric inspect`` (issue 39 item 10): what cylfric read from a run file or a campaign,
checked against what was written apart from it (the bench's file headers and settings, the
real data's README, the campaign extraction of a fit), and docs/campaign.md against the
campaign.toml schema."""

from __future__ import annotations

import inspect as python_inspect
import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.simulate.bench import BenchSettings, generate_campaign

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ROOT / "examples" / "zillen2021" / "campaign.toml"
DOC = ROOT / "docs" / "campaign.md"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

runner = CliRunner()
# four runs: two pressures x two speeds, one descending and one ascending stroke each
SETTINGS = BenchSettings.clean(points=((20.0, 5.0), (20.0, 40.0), (100.0, 5.0), (100.0, 40.0)))


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("inspect") / "campaign"
    generate_campaign(folder, SETTINGS)
    return folder


def _runs(folder: Path) -> list[Path]:
    return sorted(folder.glob("*.txt"))


def test_columns_and_units_are_the_files_own(campaign):
    from cylfric.inspect import inspect

    file = _runs(campaign)[0]
    found = inspect(file, gate=False)
    (run,) = found.runs
    # the header the bench wrote: "Time Axial Displacement Axial Force" in "s mm kN"
    lines = file.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("Time"))
    names, units = lines[at].split("\t"), lines[at + 1].split("\t")
    assert [c.name for c in run.columns] == names
    assert [c.unit for c in run.columns] == units
    assert units[2] == SETTINGS.force_unit == "kN"
    by_name = {c.name: c for c in run.columns}
    assert by_name["Axial Force"].quantity == "force"
    assert by_name["Axial Force"].key == "force [N]"
    assert by_name["Axial Force"].factor == 1000.0
    assert by_name["Axial Displacement"].si_unit == "m"
    assert by_name["Axial Displacement"].factor == pytest.approx(1e-3)
    # the range as converted, against the file read by numpy
    numeric = [line for line in lines[at + 2 :] if re.fullmatch(r"[-0-9.e\t]+", line)]
    raw = np.loadtxt(numeric, delimiter="\t")  # the data rows (not the status lines)
    assert by_name["Axial Force"].maximum == pytest.approx(raw[:, 2].max() * 1e3)
    assert by_name["Axial Displacement"].minimum == pytest.approx(raw[:, 1].min() * 1e-3)
    # the nominal values: the manifest's, with the header and file name as other sources
    assert run.source == {"pressure": "manifest", "velocity": "manifest"}
    assert set(run.nominal["pressure"]) == {"manifest", "header", "file name"}
    assert run.pressure == pytest.approx(20e5) and run.velocity == pytest.approx(5e-3)
    # no campaign.toml: the defaults, said as defaults
    balance = {t["term"]: t for t in run.force_balance}
    assert balance["force"]["value"].startswith("load cell: +1")
    assert "default" in balance["force"]["set_in"]
    assert not balance["chamber A"]["applied"] and not balance["chamber B"]["applied"]
    assert "no campaign.toml" in found.config_source


def test_windows_are_the_points_a_fit_extracts(campaign):
    from cylfric.inspect import inspect
    from cylfric.steady_state import extract_campaign

    extraction = extract_campaign(campaign, workers=1)
    per_file = extraction.points["file"].map(lambda f: Path(f).name).value_counts()
    found = inspect(campaign, gate=False, traces=False)
    assert len(found.runs) == len(SETTINGS.points)
    for run in found.runs:
        # the bench drives each run down the stroke and up again: two strokes
        assert run.strokes == 2, run.name
        assert run.strokes == per_file[run.file.name]
        assert set(run.windows["direction [-]"]) == {-1, 1}
        assert run.usable == 2
        # each window inside its stroke
        w = run.windows
        assert (w["window_start [s]"] >= w["stroke_start [s]"]).all()
        assert (w["window_end [s]"] <= w["stroke_end [s]"]).all()
        mine = extraction.points[
            extraction.points["file"].map(lambda f: Path(f).name) == run.file.name
        ]
        np.testing.assert_allclose(
            run.windows["friction [N]"].to_numpy(), mine["friction [N]"].to_numpy(), rtol=1e-12
        )


def test_cli_draws_a_png_per_file_and_reports_the_gate(campaign, tmp_path):
    out = tmp_path / "figures"
    file = _runs(campaign)[1]
    result = runner.invoke(app, ["inspect", str(file), "--out", str(out)])
    assert result.exit_code == 0, result.output
    png = out / f"{file.name}.png"
    assert png.read_bytes()[:8] == PNG_MAGIC
    assert "kN" in result.output and "force [N]" in result.output
    assert "quality gate: passes" in result.output
    # without --out: the tables only, no figure anywhere
    bare = runner.invoke(app, ["inspect", str(campaign), "--json"])
    assert bare.exit_code == 0, bare.output
    document = json.loads(bare.stdout)
    assert document["figures"] == []
    assert [r["strokes"] for r in document["runs"]] == [2, 2, 2, 2]
    assert all(r["verdict"] == "passes" for r in document["runs"])


def test_gate_exclusion_is_shown_with_its_reason(campaign, tmp_path):
    """A run whose manifest pressure contradicts its header and file name (typed 90 bar,
    measured at 20): the gate's metadata check excludes it, and inspect says so."""
    folder = tmp_path / "mislabelled"
    shutil.copytree(campaign, folder)
    manifest = folder / "manifest.csv"
    lines = manifest.read_text().splitlines()
    cells = lines[1].split(",")
    assert cells[1] == "20"
    cells[1] = "90"
    lines[1] = ",".join(cells)
    manifest.write_text("\n".join(lines) + "\n")
    target = folder / cells[0]
    result = runner.invoke(app, ["inspect", str(target), "--json"])
    assert result.exit_code == 0, result.output
    (run,) = json.loads(result.stdout)["runs"]
    assert [g["check"] for g in run["gate"]] == ["metadata"]
    assert run["verdict"].startswith("excluded: metadata")
    assert "90 bar" in run["verdict"] and "20 bar" in run["verdict"]


def test_bad_file_exits_2_naming_file_and_line(campaign, tmp_path):
    folder = tmp_path / "broken"
    shutil.copytree(campaign, folder)
    bad = _runs(folder)[2]
    lines = bad.read_text().splitlines(keepends=True)
    row = 40  # a data row (1-based line 41)
    cells = lines[row].split("\t")
    cells[1] = "1.2.3x"
    lines[row] = "\t".join(cells)
    bad.write_text("".join(lines))
    result = runner.invoke(app, ["inspect", str(bad)])
    assert result.exit_code == 2, result.output
    assert bad.name in result.output and f"line {row + 1}" in result.output
    # the folder: every run shown, then exit 2 naming the unreadable one
    whole = runner.invoke(app, ["inspect", str(folder)])
    assert whole.exit_code == 2, whole.output
    assert bad.name in whole.output and f"line {row + 1}" in whole.output
    assert "1 of 4 files unreadable" in whole.output


def test_file_outside_any_campaign_exits_2(campaign, tmp_path):
    alone = tmp_path / "loose" / "run.txt"
    alone.parent.mkdir()
    shutil.copy(_runs(campaign)[0], alone)
    result = runner.invoke(app, ["inspect", str(alone)])
    assert result.exit_code == 2, result.output
    assert "run.txt" in result.output and "outside any campaign" in result.output
    unlisted = campaign / "extra_p20bar_v5mms.txt"
    shutil.copy(_runs(campaign)[0], unlisted)
    try:
        result = runner.invoke(app, ["inspect", str(unlisted)])
    finally:
        unlisted.unlink()
    assert result.exit_code == 2, result.output
    assert "manifest.csv does not list it" in result.output


def test_real_zillen_file(shared_data, tmp_path):
    """PK seal at 3 bar (Zillen et al. 2021): the README gives the columns and units (time
    ms, ..., position mm, pressure bar, force N), 10 extend/retract strokes, bore 25 mm."""
    from cylfric.inspect import inspect
    from cylfric.steady_state import extract_campaign

    folder = shared_data / "zillen2021-pneumatic-seals"
    file = folder / "PK_3bar.csv"
    found = inspect(file, config=RECIPE)
    (run,) = found.runs
    assert [c.unit for c in run.columns] == ["ms", "V", "V", "V", "mm", "bar", "N"]
    assert [c.quantity for c in run.columns] == [
        "time",
        None,
        None,
        None,
        "position",
        "pressure_a",
        "force",
    ]
    assert run.columns[0].factor == pytest.approx(1e-3)
    assert run.columns[5].factor == pytest.approx(1e5)
    balance = {t["term"]: t for t in run.force_balance}
    assert balance["force"]["value"].startswith("load cell: -1")
    assert "load_cell_sign" in balance["force"]["set_in"]
    area = math.pi / 4 * 25.0**2  # mm^2
    assert f"{area:.5g} mm^2" in balance["chamber A"]["value"]
    assert balance["position sign"]["set_in"] == "[force_balance] position_sign"
    assert run.pressure == pytest.approx(3e5)
    assert run.source["pressure"] == "campaign.toml name_pattern"
    assert run.strokes == 20  # 10 extend/retract strokes
    from cylfric.io.campaign import Campaign

    extraction = extract_campaign(Campaign.open(folder, config=RECIPE).for_seal("PK"))
    files = extraction.points["file"].map(lambda f: Path(f).name)
    assert run.strokes == int((files == file.name).sum())
    assert run.gate == [] and found.gate.points["PK_3bar.csv"] == run.strokes
    result = runner.invoke(
        app, ["inspect", str(file), "--config", str(RECIPE), "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "PK_3bar.csv.png").read_bytes()[:8] == PNG_MAGIC
    # without the recipe the shared folder is no campaign: refused, not read with defaults
    refused = runner.invoke(app, ["inspect", str(file)])
    assert refused.exit_code == 2 and "outside any campaign" in refused.output


def _doc_rows(text: str, heading: str) -> dict[str, list[str]]:
    """The rows of the table under ``heading`` of docs/campaign.md: key -> cells."""
    section = text.split(heading, 1)[1].split("\n#", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
        match = re.fullmatch(r"`([^`]+)`.*", cells[0]) if cells else None
        if match:
            rows[match.group(1)] = cells
    return rows


def test_every_campaign_toml_key_is_documented():
    from cylfric.io.campaign import CONFIG_SCHEMA

    text = DOC.read_text(encoding="utf-8")
    for table, spec in CONFIG_SCHEMA["properties"].items():
        rows = _doc_rows(text, f"### `[{table}]`")
        missing = sorted(set(spec["properties"]) - set(rows))
        assert not missing, f"[{table}] keys not in docs/campaign.md: {missing}"
        for key, cells in rows.items():
            assert len(cells) == 5 and all(cells), f"[{table}] {key}: unit, default, example"


def test_extraction_defaults_in_the_doc_are_the_codes():
    from cylfric.steady_state import _point_rows, find_windows

    text = DOC.read_text(encoding="utf-8")
    rows = _doc_rows(text, "### `[extraction]`")
    defaults = {
        name: p.default
        for name, p in python_inspect.signature(find_windows).parameters.items()
        if p.default is not python_inspect.Parameter.empty
        and name not in ("nominal_speed", "return_components")
    }
    source = python_inspect.getsource(_point_rows)
    for name in ("spike_sigma", "velocity_window"):
        defaults[name] = float(re.search(rf'"{name}", ([0-9.]+)', source).group(1))
    assert set(defaults) == set(rows)
    for name, value in defaults.items():
        assert rows[name][2].strip("`") == (f'"{value}"' if isinstance(value, str) else str(value))


def test_every_manifest_column_is_documented():
    from cylfric.io.campaign import _MANIFEST_COLUMNS, TEMPERATURE_COLUMNS

    rows = {k.lower() for k in _doc_rows(DOC.read_text(encoding="utf-8"), "## `manifest.csv`")}
    text = DOC.read_text(encoding="utf-8").lower()
    for column in (*_MANIFEST_COLUMNS, "test", "seal", "session", "force_rate_n_s"):
        assert column in rows, column
    for column in TEMPERATURE_COLUMNS:
        assert f"`{column}`" in text, column


def test_out_that_is_a_link_is_refused_before_reading(campaign, tmp_path):
    target = tmp_path / "elsewhere"
    target.mkdir()
    link = tmp_path / "out"
    link.symlink_to(target, target_is_directory=True)
    result = runner.invoke(app, ["inspect", str(_runs(campaign)[0]), "--out", str(link)])
    assert result.exit_code == 2, result.output
    assert "is a symbolic link to" in result.output
    assert list(target.iterdir()) == []


def test_rig_without_load_cell_force_from_pressures(tmp_path):
    """The virtual servo-valve rig (its campaign.toml: force = "pressures", bore 40 mm, rod
    25 mm, single-rod, 20 kg): the chamber terms with the areas of those diameters, the
    inertia, no weight offset; the windows are the extraction's points."""
    from cylfric.inspect import inspect
    from cylfric.simulate.valve_bench import ValveRigSettings, generate_valve_campaign
    from cylfric.steady_state import extract_campaign

    folder = tmp_path / "valve"
    generate_valve_campaign(folder, ValveRigSettings(voltages=(2.0,), repeats=1))
    (run,) = inspect(folder).runs
    balance = {t["term"]: t for t in run.force_balance}
    assert balance["force"]["value"].startswith("the chamber pressures")
    assert f"+ {math.pi / 4 * 40.0**2:.5g} mm^2 x pressure_a [Pa]" == balance["chamber A"]["value"]
    annulus = math.pi / 4 * (40.0**2 - 25.0**2)
    assert f"- {annulus:.5g} mm^2 x pressure_b [Pa]" == balance["chamber B"]["value"]
    assert balance["inertia"]["applied"] and "20 kg" in balance["inertia"]["value"]
    assert run.offset == 0.0 and run.offset_from.startswith("none")
    assert run.pressure_measured and math.isnan(run.pressure)  # the rig sets no pressure
    points = extract_campaign(folder, workers=1).points
    assert run.strokes == len(points) == 2
    np.testing.assert_allclose(run.windows["pressure [Pa]"], points["pressure [Pa]"], rtol=1e-12)
