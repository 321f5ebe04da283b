"""Identification on a rough rig (issue 22): a Stribeck shape the data leave open is not
written with exploding standard errors; the exponent is held at 1 and a note says so."""

from __future__ import annotations

import warnings

import pytest

from cylfric.identify import identify
from cylfric.quality import assess
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.simulate.plant import Cylinder
from cylfric.steady_state import extract_campaign


def test_an_open_stribeck_shape_holds_alpha_and_says_so(tmp_path):
    # campaign 17 of benchmarks/bench_coverage.py: 4 pressures x 5 speeds on the rough
    # bench, whose free Stribeck fit gave v_r = 0.061 +- 2.5 m/s and alpha = 0.56 +- 1.9
    # (before: refused, the level F_c pushed to 0 N at 20 bar, "check the signs")
    settings = BenchSettings(
        cylinder=Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060),
        pressures_bar=(20.0, 60.0, 100.0, 150.0),
        speeds_mm_s=(1, 3, 10, 30, 100),
        seed=100_017,
        session_seed=200_017,
        run_seed=300_017,
    )
    generate_campaign(tmp_path / "c", settings, workers=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        points = assess(extract_campaign(tmp_path / "c", workers=1)).points
        ident = identify(points)
    model = ident.model
    assert model.friction_law == "stribeck"
    assert model.coefficients()["alpha"] == 1.0
    assert any("the data leave the Stribeck exponent open" in n for n in ident.notes)
    v_r, v_r_se = model.coefficients()["v_r"], model.stderr()["v_r"]
    assert v_r_se <= v_r  # the shape kept is identified (relative standard error <= 1)
    level = model.params_at(20e5)["F_c"]
    assert level > 0 and model.stderr()["F_c"]["intercept"] < level
    at = points["pressure [Pa]"].between(5.5e6, 6.5e6) & points["velocity [m/s]"].abs().between(
        0.009, 0.011
    )
    measured = points.loc[at, "friction [N]"].abs().mean()  # 10 mm/s at 60 bar
    assert model.friction(0.01, 60e5) == pytest.approx(measured, rel=0.25)
