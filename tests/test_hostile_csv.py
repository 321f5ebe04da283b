"""CSV outputs neutralise text cells (issue 43, item 8): control characters shown as escapes,
and a cell beginning with ``= + - @`` written with a leading ``'`` so that a spreadsheet
shows it as text (OWASP "CSV injection"). One helper, :func:`cylfric.escape.csv_text`."""

from __future__ import annotations

import csv
import io

import pandas as pd
import pytest

from cylfric.escape import csv_frame, csv_text

PAYLOADS = ['=HYPERLINK("http://evil","x")', "+1+cmd|' /C calc'!A0", "-2+3", "@SUM(A1)"]


@pytest.mark.parametrize("payload", PAYLOADS)
def test_formula_cells_become_text(payload):
    assert csv_text(payload) == "'" + payload


def test_control_characters_are_visible_and_numbers_untouched():
    assert csv_text("run\x1b[31m\n.txt") == "run\\x1b[31m\\x0a.txt"
    assert csv_text("plain name.txt") == "plain name.txt"
    assert csv_text(-5.0) == -5.0 and csv_text(None) is None
    frame = pd.DataFrame({"name": ["ok", "=1+1", None], "force [N]": [-1.0, 2.0, 3.0]})
    out = csv_frame(frame)
    assert list(out["name"][:2]) == ["ok", "'=1+1"] and pd.isna(out["name"][2])
    assert list(out["force [N]"]) == [-1.0, 2.0, 3.0]
    assert list(frame["name"][:2]) == ["ok", "=1+1"]  # the input is not changed
    clean = pd.DataFrame({"name": ["a", "b"]})
    assert csv_frame(clean) is clean


def _cells(text):
    return [cell for row in csv.reader(io.StringIO(text)) for cell in row]


def test_catalog_compare_csv_holds_no_formula_and_no_escape_code(tmp_path):
    from cylfric.catalog import Catalog
    from cylfric.model import FrictionModel

    catalog = Catalog(tmp_path / "c.sqlite")
    name = '=HYPERLINK("http://evil")'
    catalog.add(FrictionModel().to_datasheet(), name)
    catalog.compare([name], tmp_path / "out", [55e5], [0.02])
    text = (tmp_path / "out" / "compare.csv").read_text()
    assert "\x1b" not in text
    assert not any(
        cell.startswith(("=", "+", "-", "@")) and not _number(cell) for cell in _cells(text)
    )
    assert "'=HYPERLINK" in text


def _number(cell):
    try:
        float(cell)
    except ValueError:
        return False
    return True


def test_fit_many_summary_holds_no_formula(tmp_path):
    from cylfric.many import _summary_csv

    text = _summary_csv([{"campaign": "=cmd|'/C calc'!A0", "status": "ok"}])
    assert "'=cmd" in text


def test_fit_tables_hold_no_formula(tmp_path):
    """excluded.csv names run files relative to the campaign: a file named like a formula
    (listed by the gate as unlisted or a duplicate) must not become one in a spreadsheet."""
    import shutil

    from typer.testing import CliRunner

    from cylfric.cli import app
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    runner = CliRunner()

    folder = tmp_path / "c"
    generate_campaign(
        folder, BenchSettings(pressures_bar=(10, 159), speeds_mm_s=(2, 5, 10, 20, 50, 100), seed=2)
    )
    first = sorted(folder.glob("*.txt"))[0]
    shutil.copy(first, folder / "=HYPERLINK(1).txt")
    out = tmp_path / "out"
    done = runner.invoke(app, ["fit", str(folder), "--out", str(out), "--no-report"])
    assert done.exit_code == 0, done.output
    text = (out / "excluded.csv").read_text()
    assert "'=HYPERLINK(1).txt" in text
    cells = pd.read_csv(out / "excluded.csv")["file"].astype(str)
    assert not cells.str.startswith(("=", "+", "-", "@")).any()
