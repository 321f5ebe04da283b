"""The force balance is checked, not assumed (issue 39, item 2).

A rig's load cell reads the pressure force too; with the right ``load_cell_sign`` the
balance's ``A_a p_a - A_b p_b`` cancels it, with the wrong one the two add and the runs'
offset follows the pressure force with a slope of 2. Checked on a rig written apart from
cylfric (tests/synthetic_rig.py: the true balance, eq. 3.1, with the rig's own signs) and on
the real Zillen PK seal (../shared), where on main the recipe without its two sign keys gave
exit 0 and F_c slope 1.22 N/bar against 0.71 with them (the offset +99.8 N/bar: twice the
piston's 49.1 N/bar). On main, ``test_*_without_the_sign_keys_*`` and every
``ForceBalanceError`` test fail (no such check; the both-signs-wrong case was fitted).
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from synthetic_rig import friction_law, write_campaign, write_run
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.quality import QualityError, assess
from cylfric.quality.plausibility import ForceBalanceError, check_force_balance
from cylfric.steady_state import extract_campaign

RECIPE = Path(__file__).resolve().parents[1] / "examples" / "zillen2021" / "campaign.toml"
WRONG = [(None, None), (-1, None), (None, -1)]  # the recipe's (load_cell_sign, position_sign)
runner = CliRunner()


def _extraction(folder):
    return extract_campaign(folder, workers=1)


def test_the_right_balance_passes_and_gives_the_rigs_friction(tmp_path):
    extraction = _extraction(write_campaign(tmp_path / "c", recipe_signs=(-1, -1)))
    report = assess(extraction)
    assert report.excluded.empty and report.notes == ()
    runs = extraction.points[extraction.points["flag"].eq("ok")].groupby("run")
    level = runs["friction [N]"].median().to_numpy()
    bar = runs["pressure [Pa]"].median().to_numpy() / 1e5
    # the rig's law at the chamber pressure (each direction's own pressure: within 0.1 N)
    np.testing.assert_allclose(level, friction_law(bar), atol=0.1)


@pytest.mark.parametrize("signs", WRONG)
def test_each_wrong_sign_combination_is_refused_naming_the_keys(signs, tmp_path):
    folder = write_campaign(tmp_path / "c", recipe_signs=signs)
    with pytest.raises(ForceBalanceError, match="force balance contradicts the data") as caught:
        assess(_extraction(folder))
    text = str(caught.value)
    assert str(folder / "campaign.toml") in text
    assert "--accept-force-balance" in text
    lc, pos = signs
    if lc is None:  # the load cell's sign adds the pressure force: the offset follows it
        assert "slope of 2 " in text and "load_cell_sign = -1" in text
        if pos is None:  # both wrong: the friction is positive, both keys are named
            assert "load_cell_sign = -1 and position_sign = -1" in text
    else:  # the position's sign only: the friction is below 0
        assert "below 0 N in 8 of 8 runs" in text and "Set position_sign = -1" in text
    assert "(not set: the default)" in text  # the missing key is said to be missing


def test_accepting_gives_notes_and_the_gate_goes_on(tmp_path):
    extraction = _extraction(write_campaign(tmp_path / "c", recipe_signs=(None, None)))
    report = assess(extraction, accept_force_balance=True)
    assert len(report.notes) == 1
    assert report.notes[0].startswith("accepted (--accept-force-balance)")
    assert report.excluded.empty


def test_a_friction_that_follows_the_pressure_force_is_refused(tmp_path):
    """Runs with one stroke have no offset of their own (the campaign's is used): with the
    load cell's sign wrong their friction carries twice the pressure force."""
    folder = tmp_path / "c"
    write_campaign(folder, pressures_bar=(4.0,), repeats=2, recipe_signs=(None, None))
    area = math.pi / 4 * 0.025**2
    rows = (folder / "manifest.csv").read_text().splitlines()
    for index, p in enumerate((1.0, 3.0, 5.0, 7.0, 2.0, 6.0), start=2):
        name = f"run_{index:02d}_p{p:g}bar.txt"
        write_run(folder / name, p, area_a=area, area_b=0.0, strokes=1, seed=index)
        rows.append(f"{name},{p:g}")
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    extraction = _extraction(folder)
    with pytest.raises(ForceBalanceError, match="runs' friction follows the balance's pressure"):
        check_force_balance(extraction)


def test_a_rig_without_pressure_in_its_balance_is_not_judged_by_it(tmp_path):
    """No areas (the thesis rig: equal areas, equal pressures): nothing to compare the offset
    with; the right signs pass, a wrong position sign is still the friction below 0."""
    folder = write_campaign(tmp_path / "c", kind="double-rod", rod_mm=10, both_chambers=True)
    assert assess(_extraction(folder)).notes == ()


# ------------------------------------------------------------ the real Zillen PK seal
@pytest.fixture(scope="module")
def pk(shared_data, tmp_path_factory):
    folder = tmp_path_factory.mktemp("pk")
    for path in sorted((shared_data / "zillen2021-pneumatic-seals").glob("PK_*bar.csv")):
        shutil.copy(path, folder)
    return folder


def _recipe(tmp_path, signs):
    text = RECIPE.read_text()
    for key, value in zip(("load_cell_sign", "position_sign"), signs, strict=True):
        if value is None:
            text = "\n".join(line for line in text.splitlines() if not line.startswith(key))
    path = tmp_path / "recipe.toml"
    path.write_text(text + "\n")
    return path


@pytest.mark.parametrize("signs", WRONG)
def test_zillen_pk_without_the_sign_keys_exits_2_naming_them(pk, signs, tmp_path):
    recipe = _recipe(tmp_path, signs)
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["fit", str(pk), "--config", str(recipe), "--out", str(out), "--no-report"]
    )
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert "force balance contradicts the data" in text
    assert str(recipe) in text
    assert ("load_cell_sign = -1" if signs[0] is None else "position_sign = -1") in text
    assert not out.exists()


def test_zillen_pk_with_the_sign_keys_passes_the_check(pk):
    from cylfric.io.campaign import Campaign

    campaign = Campaign.open(pk, config=str(RECIPE))
    extraction = extract_campaign(campaign, workers=1)
    assert check_force_balance(extraction) == []
    assert isinstance(ForceBalanceError("x"), QualityError)  # a ValueError: exit 2


def test_zillen_pk_accepted_without_the_sign_keys_fits_with_a_note(pk, tmp_path):
    recipe = _recipe(tmp_path, (None, None))
    out = tmp_path / "out"
    result = runner.invoke(
        app,
        ["fit", str(pk), "--config", str(recipe), "--out", str(out), "--no-report"]
        + ["--accept-force-balance"],
    )
    assert result.exit_code == 0, result.output
    import json

    notes = json.loads((out / "datasheet.json").read_text())["notes"]
    assert any(n.startswith("accepted (--accept-force-balance)") for n in notes)
