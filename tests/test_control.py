"""The servo-loop study (cylfric.control): the axis against closed forms, the tuning, the
compensators and the command.

Closed forms: the hydraulic natural frequency of a symmetric cylinder at mid-stroke,
omega_h = sqrt(4 beta A^2 / (V_t m)) (Merritt 1967 eq. 6-41), and the steady no-load speed
through a critically lapped valve with turbulent orifices, v = K s sqrt((p_S - p_T)/2) / A
for a symmetric cylinder (Merritt eq. 2-4 with the load pressure zero).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.control.axis import DEFAULT_AXIS, Axis, AxisError, load_axis
from cylfric.control.kernel import COMPENSATOR_CODES, closed_loop
from cylfric.control.loop import (
    PlantFriction,
    compensator_outputs,
    controller_vector,
    make_reference,
    read_reference,
    rest_state,
    simulate_loop,
)
from cylfric.control.study import compare_compensators, robustness_cases
from cylfric.control.tuning import feedforward_lead, tune
from cylfric.model import FrictionModel

NO_FRICTION = np.array([[0, 1e-9, 0, 0, 0]] * 7, dtype=float)[:, :4]
NO_FRICTION[3, 1] = 0.01  # v_r [m/s]
NO_FRICTION[4, 1] = 1.0  # alpha [-]


def _open_loop(axis, state0, *, offset=0.0, seconds=1.0):
    """The axis with the controller off (gains 0, no feedforward), a constant command."""
    n = int(seconds * axis.control_rate) + 1
    ctrl = np.array([0, 0, 0, 0, 0, 1e-3, 0, 0, offset, axis.sample_time], dtype=float)
    x = np.full(n, axis.start_position)
    return closed_loop(
        axis.vector(),
        NO_FRICTION,
        3,
        NO_FRICTION,
        3,
        COMPENSATOR_CODES["none"],
        ctrl,
        x,
        np.zeros(n),
        axis.substeps,
        state0,
    )


def test_natural_frequency_matches_merritt():
    # symmetric (double-rod) cylinder at mid-stroke, equal dead volumes, no leakage
    axis = Axis(leakage=0.0, control_rate=20000.0, substeps=5)
    area = axis.area_a
    volume_total = sum(axis.volumes(axis.start_position))
    omega = math.sqrt(4 * axis.bulk_modulus * area**2 / (volume_total * axis.mass))
    assert_allclose(axis.natural_frequency(), omega, rtol=1e-12)
    state = rest_state(axis)
    state[2] += 1e4  # a 0.1 bar pressure step: small-signal oscillation, valve closed
    out = _open_loop(axis, state, seconds=0.2)
    t = np.arange(out.shape[0]) / axis.control_rate
    x = out[:, 0] - out[:, 0].mean()
    up = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    crossings = t[up] - x[up] / (x[up + 1] - x[up]) / axis.control_rate
    measured = 2 * math.pi / np.mean(np.diff(crossings))
    assert_allclose(measured, omega, rtol=2e-3)


def test_steady_flow_through_the_valve():
    axis = Axis(leakage=0.0, spool_order=1)
    opening = 0.3
    out = _open_loop(axis, rest_state(axis), offset=opening, seconds=0.3)
    speed = out[-50:, 1].mean()
    closed_form = (
        axis.valve_coefficient
        * opening
        * math.sqrt((axis.supply_pressure - axis.tank_pressure) / 2)
        / axis.area_a
    )
    assert_allclose(speed, closed_form, rtol=1e-3)
    assert_allclose(axis.no_load_velocity_gain()[0] * opening, closed_form, rtol=1e-12)


def test_steady_flow_differential_cylinder_both_directions():
    axis = Axis(rod_a=0.0, leakage=0.0, spool_order=1)
    extend, retract = axis.no_load_velocity_gain()
    for opening, expected in ((0.2, 0.2 * extend), (-0.2, -0.2 * retract)):
        out = _open_loop(axis, rest_state(axis), offset=opening, seconds=1.0)
        assert_allclose(out[-50:, 1].mean(), expected, rtol=1e-3)


def test_tuning_has_a_six_db_gain_margin():
    tuning = tune(DEFAULT_AXIS, viscous=380.0)
    assert_allclose(tuning.gain_margin_db, 20 * math.log10(2), rtol=1e-12)
    assert tuning.kp == pytest.approx(tuning.critical_kp / 2)
    assert 0 < tuning.loop_gain_1_s < tuning.omega_h_rad_s
    assert tuning.phase_margin_deg > 30


def test_feedforward_lead_is_the_delay_of_the_velocity_path():
    # the ZOH's half sample plus the spool's low-frequency delay (2 zeta/omega or tau)
    axis = DEFAULT_AXIS
    spool = 2 * axis.spool_damping / (2 * math.pi * axis.spool_frequency)
    assert_allclose(feedforward_lead(axis), axis.sample_time / 2 + spool, rtol=1e-12)
    first = axis.replace(spool_order=1, spool_time_constant=3e-3)
    assert_allclose(feedforward_lead(first), axis.sample_time / 2 + 3e-3, rtol=1e-12)
    # a plant with viscous friction only: without the lead the loop lags the sine by the
    # velocity path's delay; with it the error falls by more than a factor 5
    viscous = NO_FRICTION.copy()
    viscous[2, 1] = 380.0  # sigma_2 [N*s/m]
    ref = make_reference("sine", axis, duration=5.0)
    tuning = tune(axis, viscous=380.0)

    def rms(lead):
        ctrl = controller_vector(axis, tuning, FrictionModel())
        ctrl[4] = lead
        out = closed_loop(
            axis.vector(), viscous, 3, viscous, 3, 0, ctrl, ref.position, ref.velocity,
            axis.substeps, rest_state(axis),
        )  # fmt: skip
        return np.sqrt(np.mean((ref.position - out[:, 0]) ** 2))

    assert rms(feedforward_lead(axis)) < 0.2 * rms(0.0)


def test_compensation_holds_its_force_against_leakage():
    # a constant force estimate (coulomb, constant reference velocity) on a symmetric
    # cylinder at rest: the steady command opens the valve for exactly the leakage flow
    # C_i dp with dp = F / A (Jelali & Kroll eq. 3.8 at dp_A/dt = dp_B/dt = 0)
    axis = DEFAULT_AXIS.replace(leakage=5e-12)
    model = FrictionModel()
    pa, pb = 52e5, 48e5
    rows = np.tile([axis.start_position, pa, pb, axis.start_position, 0.01], (5, 1))
    force, command = compensator_outputs(model, "coulomb", rows, axis=axis)[-1]
    area, k = axis.area_a, axis.valve_coefficient
    flow_a = k * command * math.sqrt(axis.supply_pressure - pa)  # into chamber A
    flow_b = k * command * math.sqrt(pb - axis.tank_pressure)  # out of chamber B
    leak = axis.leakage * force / area
    va, vb = axis.volumes(axis.start_position)
    # the force rate of the two flows against the leakage's
    rate = axis.bulk_modulus * area * ((flow_a - leak) / va + (flow_b - leak) / vb)
    assert force > 0
    assert_allclose(rate, 0.0, atol=1e-9 * axis.bulk_modulus * area * leak / va)
    # in the loop: on a leaky axis the oracle removes nearly all the friction error
    result = compare_compensators(
        model, axis=axis, reference=make_reference("sine", axis, duration=5.0),
        robustness=False,
    )  # fmt: skip
    oracle, none = result.metrics["oracle"], result.metrics["none"]
    assert oracle["rms_error_m"] < 0.1 * none["rms_error_m"]


def test_session_scatter_cases_use_the_reproducibility_band():
    model = FrictionModel()
    assert [c.name for c in robustness_cases(model)][:4] == [
        "level +20 %",
        "level -20 %",
        "pressure slope x2",
        "pressure slope x0.5",
    ]
    sheet = model.to_datasheet()
    # the demo datasheet's record: a 14 % between-session prior (docs/uncertainty.md)
    component = {"std_percent": 0.0, "std_N": 0.0, "source": "estimated"}
    scatter = {
        "method": "one-way analysis of variance of the runs",
        "relative": True,
        "components": {
            "repeatability": component,
            "run": component,
            "session": {"std_percent": 14.0, "std_N": 19.4, "source": "prior"},
        },
        "reproducibility": {"std_percent": 14.0, "std_N": 19.4},
    }
    sheet.setdefault("fit", {})["scatter"] = scatter
    cases = {c.name: c for c in robustness_cases(FrictionModel.from_datasheet(sheet))}
    assert cases["session scatter +2 s_R"] == PlantFriction("session scatter +2 s_R", level=1.28)
    assert cases["session scatter -2 s_R"].level == pytest.approx(0.72)


def test_lugre_compensation_beats_pid_alone_on_the_thesis_law():
    model = FrictionModel()  # thesis eq. 4.1-4.3, assumed sigma_0 and sigma_1
    ref = make_reference("sine", DEFAULT_AXIS, duration=5.0)
    result = compare_compensators(model, reference=ref, robustness=False)
    assert set(result.metrics) == {"none", "coulomb", "static", "lugre", "oracle"}
    none, lugre = result.metrics["none"], result.metrics["lugre"]
    assert lugre["rms_error_m"] < none["rms_error_m"]
    assert lugre["reversal_error_m"] < none["reversal_error_m"]
    assert none["reversals"] == 1
    assert none["steady_state_error_m"] is None  # a sine never rests


def test_substeps_converge():
    # PI alone (~6 um RMS) agrees to 1e-3; the compensated loop's ~0.12 um residual is where
    # the 100 us plant step shows: 10 against 50 substeps within 2 % (1.3 % measured)
    model = FrictionModel()
    ref = make_reference("sine", DEFAULT_AXIS, duration=3.0)
    tuning = tune(DEFAULT_AXIS, 380.0)
    fine_axis = DEFAULT_AXIS.replace(substeps=50)
    for compensator, rtol in (("none", 1e-3), ("lugre", 2e-2)):
        fine = simulate_loop(model, compensator, reference=ref, tuning=tuning, axis=fine_axis)
        coarse = simulate_loop(model, compensator, reference=ref, tuning=tuning)
        assert_allclose(
            np.sqrt(np.mean(coarse.error**2)), np.sqrt(np.mean(fine.error**2)), rtol=rtol
        )


def test_steps_give_steady_state_and_hunting_metrics(tmp_path):
    model = FrictionModel()
    ref = make_reference("steps", DEFAULT_AXIS, duration=4.0, period=4.0)
    result = compare_compensators(model, reference=ref, robustness=False)
    m = result.metrics["none"]
    assert m["steady_state_error_m"] is not None and m["steady_state_error_m"] >= 0
    assert m["hunting_amplitude_m"] is not None
    written = result.write(tmp_path / "out")
    doc = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert doc["controller"]["loop_gain_1_s"] == pytest.approx(result.tuning.loop_gain_1_s)
    assert set(doc["compensators"]) == set(result.metrics)
    assert {p.name for p in written} == {
        "metrics.json",
        "timeseries.csv",
        "error.png",
        "control.html",
    }


def test_axis_toml_units_and_errors(tmp_path):
    good = tmp_path / "axis.toml"
    good.write_text(
        '[axis]\nbore = "63 mm"\ndead_volume_a = "0.2 L"\n'
        'valve_nominal_flow = "40 L/min"\nspool_frequency = "80 Hz"\nmass = 120\n'
    )
    axis = load_axis(good)
    assert axis.bore == pytest.approx(0.063)
    assert axis.dead_volume_a == pytest.approx(2e-4)
    assert axis.valve_nominal_flow == pytest.approx(40e-3 / 60)
    bad = tmp_path / "bad.toml"
    bad.write_text('[axis]\nbore = "40 mm"\nstroke = "2 L"\n')
    with pytest.raises(AxisError, match=r"bad.toml, line 3: axis.stroke"):
        load_axis(bad)
    bad.write_text("[axis]\nboar = 0.04\n")
    with pytest.raises(AxisError, match=r"line 2: unknown key axis.boar"):
        load_axis(bad)
    bad.write_text('[axis]\nrod = "50 mm"\n')
    with pytest.raises(AxisError, match=r"line 2: .*rod"):
        load_axis(bad)


def test_reference_file(tmp_path):
    path = tmp_path / "ref.csv"
    path.write_text("time [s],position [mm]\n0,100\n1,101\n2,100\n")
    ref = read_reference(path)
    assert_allclose(ref.position[[0, 1000, 2000]], [0.1, 0.101, 0.1])
    path.write_text("time [s],position [mm]\n0,100\n0,101\n")
    with pytest.raises(ValueError, match="line 3: time is not increasing"):
        read_reference(path)


def test_cli_control_errors_exit_2(tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    runner = CliRunner()
    done = runner.invoke(
        app, ["control", str(tmp_path / "none.json"), "--out", str(tmp_path / "out")]
    )
    assert done.exit_code == 2
    assert "not found" in done.output
