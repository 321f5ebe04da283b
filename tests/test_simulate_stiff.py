"""The default Rosenbrock integrator on stiff bristles (issue 12): Canudas de Wit 1995
stick-slip against Radau computed here, the sigma_0 sweep, the analytic Jacobian, batches."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.integrate import solve_ivp

from cylfric.friction import lugre_force
from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import Cylinder, SpringPull, kernels, simulate, simulate_batch

# Canudas de Wit, Olsson, Astrom, Lischinsky 1995, simulation parameters: m = 1 kg, spring
# 2 N/m pulled at 0.1 m/s; sigma_1 = sqrt(sigma_0 m) as in the paper at sigma_0 = 1e5 N/m.
MASS, K, SPEED = 1.0, 2.0, 0.1


def _canudas(sigma_0=1e5):
    params = {**CANUDAS_DE_WIT_1995.params, "sigma_0": sigma_0, "sigma_1": math.sqrt(sigma_0)}
    return FrictionModel(params, pressure_law="constant"), params


def _radau(params, duration, dt=1e-3):
    """Reference: scipy Radau at rtol 1e-10 on the model's law (issue 12's reference)."""
    p = params

    def rhs(t, y):
        x, v, z = y
        force, dz = _force_dz(v, z, p)
        return [v, (K * (SPEED * t - x) - force) / MASS, dz]

    t = np.arange(int(round(duration / dt)) + 1) * dt
    sol = solve_ivp(
        rhs,
        (0, t[-1]),
        [0, 0, 0],
        method="Radau",
        t_eval=t,
        rtol=1e-10,
        atol=[1e-12, 1e-12, 1e-10 * p["F_c"] / p["sigma_0"]],
    )
    assert sol.success
    x, v, z = sol.y
    return t, v, np.array([_force_dz(vi, zi, p)[0] for vi, zi in zip(v, z, strict=True)])


def _force_dz(v, z, p):
    """LuGre force and dz/dt from the model's law (eq. 2.5): dz/dt from the force identity
    F = sigma_0 z + sigma_1 dz + sigma_2 v."""
    force = float(
        lugre_force(
            v,
            z,
            p["sigma_0"],
            p["sigma_1"],
            p["sigma_2"],
            p["F_c"],
            p["F_s"],
            p["v_r"],
            alpha=p["alpha"],
        )
    )
    return force, (force - p["sigma_0"] * z - p["sigma_2"] * v) / p["sigma_1"]


def _slip_starts(t, v, threshold=0.02):
    """Times at which the velocity rises through ``threshold`` [m/s] (a slip begins)."""
    up = np.flatnonzero((v[:-1] < threshold) & (v[1:] >= threshold))
    return t[up] + (threshold - v[up]) / (v[up + 1] - v[up]) * (t[1] - t[0])


@pytest.fixture(scope="module")
def canudas_reference():
    model, params = _canudas()
    return model, params, _radau(params, 14.5)  # slips begin at 7.48 s and 13.84 s


def test_canudas_stick_slip_period_matches_radau(canudas_reference):
    model, params, (t, v_ref, f_ref) = canudas_reference
    result = simulate(Cylinder(MASS), model, SpringPull(K, SPEED), 14.5)
    starts = _slip_starts(result.time, result.states["velocity"])
    starts_ref = _slip_starts(t, v_ref)
    assert len(starts) == len(starts_ref) >= 2  # at least one full stick-slip period
    assert_allclose(np.diff(starts), np.diff(starts_ref), atol=1e-4)  # period to 0.1 ms
    error = np.sqrt(np.mean((result.outputs["friction_force"] - f_ref) ** 2)) / params["F_c"]
    assert error <= 1e-4  # the accuracy goal of issue 12


@pytest.mark.parametrize("sigma_0", [1e5, 1e7, 1e10])
def test_sigma_0_sweep_finishes_without_nan_within_the_force_error_bound(sigma_0):
    model, params = _canudas(sigma_0)
    duration = 9.0  # the first slip (about 7.5 s) and the stick that follows
    result = simulate(Cylinder(MASS), model, SpringPull(K, SPEED), duration)
    force = result.outputs["friction_force"]
    assert np.all(np.isfinite(force)) and np.all(np.isfinite(result.states["velocity"]))
    _, _, f_ref = _radau(params, duration)
    error = np.sqrt(np.mean((force - f_ref) ** 2)) / params["F_c"]
    assert error <= 1e-4
    # the cost does not grow with sigma_0: a few hundred steps, not ~sqrt(sigma_0)
    assert result.info["accepted"] < 1000


def test_analytic_jacobian_matches_finite_differences_of_the_law():
    rng = np.random.default_rng(3)
    for _ in range(200):
        p = {
            "sigma_0": 10 ** rng.uniform(4, 10),
            "F_c": rng.uniform(1, 100),
            "v_r": 10 ** rng.uniform(-4, -1),
            "alpha": rng.choice([1.0, 2.0, 1.5]),
        }
        p["F_s"] = p["F_c"] * rng.uniform(1, 2)
        p["sigma_1"], p["sigma_2"] = 1.0, 0.0
        v = rng.choice([-1, 1]) * 10 ** rng.uniform(-5, 0)
        z = rng.uniform(-1, 1) * p["F_c"] / p["sigma_0"]
        d_v, d_z, _, _ = kernels.lugre_partials(
            v, z, p["sigma_0"], p["F_c"], p["F_s"], p["v_r"], p["alpha"]
        )
        hv, hz = 1e-6 * abs(v), 1e-6 * p["F_c"] / p["sigma_0"]
        fd_v = (_force_dz(v + hv, z, p)[1] - _force_dz(v - hv, z, p)[1]) / (2 * hv)
        fd_z = (_force_dz(v, z + hz, p)[1] - _force_dz(v, z - hz, p)[1]) / (2 * hz)
        assert d_v == pytest.approx(fd_v, rel=1e-3, abs=1e-8 * (1 + abs(fd_v)))
        assert d_z == pytest.approx(fd_z, rel=1e-3, abs=1e-6)


def test_heterogeneous_batch_gives_the_simulation_results_of_single_runs():
    models = [_canudas(s0)[0] for s0 in (1e5, 1e8, 1e10)]
    drives = [SpringPull(2.0, 0.1), SpringPull(3.0, 0.05), SpringPull(1.5, 0.2)]
    # one run per set at simulate()'s tolerance (no accuracy check): the same kernel
    batch = simulate_batch(
        Cylinder(MASS), models, drives, 3.0, record_every=1, rtol=1e-6, accuracy=None
    )
    assert len(batch) == 3 and batch.friction_force.shape == (3, 3001)
    for i, (model, drive) in enumerate(zip(models, drives, strict=True)):
        single = simulate(Cylinder(MASS), model, drive, 3.0)
        got = batch[i]
        for name in ("position", "velocity", "z"):
            assert_allclose(got.states[name], single.states[name], rtol=0, atol=1e-12)
        for name in ("friction_force", "drive_force"):
            assert_allclose(got.outputs[name], single.outputs[name], rtol=0, atol=1e-9)
    assert [r.info["set"] for r in batch.results()] == [0, 1, 2]
    with pytest.raises(ValueError, match="2 drives for 3 sets"):
        simulate_batch(Cylinder(MASS), models, drives[:2], 1.0)


def test_batch_accuracy_check_keeps_every_set_within_its_goal():
    """Issue 26: a fixed rtol does not bound a set's error. The first set (sigma_0 9.8064e9
    N/m, a 3.3649 N/m spring at 0.1808 m/s: many stick-slip cycles in 10 s; from a random
    batch of 2,000) misses 1e-4 at rtol 1e-6 (2.0e-4 on the 10 ms record grid); the per-set
    check tightens it until successive runs agree, the easy set keeps rtol 1e-6."""
    sets = [(9.8064e9, 3.3649, 0.1808), (1e5, 2.0, 0.1)]
    models = [_canudas(s0)[0] for s0, _, _ in sets]
    drives = [SpringPull(k, speed) for _, k, speed in sets]
    batch = simulate_batch(Cylinder(MASS), models, drives, 10.0, record_every=10)
    once = simulate_batch(Cylinder(MASS), models, drives, 10.0, rtol=1e-6, accuracy=None)
    for i, (model, drive) in enumerate(zip(models, drives, strict=True)):
        # reference: the same integrator at rtol 1e-9 (its error decreases tenfold a decade)
        ref = simulate(Cylinder(MASS), model, drive, 10.0, rtol=1e-9)
        ref_force = ref.outputs["friction_force"][::10]
        f_c = CANUDAS_DE_WIT_1995.params["F_c"]

        def error(force, ref_force=ref_force, f_c=f_c):
            return np.sqrt(np.mean((force - ref_force) ** 2)) / f_c

        assert error(batch.friction_force[i]) <= 1e-4
        assert batch.info["accuracy_passed"][i]
        if i == 0:  # the check was needed: one run at 1e-6 misses the goal
            assert error(once.friction_force[i]) > 1e-4
            assert batch.info["rtol"][0] < 1e-6 <= batch.info["rtol"][1]
    with pytest.raises(ValueError, match="accuracy"):
        simulate_batch(Cylinder(MASS), models, drives, 1.0, accuracy=0.0)
