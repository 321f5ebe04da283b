"""FrictionModel.assumptions: what a datasheet assumed is said wherever it is used.

Issue 39.4: a datasheet from steady-state runs carries sigma_0/sigma_1 "assumed" (1e6 N/m);
``simulate`` and ``export`` used them without a word. Each now names them on stderr and in
its outputs; an identified pair is not flagged.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel

runner = CliRunner()
VALIDITY = {"pressure_min": 1e4, "pressure_max": 159e5, "velocity_min": 1e-3, "velocity_max": 0.135}
IDENTIFIED = {
    "sigma_0": ("identified", "presliding tests, 3 pressures"),
    "sigma_1": ("identified", "presliding tests, 3 pressures"),
}


@pytest.fixture(scope="module")
def sheets(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sheets")
    assumed = FrictionModel(validity=VALIDITY)  # sigma_0/sigma_1 at their defaults
    identified = FrictionModel(
        validity=VALIDITY, sigma_0=9.5e6, sigma_1=4.2e3, dynamic_status=IDENTIFIED
    )
    paths = {}
    for name, model in (("assumed", assumed), ("identified", identified)):
        paths[name] = folder / f"{name}.json"
        paths[name].write_text(json.dumps(model.to_datasheet()))
    return paths


def test_assumptions_name_the_assumed_parameters_only(sheets):
    assumed = FrictionModel.from_datasheet(sheets["assumed"]).assumptions()
    assert len(assumed) == 1 and "sigma_0 = 1000 N/mm" in assumed[0]
    assert "sigma_1 = 1.58 N*s/mm" in assumed[0] and "dynamic_parameters.md" in assumed[0]
    assert FrictionModel.from_datasheet(sheets["identified"]).assumptions() == []


@pytest.mark.parametrize("target", ["matlab", "modelica", "hopsan"])
def test_export_names_assumed_sigma_on_stderr_and_in_its_files(sheets, tmp_path, target):
    out = tmp_path / target
    result = runner.invoke(
        app, ["export", str(sheets["assumed"]), "--to", target, "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "assumed, not identified: sigma_0" in " ".join(result.stderr.split())
    written = " ".join(p.read_text(errors="replace") for p in out.rglob("*") if p.is_file())
    assert "assumed" in written.lower() and "typical of hydraulic seals" in written
    quiet = runner.invoke(
        app, ["export", str(sheets["identified"]), "--to", target, "--out", str(tmp_path / "i")]
    )
    assert quiet.exit_code == 0 and "assumed, not identified" not in quiet.stderr


def test_export_json_lists_the_assumptions(sheets, tmp_path):
    result = runner.invoke(
        app, ["export", str(sheets["assumed"]), "--to", "matlab", "--out", str(tmp_path), "--json"]
    )
    assert result.exit_code == 0, result.output
    assert "sigma_0 = 1000 N/mm" in json.loads(result.stdout)["assumptions"][0]


def test_simulate_names_assumed_sigma_on_stderr_and_in_simulation_json(sheets, tmp_path):
    result = runner.invoke(
        app, ["simulate", str(sheets["assumed"]), "--out", str(tmp_path), "--duration", "0.5s"]
    )
    assert result.exit_code == 0, result.output
    assert "assumed, not identified: sigma_0" in " ".join(result.stderr.split())
    record = json.loads((tmp_path / "simulation.json").read_text())
    assert "sigma_1 = 1.58 N*s/mm" in record["assumptions"][0]
    result = runner.invoke(
        app,
        ["simulate", str(sheets["identified"]), "--out", str(tmp_path / "i"), "--duration", "0.5s"],
    )
    assert result.exit_code == 0, result.output
    assert json.loads((tmp_path / "i" / "simulation.json").read_text())["assumptions"] == []
