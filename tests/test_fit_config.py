"""``cylfric fit DIR --config FILE``: a recipe from outside the data folder (issue 22).

Read-only data (the shared Zillen folder) is fitted with the shipped recipe without copying
it in; the folder is left untouched, the datasheet names the recipe, and a bad or missing
recipe is refused naming its own path (and line).
"""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from cylfric.cli import app

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RECIPE = EXAMPLES / "zillen2021" / "campaign.toml"


def _fit(*args):
    return CliRunner().invoke(app, ["fit", *map(str, args)])


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    return {
        p.relative_to(folder).as_posix(): (p.stat().st_size, p.stat().st_mtime_ns)
        for p in folder.rglob("*")
    }


def test_shared_zillen_folder_fitted_with_the_shipped_recipe(shared_data, tmp_path):
    folder = shared_data / "zillen2021-pneumatic-seals"
    assert not (folder / "campaign.toml").exists()  # the recipe is not in the data
    before = _snapshot(folder)
    out = tmp_path / "out"
    result = _fit(folder, "--config", RECIPE, "--out", out, "--no-report")
    assert result.exit_code == 0, result.output
    for seal in ("NAPN", "O-ring", "PK"):
        sheet = json.loads((out / seal / "datasheet.json").read_text())
        assert sheet["fit"]["source"]["recipe"] == str(RECIPE)
        assert sheet["model"]["pressure_reference_basis"]["kind"] == "single-acting"
        assert {f["name"] for f in sheet["fit"]["source"]["files"]} == {
            f"{seal}_{p}bar.csv" for p in (1, 3, 5, 7)
        }
    assert _snapshot(folder) == before  # nothing written into the data folder


def _small_campaign(folder: Path) -> Path:
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    generate_campaign(
        folder, BenchSettings.clean(pressures_bar=(10.0, 80.0), speeds_mm_s=(2, 10, 50))
    )
    return folder


def test_a_bad_recipe_names_its_own_path_and_line(tmp_path):
    folder = _small_campaign(tmp_path / "camp")
    recipe = tmp_path / "recipes" / "rig.toml"
    recipe.parent.mkdir()
    recipe.write_text(
        '[files]\nglob = "*.txt"\n\n[cylinder]\nbore = "50000 mm"\n', encoding="utf-8"
    )
    result = _fit(folder, "--config", recipe, "--out", tmp_path / "out", "--no-report")
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert "rig.toml" in text and "line 5" in text and "cylinder.bore" in text
    assert not (tmp_path / "out").exists()


def test_a_missing_recipe_is_refused_with_exit_2(tmp_path):
    folder = _small_campaign(tmp_path / "camp")
    missing = tmp_path / "nowhere.toml"
    result = _fit(folder, "--config", missing, "--out", tmp_path / "out")
    assert result.exit_code == 2
    text = " ".join(result.output.split())
    assert "--config" in text and "does not exist" in text and "nowhere.toml" in text
