"""Issue 22, deliverable 7: one model per seal, never pooled silently.

A campaign whose runs carry several seal labels (a ``seal`` group of ``name_pattern`` or a
manifest.csv column ``seal``) gives OUT/<seal>/datasheet.json for each seal and the summary
OUT/seals.csv; ``--seal NAME`` fits one seal into OUT; a campaign of one seal is fitted as
before (tests/test_golden_outputs.py).
"""

from __future__ import annotations

import csv
import json
import shutil
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest
from fit_helpers import runner  # tests/fit_helpers.py

from cylfric.cli import app
from cylfric.model import FrictionModel
from cylfric.pipeline import SEAL_COLUMNS, fit_campaign, fit_seals
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.simulate.plant import Cylinder

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# small campaigns (as tests/test_many.py): 60 mm strokes, 2 pressures x 6 speeds
SMALL = BenchSettings.clean(
    cylinder=Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060),
    pressures_bar=(20.0, 120.0),
    speeds_mm_s=(2, 4, 8, 15, 30, 60),
)
RATIO = 1.5
"""Seal B's friction: the thesis law's F_c, F_s and sigma_2 times this (seal A: the law)."""


def _scaled(model: FrictionModel, ratio: float) -> FrictionModel:
    coefficients = model.coefficients(include_dynamic=False)
    for name in ("F_c", "F_s", "sigma_2"):
        coefficients[name] = {
            c: (v if c == "law" else v * ratio) for c, v in coefficients[name].items()
        }
    return model.replace(coefficients=coefficients)


def _two_seals(folder: Path, seals=("A", "B")) -> Path:
    """One folder with the runs of two virtual seals, labelled in manifest.csv's ``seal``
    column (the second seal's friction :data:`RATIO` times the first's)."""
    rows = []
    for index, (seal, ratio) in enumerate(zip(seals, (1.0, RATIO), strict=True)):
        part = folder.parent / f".part{index}"
        settings = replace(SMALL, friction=_scaled(FrictionModel(), ratio), seed=index)
        generate_campaign(part, settings)
        with open(part / "manifest.csv", newline="") as handle:
            for row in csv.DictReader(handle):
                name = f"s{index}_{row['file']}"
                shutil.move(part / row["file"], folder / name)
                rows.append({**row, "file": name, "seal": seal})
        shutil.rmtree(part)
    with open(folder / "manifest.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return folder


@pytest.fixture(scope="module")
def two_seals(tmp_path_factory):
    folder = tmp_path_factory.mktemp("seals") / "campaign"
    folder.mkdir()
    return _two_seals(folder)


def _fit(*args):
    return runner.invoke(app, ["fit", *map(str, args)])


def _files(sheet) -> set[str]:
    return {Path(f["name"]).name for f in sheet["fit"]["source"]["files"]}


def test_two_seals_give_one_datasheet_each(two_seals, tmp_path):
    out = tmp_path / "out"
    result = _fit(two_seals, "--out", out, "--no-report")
    assert result.exit_code == 0, result.output
    assert "2 seals, one model each: A, B" in result.output
    summary = pd.read_csv(out / "seals.csv")
    assert list(summary.columns) == list(SEAL_COLUMNS)
    assert list(summary["seal"]) == ["A", "B"] and list(summary["runs [-]"]) == [12, 12]
    assert not (out / "datasheet.json").exists()  # never one pooled model
    truth = FrictionModel().coefficients()["F_c"]["intercept"]  # 70.2 N (thesis eq. 4.1)
    for index, seal in enumerate(("A", "B")):
        sheet = json.loads((out / seal / "datasheet.json").read_text())
        assert _files(sheet) == {p.name for p in two_seals.glob(f"s{index}_*")}
        assert sheet["name"] == f"campaign: {seal}"
        # each seal's own level: seal B is 1.5 times seal A (a pooled fit lies between)
        expected = truth * (1.0, RATIO)[index]
        assert sheet["parameters"]["F_c"]["intercept"] == pytest.approx(expected, rel=0.03)
    listed = (out / ".cylfric-output").read_text()
    assert "A/datasheet.json" in listed and "seals.csv" in listed
    again = _fit(two_seals, "--out", out, "--no-report")  # the output folder is re-used
    assert again.exit_code == 0, again.output


def test_seal_picks_one_and_an_unknown_one_is_refused(two_seals, tmp_path):
    out = tmp_path / "b"
    result = _fit(two_seals, "--out", out, "--no-report", "--seal", "B")
    assert result.exit_code == 0, result.output
    sheet = json.loads((out / "datasheet.json").read_text())  # into OUT, as a plain fit
    assert _files(sheet) == {p.name for p in two_seals.glob("s1_*")}
    assert not (out / "seals.csv").exists()
    result = _fit(two_seals, "--out", tmp_path / "c", "--no-report", "--seal", "C")
    assert result.exit_code == 2
    text = " ".join(result.output.split())
    assert "no seal 'C'" in text and "the seals found: A, B" in text
    assert not (tmp_path / "c").exists()


def test_the_python_api_never_pools_seals(two_seals, tmp_path):
    with pytest.raises(ValueError, match=r"holds 2 seals \(A, B\); a model pools no seals"):
        fit_campaign(two_seals, tmp_path / "pooled", report=False)
    assert not (tmp_path / "pooled").exists()
    result = fit_seals(two_seals, tmp_path / "each", report=False, workers=1)
    assert list(result.seals) == ["A", "B"]
    assert result.seals["B"].out == tmp_path / "each" / "B"
    assert result.seals["B"].files["datasheet"] == tmp_path / "each" / "B" / "datasheet.json"
    assert (
        result.summary["F_c at pressure max [N]"].iloc[1]
        > result.summary["F_c at pressure max [N]"].iloc[0]
    )


def test_json_lists_the_seals(two_seals, tmp_path):
    out = tmp_path / "out"
    result = _fit(two_seals, "--out", out, "--no-report", "--json")
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert list(document["seals"]) == ["A", "B"]
    assert document["seals"]["A"]["datasheet"] == str(out / "A" / "datasheet.json")
    assert document["seals"]["B"]["summary"]["runs [-]"] == 12


def test_fit_many_gives_a_clear_row_for_a_campaign_of_several_seals(two_seals, tmp_path):
    from cylfric.many import fit_many

    root = tmp_path / "root"
    shutil.copytree(two_seals, root / "line")
    result = fit_many(root, tmp_path / "many", scheduler="serial", report=False)
    (row,) = result.rows
    assert row["status"] == "failed"
    assert "holds 2 seals (A, B); a model pools no seals" in row["reason"]


@pytest.mark.parametrize(
    "label", ["../escaped", "a/b", ".cylfric-output", "seals.csv", "..", "x\x1b[2Jy"]
)
def test_a_hostile_seal_name_is_refused_and_nothing_leaves_out(two_seals, tmp_path, label):
    folder = shutil.copytree(two_seals, tmp_path / "campaign")
    manifest = folder / "manifest.csv"
    manifest.write_text(manifest.read_text().replace(",B\n", f",{label}\n"))
    out = tmp_path / "fits" / "out"
    result = _fit(folder, "--out", out, "--no-report")
    assert result.exit_code == 2, result.output
    assert "cannot name a" in " ".join(result.output.split())
    assert "\x1b" not in result.output  # printed through escape.terminal
    assert [p.name for p in tmp_path.iterdir()] == ["campaign"]  # refused before writing


def test_a_seal_name_with_markup_is_data(two_seals, tmp_path):
    folder = shutil.copytree(two_seals, tmp_path / "campaign")
    label = "[bold red]PK $(id) <b>"
    manifest = folder / "manifest.csv"
    manifest.write_text(manifest.read_text().replace(",B\n", f",{label}\n"))
    out = tmp_path / "out"
    result = _fit(folder, "--out", out, "--no-report")
    assert result.exit_code == 0, result.output
    assert (out / label / "datasheet.json").is_file()  # a folder inside OUT, named as is
    assert "[bold red]PK" in result.output  # shown as text, not as rich markup
    assert list(pd.read_csv(out / "seals.csv")["seal"]) == ["A", label]


def test_runs_without_a_seal_beside_labelled_ones_are_refused(two_seals, tmp_path):
    folder = shutil.copytree(two_seals, tmp_path / "campaign")
    manifest = folder / "manifest.csv"
    lines = manifest.read_text().splitlines(keepends=True)
    lines[1] = lines[1].replace(",A\n", ",\n")
    manifest.write_text("".join(lines))
    result = _fit(folder, "--out", tmp_path / "out", "--no-report")
    assert result.exit_code == 2
    assert "1 run(s) carry no seal label (s0_run_000" in " ".join(result.output.split())


def test_zillen_folder_gives_one_datasheet_per_seal(shared_data, tmp_path):
    """The acceptance of issue 22: the shared Zillen folder and the shipped recipe."""
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    assert any((folder / "repeatability").glob("*.csv"))  # there, and not swept in
    out = tmp_path / "out"
    result = _fit(folder, "--out", out, "--no-report")
    assert result.exit_code == 0, result.output
    assert "3 seals, one model each: NAPN, O-ring, PK" in result.output
    summary = pd.read_csv(out / "seals.csv")
    assert list(summary["seal"]) == ["NAPN", "O-ring", "PK"]
    assert list(summary["runs [-]"]) == [4, 4, 4]
    for seal in ("NAPN", "O-ring", "PK"):
        sheet = json.loads((out / seal / "datasheet.json").read_text())
        assert _files(sheet) == {f"{seal}_{p}bar.csv" for p in (1, 3, 5, 7)}
    # each datasheet is the fit of that seal alone (the --glob fits of docs/catalog.md:
    # Coulomb levels at 5 bar PK 5.33, O-ring 6.91, NAPN 9.56 N; regression values)
    levels = {
        seal: FrictionModel.from_datasheet(
            json.loads((out / seal / "datasheet.json").read_text())
        ).params_at(5e5)["F_c"]
        for seal in ("PK", "O-ring", "NAPN")
    }
    assert [levels[s] for s in ("PK", "O-ring", "NAPN")] == pytest.approx(
        [5.33, 6.91, 9.56], abs=0.01
    )
