"""Catalogue integrity against careless and hostile files (issue 43, item 6): foreign and
tampered SQLite files refused unchanged, every entry validated on add/import by ``show``'s
rules, a bad entry named without breaking ``select``, look-alike names one name, metadata
type-checked, and a clear error without HOME or under a file. Each test fails on the code
before."""

from __future__ import annotations

import hashlib
import json
import sqlite3

import pytest
from typer.testing import CliRunner

from cylfric.catalog import Catalog, CatalogError
from cylfric.cli import app
from cylfric.datasheet import DatasheetError
from cylfric.model import FrictionModel

runner = CliRunner()


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture
def sheet() -> dict:
    return FrictionModel().to_datasheet()


def test_a_catalogue_with_a_trigger_is_refused_and_left_unchanged(tmp_path, sheet):
    path = tmp_path / "seals.sqlite"
    Catalog(path).add(sheet, "good")
    with sqlite3.connect(path) as db:
        db.execute("PRAGMA journal_mode = DELETE")
        db.execute(
            "CREATE TRIGGER spy AFTER INSERT ON seals BEGIN UPDATE seals SET fluid = 'x'; END"
        )
    before = _digest(path)
    with pytest.raises(CatalogError, match="not a cylfric catalogue: it holds trigger 'spy'"):
        Catalog(path)
    result = runner.invoke(app, ["catalog", "add", "x", "--name", "n", "--db", str(path)])
    assert result.exit_code == 2
    assert _digest(path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seals.sqlite"]


def test_a_foreign_sqlite_file_is_refused_without_switching_it_to_wal(tmp_path):
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE users (id INTEGER)")
    before = _digest(path)
    result = runner.invoke(app, ["catalog", "list", "--db", str(path)])
    assert result.exit_code == 2, result.output
    assert "not a cylfric catalogue" in result.output
    assert _digest(path) == before  # bytes 18-19 of the header say WAL once switched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.sqlite"]


def test_a_file_that_is_not_sqlite_is_refused_unchanged(tmp_path):
    path = tmp_path / "notes.sqlite"
    path.write_text("my notes\n" * 200)
    with pytest.raises(CatalogError, match="notes.sqlite: not a usable catalogue .*left as it is"):
        Catalog(path)
    assert path.read_text() == "my notes\n" * 200


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda s: s["fit"].update(
                covariance={"names": ["F_c.intercept", "F_c.slope"], "matrix": [[1.0]]}
            ),
            "covariance is",
        ),
        (lambda s: s["stderr"]["F_c"].update(intercept="abc"), "abc"),
    ],
)
def test_add_and_import_refuse_what_show_refuses(tmp_path, sheet, edit, message):
    edit(sheet)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(sheet))
    shown = runner.invoke(app, ["show", str(path)])
    assert shown.exit_code == 2
    catalog = Catalog(tmp_path / "c.sqlite")
    with pytest.raises(DatasheetError, match=f"bad.json: .*{message}"):
        catalog.add(path, "bad")
    export = {"format": "cylfric-catalog/1", "entries": [{"name": "bad", "datasheet": sheet}]}
    (tmp_path / "export.json").write_text(json.dumps(export))
    with pytest.raises(DatasheetError, match=f"entries/0 \\('bad'\\)/datasheet: .*{message}"):
        catalog.import_json(tmp_path / "export.json")
    assert len(catalog) == 0


def test_one_bad_entry_is_named_and_select_ranks_the_others(tmp_path, sheet):
    catalog = Catalog(tmp_path / "c.sqlite")
    catalog.add(sheet, "good")
    broken = {**sheet, "model": "gone"}
    with sqlite3.connect(catalog.path) as db:  # written by an older or foreign tool
        db.execute(
            "INSERT INTO seals (name, datasheet, added) VALUES ('broken', ?, 'x')",
            (json.dumps(broken),),
        )
    with pytest.raises(CatalogError, match="catalogue entry 'broken' .* cannot be read"):
        catalog.model("broken")
    ranked = catalog.select(55e5, 0.02)
    assert list(ranked["name"]) == ["good"]
    assert "broken" in ranked.attrs["unreadable"]
    result = runner.invoke(
        app,
        ["catalog", "select", "--pressure", "55", "--velocity", "20", "--db", str(catalog.path)],
    )
    assert result.exit_code == 0, result.output
    assert "left out: catalogue entry 'broken'" in result.output
    listed = runner.invoke(app, ["catalog", "list", "--db", str(catalog.path)])
    assert listed.exit_code == 0, listed.output


@pytest.mark.parametrize(
    ("first", "second"),
    [("Seal \u00c4", "Seal A\u0308"), ("ABC", "\uff21\uff22\uff23")],
    ids=["nfc-nfd", "full-width"],
)
def test_look_alike_names_are_one_name(tmp_path, sheet, first, second):
    catalog = Catalog(tmp_path / "c.sqlite")
    catalog.add(sheet, first)
    with pytest.raises(CatalogError, match="already in the catalogue"):
        catalog.add(sheet, second)
    assert second in catalog
    assert catalog.names() == [first if first.isascii() else "Seal \u00c4"]


@pytest.mark.parametrize("value", [True, "0.04", [0.04]])
def test_metadata_numbers_are_type_checked(tmp_path, sheet, value):
    catalog = Catalog(tmp_path / "c.sqlite")
    with pytest.raises(CatalogError, match="bore = .*: expected a number in m"):
        catalog.add(sheet, "x", bore=value)
    export = {
        "format": "cylfric-catalog/1",
        "entries": [{"name": "x", "datasheet": sheet, "metadata": {"bore": value}}],
    }
    (tmp_path / "export.json").write_text(json.dumps(export))
    with pytest.raises(CatalogError, match="entries/0: bore = "):
        catalog.import_json(tmp_path / "export.json")


def test_without_home_the_catalogue_is_a_clear_error_and_nothing_is_created(tmp_path, monkeypatch):
    for name in ("HOME", "XDG_DATA_HOME", "CYLFRIC_CATALOG"):
        monkeypatch.delenv(name, raising=False)
    from pathlib import Path

    home = Path.home() / ".local" / "share" / "cylfric"  # the password database's home
    existed = home.exists()
    result = runner.invoke(app, ["catalog", "list"])
    created = not existed and home.exists()
    assert result.exit_code == 2, result.output
    assert "HOME is not set" in result.output
    assert not created


def test_a_catalogue_path_under_a_file_is_a_clear_error(tmp_path, monkeypatch):
    (tmp_path / "file.txt").write_text("x")
    monkeypatch.setenv("CYLFRIC_CATALOG", str(tmp_path / "file.txt" / "c.sqlite"))
    result = runner.invoke(app, ["catalog", "list"])
    assert result.exit_code == 2, result.output
    assert "file.txt is a file, not a folder" in result.output
