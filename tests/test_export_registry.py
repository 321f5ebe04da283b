"""Every export target through the dispatcher and the command line (after the two branches
of issue 13 met): files written, loss reports exactly for the lossy targets."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.export import LOSSLESS, TARGETS, export
from cylfric.model import FrictionModel

VALIDITY = {
    "pressure_min": 0.1e5,
    "pressure_max": 159e5,
    "velocity_min": 1e-3,
    "velocity_max": 0.135,
}


@pytest.fixture(scope="module")
def sheet_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("sheet") / "datasheet.json"
    sheet = FrictionModel(validity=VALIDITY).to_datasheet()
    sheet["created"] = "2026-01-01T00:00:00"
    path.write_text(json.dumps(sheet))
    return path


@pytest.mark.parametrize("target", sorted(TARGETS))
def test_every_target_exports_through_the_dispatcher(target, sheet_path, tmp_path):
    result = export(sheet_path, target, tmp_path / target)
    assert result.files and all(p.exists() and p.stat().st_size > 0 for p in result.files)
    assert (result.loss is None) == (target in LOSSLESS)


def test_cli_exports_the_cylinder_fmu_and_refuses_element_elsewhere(sheet_path, tmp_path):
    runner = CliRunner()
    ok = runner.invoke(
        app,
        [
            "export",
            str(sheet_path),
            "--to",
            "fmu",
            "--element",
            "cylinder",
            "--out",
            str(tmp_path / "f"),
        ],
    )
    assert ok.exit_code == 0, ok.output
    assert list((tmp_path / "f").glob("*.fmu"))
    bad = runner.invoke(
        app,
        [
            "export",
            str(sheet_path),
            "--to",
            "matlab",
            "--element",
            "cylinder",
            "--out",
            str(tmp_path / "m"),
        ],
    )
    assert bad.exit_code == 2 and "--element is for --to fmu only" in bad.output
    unknown = runner.invoke(app, ["export", str(sheet_path), "--to", "fmu", "--element", "pump"])
    assert unknown.exit_code == 2 and "pump" in unknown.output
