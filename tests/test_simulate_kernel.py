"""The compiled Rodas3 kernel's pieces (issue 12's speed work): the cheap exp(-x), the compact
input block, the drive force computed in the kernel, and the remembered friction parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import AppliedForce, Cylinder, PositionServo, SpringPull, kernels, simulate
from cylfric.simulate.plant import MAX_STEPS, rosenbrock_tolerances


def _canudas(sigma_0=1e5):
    params = {**CANUDAS_DE_WIT_1995.params, "sigma_0": sigma_0, "sigma_1": math.sqrt(sigma_0)}
    return FrictionModel(params, pressure_law="constant"), params


def test_exp_neg_is_math_exp_to_one_ulp():
    # the series branch (x < 1e-3), math.exp between, and 0.0 where exp underflows (x > 746)
    x = np.concatenate(
        ([0.0, 1e-300, 1e-17], np.geomspace(1e-16, 1e-3, 4000), np.linspace(9e-4, 760.0, 4000))
    )
    for value in x:
        expected = math.exp(-value)
        got = kernels.exp_neg(value)
        assert abs(got - expected) <= 2.3e-16 * expected + 5e-324, value
    assert kernels.exp_neg(746.5) == 0.0 == math.exp(-746.5)


def _rodas3(sig, dt_s, ramp, n, params, k=2.0, rtol=1e-6):
    p = params
    return kernels.rosenbrock(
        sig, dt_s, ramp, 1e-3, n, 0.0, 0.0, 0.0, 1.0, k, 0.0, 0.0, p["sigma_0"], p["sigma_1"],
        p["v_r"], p["alpha"], rtol, *rosenbrock_tolerances(rtol, p), MAX_STEPS, 0.0,
    )  # fmt: skip


def test_compact_and_interpolated_input_blocks_give_the_grid_block_result():
    """Two rows and a ramp (a spring at constant speed), a coarse block interpolated in time
    and one row per grid point describe the same inputs: same steps, same outputs to
    rounding (over 9 s: sticking, the first slip at about 7.5 s and the slide after it)."""
    _, p = _canudas(1e7)
    n = 9001
    t = np.arange(n) * 1e-3
    friction = [p["F_c"], p["F_s"], p["sigma_2"]]
    grid = np.column_stack(
        [0.1 * t, np.full(n, 0.1), np.zeros(n), *(np.full(n, f) for f in friction)]
    )
    compact = np.array([[0.0, 0.0, 0.0, *friction]] * 2)
    coarse = grid[::1500]  # 7 rows 1.5 s apart: x_ref is linear, so interpolation is exact
    reference = _rodas3(grid, 1e-3, 0.0, n, p)
    assert reference[1][1].max() > 0.3  # it slips
    # position [m], velocity [m/s], z [m], friction [N], drive force [N]: 1e-9 of their scale
    atol = np.array([0.4, 0.4, 1.5e-7, 1.5, 1.5])[:, None] * 1e-9
    for sig, dt_s, ramp in ((compact, 9.0, 0.1), (coarse, 1.5, 0.0)):
        time, out, accepted, rejected, reached = _rodas3(sig, dt_s, ramp, n, p)
        assert (reached, accepted, rejected) == (n, reference[2], reference[3])
        assert_allclose(time, reference[0], rtol=0, atol=0)
        assert np.all(np.abs(out - reference[1]) <= atol)


def test_drive_force_from_the_kernel_is_the_drive_law_on_the_states():
    """The kernel writes k (x_ref - x) + c (v_ref - v) + f_ext (pressure force excluded): it
    equals the drive law applied to the returned states, for constant and varying pressure."""
    model, _ = _canudas(1e6)
    cylinder = Cylinder.from_diameters(0.040, 0.028, 1.0)  # single rod: pressure pushes
    drive = SpringPull(3.0, 0.05, damping=0.5)
    for pressure in (2e5, lambda t: 1e5 + 2e5 * t):
        result = simulate(cylinder, model, drive, 2.0, pressure_a=pressure, pressure_b=0.0)
        x, v = result.states["position"], result.states["velocity"]
        expected = 3.0 * (0.05 * result.time - x) + 0.5 * (0.05 - v)
        assert_allclose(result.outputs["drive_force"], expected, rtol=0, atol=1e-12)


def test_servo_drive_force_balances_the_momentum():
    """With an integral gain the kernel's drive force uses its integral state: m a equals
    drive + pressure force - friction along the run (central differences of v, 0.1 ms)."""
    model = FrictionModel(sigma_0=1e6, sigma_1=float(np.sqrt(1e6 * 2.5)))
    drive = PositionServo(lambda t: 0.002 * np.sin(2 * np.pi * t), kp=2e5, ki=1e6, kd=3e3)
    result = simulate(Cylinder(2.5), model, drive, 1.0, dt=1e-4, pressure_a=50e5)
    v = result.states["velocity"]
    accel = np.gradient(v, result.time)
    net = result.outputs["drive_force"] - result.outputs["friction_force"]
    residual = 2.5 * accel[1:-1] - net[1:-1]
    assert np.sqrt(np.mean(residual**2)) <= 1e-2 * np.sqrt(np.mean(net**2))


def test_remembered_parameters_follow_the_model_and_the_pressure():
    model, _ = _canudas(1e5)
    stiffer = model.replace(sigma_0=1e8, sigma_1=1e4)
    runs = [
        simulate(Cylinder(1.0), m, AppliedForce(0.8), 0.2, pressure_a=p)
        for m, p in ((model, 0.0), (stiffer, 0.0), (model, 0.0))
    ]
    z = [r.states["z"][-1] for r in runs]
    assert z[0] == z[2] and z[1] != pytest.approx(z[0], rel=1e-3)
    # presliding under a constant 0.8 N (below F_c = 1 N): z settles at 0.8 N / sigma_0
    assert_allclose(z[0], 0.8 / 1e5, rtol=1e-3)
    assert_allclose(z[1], 0.8 / 1e8, rtol=1e-3)


def test_remembered_parameters_follow_the_pressure():
    """The thesis law's F_c grows with pressure: the same model at 20, 100 and again 20 bar
    gives the 20 bar result twice and a larger steady sliding force at 100 bar."""
    model = FrictionModel(sigma_0=1e6, sigma_1=float(np.sqrt(1e6 * 10.0)))
    drive = SpringPull(2e4, 0.05)
    runs = [simulate(Cylinder(10.0), model, drive, 0.5, pressure_a=p) for p in (20e5, 100e5, 20e5)]
    force = [r.outputs["friction_force"] for r in runs]
    assert_allclose(force[0], force[2], rtol=0, atol=0)
    assert force[1][-1] > force[0][-1] + 5.0  # [N]; F_c(100 bar) - F_c(20 bar) is about 40 N


@pytest.mark.parametrize("alpha", [1.0, 2.0])
def test_vectorised_output_is_the_lugre_force_on_the_states(alpha):
    """Issue 26: the output loop takes g(v) without math.exp where exp_neg needs none (the
    series below 1e-3, zero above 746) and fixes up the other points after. The friction it
    writes is eq. 2.5 on the returned states at every point, in all three ranges."""
    _, p = _canudas(1e5)
    p = {**p, "alpha": alpha}
    model = FrictionModel(p, pressure_law="constant")
    result = simulate(Cylinder(1.0), model, SpringPull(2.0, 0.1), 10.0)
    v, z = result.states["velocity"], result.states["z"]
    arg = (np.abs(v) / p["v_r"]) ** alpha
    assert np.any(arg < 1e-3)  # sticking: the series
    assert np.any(arg > 746.0) == (alpha == 2.0)  # slipping at 0.1 m/s: zero for alpha 2
    assert np.count_nonzero((arg >= 1e-3) & (arg <= 746.0)) > 10  # fixed-up points exist
    g = p["F_c"] + (p["F_s"] - p["F_c"]) * np.exp(-arg)
    expected = p["sigma_0"] * z + p["sigma_1"] * (v - p["sigma_0"] * np.abs(v) * z / g)
    expected += p["sigma_2"] * v
    assert_allclose(result.outputs["friction_force"], expected, rtol=1e-12, atol=1e-12)
