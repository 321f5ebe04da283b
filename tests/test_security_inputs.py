"""What the independent hostile check of issue 23 found, each case fixed (issue 23, items 1,
2 and 6; docs/security.md): names with a trailing newline, patterns and globs that could not
end in time, names that are not UTF-8, one bad campaign in fit-many, manifest lines split at
Unicode separators, and inputs that ended in unexpected errors."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.io import BenchFileError
from cylfric.io.campaign import Campaign, load_config
from cylfric.model import FrictionModel

runner = CliRunner()
SMALL = {"pressures_bar": (10.0, 80.0), "speeds_mm_s": (2, 10, 50)}


def _campaign(folder: Path) -> Path:
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    generate_campaign(folder, BenchSettings.clean(**SMALL))
    return folder


@pytest.mark.parametrize("target", ["matlab", "fmu"])
def test_a_name_with_a_trailing_newline_is_refused(tmp_path, target):
    from cylfric.export import export

    with pytest.raises(ValueError, match="not a valid model identifier"):
        export(FrictionModel(), target, tmp_path, name="abc\n")
    assert not list(tmp_path.iterdir())


def test_a_huge_name_pattern_is_refused_at_once_with_its_line(tmp_path):
    n = 20_000
    (tmp_path / "campaign.toml").write_text(
        "[files]\nname_pattern = '" + "(" * n + "a" + ")" * n + "'\n"
    )
    started = time.perf_counter()
    with pytest.raises(BenchFileError, match=r"line 2: files.name_pattern is 40001 characters"):
        load_config(tmp_path)
    assert time.perf_counter() - started < 5


@pytest.mark.parametrize(
    ("glob", "message"),
    [
        ("**/**/*.txt", "more than one '\\*\\*'"),
        ("a**/*.txt", "'\\*\\*' inside a name"),
        (".", "names no files"),
        ("*" * 10_000 + "x", "characters long"),
    ],
)
def test_globs_that_cannot_end_in_time_or_name_nothing_are_refused(tmp_path, glob, message):
    (tmp_path / "campaign.toml").write_text(f"[files]\nglob = '{glob}'\n")
    with pytest.raises(BenchFileError, match=f"line 2: files.glob = .* {message}"):
        load_config(tmp_path)


def test_a_deep_folder_chain_with_one_double_star_ends(tmp_path):
    folder = _campaign(tmp_path / "c")
    (folder / "manifest.csv").unlink()
    deep = folder
    for _ in range(40):
        deep = deep / "ddddd"
    deep.mkdir(parents=True)
    (folder / "campaign.toml").write_text("[files]\nglob = '**/*.txt'\n")
    started = time.perf_counter()
    assert len(Campaign.open(folder).runs) == 6
    assert time.perf_counter() - started < 10


@pytest.mark.skipif(sys.platform != "linux", reason="a non-UTF-8 file name needs Linux")
def test_a_file_name_that_is_not_utf8_is_named(tmp_path):
    folder = _campaign(tmp_path / "c")
    (folder / "manifest.csv").unlink()
    first = sorted(folder.glob("*.txt"))[0]
    os.rename(first, os.fsencode(folder) + b"/" + first.stem.encode() + b"_\xff\xfe.txt")
    result = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "the name is not valid UTF-8" in result.output and "\\udcff" in result.output
    assert "Traceback" not in result.output


def test_fit_many_lists_a_campaign_it_cannot_fit_and_fits_the_others(tmp_path):
    root = tmp_path / "root"
    _campaign(root / "good")
    _campaign(root / "bad\tname")
    first = sorted((root / "good").glob("*.txt"))[0]
    (tmp_path / first.name).write_bytes(first.read_bytes())  # ROOT's parent: a campaign too
    (root / "loop").symlink_to("..", target_is_directory=True)  # a link back up: a loop
    result = runner.invoke(
        app, ["fit-many", str(root), "--out", str(tmp_path / "out"), "--no-report", "-j", "1"]
    )
    assert result.exit_code == 0, result.output
    table = (tmp_path / "out" / "fit_many.csv").read_text()
    assert "good,ok" in table.replace('"', "")
    rows = {line.split(",")[0].strip('"'): line for line in table.splitlines()[1:]}
    # the tab is written as a visible escape (escape.csv_text), not raw
    assert "failed" in rows["bad\\x09name"] and "control character" in rows["bad\\x09name"]
    assert "failed" in rows["loop"] and "not fitted" in rows["loop"]


def test_manifest_file_names_may_hold_unicode_line_separators(tmp_path):
    folder = _campaign(tmp_path / "c")
    text = (folder / "manifest.csv").read_text()
    first = sorted(folder.glob("*.txt"))[0]
    odd = first.stem + "\u2028x\u000c.txt"
    first.rename(folder / odd)
    (folder / "manifest.csv").write_text(text.replace(first.name, f'"{odd}"'))
    campaign = Campaign.open(folder)
    assert odd in {info.path.name for info in campaign.runs}


def test_absurd_diameters_and_deep_nesting_are_clean_refusals(tmp_path):
    (tmp_path / "campaign.toml").write_text('[cylinder]\nbore = "1e308 mm"\nrod = "1e307 mm"\n')
    with pytest.raises(BenchFileError, match="line 2: cylinder.bore = 1e\\+305 m is not"):
        load_config(tmp_path)
    deep = "[files]\nglob = " + "[" * 100_000 + "]" * 100_000 + "\n"
    (tmp_path / "campaign.toml").write_text(deep)
    # too deep for tomllib's recursion, or (where the recursion limit is raised, as in
    # pytest-xdist's workers) read and refused by the schema: a BenchFileError either way
    with pytest.raises(BenchFileError, match="nested too deeply|files.glob: .* is not of type"):
        load_config(tmp_path)


def test_markdown_escapes_angle_brackets_as_entities_only():
    from cylfric.escape import markdown_text

    assert markdown_text("a<b>") == "a&lt;b&gt;"


def test_cli_refusals_are_exit_2_not_unexpected(tmp_path):
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "campaign.toml").write_text("[files]\nglob = '.'\n")
    done = subprocess.run(
        [str(Path(sys.executable).with_name("cylfric")), "fit", str(tmp_path / "c")]
        + ["--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2 and "names no files" in done.stderr, done.stderr
