"""`cylfric control` on every datasheet kind, with assumed dynamic parameters named, the
sigma_0 sensitivity in its outputs, a reference file ramped in, progress on stderr."""

from __future__ import annotations

import json
import math

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel

AXIS = '[axis]\ncontrol_rate = "1 kHz"\n'


def _sheet(tmp_path, model, name="sheet.json"):
    path = tmp_path / name
    path.write_text(json.dumps(model.to_datasheet()))
    return path


def _flat(path) -> str:
    """A generated file's comment text with the line breaks and comment prefixes removed."""
    return " ".join(line.strip(" */%") for line in path.read_text().splitlines())


def _run(args):
    return CliRunner().invoke(app, ["control", *args])


@pytest.mark.parametrize(
    "law, coefficients",
    [
        ("coulomb", {"F_c": {"intercept": 60.0, "slope": 3e-6}}),
        ("coulomb_viscous", {"F_c": {"intercept": 60.0, "slope": 3e-6}, "sigma_2": 300.0}),
    ],
)
def test_control_on_reduced_datasheets(tmp_path, law, coefficients):
    # a Coulomb-only datasheet (one speed per direction) failed with "KeyError: None", exit 1
    sheet = _sheet(tmp_path, FrictionModel(coefficients, friction_law=law))
    ref = tmp_path / "ref.csv"
    ref.write_text("time [s],position [mm]\n0,100\n0.5,100.5\n1,100\n")
    done = _run([str(sheet), "--out", str(tmp_path / "out"), "--no-robustness",
                 "--reference", str(ref)])  # fmt: skip
    assert done.exit_code == 0, done.output
    doc = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert set(doc["compensators"]) == {"none", "coulomb", "static", "lugre", "oracle"}
    assert all(m["rms_error_m"] > 0 for m in doc["compensators"].values())


def test_assumed_sigma_named_and_sensitivity_written(tmp_path):
    sheet = _sheet(tmp_path, FrictionModel())  # the thesis law: sigma_0, sigma_1 assumed
    ref = tmp_path / "ref.csv"  # starts 2 mm away from the default start position (100 mm)
    ref.write_text("time [s],position [mm]\n0,102\n0.5,102.5\n1,102\n")
    done = _run([str(sheet), "--out", str(tmp_path / "out"), "--no-robustness",
                 "--reference", str(ref)])  # fmt: skip
    assert done.exit_code == 0, done.output
    err = done.stderr if done.stderr_bytes is not None else done.output
    assert "sigma_0 = 1e+06 N/m" in err and "ASSUMED" in err and "presliding" in err
    assert "starts at 102 mm" in err and "ramp" in err
    assert "running the loop: none" in err and "compiles" in err
    doc = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert doc["dynamic_parameters"]["sigma_0"]["status"] == "assumed"
    assert doc["reference"].endswith("(ramped in)")
    cases = doc["sensitivity"]["cases"]
    assert [row["factor"] for row in cases["sigma_0"]] == [0.1, 0.3, 1.0, 3.0, 10.0]
    assert [row["factor"] for row in cases["friction_level"]] == [0.8, 1.0, 1.2]
    # the plant's sigma_0 changes the loop: the ratios are not all one number
    ratios = {round(row["lugre_over_none"], 6) for row in cases["sigma_0"]}
    assert len(ratios) > 1
    html = (tmp_path / "out" / "control.html").read_text()
    assert "assumed, not identified" in html and "Sensitivity of the LuGre gain" in html
    # ... and the exports say it in their headers
    done = _run([str(sheet), "--out", str(tmp_path / "exp"), "--export-compensator", "c,matlab",
                 "--export-only"])  # fmt: skip
    assert done.exit_code == 0, done.output
    header = _flat(tmp_path / "exp" / "compensator" / "cylfric_compensator_params.h")
    assert "sigma_0 = 1e+06 N/m (ASSUMED, not identified)" in header
    matlab = next((tmp_path / "exp" / "compensator").glob("*_step.m")).read_text()
    assert "ASSUMED" in matlab


def test_identified_sigma_not_flagged(tmp_path):
    coefficients = {**FrictionModel().coefficients(), "sigma_0": 1e7, "sigma_1": 2e4}
    sheet = _sheet(tmp_path, FrictionModel(coefficients))
    done = _run([str(sheet), "--out", str(tmp_path / "exp"), "--export-compensator", "c",
                 "--export-only"])  # fmt: skip
    assert done.exit_code == 0, done.output
    assert "ASSUMED" not in done.output
    header = _flat(tmp_path / "exp" / "compensator" / "cylfric_compensator_params.h")
    assert "sigma_0 = 1e+07 N/m (identified)" in header


def test_force_filter_option_reaches_loop_and_export(tmp_path):
    sheet = _sheet(tmp_path, FrictionModel())
    ref = tmp_path / "ref.csv"
    ref.write_text("time [s],position [mm]\n0,100\n0.5,100.5\n1,100\n")
    done = _run([str(sheet), "--out", str(tmp_path / "out"), "--no-robustness",
                 "--reference", str(ref), "--force-filter-ms", "3",
                 "--export-compensator", "c", "--velocity-input"])  # fmt: skip
    assert done.exit_code == 0, done.output
    doc = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert doc["controller"]["force_filter_s"] == pytest.approx(3e-3)
    header = (tmp_path / "out" / "compensator" / "cylfric_compensator_params.h").read_text()
    assert "#define CYLFRIC_VELOCITY_INPUT (1.0)" in header
    gain = -math.expm1(-1e-3 / 3e-3)
    assert f"#define CYLFRIC_FORCE_FILTER_GAIN ({gain!r})" in header
    bad = _run([str(sheet), "--out", str(tmp_path / "o2"), "--force-filter-ms", "-1"])
    assert bad.exit_code == 2 and "--force-filter-ms" in bad.output
