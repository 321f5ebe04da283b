"""cylfric.pipeline: one in-memory fit (``cylfric.fit``) behind every path.

Issue 39: the README's Python route (``identify(extract_campaign(folder).points).model``)
was another model than ``cylfric fit`` (the pressure reference ``mean`` instead of the
campaign's ``a``, no gate, no viscosity correction, no dynamic parameters): on the
single-acting Zillen PK seal at (5 bar, 0 bar) 3.60 N against the CLI's 5.33 N. Now both
go through :func:`cylfric.fit`; these tests fit the same campaigns both ways and compare
the datasheets byte for byte.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

import cylfric
from cylfric.cli import app
from cylfric.identify import identify
from cylfric.model import FrictionModel
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _both_ways(folder: Path, tmp_path: Path, *cli_options: str, **fit_options):
    """(datasheet of cylfric.fit(...).write, of ``cylfric fit``, the FitResult); the
    datasheets as text without their ``created`` time stamp, which is the only difference."""
    result = cylfric.fit(folder, **fit_options)
    written = result.write(tmp_path / "python", report=False)
    cli = runner.invoke(
        app, ["fit", str(folder), "--out", str(tmp_path / "cli"), "--no-report", *cli_options]
    )
    assert cli.exit_code == 0, cli.output
    return (
        _undated(Path(written.files["datasheet"])),
        _undated(tmp_path / "cli" / "datasheet.json"),
        result,
    )


def _undated(path: Path) -> str:
    lines = path.read_text().splitlines()
    dated = [line for line in lines if line.strip().startswith('"created":')]
    assert len(dated) == 1
    return "\n".join(line for line in lines if line not in dated)


def test_python_route_and_cli_give_the_same_datasheet_on_the_bench(tmp_path):
    folder = tmp_path / "bench"
    generate_campaign(folder, BenchSettings(pressures_bar=(10, 80, 159), seed=3))
    python, cli, result = _both_ways(folder, tmp_path)
    assert python == cli
    assert isinstance(result, cylfric.FitResult)
    from_file = FrictionModel.from_datasheet(tmp_path / "cli" / "datasheet.json")
    assert result.model.coefficients() == from_file.coefficients()  # the in-memory model


def test_python_route_and_cli_give_the_same_datasheet_on_a_valve_rig(tmp_path):
    from cylfric.simulate.valve_bench import ValveRigSettings, generate_valve_campaign

    folder = tmp_path / "rig"
    generate_valve_campaign(folder, ValveRigSettings(seed=1))
    python, cli, result = _both_ways(folder, tmp_path)
    assert python == cli
    # the rig's campaign.toml says which pressures balance the force: a pressure basis from
    # the campaign, not identify()'s assumption
    assert not result.model.pressure_reference_basis["stated_by"].startswith("default: identify()")


def test_zillen_single_acting_seal_python_route_is_the_cli_model(shared_data, tmp_path):
    """The issue's case: the PK seal (single-acting, reference "a") at (5 bar, 0 bar)."""
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    python, cli, result = _both_ways(folder, tmp_path, "--seal", "PK", seal="PK")
    assert python == cli
    model = result.model
    assert model.reference == "a"
    level = model.friction(0.01, model.operating_pressure(5e5, 0.0))
    from_file = FrictionModel.from_datasheet(tmp_path / "cli" / "datasheet.json")
    assert level == pytest.approx(from_file.friction(0.01, from_file.operating_pressure(5e5, 0.0)))
    # the pooled points of that seal through identify() without a reference: "mean" assumed,
    # which halves the single-acting chamber's pressure (the 3.60 N against 5.33 N)
    bare = identify(result.points, sensitivity=False)
    assert bare.model.reference == "mean"
    assert any("identify() was not told" in note for note in bare.notes)
    told = identify(result.points, sensitivity=False, pressure_reference="a")
    assert told.model.friction(0.01, told.model.operating_pressure(5e5, 0.0)) == pytest.approx(
        level, rel=1e-9
    )


def test_a_campaign_of_several_seals_needs_a_seal(shared_data, tmp_path):
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    with pytest.raises(ValueError, match=r"holds 3 seals \(NAPN, O-ring, PK\)"):
        cylfric.fit(folder)


def test_identify_refuses_an_unknown_pressure_reference(tmp_path):
    folder = tmp_path / "bench"
    generate_campaign(
        folder, BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=1)
    )
    points = cylfric.fit(folder).points
    with pytest.raises(ValueError, match="unknown pressure reference 'chamber'"):
        identify(points, pressure_reference="chamber")


def test_fit_result_write_refuses_an_out_inside_the_campaign(tmp_path):
    folder = tmp_path / "bench"
    generate_campaign(
        folder, BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=1)
    )
    result = cylfric.fit(folder)
    with pytest.raises(ValueError, match="inside the campaign folder"):
        result.write(folder / "fit")
    assert "points" in repr(result) and result.notes == list(result.identification.notes)


def test_the_datasheet_names_its_cylinder_and_the_catalogue_takes_the_bore(shared_data, tmp_path):
    """Issue 39.11: the bore is in the datasheet (catalog add asked for it again), and
    ``fit --json`` names the seal as ``show`` does (it printed "name": null)."""
    from cylfric.catalog import Catalog
    from cylfric.catalog.store import CatalogError

    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    out = tmp_path / "fit"
    done = runner.invoke(
        app, ["fit", str(folder), "--seal", "PK", "--out", str(out), "--no-report", "--json"]
    )
    assert done.exit_code == 0, done.output
    document = json.loads(done.stdout)
    assert document["name"] == "zillen: PK"
    sheet = json.loads((out / "datasheet.json").read_text())
    assert sheet["cylinder"] == {
        "kind": "single-acting",
        "bore": 0.025,  # examples/zillen2021/campaign.toml: bore = "25 mm"
        "rod": None,
        "area_a": pytest.approx(math.pi / 4 * 0.025**2),
        "area_b": 0.0,
    }
    catalog = Catalog(tmp_path / "seals.sqlite")
    catalog.add(out, "PK 25")
    assert catalog.list().loc[0, "bore [m]"] == pytest.approx(0.025)
    with pytest.raises(CatalogError, match="--bore 40 mm contradicts the datasheet's cylinder"):
        catalog.add(out, "PK 40", bore=0.040)


def test_print_model_shows_the_laws_and_parameters_show_engineering_units(tmp_path):
    folder = tmp_path / "bench"
    generate_campaign(
        folder,
        BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=1),
    )
    model = cylfric.fit(folder).model
    text = str(model)
    assert "F_c(p) = (" in text and "N/bar * p" in text and "sigma_0 = 1000 N/mm (assumed" in text
    slope = model.parameters["F_c.slope"]
    value, _, unit = slope.engineering()
    assert unit == "N/bar" and f"[{value:.6g} N/bar]" in repr(slope)
    assert f"value={slope.value:.6g} N/Pa" in repr(slope)


def test_the_report_says_what_its_degrees_of_freedom_and_scatter_components_are(tmp_path):
    """Issue 39.11: "degrees of freedom = 262" for 534 points and "repeatability 0.00089 %"
    were printed without a word of what they measure."""
    from cylfric.report.html import scatter_html

    folder = tmp_path / "bench"
    generate_campaign(
        folder,
        BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=1),
    )
    model = cylfric.fit(folder).model
    stats = model.statistics
    line = next(x for x in model.fit_report(min_correlation=1).splitlines() if "degrees" in x)
    runs = stats["dof"] + stats["n_variables"]
    assert stats["dof"] < stats["n_points"] - stats["n_variables"]  # clustered by run
    assert f"runs - variables = {runs} - {stats['n_variables']}" in line
    page = scatter_html(model.record["fit"]["scatter"], None)
    assert "what it measures" in page and "stroke to stroke in one file" in page


def test_identify_refuses_a_basis_without_its_keys(tmp_path):
    folder = tmp_path / "bench"
    generate_campaign(
        folder,
        BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=1),
    )
    points = cylfric.fit(folder).points
    with pytest.raises(ValueError, match=r"a basis needs \['chamber', 'kind', 'stated_by'\] too"):
        identify(points, pressure_reference={"rule": "a"})
