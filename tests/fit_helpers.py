"""Helpers shared by the quality-gate tests: `cylfric fit --no-report` through the CLI runner,
and the excluded runs it wrote."""

from __future__ import annotations

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
