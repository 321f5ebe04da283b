"""Servo-valve rigs (issue 22, deliverables 4-5): a valve-driven axis without a load cell.

The virtual rig (:mod:`cylfric.simulate.valve_bench`) drives a single-rod cylinder with a
proportional valve; its files carry position, p_A, p_B and the valve voltage only. The truth
of each level is the rig's friction model at the true steady state at the end of the step.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from cylfric.identify import IdentificationWarning
from cylfric.io.campaign import CampaignConfig
from cylfric.pipeline import fit_campaign
from cylfric.simulate.valve_bench import ValveRigSettings, generate_valve_campaign
from cylfric.steady_state import find_windows, friction_signal

LEVEL_TOLERANCE = 2.0  # [N], the acceptance of issue 22


def _fit(tmp_path, settings):
    campaign = generate_valve_campaign(tmp_path / "campaign", settings)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        out = fit_campaign(tmp_path / "campaign", tmp_path / "out", report=False, workers=1)
    return campaign, out


def _level_errors(campaign, out):
    points = out.identification.points.copy()
    points["file"] = points["file"].map(lambda f: f.rsplit("/", 1)[-1])
    merged = points.merge(campaign.truth, on=["file", "direction [-]"], suffixes=("", "_true"))
    model = out.identification.model
    fitted = np.abs(model.friction(merged["velocity [m/s]"].to_numpy(), merged["pressure [Pa]"]))
    return fitted - merged["friction [N]_true"].to_numpy(), len(merged)


def test_tied_valve_campaign_levels_and_confounded_slopes(tmp_path):
    campaign, out = _fit(tmp_path, ValveRigSettings())  # 20 runs, 40 levels
    errors, n = _level_errors(campaign, out)
    assert n >= 0.9 * len(campaign.truth)  # nearly every level kept
    assert np.max(np.abs(errors)) < LEVEL_TOLERANCE
    sheet = json.loads((tmp_path / "out" / "datasheet.json").read_text())
    assert "F_c.slope" in sheet["not_identified"]
    assert "confounded" in sheet["not_identified"]["F_c.slope"]
    record = sheet["fit"]["confounding"]
    assert record["confounded"] and record["tied_to"] == "direction" and not record["overlap"]


def test_untied_valve_campaign_identifies_the_slopes(tmp_path):
    settings = ValveRigSettings(
        voltages=(1.0, 1.4, 2.0, 2.7, 3.6, 4.2), supply_pressures_bar=(40, 70, 100, 130, 160)
    )
    campaign, out = _fit(tmp_path, settings)
    sheet = json.loads((tmp_path / "out" / "datasheet.json").read_text())
    assert "F_c.slope" not in sheet["not_identified"]
    assert "confounding" not in sheet["fit"]
    slope = sheet["parameters"]["F_c"]["slope"]
    true_slope = campaign.friction.coefficients()["F_c"]["slope"]
    assert slope == pytest.approx(true_slope, rel=0.3)


def test_injected_start_transients_never_pass_the_gate(tmp_path):
    """Issue 39 item 7: three runs of 30 step for 0.38 s only (ValveRigSettings
    start_transients), so their strokes end in the start transient. A window whose level is
    more than 1 % off its setting's steady level (the truth of the full-length steps at that
    voltage and direction) is a transient point: none is accepted (the gate's ``transient``
    check: the other strokes of the setting, MAD-based), and the law is within 2 % of the
    truth at every steady operating point of the rig. On main the transient points were
    accepted (5 of them, 2-18 % off)."""
    settings = ValveRigSettings(repeats=3, start_transients=(3, 11, 20))
    campaign, out = _fit(tmp_path, settings)
    truth = campaign.truth
    steady = truth[~truth["transient [-]"]]
    level = steady.groupby(["voltage [V]", "direction [-]"])["friction [N]"].mean()
    points = out.extraction.points.assign(file=lambda f: f["file"].str.rsplit("/", n=1).str[-1])
    injected = truth.loc[truth["transient [-]"], "file"].unique()
    voltage = dict(zip(truth["file"], truth["voltage [V]"], strict=False))
    candidates = points[points["file"].isin(injected) & points["flag"].eq("ok")]
    steady_level = np.array(
        [
            level[(voltage[file], direction)]
            for file, direction in zip(candidates["file"], candidates["direction [-]"], strict=True)
        ]
    )
    off = np.abs(candidates["friction [N]"].to_numpy() / steady_level - 1)
    transient = candidates.index[off > 0.01]
    assert len(transient) >= 3  # the injection makes transient points
    accepted = out.identification.points
    accepted = accepted[accepted["flag"].eq("ok")] if "flag" in accepted else accepted
    kept = set(zip(accepted["run"], accepted["stroke"], strict=True))
    shown = points.loc[transient, ["file", "direction [-]", "friction [N]"]]
    windows = zip(points.loc[transient, "run"], points.loc[transient, "stroke"], strict=True)
    assert not kept & set(windows), shown
    assert set(out.excluded["check"]) <= {"transient", "motion"}
    model = out.identification.model
    fitted = np.abs(
        model.friction(steady["velocity [m/s]"].to_numpy(), steady["pressure_a [Pa]"].to_numpy())
    )
    error = np.abs(fitted / steady["friction [N]"].to_numpy() - 1)
    assert error.max() < 0.02


def test_start_up_transient_is_left_out():
    """A force that settles 1 s after the speed: the window starts once it has settled."""
    rng = np.random.default_rng(1)
    time = np.arange(0.0, 4.0, 1e-3)
    velocity = np.full(time.size, 0.05)
    final = 200.0
    force = final - 60.0 * np.exp(-time / 0.25) + rng.normal(0.0, 10.0, time.size)
    (window,) = find_windows(time, velocity, force, nominal_speed=0.05)
    assert window.flag == "ok"
    assert time[window.start] > 0.8  # 60 N e^(-t/0.25) < 1 N after 1.0 s
    assert force[window.start : window.stop].mean() == pytest.approx(final, abs=1.0)


def test_force_balance_without_load_cell():
    """F = A_A p_A - A_B p_B - m a on a synthetic record equals the friction put in."""
    area_a, area_b, mass = 1.2566e-3, 7.658e-4, 20.0
    time = np.linspace(0.0, 2.0, 2001)
    velocity = 0.05 * np.sin(np.pi * time)
    acceleration = 0.05 * np.pi * np.cos(np.pi * time)
    friction = 150.0 + 20.0 * time
    pressure_b = np.full(time.size, 30e5)
    pressure_a = (friction + mass * acceleration + area_b * pressure_b) / area_a
    config = CampaignConfig(
        area_a=area_a, area_b=area_b, moving_mass=mass, force_source="pressures"
    )
    data = {"time [s]": time, "pressure_a [Pa]": pressure_a, "pressure_b [Pa]": pressure_b}
    signal = friction_signal(data, config, velocity)
    np.testing.assert_allclose(signal[5:-5], friction[5:-5], atol=0.05)
