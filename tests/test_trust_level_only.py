"""Level-only mode (at most three speeds per pressure): every --fix, --law and
--per-direction is honoured or refused with a reason naming the option (issue 11).

The issue 11 audit found `--fix F_c=70N` and `--fix alpha=1` silently ignored in this mode
(the datasheet said fixed = {}).
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.model import FrictionModel
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
# two speeds per pressure: the Stribeck shape is not identifiable, the level against pressure is
LEVELS = BenchSettings.clean(pressures_bar=(10.0, 50.0, 100.0, 150.0), speeds_mm_s=(5, 50))


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("levels")
    generate_campaign(folder, LEVELS)
    return folder


def _fit(campaign, tmp_path, *extra):
    out = tmp_path / "out"
    result = runner.invoke(
        app, ["fit", str(campaign), "--out", str(out), "--no-report", *extra], color=False
    )
    return result, out


def _used(out):
    """The points the fit used (flag ok): |v| [m/s], p [Pa], friction [N]."""
    points = pd.read_csv(out / "points.csv")
    ok = points[points["flag"].eq("ok")]
    return (
        ok["velocity [m/s]"].abs().to_numpy(),
        ok["pressure [Pa]"].to_numpy(),
        ok["friction [N]"].to_numpy(),
    )


def test_a_fixed_friction_level_is_held(campaign, tmp_path):
    result, out = _fit(campaign, tmp_path, "--fix", "F_c=70N")
    assert result.exit_code == 0, result.output
    sheet = json.loads((out / "datasheet.json").read_text())
    assert sheet["fit"]["fixed"] == {"F_c": 70.0}
    assert sheet["parameters"]["F_c"] == {"law": "constant", "intercept": 70.0}
    assert sheet["model"]["friction_law"] == "coulomb"
    _, _, friction = _used(out)
    rmse = float(np.sqrt(np.mean((friction - 70.0) ** 2)))  # the residuals of the held level
    assert_allclose(sheet["fit"]["rmse"], rmse, rtol=1e-9)
    # the note compares with the fitted level: a held level far from the data is visible
    assert f"F_c held at 70 N (--fix): RMSE {rmse:.3g} N, where the fitted level" in (
        " ".join(result.output.split())
    )
    per_pressure = pd.read_csv(out / "per_pressure.csv")
    assert_allclose(per_pressure["F_c [N]"], 70.0)


def test_a_fixed_viscous_coefficient_is_subtracted_before_the_level_is_fitted(campaign, tmp_path):
    result, out = _fit(campaign, tmp_path, "--fix", "sigma_2=0.5Ns/mm")
    assert result.exit_code == 0, result.output
    sheet = json.loads((out / "datasheet.json").read_text())
    assert sheet["fit"]["fixed"] == {"sigma_2": 500.0}  # N*s/m
    assert sheet["model"]["friction_law"] == "coulomb_viscous"
    speed, pressure, friction = _used(out)
    # independent check: ordinary least squares of friction - 500 |v| on [1, p]
    slope, intercept = np.polyfit(pressure, friction - 500.0 * speed, 1)
    assert_allclose(sheet["parameters"]["F_c"]["intercept"], intercept, rtol=1e-9)
    assert_allclose(sheet["parameters"]["F_c"]["slope"], slope, rtol=1e-9)
    model = FrictionModel.from_datasheet(out / "datasheet.json")
    assert_allclose(
        model.friction(0.05, 100e5), intercept + slope * 100e5 + 500.0 * 0.05, rtol=1e-12
    )
    for name in ("F_s", "v_r", "alpha"):
        assert sheet["parameters"][name] is None and name in sheet["not_identified"]


@pytest.mark.parametrize(
    "fix, named",
    [
        ("alpha=1", "fixed alpha (--fix alpha)"),
        ("F_s=100N,v_r=10mm/s", "fixed F_s, v_r (--fix F_s, --fix v_r)"),
        ("F_c=70N,alpha=1", "fixed alpha (--fix alpha)"),
    ],
)
def test_fixing_a_stribeck_shape_parameter_is_refused(campaign, tmp_path, fix, named):
    result, out = _fit(campaign, tmp_path, "--fix", fix)
    assert result.exit_code == 2, result.output
    message = " ".join(result.output.split())
    assert f"error: {named}: at most 2 distinct speed(s) per pressure" in message
    assert "fix only F_c or sigma_2 here, or measure at least 4 speeds per pressure" in message
    assert "Traceback" not in result.output and not out.exists()


def test_a_nonlinear_pressure_law_is_refused(campaign, tmp_path):
    result, out = _fit(campaign, tmp_path, "--law", "quadratic")
    assert result.exit_code == 2, result.output
    assert "the quadratic pressure law is not available for it" in " ".join(result.output.split())
    assert not out.exists()


def test_per_direction_is_honoured(campaign, tmp_path):
    result, out = _fit(campaign, tmp_path, "--per-direction")
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "per_direction.csv")
    assert sorted(set(table["direction"])) == ["extension", "retraction"]
    pooled = pd.read_csv(out / "per_pressure.csv")
    for _, rows in table.groupby("direction"):
        assert_allclose(rows["pressure [Pa]"], pooled["pressure [Pa]"], rtol=0.01)
        # each direction's level within 5 % of the pooled one (friction is the stroke pair's
        # (F_up + F_down) / 2 less the offset, so the directions differ only where a window
        # is missing in one of them)
        assert_allclose(rows["F_c [N]"], pooled["F_c [N]"], rtol=0.05)
        assert rows["F_s [N]"].isna().all() and rows["sigma_2 [N*s/m]"].isna().all()
    # and the fit says why the two directions agree
    sheet = json.loads((out / "datasheet.json").read_text())
    assert any(
        note.startswith("per direction: each run's own load-cell offset")
        for note in (sheet["notes"])
    )
