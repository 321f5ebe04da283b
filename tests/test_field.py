"""Friction in service from machine logs (issue 41): the virtual field bench against second
formulations, and the identification's round trip against the bench's truth.

Round trips: the bench simulates a boom crane with known Coulomb + viscous friction, noise
and quantisation; ``fit_field`` sees only the logged position and pressures. Tolerances are
the issue's acceptance (5 % friction per speed band and direction, 5 % mass and load, the
truth inside the 95 % band at >= 90 % of checked points).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.identify.field import fit_field, holding_check
from cylfric.io.fieldlog import FieldConfig, FieldRecord
from cylfric.simulate.field_bench import (
    GRAVITY,
    Crane,
    FieldSettings,
    crane_geometry,
    field_records,
    simulate_log,
)

SETTINGS = FieldSettings()
CONFIG = FieldConfig(bore=SETTINGS.crane.bore, rod=SETTINGS.crane.rod)


def _records(settings, days, duration=300.0, seed=0, logs_per_day=2):
    """days: friction scale per day; returns (records, truths)."""
    return field_records(settings, days, duration=duration, seed=seed, logs_per_day=logs_per_day)


def _true_friction(settings, speed, scale=1.0):
    return scale * (settings.F_c * math.tanh(speed / settings.v_s) + settings.F_v * speed)


# --- the bench against second formulations -----------------------------------------------


def test_moment_arm_is_the_derivative_of_the_cylinder_length():
    """dl/dtheta (virtual work) against a central difference of l(theta)."""
    crane = Crane()
    theta = np.radians(np.linspace(-20, 30, 11))
    h = 1e-6
    g = crane_geometry(crane, theta, 500.0)
    numeric = (
        crane_geometry(crane, theta + h, 500.0)["length"]
        - crane_geometry(crane, theta - h, 500.0)["length"]
    ) / (2 * h)
    assert_allclose(g["arm"], numeric, rtol=1e-7)


def test_reflected_mass_conserves_kinetic_energy_and_load_does_the_gravity_work():
    """1/2 m(x) v^2 = 1/2 J theta_dot^2, and F_load dx = the potential energy's change."""
    crane = Crane()
    payload = 700.0
    theta = np.radians(np.linspace(-20, 30, 2001))
    g = crane_geometry(crane, theta, payload)
    inertia = crane.boom_mass * crane.boom_length**2 / 3 + payload * crane.boom_length**2
    theta_dot = 0.1
    v = g["arm"] * theta_dot
    assert_allclose(0.5 * (g["mass"] - crane.rod_mass) * v**2, 0.5 * inertia * theta_dot**2)
    # work of the load along the stroke = rise of the potential energy (trapezoid rule)
    work = np.trapezoid(g["load"], g["length"])
    lift = crane.boom_mass * crane.boom_length / 2 + payload * crane.boom_length
    energy = GRAVITY * lift * (np.sin(theta[-1]) - np.sin(theta[0]))
    assert_allclose(work, energy, rtol=1e-5)


def test_gravity_load_is_20_to_50_times_the_friction():
    s = SETTINGS
    for payload in s.payloads:
        g = crane_geometry(s.crane, np.radians(np.linspace(-25, 35, 50)), payload)
        low = g["load"].min() / _true_friction(s, max(s.speeds))
        high = g["load"].max() / _true_friction(s, min(s.speeds))
        assert 20 <= low and high <= 50, (payload, low, high)


def test_bench_holds_the_load_with_the_chamber_pressures():
    """At rest, p_A A_A - p_B A_B = F_load(x) within the Coulomb friction (static balance)."""
    log = simulate_log(SETTINGS, duration=60.0, payload=700.0, seed=3)
    t = log.truth
    # held: at rest for the last 0.5 s (the transients of the stop have died out)
    from scipy.ndimage import minimum_filter1d

    rest = (np.abs(t["velocity [m/s]"]) < 1e-5).astype(np.int8)
    still = minimum_filter1d(rest, 51, origin=25) > 0
    force = log.pressure_a * t["area_a [m^2]"] - log.pressure_b * t["area_b [m^2]"]
    load = np.interp(log.position, t["position [m]"], t["load [N]"])
    noise = 3 * SETTINGS.pressure_noise * t["area_a [m^2]"]
    assert np.count_nonzero(still) > 500
    assert np.all(np.abs(force - load)[still] < SETTINGS.F_c + noise)


# --- round trip ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def one_day():
    records, truths = _records(SETTINGS, [1.0], duration=600.0, seed=1)
    return fit_field(records, CONFIG), truths


def test_friction_within_5_percent_per_speed_band_in_both_directions(one_day):
    fit, _ = one_day
    assert fit.identified
    assert len(fit.bands) >= 6  # three speed bands x two directions
    for band in fit.bands:
        truth = _true_friction(SETTINGS, band["speed [m/s]"])
        assert abs(band["friction [N]"] / truth - 1) < 0.05, band


def test_truth_inside_the_band_at_90_percent_of_points():
    """Several draws (seeds) so that the share means something: >= 90 % inside."""
    inside = total = 0
    for seed in (11, 12, 13):
        records, _ = _records(SETTINGS, [1.0], duration=300.0, seed=seed)
        fit = fit_field(records, CONFIG)
        for band in fit.bands:
            total += 1
            truth = _true_friction(SETTINGS, band["speed [m/s]"])
            inside += abs(band["friction [N]"] - truth) <= band["band [N]"]
    assert total >= 12
    assert inside / total >= 0.9, (inside, total)


def test_cross_check_is_model_free_and_within_5_percent(one_day):
    fit, _ = one_day
    assert len(fit.cross_check) >= 3
    for row in fit.cross_check:
        truth = _true_friction(SETTINGS, row["speed [m/s]"])
        assert abs(row["friction [N]"] / truth - 1) < 0.05, row
        assert abs(row["friction [N]"] - truth) < 4 * row["stderr [N]"] + 0.01 * truth


def test_effective_mass_and_load_curve_within_5_percent(one_day):
    """Both within 5 % over the logged stroke (1-99 % of the moving positions). The mass
    needs the errors-in-variables correction: without it, it came out up to 6 % low at the
    retracted end here (20 % in one log of the benchmark's draws)."""
    fit, truths = one_day
    for load, mass, truth in zip(fit.loads, fit.masses, truths, strict=True):
        x = np.array(load["position [m]"])
        true_load = np.interp(x, truth["position [m]"], truth["load [N]"])
        true_mass = np.interp(x, truth["position [m]"], truth["mass [kg]"])
        assert np.max(np.abs(np.array(load["load [N]"]) / true_load - 1)) < 0.05
        assert np.max(np.abs(np.array(mass["mass [kg]"]) / true_mass - 1)) < 0.05


def test_pressure_slope_not_identified_when_the_pressure_follows_the_load(one_day):
    fit, _ = one_day
    assert fit.parameters["k_p"] is None
    assert fit.status["k_p"].startswith("not identified")
    assert "follows the position" in fit.status["k_p"]
    assert fit.status["asymmetry"].startswith("not identified")


def test_speed_dependence_not_identified_at_one_speed():
    settings = FieldSettings(speeds=(0.06,), step_share=0.0)
    records, _ = _records(settings, [1.0], duration=300.0, seed=5)
    fit = fit_field(records, CONFIG)
    assert fit.parameters["F_v"] is None
    assert "one speed" in fit.status["F_v"]
    # F_c is then the friction level at that speed
    truth = _true_friction(settings, 0.06)
    assert abs(fit.parameters["F_c"] / truth - 1) < 0.05


# --- trend and change test (a smaller version of benchmarks/bench_field.py) --------------


@pytest.mark.parametrize("seed", [100, 200])
def test_a_15_percent_rise_is_detected_and_equal_days_are_not(seed):
    for scales, expected in (([1.0, 1.15], True), ([1.0, 1.0], False)):
        records, _ = _records(SETTINGS, scales, duration=200.0, seed=seed, logs_per_day=1)
        fit = fit_field(records, CONFIG)
        assert len(fit.days) == 2
        (change,) = fit.changes
        assert change["significant"] is expected, (scales, change)
        if expected:
            assert abs(change["change [%]"] - 15) < 3


# --- counter-balance valve -----------------------------------------------------------------


def test_holding_check_flags_a_collapsing_pressure_only():
    rate = 100.0
    t = np.arange(0, 60, 1 / rate)
    velocity = np.where((t % 10) < 5, 0.05, 0.0)  # 5 s moving, 5 s held
    held = 80e5 * np.ones_like(t)
    collapsed = np.where(velocity == 0, 2e5, 80e5)
    assert not holding_check(held, velocity, rate)["flagged"]
    result = holding_check(collapsed, velocity, rate)
    assert result["flagged"] and result["collapsed"] == result["episodes"] >= 3


def test_valve_side_pressure_is_flagged_and_not_used():
    settings = FieldSettings(counterbalance=True)
    records, _ = _records(settings, [1.0], duration=200.0, seed=7, logs_per_day=1)
    fit = fit_field(records, CONFIG)  # field.toml says "chamber": the check must catch it
    assert any("pressure_a collapses" in flag for flag in fit.flags)
    assert not fit.identified
    assert fit.parameters["F_c"] is None
    assert "valid in one direction only" in fit.status["F_c"]


# --- against a seal datasheet --------------------------------------------------------------


def _sheet(scale=1.0):
    from cylfric.model import FrictionModel

    return FrictionModel(
        {
            "F_c": {"intercept": scale * SETTINGS.F_c, "slope": 0.0},
            "sigma_2": {"intercept": scale * SETTINGS.F_v, "slope": 0.0},
        },
        friction_law="coulomb_viscous",
    )


def test_datasheet_comparison_at_the_operating_points(one_day):
    """The bench's own law as the datasheet: as the datasheet; 30 % lower: above it."""
    from cylfric.identify.field import compare_datasheet

    fit, _ = one_day
    same = compare_datasheet(fit, _sheet())
    assert same["verdict"] == "as the datasheet"
    assert len(same["points"]) == len(fit.cross_check)
    for point in same["points"]:
        assert abs(point["difference [%]"]) < 1
        assert point["pressure [Pa]"] > 10e5  # the logged chambers, not a default
    lower = compare_datasheet(fit, _sheet(0.7))
    assert lower["verdict"] == "above the datasheet"
    assert all(abs(p["difference [%]"] - 100 * (1 / 0.7 - 1)) < 2 for p in lower["points"])


def test_a_position_that_counts_down_on_extension_gives_the_same_friction():
    """[cylinder] extension = "position decreases": the log's position negated and offset
    (a sensor counting down) gives the same law, the curves in the log's coordinate."""
    from dataclasses import replace

    records, _ = _records(SETTINGS, [1.0], duration=200.0, seed=21, logs_per_day=1)
    flipped = [replace(r, position=1.0 - r.position) for r in records]
    up = fit_field(records, CONFIG)
    down = fit_field(flipped, replace(CONFIG, extension="position decreases"))
    assert_allclose(down.parameters["F_c"], up.parameters["F_c"], rtol=1e-6)
    assert_allclose(down.parameters["F_v"], up.parameters["F_v"], rtol=1e-6)
    assert_allclose(
        1.0 - np.array(down.loads[0]["position [m]"]), up.loads[0]["position [m]"], atol=1e-9
    )
    assert_allclose(down.loads[0]["load [N]"], up.loads[0]["load [N]"], rtol=1e-6)


def test_a_payload_change_at_rest_splits_the_log():
    """One log in which the crane sets down a load while holding still (payload 900 kg,
    then 500 kg from the same position): two segments, each its own load curve; the friction
    still within 5 %. Without the split one load curve would serve both payloads."""
    first = simulate_log(SETTINGS, duration=300.0, payload=900.0, seed=31)
    rest = np.flatnonzero(np.abs(first.truth["velocity [m/s]"]) < 1e-6)
    cut = int(rest[rest > 250 * SETTINGS.rate][0]) + 1  # at rest, after 250 s
    start = float(first.position[cut - 1])
    second = simulate_log(SETTINGS, duration=300.0, payload=500.0, seed=32, start=start)
    record = FieldRecord(
        "joined",
        "day",
        np.concatenate((first.time[:cut], first.time[cut - 1] + second.time)),
        np.concatenate((first.position[:cut], second.position)),
        np.concatenate((first.pressure_a[:cut], second.pressure_a)),
        np.concatenate((first.pressure_b[:cut], second.pressure_b)),
        np.concatenate((first.valve[:cut], second.valve)),
        {"kind": "memory"},
    )
    fit = fit_field([record], CONFIG)
    assert len(fit.loads) == 2
    assert any("payload" in note for note in fit.notes)
    for band in fit.bands:
        truth = _true_friction(SETTINGS, band["speed [m/s]"])
        assert abs(band["friction [N]"] / truth - 1) < 0.05, band
    # the same log as one payload (no split): the friction is far off (measured: 99-220 %)
    unsplit = fit_field([record], CONFIG, {"payload_step": 10.0})
    assert len(unsplit.loads) == 1
    assert (
        max(
            abs(b["friction [N]"] / _true_friction(SETTINGS, b["speed [m/s]"]) - 1)
            for b in unsplit.bands
        )
        > 0.2
    )


def test_a_gap_in_the_log_is_named_and_bridged_without_bias():
    from dataclasses import replace

    records, _ = _records(SETTINGS, [1.0], duration=300.0, seed=41, logs_per_day=1)
    (r,) = records
    keep = np.ones(r.time.size, dtype=bool)
    keep[10_000:10_700] = False  # 7 s the logger missed, perhaps mid-move
    gapped = replace(
        r,
        time=r.time[keep],
        position=r.position[keep],
        pressure_a=r.pressure_a[keep],
        pressure_b=r.pressure_b[keep],
        valve=r.valve[keep],
    )
    fit = fit_field([gapped], CONFIG)
    assert any("gap" in note for note in fit.flags)
    for band in fit.bands:
        truth = _true_friction(SETTINGS, band["speed [m/s]"])
        assert abs(band["friction [N]"] / truth - 1) < 0.05, band
