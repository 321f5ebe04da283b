"""Terminal output escapes user text (issue 23, item 3; docs/security.md).

Catalogue names, seal metadata, a datasheet's method, campaign folder names and file names
holding rich markup (``[bold]``, a lone ``[/]`` that used to crash the table), ANSI escape
sequences (colours, a window title, clear screen) and emoji codes are printed as the text
they are: every command exits as usual, no escape character reaches the terminal, and the
text is shown visibly escaped.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel

runner = CliRunner()
HOSTILE = "seal [bold]x[/] [/red] \x1b[31mred\x1b]0;title\x07 :smile: \x1b[2J"


def _run(*args):
    return runner.invoke(app, [str(a) for a in args])


def _assert_shown_as_text(output: str) -> None:
    assert "\x1b" not in output and "\x07" not in output
    assert "[/]" in output and ":smile:" in output and "\\x1b" in output


@pytest.fixture
def hostile_sheet(tmp_path):
    model = FrictionModel().replace(
        validity={
            "pressure_min": 5e5,
            "pressure_max": 160e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.135,
        }
    )
    sheet = model.to_datasheet()
    sheet["name"] = HOSTILE
    sheet["fit"]["method"] = HOSTILE
    path = tmp_path / "sheet.json"
    path.write_text(json.dumps(sheet))
    return path


def test_catalogue_commands_print_hostile_names_as_text(tmp_path, hostile_sheet):
    db = tmp_path / "c.sqlite"
    added = _run("catalog", "add", hostile_sheet, "--name", HOSTILE, "--seal", HOSTILE, "--db", db)
    assert added.exit_code == 0, added.output
    _assert_shown_as_text(added.output)
    for args in (
        ("catalog", "list"),
        ("catalog", "show", HOSTILE),
        ("catalog", "select", "--pressure", "50", "--velocity", "20"),
        ("catalog", "compare", HOSTILE, "--out", tmp_path / "cmp", "--pressures", "50"),
    ):
        result = _run(*args, "--db", db)
        assert result.exit_code == 0, (args, result.output)
        _assert_shown_as_text(result.output)
    removed = _run("catalog", "remove", HOSTILE, "--db", db)
    assert removed.exit_code == 0, removed.output
    _assert_shown_as_text(removed.output)


def test_show_prints_a_hostile_datasheet_as_text(hostile_sheet):
    result = _run("show", hostile_sheet)
    assert result.exit_code == 0, result.output
    _assert_shown_as_text(result.output)


def test_errors_naming_a_hostile_file_are_one_escaped_line(tmp_path):
    missing = tmp_path / f"{HOSTILE}.json"
    result = _run("show", missing)
    assert result.exit_code == 2
    assert "\x1b" not in result.output and "\\x1b" in result.output
    assert "Traceback" not in result.output


def test_fit_of_a_campaign_folder_with_a_hostile_name(tmp_path):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path / HOSTILE.replace("/", "|")  # a folder name holds no slash
    generate_campaign(
        folder, BenchSettings.clean(pressures_bar=(10.0, 50.0), speeds_mm_s=(5, 20, 80))
    )
    result = _run("fit", folder, "--out", tmp_path / "out", "--no-report")
    assert result.exit_code == 0, result.output
    assert "\x1b" not in result.output and "\x07" not in result.output
    sheet = json.loads((tmp_path / "out" / "datasheet.json").read_text())
    assert sheet["name"] == folder.name  # the datasheet keeps the text as it is (JSON escapes it)
