"""Viscosity correction as a ``cylfric fit`` option (issue 15): ``campaign.toml [oil]`` and
the runs' oil temperatures in ``manifest.csv``.

The virtual bench has no oil temperature, so the campaign is built from it: a seal whose
Stribeck curve follows the Hersey number (thesis eq. 2.8) has at oil temperature T the
friction ``F_T(v) = F_ref(v nu(T) / nu(T_ref))``; for the Stribeck law (eq. 2.7) that is
the reference model with ``v_r / k`` and ``sigma_2 k`` (``k = nu(T) / nu(T_ref)``). Each
temperature's runs are simulated with that model and gathered into one campaign whose
``manifest.csv`` lists each run's temperature.
"""

from __future__ import annotations

import csv
import json
import shutil
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.io import BenchFileError, load_config
from cylfric.model import FrictionModel
from cylfric.pipeline import fit_campaign
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.simulate.plant import Cylinder
from cylfric.viscosity import walther_viscosity

OIL_VG46 = ((313.15, 46e-6), (373.15, 6.8e-6))
"""ISO VG 46 mineral oil, viscosity index about 100: 46 and 6.8 mm^2/s at 40 and 100 degC
(typical data-sheet values, as in tests/test_drift.py)."""
OIL_TOML = '[oil]\nviscosity_40C = "46 mm2/s"\nviscosity_100C = "6.8 cSt"\n'
PRESSURES_BAR = (20, 80, 150)
SPEEDS_MM_S = (2, 4, 7, 12, 20, 35, 60, 100)  # 24 runs, 60 mm strokes: about 1 s to fit
TEMPERATURES_C = (30.0, 40.0, 55.0)  # speed ratios nu(T)/nu(40 degC) about 1.6, 1, 0.5
BENCH = BenchSettings.clean(
    cylinder=Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060),
    pressures_bar=PRESSURES_BAR,
    speeds_mm_s=SPEEDS_MM_S,
)


def _at_temperature(model: FrictionModel, ratio: float) -> FrictionModel:
    """The model whose steady friction at v is ``model``'s at ``ratio * v`` (eq. 2.7)."""
    coefficients = model.coefficients(include_dynamic=False)
    coefficients["v_r"] = coefficients["v_r"] / ratio
    coefficients["sigma_2"] = {
        c: (v if c == "law" else v * ratio) for c, v in coefficients["sigma_2"].items()
    }
    return model.replace(coefficients=coefficients)


@pytest.fixture(scope="module")
def warm_and_cold(tmp_path_factory):
    """One campaign of 18 runs at 30, 40 and 55 degC (in turn along the runs, shifted at
    each pressure so that temperature is not tied to speed), its manifest naming each
    run's temperature in degC; the truth is the thesis law at 40 degC."""
    base = tmp_path_factory.mktemp("oil")
    folder = base / "campaign"
    folder.mkdir()
    truth = FrictionModel()  # thesis eq. 4.1-4.3 at the reference 40 degC
    runs = [
        (p, v, TEMPERATURES_C[(i + j) % 3])
        for i, p in enumerate(PRESSURES_BAR)
        for j, v in enumerate(SPEEDS_MM_S)
    ]
    rows = []
    for k, temperature in enumerate(TEMPERATURES_C):
        points = tuple((p, v) for p, v, t in runs if t == temperature)
        ratio = walther_viscosity(temperature + 273.15, OIL_VG46) / walther_viscosity(
            313.15, OIL_VG46
        )
        settings = replace(
            BENCH, friction=_at_temperature(truth, ratio), points=points, seed=10 + k
        )
        group = base / f"T{temperature:g}"
        info = generate_campaign(group, settings)
        for path, (p, v) in zip(info["files"], points, strict=True):
            name = f"T{temperature:g}C_{path.name}"
            shutil.move(str(path), folder / name)
            rows.append((name, p, v, temperature))
    with (folder / "manifest.csv").open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["file", "pressure_bar", "velocity_mm_s", "temperature_C"])
        writer.writerows(rows)
    return folder, truth


def _worst_error(model: FrictionModel, truth: FrictionModel) -> float:
    """Largest |friction - truth| [N] over speeds 2-100 mm/s at the campaign's pressures."""
    v = np.geomspace(0.002, 0.1, 15)[:, None]
    p = np.array(PRESSURES_BAR)[None, :] * 1e5
    return float(np.abs(model.friction(v, p) - truth.friction(v, p)).max())


def test_fit_at_several_oil_temperatures_recovers_the_reference_model(warm_and_cold, tmp_path):
    """With [oil] the fit gives back the 40 degC truth within the virtual campaign's
    tolerance (1.5 N: the bench's 0.8 N force noise, as the pipeline tests allow); without
    it the same points do measurably worse."""
    folder, truth = warm_and_cold
    (folder / "campaign.toml").write_text(OIL_TOML)
    try:
        corrected = fit_campaign(folder, tmp_path / "on", report=False)
        plain = fit_campaign(folder, tmp_path / "off", report=False, viscosity_correction=False)
    finally:
        (folder / "campaign.toml").unlink()
    good = _worst_error(corrected.identification.model, truth)
    bad = _worst_error(plain.identification.model, truth)
    assert good < 1.5
    assert bad > 3 * good
    assert_allclose(corrected.identification.model.parameters["v_r"].value, 0.010, rtol=0.1)
    sheet = json.loads((tmp_path / "on" / "datasheet.json").read_text())
    record = sheet["fit"]["viscosity_correction"]
    assert record["reference_temperature"] == pytest.approx(313.15)
    assert record["oil"]["viscosity"] == pytest.approx([46e-6, 6.8e-6])
    assert record["oil"]["temperature"] == pytest.approx([313.15, 373.15])
    assert record["temperature_min"] == pytest.approx(303.15)
    assert record["temperature_max"] == pytest.approx(328.15)
    assert record["temperature_source"] == "manifest.csv"
    assert "Hersey" in record["rule"] and "Walther" in record["rule"]
    assert any(note.startswith("viscosity correction: runs at 30 degC") for note in sheet["notes"])
    points = corrected.extraction.points
    assert {"velocity measured [m/s]", "temperature [K]"} <= set(points.columns)
    off = json.loads((tmp_path / "off" / "datasheet.json").read_text())
    assert "viscosity_correction" not in off["fit"]
    assert any("turned off" in note for note in off["notes"])


def test_cli_states_the_correction_and_refuses_it_without_oil(warm_and_cold, tmp_path):
    folder, _ = warm_and_cold
    runner = CliRunner()
    # temperatures without [oil]: fitted as measured, and the summary says so
    done = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "a"), "--no-report"])
    assert done.exit_code == 0, done.output
    assert "no [oil] table" in done.output
    # --viscosity-correction asked for without [oil]: exit 2, one line
    done = runner.invoke(
        app,
        ["fit", str(folder), "--out", str(tmp_path / "b"), "--no-report", "--viscosity-correction"],
    )
    assert done.exit_code == 2
    assert "campaign.toml has no [oil] table" in done.output
    assert "Traceback" not in done.output
    (folder / "campaign.toml").write_text(OIL_TOML + 'reference_temperature = "50 degC"\n')
    try:
        done = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "c"), "--no-report"])
    finally:
        (folder / "campaign.toml").unlink()
    assert done.exit_code == 0, done.output
    assert "viscosity correction" in " ".join(done.output.split())
    assert "holds at 50 degC" in " ".join(done.output.split())


def _campaign_with(tmp_path, toml=None, temperatures=None):
    """An 8-run campaign (2 pressures x 4 speeds); ``temperatures`` fills the manifest's
    temperature_C column (None: no column)."""
    folder = tmp_path / "c"
    settings = replace(BENCH, pressures_bar=(20, 150), speeds_mm_s=(5, 10, 20, 60))
    generate_campaign(folder, settings)
    if temperatures is not None:
        lines = (folder / "manifest.csv").read_text().splitlines()
        lines = [lines[0] + ",temperature_C"] + [
            f"{line},{t}" for line, t in zip(lines[1:], temperatures, strict=True)
        ]
        (folder / "manifest.csv").write_text("\n".join(lines) + "\n")
    if toml is not None:
        (folder / "campaign.toml").write_text(toml)
    return folder


SMALL_FIT = pytest.mark.filterwarnings("ignore:the Stribeck fit at")  # 8 runs: rows unreliable


@SMALL_FIT
def test_oil_alone_is_a_note_and_a_campaign_temperature_corrects(tmp_path):
    folder = _campaign_with(tmp_path, OIL_TOML)
    result = fit_campaign(folder, tmp_path / "o1", report=False)
    assert any("no run has an oil temperature" in n for n in result.identification.notes)
    assert "viscosity_correction" not in result.datasheet["fit"]
    with pytest.raises(ValueError, match="no run has an oil temperature"):
        fit_campaign(folder, tmp_path / "o2", report=False, viscosity_correction=True)
    (folder / "campaign.toml").write_text(OIL_TOML + 'temperature = "313.15 K"\n')
    result = fit_campaign(folder, tmp_path / "o3", report=False)
    record = result.datasheet["fit"]["viscosity_correction"]
    assert record["temperature_source"] == "campaign.toml [oil] temperature"
    # every run at the reference temperature: the speeds are unchanged (ratio 1)
    assert_allclose([record["speed_ratio_min"], record["speed_ratio_max"]], 1.0, rtol=1e-12)


@SMALL_FIT
def test_a_run_without_temperature_among_others_is_refused(tmp_path):
    folder = _campaign_with(
        tmp_path, OIL_TOML, temperatures=("30", "", "45", "50", "35", "40", "45", "50")
    )
    with pytest.raises(
        ValueError,
        match="manifest.csv: no oil temperature for 1 run\\(s\\) \\(run_001_p20bar_v10mms.txt\\)",
    ):
        fit_campaign(folder, tmp_path / "o", report=False)
    # an [oil] temperature fills the gap
    (folder / "campaign.toml").write_text(OIL_TOML + 'temperature = "40 degC"\n')
    result = fit_campaign(folder, tmp_path / "o", report=False)
    assert result.datasheet["fit"]["viscosity_correction"]["temperature_source"] == (
        "manifest.csv and campaign.toml [oil] temperature"
    )


@pytest.mark.parametrize(
    ("toml", "message"),
    [
        (OIL_TOML + 'viscosity = "46 cSt"\n', "line 4: unknown key 'viscosity' in \\[oil\\]"),
        (
            '[oil]\nviscosity_40C = 46\nviscosity_100C = "6.8 mm2/s"\n',
            "line 2: oil.viscosity_40C: 46 is not of type 'string'",
        ),
        (
            '[oil]\nviscosity_40C = "46 mm2/s"\n',
            "line 1: oil: 'viscosity_100C' is a required property",
        ),
        (
            '[oil]\nviscosity_40C = "46 bar"\nviscosity_100C = "6.8 mm2/s"\n',
            "line 2: oil.viscosity_40C: unit 'bar' is a pressure unit",
        ),
        (
            '[oil]\nviscosity_40C = "6.8 mm2/s"\nviscosity_100C = "46 mm2/s"\n',
            "line 3: oil.viscosity_40C \\(6.8 mm2/s\\) must be larger than oil.viscosity_100C",
        ),
        (
            '[oil]\nviscosity_40C = "46 mm2/s"\nviscosity_100C = "1 mm2/s"\n',
            "line 3: oil.viscosity_100C = '1 mm2/s': expected .* holds from 2 mm2/s",
        ),
        (
            OIL_TOML + 'reference_temperature = "warm"\n',
            "line 4: oil.reference_temperature: cannot read 'warm' as a temperature",
        ),
        (OIL_TOML + 'temperature = "40 K"\n', "line 4: oil.temperature = '40 K' \\(-233.1 degC\\)"),
    ],
)
def test_oil_table_errors_name_the_key_and_line(tmp_path, toml, message):
    (tmp_path / "campaign.toml").write_text(toml)
    with pytest.raises(BenchFileError, match=message):
        load_config(tmp_path)


def test_manifest_temperature_errors_name_the_line(tmp_path):
    folder = _campaign_with(
        tmp_path, temperatures=("30", "hot", "45", "50", "35", "40", "45", "50")
    )
    runner = CliRunner()
    done = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "o"), "--no-report"])
    assert done.exit_code == 2
    assert "line 3" in done.output and "temperature_c = 'hot'" in done.output
    lines = (folder / "manifest.csv").read_text().replace("hot", "30").splitlines()
    lines = [lines[0] + ",temperature [K]"] + [line + ",300" for line in lines[1:]]
    (folder / "manifest.csv").write_text("\n".join(lines) + "\n")
    done = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "o"), "--no-report"])
    assert done.exit_code == 2
    assert "two temperature columns" in done.output


def test_oil_settings_in_si():
    """The [oil] table read into SI (data-sheet points in K and m^2/s, 40 degC default)."""
    from cylfric.io.campaign import _oil

    oil = _oil({"viscosity_40C": "46 mm2/s", "viscosity_100C": "6.8"}, "campaign.toml")
    assert_allclose(oil.points, OIL_VG46, rtol=1e-12)
    assert oil.reference_temperature == pytest.approx(313.15) and oil.temperature is None
