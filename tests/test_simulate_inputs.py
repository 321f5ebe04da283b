"""Bad simulation inputs give a clear ValueError (issue 12), and literature sets keep their
dynamic parameters."""

from __future__ import annotations

import math
import re

import pytest

from cylfric.friction.literature import CANUDAS_DE_WIT_1995
from cylfric.model import FrictionModel
from cylfric.simulate import Cylinder, SpringPull, simulate, simulate_batch


def _canudas(**changes):
    return FrictionModel({**dict(CANUDAS_DE_WIT_1995.params), **changes}, pressure_law="constant")


def test_canudas_set_keeps_its_bristle_parameters():
    params = _canudas().params_at(0.0)
    assert params["sigma_0"] == 1e5 and params["sigma_1"] == pytest.approx(math.sqrt(1e5))


@pytest.mark.parametrize(
    "run, message",
    [
        (lambda: _canudas(F_c=math.nan), r"parameter F_c = nan is not finite"),
        (lambda: SpringPull(math.nan, 0.1), r"SpringPull stiffness = nan .* finite stiffness"),
        (lambda: Cylinder(math.inf), r"Cylinder mass = inf .* finite mass > 0 kg"),
        (
            lambda: simulate(Cylinder(1.0), _canudas(F_c=0.0, F_s=0.0), SpringPull(2, 0.1), 1.0),
            r"cannot be simulated: parameters F_c and F_s must both be > 0 N",
        ),
        (
            lambda: simulate(Cylinder(1.0), _canudas(v_r=0.0), SpringPull(2, 0.1), 1.0),
            r"cannot be simulated: parameter v_r = 0.0 is out of range; expected > 0 m/s",
        ),
        (
            lambda: simulate(Cylinder(1.0), _canudas(F_c=-1.0), SpringPull(2, 0.1), 1.0),
            r"cannot be simulated: parameter F_c = -1.0 is out of range",
        ),
        (
            lambda: simulate(
                Cylinder(1.0), _canudas(), SpringPull(2, 0.1), 1.0, method="fixed", step=0.0
            ),
            r"step = 0.0 s is out of range; expected a finite step > 0 s",
        ),
        (
            lambda: simulate(Cylinder(1.0), _canudas(), SpringPull(2, 0.1), math.inf),
            r"need 0 < dt <= duration < inf; got dt = 0.001 s, duration = inf s",
        ),
        (
            lambda: simulate(
                Cylinder(1.0), FrictionModel(), SpringPull(2, 0.1), 1.0, pressure_a=-5e5
            ),
            r"pressure_a goes down to -5e\+05 Pa; expected pressures >= 0 Pa",
        ),
        (
            lambda: FrictionModel(
                {k: v for k, v in CANUDAS_DE_WIT_1995.params.items() if k != "alpha"},
                pressure_law="constant",
            ),
            r"the stribeck law needs alpha",
        ),
        (
            lambda: simulate_batch(
                Cylinder(1.0), [_canudas(v_r=0.0)], SpringPull(2, 0.1), 1.0, pressures=[0.0]
            ),
            r"cannot be simulated: parameter v_r = 0.0",
        ),
    ],
)
def test_bad_inputs_give_a_clear_value_error(run, message):
    with pytest.raises(ValueError, match=message):
        run()


def test_the_literature_set_as_coefficients_keeps_sigma_0_and_sigma_1():
    # the exact call of issue 12: no pressure law named
    params = FrictionModel(coefficients=CANUDAS_DE_WIT_1995.params).params_at(0.0)
    assert params["sigma_0"] == 1e5 and params["sigma_1"] == pytest.approx(math.sqrt(1e5))


@pytest.mark.parametrize(
    "run, message",
    [
        (
            lambda: simulate(Cylinder(1.0), _canudas(), SpringPull(2, 0.1), 1.0, rtol=0.0),
            r"rtol = 0.0 is out of range; expected 0 < rtol < 1",
        ),
        (
            lambda: simulate_batch(Cylinder(1.0), _canudas(), SpringPull(2, 0.1), 1.0, rtol=2.0),
            r"rtol = 2.0 is out of range",
        ),
        (
            lambda: simulate_batch(
                Cylinder(1.0), _canudas(), SpringPull(2, 0.1), 1.0, pressures=[1e5, -1.0]
            ),
            r"pressures go down to -1 Pa or are not finite; expected finite pressures >= 0 Pa",
        ),
        (
            lambda: simulate_batch(
                Cylinder(1.0), _canudas(), SpringPull(2, 0.1), 1.0, pressures=[math.nan]
            ),
            r"not finite",
        ),
        (
            lambda: simulate_batch(Cylinder(1.0), _canudas(), SpringPull(2, 0.1), math.inf),
            r"need 0 < dt <= duration and record_every >= 1 \(duration < inf\)",
        ),
        (
            lambda: simulate_batch([Cylinder(1.0)] * 2, _canudas(), [SpringPull(2, 0.1)] * 3, 1.0),
            r"2 cylinders for 3 sets; expected one per set \(or a single one\)",
        ),
    ],
)
def test_bad_tolerances_and_batch_inputs_give_a_clear_value_error(run, message):
    with pytest.raises(ValueError, match=message):
        run()


@pytest.mark.parametrize("method", ["rosenbrock", "dopri", "fixed", "scipy"])
@pytest.mark.parametrize(
    "state, value",
    [("x0", math.nan), ("v0", math.nan), ("z0", math.nan), ("v0", math.inf), ("x0", -math.inf)],
)
def test_non_finite_initial_states_are_named(method, state, value):
    """Issue 26: a NaN or inf initial state ended in a ZeroDivisionError (rosenbrock) or ran
    to NaN output (fixed); now a ValueError naming the state, its value and unit."""
    with pytest.raises(ValueError, match=rf"^{state} = {value!r} m"):
        simulate(
            Cylinder(2.5),
            _canudas(),
            SpringPull(2e3, 1e-3),
            duration=0.05,
            dt=1e-3,
            method=method,
            **{state: value},
        )


@pytest.mark.parametrize("state", ["x0", "v0"])
def test_non_finite_initial_states_are_named_in_a_batch(state):
    with pytest.raises(ValueError, match=rf"^{state} = nan"):
        simulate_batch(
            _canudas(), [SpringPull(2e3, 1e-3)], [Cylinder(2.5)], duration=0.05, dt=1e-3,
            **{state: math.nan},
        )  # fmt: skip


def test_an_initial_state_that_is_not_a_number_is_named():
    with pytest.raises(ValueError, match=r"^z0 = 'a'; expected a finite number in m"):
        simulate(Cylinder(2.5), _canudas(), SpringPull(2e3, 1e-3), duration=0.05, dt=1e-3, z0="a")


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("name", ["sigma_0", "sigma_1", "sigma_2", "F_c", "F_s", "v_r", "alpha"])
def test_non_finite_friction_parameters_are_named(name, value):
    """Issue 26: every LuGre parameter that is NaN or infinite gives a ValueError naming it
    (at the model for the pressure coefficients, or before the integrator runs)."""
    with pytest.raises(ValueError, match=rf"parameter {name} (= -?inf|= nan|is NaN)"):
        simulate(Cylinder(1.0), _canudas(**{name: value}), SpringPull(2.0, 0.1), 0.1)


@pytest.mark.parametrize("value", [math.nan, math.inf])
@pytest.mark.parametrize(
    "run, shown",
    [
        (lambda v: simulate(Cylinder(v), _canudas(), SpringPull(2.0, 0.1), 0.1), "mass = {}"),
        (
            lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(v, 0.1), 0.1),
            "stiffness = {}",
        ),
        (lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(2.0, v), 0.1), "speed = {}"),
        (
            lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(2.0, 0.1), 0.1, dt=v),
            "dt = {} s",
        ),
        (lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(2.0, 0.1), v), "duration = {} s"),
        (
            lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(2.0, 0.1), 0.1, rtol=v),
            "rtol = {}",
        ),
        (
            lambda v: simulate(Cylinder(1.0), _canudas(), SpringPull(2.0, 0.1), 0.1, pressure_a=v),
            "pressure_a contains NaN or inf",
        ),
        (
            lambda v: simulate_batch(Cylinder(1.0), [_canudas(sigma_0=v)], SpringPull(2, 0.1), 0.1),
            "parameter sigma_0 ",
        ),
    ],
)
def test_non_finite_plant_and_run_parameters_are_named(run, shown, value):
    """Issue 26: a NaN or inf mass, spring, speed, grid, tolerance or pressure gives a
    ValueError whose message names the parameter (with its value where it has one)."""
    with pytest.raises(ValueError, match=re.escape(shown.format(value))):
        run(value)
