"""Faults found by the hostile test of the quality gate and the readers (issue 11, second
audit, F1-F13): each with its exact expected outcome."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.quality import assess
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign, find_windows

runner = CliRunner()
GRID = dict(pressures_bar=(10.0, 55.0, 103.0, 159.0), speeds_mm_s=(1, 2, 5, 10, 20, 50, 100))


@pytest.fixture(scope="module")
def seed1(tmp_path_factory):
    """`cylfric generate --pressures 10,55,103,159 --speeds 1,2,5,10,20,50,100 --seed 1`."""
    folder = tmp_path_factory.mktemp("seed1")
    generate_campaign(folder, BenchSettings(**GRID, seed=1))
    return folder


def _fit(folder, tmp_path, *extra):
    out = tmp_path / "out"
    result = runner.invoke(app, ["fit", str(folder), "--out", str(out), "--no-report", *extra])
    return result, out


def _excluded(out):
    path = out / "excluded.csv"
    return pd.read_csv(path) if path.exists() else pd.DataFrame(columns=["file", "check"])


# ---- F4: one-sample spikes no longer cost a run ------------------------------------------


def test_a_single_sample_spike_in_mid_stroke_keeps_the_window():
    """A 150 N spike (the virtual bench's amplitude) in the middle of a 3650-sample stroke
    with 0.8 N noise: the cushion trimming's rolling mean used to leave its limit around
    the spike on both sides of the middle and trim the whole stroke away."""
    rng = np.random.default_rng(0)
    n = 3650
    time = np.arange(n) * 0.02
    velocity = np.full(n, 2e-3)
    force = 138.0 + 0.8 * rng.standard_normal(n)
    force[n // 2 - 60] += 150.0
    (window,) = find_windows(time, velocity, force, nominal_speed=2e-3)
    assert window.flag == "ok"
    assert window.stop - window.start > 0.9 * n  # nothing but noise to trim


def test_seed_1_loses_no_run_and_run_008_keeps_both_strokes(seed1, tmp_path):
    """F4: run_008 (55 bar, 2 mm/s) has a bench spike in each stroke (t = 36.3 s and
    110.22 s); it was excluded as 'no motion, or too short' and --strict exited 2."""
    points = extract_campaign(seed1, workers=1).points
    run = points[points["file"].str.endswith("run_008_p55bar_v2mms.txt")]
    assert sorted(run["direction [-]"]) == [-1, 1]
    assert list(run["flag"]) == ["ok", "ok"]
    assert (run["spikes [-]"] >= 1).all()  # the spikes are rejected, and counted
    # the bench's truth at 55 bar and 2 mm/s is about 138 N (friction of both directions)
    assert_allclose = np.testing.assert_allclose
    assert_allclose(run["friction [N]"], 137.95, atol=0.5)
    result, out = _fit(seed1, tmp_path, "--strict")
    assert result.exit_code == 0, result.output
    assert not (out / "excluded.csv").exists()
