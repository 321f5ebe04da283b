"""The campaign folder is a boundary (issue 43, item 4): no manifest row, glob or symbolic
link reads a file outside it, and manifest rows naming ``sub/run.txt`` are matched by their
path relative to the folder, not by base name. Every test here fails on the code before."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cylfric.io import BenchFileError
from cylfric.io.campaign import Campaign

SMALL = {"pressures_bar": (10.0, 80.0), "speeds_mm_s": (2, 10, 50)}


@pytest.fixture(scope="module")
def bench(tmp_path_factory) -> Path:
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path_factory.mktemp("bench") / "c"
    generate_campaign(folder, BenchSettings.clean(**SMALL))
    return folder


def _copy(bench: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "campaign"
    shutil.copytree(bench, folder)
    return folder


def _runs(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.name.startswith("run_"))


def _outside(folder: Path, tmp_path: Path) -> Path:
    """Move the first run out of the campaign; the manifest row keeps naming it."""
    outside = tmp_path / "outside"
    outside.mkdir()
    first = _runs(folder)[0]
    target = outside / "x.txt"
    shutil.move(first, target)
    return target


@pytest.mark.parametrize("row", ["../outside/x.txt", "ABSOLUTE"])
def test_a_manifest_row_outside_the_campaign_is_refused_with_its_line(bench, tmp_path, row):
    folder = _copy(bench, tmp_path)
    target = _outside(folder, tmp_path)
    row = str(target) if row == "ABSOLUTE" else row
    manifest = folder / "manifest.csv"
    lines = manifest.read_text().splitlines()
    lines[1] = row + "," + lines[1].split(",", 1)[1]
    manifest.write_text("\n".join(lines) + "\n")
    problem = "is absolute" if row.startswith("/") else "climbs out of the campaign folder"
    with pytest.raises(BenchFileError, match=rf"manifest.csv, line 2: file .* {problem}"):
        Campaign.open(folder)


def test_a_run_file_linking_outside_is_refused(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    first = _runs(folder)[0]
    target = _outside(folder, tmp_path)
    first.symlink_to(target)
    (folder / "manifest.csv").unlink()
    with pytest.raises(
        BenchFileError, match=rf"run file {first.name} resolves to .*x.txt, outside"
    ):
        Campaign.open(folder)


def test_a_listed_run_file_linking_outside_is_refused_with_its_row(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    first = _runs(folder)[0]
    first.symlink_to(_outside(folder, tmp_path))
    with pytest.raises(BenchFileError, match=r"manifest.csv, line 2: lists .* outside"):
        Campaign.open(folder)


def test_a_subfolder_linking_outside_is_refused(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "manifest.csv").unlink()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for run in _runs(folder)[3:]:
        shutil.move(run, elsewhere / run.name)
    (folder / "day2").symlink_to(elsewhere, target_is_directory=True)
    (folder / "day1").mkdir()
    for run in _runs(folder):
        shutil.move(run, folder / "day1" / run.name)
    (folder / "campaign.toml").write_text('[files]\nglob = "*/*.txt"\n')
    with pytest.raises(BenchFileError, match=r"run file day2/run_00\d.* resolves to .*elsewhere"):
        Campaign.open(folder)


def test_a_link_inside_the_campaign_is_read(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "manifest.csv").unlink()
    kept = folder / "kept"
    kept.mkdir()
    first = _runs(folder)[0]
    shutil.move(first, kept / first.name)
    first.symlink_to(kept / first.name)
    assert len(Campaign.open(folder, glob="*.txt").runs) == 6


def test_manifest_rows_in_subfolders_are_matched_by_their_path(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "sub").mkdir()
    manifest = folder / "manifest.csv"
    rows = manifest.read_text().splitlines()
    for i, run in enumerate(_runs(folder)[3:], start=4):
        shutil.move(run, folder / "sub" / run.name)
        rows[i] = "sub/" + rows[i]
    # the same base name again at the top: listed by its row, not as 'sub/...'
    manifest.write_text("\n".join(rows) + "\n")
    campaign = Campaign.open(folder)
    by_name = {info.path.relative_to(folder).as_posix(): info for info in campaign.runs}
    assert len(by_name) == 6
    for i, row in enumerate(rows[1:], start=2):
        name, pressure_bar, velocity_mm_s = row.split(",")[:3]
        info = by_name[name]
        assert info.manifest_line == i
        assert info.pressure == pytest.approx(float(pressure_bar) * 1e5)
        assert info.velocity == pytest.approx(float(velocity_mm_s) * 1e-3)
        assert info.source == {"pressure": "manifest", "velocity": "manifest"}


def test_a_file_in_a_subfolder_is_not_listed_by_a_top_level_row_of_its_base_name(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    first = _runs(folder)[0]
    (folder / "sub").mkdir()
    shutil.copy(first, folder / "sub" / first.name)
    campaign = Campaign.open(folder, glob="**/*.txt")
    assert campaign.unlisted == (f"sub/{first.name}",)


@pytest.mark.parametrize(
    ("text", "key", "line"),
    [
        ('[cylinder]\nbore = "25"\nrod = "12 mm"\n', "cylinder.bore", 2),
        ('[cylinder]\nbore = "25 mm"\nrod = "12"\n', "cylinder.rod", 3),
        ('[force_balance]\n\nmoving_mass = "12.5"\n', "force_balance.moving_mass", 3),
    ],
)
def test_a_length_or_mass_without_its_unit_is_refused_with_the_line(tmp_path, text, key, line):
    """Issue 39: ``bore = "25"`` was taken as 25 mm without a word (and "12.5" as kg)."""
    from cylfric.io.campaign import load_config

    (tmp_path / "campaign.toml").write_text(text)
    with pytest.raises(BenchFileError, match=rf"line {line}: {key} = '[0-9.]+' has no unit"):
        load_config(tmp_path)


def test_values_with_units_and_a_bare_zero_are_read(tmp_path):
    from cylfric.io.campaign import load_config

    (tmp_path / "campaign.toml").write_text(
        '[cylinder]\nbore = "25 mm"\nrod = "0.012 m"\n[force_balance]\nmoving_mass = "0"\n'
    )
    config = load_config(tmp_path)
    assert config.area_a == pytest.approx(3.14159265 / 4 * (0.025**2 - 0.012**2))


def _fit(folder, tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    return CliRunner().invoke(
        app, ["fit", str(folder), "--out", str(tmp_path / "out"), "--no-report"]
    )


def test_an_infinite_pressure_from_the_file_name_is_named_not_an_svd_failure(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "manifest.csv").unlink()
    first = _runs(folder)[0]
    first.rename(folder / first.name.replace("p10bar", "pinfbar"))
    (folder / "campaign.toml").write_text(
        '[files]\nname_pattern = "_p(?P<pressure_bar>[a-z0-9.]+)bar"\n'
    )
    result = _fit(folder, tmp_path)
    assert result.exit_code == 2, result.output
    assert "name_pattern gives pressure_bar = 'inf'; expected a finite pressure" in result.output


def test_an_infinite_pressure_in_a_header_line_is_named(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "manifest.csv").unlink()
    first = _runs(folder)[0]
    first.write_text(first.read_text().replace("Pressure: 10 bar", "Pressure: 1e400 bar"))
    first.rename(folder / first.name.replace("_p10bar", ""))
    result = _fit(folder, tmp_path)
    assert result.exit_code == 2, result.output
    assert "'1e400 bar' is not a finite pressure" in result.output
