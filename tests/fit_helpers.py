"""Helpers shared by the quality-gate tests: edited copies of a campaign, `cylfric fit
--no-report` through the CLI runner, and the excluded runs it wrote."""

from __future__ import annotations

import shutil

import pandas as pd
from typer.testing import CliRunner

from cylfric.cli import app

runner = CliRunner()


def fit_no_report(folder, tmp_path, *extra):
    """(CliRunner result, output folder) of ``cylfric fit FOLDER --out TMP/out --no-report``."""
    out = tmp_path / "out"
    result = runner.invoke(app, ["fit", str(folder), "--out", str(out), "--no-report", *extra])
    return result, out


def excluded_table(out):
    """``excluded.csv`` of an output folder (empty, with its columns, when none was written)."""
    path = out / "excluded.csv"
    return pd.read_csv(path) if path.exists() else pd.DataFrame(columns=["file", "check"])


def copy_campaign(folder, tmp_path, name="campaign"):
    """A copy of a campaign folder under ``tmp_path`` to edit (the original stays clean)."""
    target = tmp_path / name
    shutil.copytree(folder, target)
    return target


def edit_file(path, old, new):
    """Replace ``old`` (which must be there) by ``new`` in a text file."""
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))
