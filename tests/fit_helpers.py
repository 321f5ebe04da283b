"""Helpers shared by the tests: edited copies of a campaign, `cylfric fit --no-report`
through the CLI runner, the excluded runs it wrote, and :func:`needs_fork`."""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys

import pandas as pd
from typer.testing import CliRunner

from cylfric._parallel import can_fork
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


def needs_fork(test):
    """Run ``test`` here when this process can fork workers, else in a fresh pytest process:
    an earlier test of this worker may have left threads behind (Dask's thread pool), and a
    process with other threads does not fork (:func:`cylfric._parallel.can_fork`)."""

    @functools.wraps(test)
    def wrapper(*args, **kwargs):
        if can_fork():
            return test(*args, **kwargs)
        assert not os.environ.get("CYLFRIC_FRESH_TEST"), "a fresh process cannot fork either"
        done = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist"]
            + [f"{test.__code__.co_filename}::{test.__name__}"],
            env={**os.environ, "CYLFRIC_FRESH_TEST": "1"},
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.returncode == 0, done.stdout[-3000:]

    return wrapper
