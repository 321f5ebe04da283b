"""``--json`` for scripts and tables that never cut a number (issue 24 item 5)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.cli.common import _numeric
from cylfric.model import FrictionModel

runner = CliRunner()


@pytest.fixture
def sheet(tmp_path):
    model = FrictionModel().replace(
        validity={
            "pressure_min": 5e5,
            "pressure_max": 160e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.135,
        }
    )
    path = tmp_path / "datasheet.json"
    path.write_text(json.dumps(model.to_datasheet()))
    return path


def _json(result):
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_show_json_gives_si_coefficients_with_units(sheet):
    document = _json(runner.invoke(app, ["show", str(sheet), "--json"]))
    slope = document["parameters"]["F_c.slope"]
    assert slope["unit"] == "N/Pa" and slope["value"] == pytest.approx(0.5e-5)
    assert document["pressure_reference"] == "mean"
    assert document["validity"]["pressure_max"] == 160e5


def test_catalog_and_drift_and_export_json(tmp_path, sheet):
    db = str(tmp_path / "c.sqlite")
    assert (
        runner.invoke(app, ["catalog", "add", str(sheet), "--name", "A", "--db", db]).exit_code == 0
    )
    listed = _json(runner.invoke(app, ["catalog", "list", "--db", db, "--json"]))
    assert [e["name"] for e in listed["entries"]] == ["A"]
    shown = _json(runner.invoke(app, ["catalog", "show", "A", "--db", db, "--json"]))
    assert shown["name"] == "A" and "bore [m]" in shown["metadata"]
    ranked = _json(
        runner.invoke(
            app, ["catalog", "select", "--pressure", "50", "--velocity", "10", "--db", db, "--json"]
        )
    )
    expected = FrictionModel().friction(0.010, 50e5)
    assert ranked["ranked"][0]["friction [N]"] == pytest.approx(expected)
    drift = _json(runner.invoke(app, ["drift", str(sheet), str(sheet), "--json"]))
    assert all(row["change"] == 0 for row in drift["rows"])
    exported = _json(
        runner.invoke(
            app, ["export", str(sheet), "--to", "matlab", "--out", str(tmp_path / "m"), "--json"]
        )
    )
    assert exported["lossless"] and len(exported["files"]) == 4


@pytest.mark.parametrize(
    ("text", "numeric"),
    [
        ("70.18", True),
        ("-3.2e-05", True),
        ("0.947-7.02", True),
        ("70.2 ± 0.05", True),
        ("12.3 N", False),
        ("yes", False),
        ("-", True),
    ],
)
def test_numeric_cells_are_recognised(text, numeric):
    assert _numeric(text) is numeric


def test_a_wide_table_is_printed_wider_rather_than_cutting_numbers(tmp_path):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    generate_campaign(
        tmp_path / "c", BenchSettings.clean(pressures_bar=(10.0, 90.0), speeds_mm_s=(2, 10, 50))
    )
    fitted = runner.invoke(
        app, ["fit", str(tmp_path / "c"), "--out", str(tmp_path / "o"), "--no-report"]
    )
    assert fitted.exit_code == 0, fitted.output
    sheet = tmp_path / "o" / "datasheet.json"  # with its per-pressure table (7 columns)
    result = runner.invoke(app, ["show", str(sheet)], env={"COLUMNS": "40"})
    assert "F_c(p)" in result.output
    assert result.exit_code == 0, result.output
    assert "…" not in result.output
    table = json.loads(sheet.read_text())["per_pressure"]
    for row in table:  # every number of the per-pressure table, whole
        assert f"{row['F_c']:.1f}" in result.output and f" {row['n_points']} " in result.output
