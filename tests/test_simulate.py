"""Simulation: reference accuracy, closed forms, energy and the phenomena of thesis 2.1.3."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.simulate import (
    AppliedForce,
    Cylinder,
    FrictionModel,
    PositionServo,
    PrescribedMotion,
    SpringPull,
    phenomena,
    simulate,
)

MASS = 10.0
SIGMA_0 = 1e6


def _model(sigma_0=SIGMA_0, mass=MASS):
    return FrictionModel(sigma_0=sigma_0, sigma_1=float(np.sqrt(sigma_0 * mass)))


def _rms_rel(a, b, F_c):
    return float(np.sqrt(np.mean((a - b) ** 2)) / F_c)


@pytest.fixture(scope="module")
def stick_slip_reference():
    """Case A of the benchmark: 10 s, m = 10 kg, k = 2e4 N/m at 5 mm/s, 50 bar (Radau)."""
    return simulate(
        Cylinder(MASS),
        _model(),
        SpringPull(2e4, 5e-3),
        10.0,
        pressure_a=50e5,
        method="scipy",
        rtol=1e-10,
    )


@pytest.fixture(scope="module")
def sine_reference():
    """Case B: prescribed 50 mm/s sin(2 pi t) for 10 s, sigma_0 = 1e7 N/m (Radau)."""
    drive = PrescribedMotion(lambda t: 0.05 * np.sin(2 * np.pi * t))
    return simulate(
        Cylinder(MASS), _model(1e7), drive, 10.0, pressure_a=50e5, method="scipy", rtol=1e-10
    )


def test_stick_slip_case_really_sticks_and_slips(stick_slip_reference):
    v = stick_slip_reference.states["velocity"]
    assert v.max() > 0.03 and abs(v[5000:]).min() < 1e-3  # slips well above 5 mm/s, sticks


@pytest.mark.parametrize("method", ["fixed", "dopri", "rosenbrock"])
def test_default_settings_match_radau_on_stick_slip(stick_slip_reference, method):
    F_c = _model().params_at(50e5)["F_c"]
    result = simulate(
        Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 10.0, pressure_a=50e5, method=method
    )
    err = _rms_rel(
        result.outputs["friction_force"], stick_slip_reference.outputs["friction_force"], F_c
    )
    assert err <= 1e-4, err


def test_default_settings_match_radau_on_sinusoidal_velocity(sine_reference):
    F_c = _model(1e7).params_at(50e5)["F_c"]
    drive = PrescribedMotion(lambda t: 0.05 * np.sin(2 * np.pi * t))
    result = simulate(Cylinder(MASS), _model(1e7), drive, 10.0, pressure_a=50e5)
    err = _rms_rel(result.outputs["friction_force"], sine_reference.outputs["friction_force"], F_c)
    assert err <= 1e-4, err


def test_fixed_step_converges_with_second_order():
    ref = simulate(
        Cylinder(MASS),
        _model(),
        SpringPull(2e4, 5e-3),
        3.0,
        pressure_a=50e5,
        method="fixed",
        step=1e-5,
    )
    errs = []
    for step in (4e-4, 2e-4):
        r = simulate(
            Cylinder(MASS),
            _model(),
            SpringPull(2e4, 5e-3),
            3.0,
            pressure_a=50e5,
            method="fixed",
            step=step,
        )
        errs.append(_rms_rel(r.outputs["friction_force"], ref.outputs["friction_force"], 100))
    assert errs[0] / errs[1] > 2.5  # second order: about 4 when the step halves


@pytest.mark.parametrize("method", ["fixed", "dopri", "rosenbrock", "scipy"])
def test_linear_viscous_only_matches_mass_damper(method):
    # Negligible Coulomb/stiction levels and no bristle damping: F_f = sigma_2 v up to
    # sigma_0 |z| <= 1e-4 N; under a constant force F the closed form is
    # v = F/c (1 - e^{-c t/m}). (The bristle rate sigma_0 |v| / F_c = 400 1/s keeps the
    # explicit Dormand-Prince scheme out of stiffness.)
    c, m, force = 500.0, 10.0, 20.0
    model = FrictionModel(
        coefficients={"F_c": 1e-4, "F_s": 1e-4, "sigma_2": c, "v_r": 0.01, "alpha": 1.0},
        sigma_0=1.0,
        sigma_1=0.0,
    )
    # Rodas3's default rtol (1e-6) gives 1.8e-6 m/s here (local order 3, steps of 1.3 ms over a
    # 20 ms time constant); at rtol 1e-8 it meets the closed form like the others
    rtol = 1e-8 if method == "rosenbrock" else None
    result = simulate(
        Cylinder(m), model, AppliedForce(force), 0.2, dt=1e-3, method=method, rtol=rtol
    )
    t = result.time
    v_exact = force / c * (1 - np.exp(-c * t / m))
    x_exact = force / c * t - force * m / c**2 * (1 - np.exp(-c * t / m))
    assert_allclose(result.states["velocity"], v_exact, atol=4e-7)  # 1e-4 N / c = 2e-7 m/s
    assert_allclose(result.states["position"], x_exact, atol=1e-7)


@pytest.mark.parametrize("pressure", [0.1e5, 100e5])
def test_friction_work_is_never_negative_over_a_closed_stroke(pressure):
    def velocity(t):  # down 20 mm and back up at 20 mm/s with smooth ends
        return -0.02 * np.sin(np.pi * t) * (t < 1) + 0.02 * np.sin(np.pi * (t - 1)) * (t >= 1)

    result = simulate(
        Cylinder(2.5),
        _model(mass=2.5),
        PrescribedMotion(velocity),
        2.0,
        dt=1e-4,
        pressure_a=pressure,
    )
    power = result.outputs["friction_force"] * result.states["velocity"]
    assert abs(result.states["position"][-1]) < 1e-9
    cumulative = np.concatenate(([0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * 1e-4)))
    assert cumulative[-1] > 0 and cumulative.min() >= -1e-6


def test_position_servo_tracks_a_step():
    result = simulate(
        Cylinder(2.5),
        _model(mass=2.5),
        PositionServo(lambda t: 0.01 * (t > 0.05), kp=2e5, ki=1e6, kd=3e3),
        1.0,
        pressure_a=50e5,
        method="fixed",
    )
    assert_allclose(result.states["position"][-1], 0.01, atol=2e-5)


def test_result_to_pandas_names_units():
    result = simulate(Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 0.1)
    frame = result.to_pandas()
    assert {"time [s]", "position [m]", "friction_force [N]", "pressure_a [Pa]"} <= set(frame)


def test_plot_delegates_and_labels_units():
    import matplotlib

    matplotlib.use("Agg")
    result = simulate(Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 0.1)
    axes = result.plot()
    assert axes[2].get_ylabel() == "friction force [N]"


def test_simulation_errors_name_the_problem():
    with pytest.raises(
        ValueError,
        match=r"unknown method 'rk4'; valid: \['rosenbrock', 'dopri', 'fixed', 'scipy'\]",
    ):
        simulate(Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 1.0, method="rk4")
    with pytest.raises(ValueError, match="need 0 < dt <= duration"):
        simulate(Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 1.0, dt=2.0)
    with pytest.raises(ValueError, match="pressure_a has 3 samples; expected 11"):
        simulate(Cylinder(MASS), _model(), SpringPull(2e4, 5e-3), 0.01, pressure_a=[1, 2, 3])
    with pytest.raises(ValueError, match="Cylinder mass = 0 is out of range"):
        Cylinder(0)
    with pytest.raises(ValueError, match="SpringPull stiffness = -1 is out of range"):
        SpringPull(-1, 0.01)
    with pytest.raises(ValueError, match="law 'stribeck' runs only with method='scipy'"):
        simulate(
            Cylinder(MASS), FrictionModel(simulation_law="stribeck"), SpringPull(2e4, 5e-3), 0.1
        )
    with pytest.raises(TypeError, match="unknown drive str"):
        simulate(Cylinder(MASS), _model(), "spring", 0.1)


def test_static_law_runs_in_scipy_backend():
    result = simulate(
        Cylinder(MASS),
        FrictionModel(simulation_law="stribeck"),
        AppliedForce(200.0),
        0.5,
        method="scipy",
        rtol=1e-6,
    )
    assert result.states["velocity"][-1] > 0


def test_pressure_time_series_changes_friction():
    # Prescribed 20 mm/s, pressure ramping 0 -> 150 bar in 1 s: friction follows eq. 4.1-4.3,
    # trailing the steady law by about dF_c/dt * g / (sigma_0 v) = 75 N/s * 5 ms = 0.4 N
    # (the bristle state relaxes with time constant g / (sigma_0 |v|)).
    time = np.arange(0, 1.0001, 1e-3)
    result = simulate(
        Cylinder(2.5), _model(mass=2.5), PrescribedMotion(0.02), 1.0, pressure_a=150e5 * time
    )
    p = _model().params_at(150e5 * time)
    steady = p["F_c"] + (p["F_s"] - p["F_c"]) * np.exp(-2.0) + p["sigma_2"] * 0.02
    lag = steady[200:] - result.outputs["friction_force"][200:]
    assert np.all((lag > 0) & (lag < 0.5))


# ----------------------------------------------------------------------------- phenomena


def test_stick_slip_grows_with_pressure():
    amplitudes = [phenomena.stick_slip(p)[1] for p in (0.1e5, 80e5, 160e5)]
    assert amplitudes[0] > 20  # real stick-slip, not noise
    assert np.all(np.diff(amplitudes) > 1.0)


def test_friction_lag_is_higher_while_accelerating():
    _, _, lag = phenomena.friction_lag(50e5)
    assert lag > 1.0  # N, friction hysteresis of thesis Fig. 2.1d


def test_presliding_is_spring_like_below_breakaway():
    result, at_peak, estimate = phenomena.presliding(50e5)
    assert 0.8 * estimate < at_peak < 2.0 * estimate
    assert np.abs(result.states["position"]).max() < 1e-3  # never slides a millimetre


def test_breakaway_force_falls_with_force_rate():
    forces = [phenomena.breakaway_force(50e5, rate) for rate in (30.0, 100.0, 300.0, 1000.0)]
    assert np.all(np.diff(forces) < 0)
    assert forces[0] < _model().params_at(50e5)["F_s"] * 1.05
    with pytest.raises(RuntimeError, match="without a distinct breakaway"):
        phenomena.breakaway_force(50e5, 1e4)


def test_batch_matches_single_runs():
    from cylfric.simulate import simulate_batch

    models = [_model(s0) for s0 in (1e5, 1e6, 1e7)]
    pressures = [0.1e5, 80e5, 200e5]
    batch = simulate_batch(
        Cylinder(MASS), models, SpringPull(2e4, 5e-3), 3.0, pressures=pressures, record_every=10
    )
    assert batch.friction_force.shape == (3, 301) and batch.time[-1] == pytest.approx(3.0)
    for i, (model, p) in enumerate(zip(models, pressures, strict=True)):
        single = simulate(Cylinder(MASS), model, SpringPull(2e4, 5e-3), 3.0, pressure_a=p)
        assert_allclose(
            batch.friction_force[i], single.outputs["friction_force"][::10], rtol=0, atol=1e-9
        )
    with pytest.raises(ValueError, match="2 models for 3 pressures"):
        simulate_batch(Cylinder(MASS), models[:2], SpringPull(2e4, 5e-3), 1.0, pressures=pressures)
    with pytest.raises(ValueError, match="takes AppliedForce, SpringPull or PositionServo"):
        simulate_batch(Cylinder(MASS), models, PrescribedMotion(0.01), 1.0, pressures=pressures)


def test_batch_includes_the_net_pressure_force_of_an_asymmetric_cylinder():
    from cylfric.simulate import simulate_batch

    cylinder = Cylinder.from_diameters(0.040, 0.028, 2.5)  # single rod: A_a > A_b
    batch = simulate_batch(  # one run per set at simulate()'s tolerance: the same kernel
        cylinder, _model(mass=2.5), AppliedForce(0.0), 0.5, pressures=[0.0, 20e5], rtol=1e-6,
        accuracy=None,
    )  # fmt: skip
    single = simulate(cylinder, _model(mass=2.5), AppliedForce(0.0), 0.5, pressure_a=20e5)
    assert batch.position[0, -1] == 0.0 and batch.position[1, -1] > 1e-3  # pushed out
    assert_allclose(batch.position[1], single.states["position"][::10], atol=1e-9)


def test_prescribed_motion_with_a_pressure_signal_on_the_scipy_reference():
    """Regression: the Radau reference broke (jac of shape (1, 1, n)) when a pressure signal
    made sigma_0 an array; it now agrees with the compiled prescribed-velocity kernel."""
    import warnings

    from cylfric.model import FrictionModel
    from cylfric.simulate import Cylinder, PrescribedMotion, simulate

    drive = PrescribedMotion(lambda t: 0.01 * np.sin(20 * t))
    kwargs = {"pressure_a": lambda t: 50e5 + 100e5 * t}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scipy_run = simulate(Cylinder(10.0), FrictionModel(), drive, 0.2, method="scipy", **kwargs)
        compiled = simulate(Cylinder(10.0), FrictionModel(), drive, 0.2, **kwargs)
    force = scipy_run.outputs["friction_force"]
    assert np.ptp(force) > 150  # a real stroke: -70 to +130 N
    np.testing.assert_allclose(force, compiled.outputs["friction_force"], atol=1e-3)
