"""``cylfric catalog ...`` and ``cylfric drift``: the commands, their error paths, and the
worked example of docs/catalog.md on the real Zillen data."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel

runner = CliRunner()
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _sheet(tmp_path, ratio=1.0, name="datasheet.json") -> Path:
    """The thesis law (eq. 4.1-4.3) scaled by ``ratio`` with a made-up 1 % diagonal
    covariance and the thesis' validity ranges, written to a file."""
    import numpy as np

    model = FrictionModel()
    coefficients = model.coefficients(include_dynamic=False)
    for key in ("F_c", "F_s", "sigma_2"):
        coefficients[key] = {c: v * ratio for c, v in coefficients[key].items()}
    model = model.replace(coefficients=coefficients)
    names = ["F_c.intercept", "F_c.slope", "F_s.intercept", "F_s.slope"]
    values = {n: model.parameters[n].value for n in names}
    model = model.replace(
        covariance=(names, np.diag([(0.01 * values[n]) ** 2 for n in names])),
        statistics={"dof": 100},
        validity={
            "pressure_min": 5e5,
            "pressure_max": 160e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.135,
        },
    )
    path = tmp_path / name
    path.write_text(json.dumps(model.to_datasheet()))
    return path


def _run(*args, env=None):
    return runner.invoke(app, [str(a) for a in args], env=env)


def test_catalog_commands_end_to_end(tmp_path):
    db = tmp_path / "seals.sqlite"
    a = _sheet(tmp_path, 1.0, "a.json")
    b = _sheet(tmp_path, 0.8, "b.json")
    result = _run(
        "catalog",
        "add",
        a,
        "--name",
        "A",
        "--bore",
        "40mm",
        "--rod",
        "28",
        "--temperature",
        "40degC",
        "--seal",
        "U-cup",
        "--db",
        db,
    )
    assert result.exit_code == 0, result.output
    result = _run(
        "catalog", "add", b, "--name", "B", "--bore", "4cm", env={"CYLFRIC_CATALOG": str(db)}
    )
    assert result.exit_code == 0, result.output
    from cylfric.catalog import Catalog

    catalog = Catalog(db)
    assert catalog.metadata("A")["bore"] == pytest.approx(0.040)
    assert catalog.metadata("A")["rod"] == pytest.approx(0.028)
    assert catalog.metadata("A")["temperature"] == pytest.approx(313.15)
    assert catalog.metadata("B")["bore"] == pytest.approx(0.040)

    result = _run("catalog", "list", "--db", db)
    assert result.exit_code == 0 and "U-cup" in result.output and "B" in result.output
    result = _run("catalog", "show", "A", "--db", db)
    assert result.exit_code == 0 and "F_c(p)" in result.output and "40 degC" in result.output

    result = _run("catalog", "select", "--pressure", "100bar", "--velocity", "20mm/s", "--db", db)
    assert result.exit_code == 0, result.output
    assert result.output.index(" B ") < result.output.index(" A ")  # B has 0.8x the friction
    mid = FrictionModel().friction(0.020, 100e5)  # 135.7 N, the thesis law
    result = _run(
        "catalog",
        "select",
        "--pressure",
        "100",
        "--velocity",
        "20",
        "--max-friction",
        f"{0.9 * mid:.1f}N",
        "--db",
        db,
    )
    assert result.exit_code == 0 and " B " in result.output and " A " not in result.output

    result = _run(
        "catalog",
        "compare",
        "A",
        "B",
        "--out",
        tmp_path / "cmp",
        "--pressures",
        "20,150",
        "--speeds",
        "5,50",
        "--db",
        db,
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "cmp" / "compare.png").exists()
    assert len((tmp_path / "cmp" / "compare.csv").read_text().splitlines()) == 1 + 8

    out = tmp_path / "pred.json"
    result = _run("catalog", "predict", "A", "--bore", "63mm", "--out", out, "--db", db)
    assert result.exit_code == 0, result.output
    assert "k = 63 mm / 40 mm = 1.575" in result.output and "10%" in result.output
    predicted = FrictionModel.from_datasheet(out)
    assert predicted.friction(0.02, 80e5) == pytest.approx(
        1.575 * catalog.model("A").friction(0.02, 80e5), rel=1e-12
    )

    export = tmp_path / "export.json"
    assert _run("catalog", "export", export, "--db", db).exit_code == 0
    other = tmp_path / "other.sqlite"
    result = _run("catalog", "import", export, "--db", other)
    assert result.exit_code == 0 and "imported 2 entries" in result.output
    assert Catalog(other).get("A") == catalog.get("A")
    assert _run("catalog", "remove", "B", "--db", other).exit_code == 0
    assert Catalog(other).names() == ["A"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["catalog", "show", "nope"], "'nope' is not in the catalogue"),
        (["catalog", "add", "{a}", "--name", "A"], "'A' is already in the catalogue"),
        (["catalog", "add", "{missing}", "--name", "C"], "missing.json: cannot read"),
        (["catalog", "add", "{a}", "--name", "C", "--bore", "fast"], "cannot read 'fast'"),
        (
            ["catalog", "add", "{a}", "--name", "C", "--bore", "40,50"],
            "--bore '40,50': expected one",
        ),
        (["catalog", "add", "{a}", "--name", "C", "--temperature", "hot"], "--temperature 'hot'"),
        (
            ["catalog", "add", "{a}", "--name", "C", "--bore", "40mm", "--rod", "50mm"],
            "must be smaller than the bore",
        ),
        (
            ["catalog", "select", "--pressure", "100bar", "--velocity", "3N"],
            "expected a velocity unit",
        ),
        (
            ["catalog", "select", "--pressure", "1bar", "--velocity", "1", "--max-friction", "-4"],
            "max_friction = -4.0 N",
        ),
        (
            [
                "catalog",
                "predict",
                "A",
                "--bore",
                "63mm",
                "--out",
                "{tmp}/p.json",
                "--contact",
                "rod",
            ],
            "does not record the tested rod",
        ),
        (["catalog", "predict", "A", "--bore", "400mm", "--out", "{tmp}/p.json"], "beyond 0.25-4"),
        (["catalog", "import", "{a}"], "format: expected 'cylfric-catalog/1'"),
        (["catalog", "compare", "A", "nope", "--out", "{tmp}/c"], "'nope' is not in"),
        (["drift", "{missing}"], "missing.json: not found"),
        (["drift", "{a}"], "no points.csv beside the datasheet"),
        (["drift", "{a}", "{a}", "--order", "mtime"], "--order and --campaign apply to one"),
    ],
)
def test_bad_input_exits_2_naming_the_problem(tmp_path, args, message):
    db = tmp_path / "seals.sqlite"
    a = _sheet(tmp_path, name="a.json")
    assert _run("catalog", "add", a, "--name", "A", "--bore", "40mm", "--db", db).exit_code == 0
    filled = [x.format(a=a, missing=tmp_path / "missing.json", tmp=tmp_path) for x in args]
    result = runner.invoke(app, filled, env={"CYLFRIC_CATALOG": str(db)})
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output


def test_drift_command_writes_tables(tmp_path):
    a = _sheet(tmp_path, 1.0, "a.json")
    b = _sheet(tmp_path, 1.1, "b.json")
    result = _run("drift", a, b, "--out", tmp_path / "drift")
    assert result.exit_code == 0, result.output
    assert "25 of 25 operating points changed" in result.output
    summary = json.loads((tmp_path / "drift" / "drift.json").read_text())
    assert summary["significant_points"] == 25
    result = _run("drift", a, a)
    assert result.exit_code == 0 and "0 of 25 operating points changed" in result.output


def test_zillen_worked_example(shared_data, tmp_path):
    """docs/catalog.md: the three Zillen seals fitted one by one (--glob), catalogued,
    compared and ranked; then the run-order trend of one seal."""
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    db = tmp_path / "seals.sqlite"
    for seal in ("O-ring", "NAPN", "PK"):
        out = tmp_path / "fits" / seal
        result = _run("fit", folder, "--glob", f"{seal}_*", "--out", out, "--no-report")
        assert result.exit_code == 0, result.output
        sheet = json.loads((out / "datasheet.json").read_text())
        files = {Path(f["name"]).name for f in sheet["fit"]["source"]["files"]}
        assert files == {f"{seal}_{p}bar.csv" for p in (1, 3, 5, 7)}  # the glob took 4 files
        result = _run(
            "catalog",
            "add",
            out,
            "--name",
            f"zillen-{seal}",
            "--seal",
            seal,
            "--bore",
            "25mm",
            "--fluid",
            "air",
            "--db",
            db,
        )
        assert result.exit_code == 0, result.output
    from cylfric.catalog import Catalog

    catalog = Catalog(db)
    ranked = catalog.select(5e5, 0.010)
    # regression values of docs/catalog.md (Coulomb levels at 5 bar: PK 5.3, O-ring 6.9,
    # NAPN 9.5 N); the dataset README gives +-2-3 N repeatability between re-runs
    assert list(ranked["name"]) == ["zillen-PK", "zillen-O-ring", "zillen-NAPN"]
    assert ranked["friction [N]"].tolist() == pytest.approx([5.33, 6.91, 9.56], abs=0.01)
    assert ranked["inside validity"].all()
    result = _run(
        "catalog",
        "compare",
        "zillen-O-ring",
        "zillen-NAPN",
        "zillen-PK",
        "--out",
        tmp_path / "compare",
        "--pressures",
        "1,4,7",
        "--speeds",
        "10mm/s",
        "--db",
        db,
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "compare" / "compare.svg").stat().st_size > 10_000
    result = _run("drift", tmp_path / "fits" / "O-ring", "--out", tmp_path / "warmup")
    assert result.exit_code == 0, result.output
    assert "within runs: +0.02547" in result.output  # friction rises along the 10 strokes
