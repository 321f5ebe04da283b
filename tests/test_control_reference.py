"""cylfric's loop study against an independently written axis (cylfric.control.reference_loop).

The reference loop shares no code with control/kernel.py, axis.py, loop.py or tuning.py: RK4
on one right-hand side, four turbulent orifices with null leakage, friction integrated with
the other states, PI gains from eigenvalues of the discretised Jacobian. Both run the example
differential axis (examples/servo_axis/axis.toml, 50/28 x 300 mm, 1 um position resolution)
and its double-rod twin, with the same seal; their RMS tracking errors must agree within 10 %
for PI alone, the oracle and the LuGre compensator (cylfric's compensator step, its force
turned into a command by each loop's own force path).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cylfric.control.axis import load_axis
from cylfric.control.loop import compensator_function, make_reference, simulate_loop
from cylfric.control.reference_loop import (
    ReferenceAxis,
    ReferenceSeal,
    reference_tuning,
    rest_equilibrium,
    run_reference,
)
from cylfric.control.tuning import tune
from cylfric.model import FrictionModel

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "servo_axis" / "axis.toml"
DOUBLE_ROD = EXAMPLE.with_name("axis_double_rod.toml")
# the seal: F_c, F_s linear in p_A + p_B [N, N/Pa], sigma_0 = 1e7 N/m (identified)
SEAL = dict(fc0=40.0, fc1=4e-6, fs0=45.0, fs1=4.5e-6, sigma_2=2000.0, v_r=0.01, alpha=1.0,
            sigma_0=1e7, sigma_1=2e4)  # fmt: skip
NULL_LEAKAGE = 1e-7  # m^3/s (0.006 L/min), the reference valve's null leakage


def _model(seal: dict) -> FrictionModel:
    coefficients = {
        "F_c": {"intercept": seal["fc0"], "slope": seal["fc1"]},
        "F_s": {"intercept": seal["fs0"], "slope": seal["fs1"]},
        "sigma_2": seal["sigma_2"],
        "v_r": seal["v_r"],
        "alpha": seal["alpha"],
        "sigma_0": seal["sigma_0"],
        "sigma_1": seal["sigma_1"],
    }
    return FrictionModel(coefficients, reference="sum")


def _both(axis, seal: dict, duration: float = 3.0) -> dict[str, tuple[float, float]]:
    model = _model(seal)
    reference = make_reference("sine", axis, duration=duration)
    tuning = tune(axis, viscous=seal["sigma_2"])
    ref_axis = ReferenceAxis.from_axis(
        axis, null_leakage=NULL_LEAKAGE, resolution=axis.position_resolution
    )
    ref_seal = ReferenceSeal(**seal)
    ref_tuning = reference_tuning(ref_axis, ref_seal, seal["sigma_2"])
    out = {}
    for name in ("none", "oracle", "lugre"):
        run = simulate_loop(model, name, axis=axis, reference=reference, tuning=tuning)
        ours = float(np.sqrt(np.mean(run.error**2)))
        compensator = compensator_function(model, axis) if name == "lugre" else name
        theirs = run_reference(
            ref_axis, ref_seal, reference.position, reference.velocity,
            compensator=compensator, tuning=ref_tuning,
        ).rms_error  # fmt: skip
        out[name] = (ours, theirs)
    return out


@pytest.mark.parametrize("kind", ["differential", "double-rod"])
def test_loop_study_agrees_with_the_independent_axis(kind):
    axis = load_axis(EXAMPLE if kind == "differential" else DOUBLE_ROD)
    assert axis.position_resolution == pytest.approx(1e-6)
    assert (axis.rod_a == 0) == (kind == "differential")
    assert axis.replace(rod_a=0) == load_axis(EXAMPLE).replace(rod_a=0)  # twins
    errors = _both(axis, SEAL)
    for name, (ours, theirs) in errors.items():
        assert ours == pytest.approx(theirs, rel=0.10), (name, errors)
    if kind == "double-rod":  # the comparison has teeth: the oracle moves the error > 10 %
        assert errors["oracle"][0] < 0.6 * errors["none"][0], errors


def test_reference_axis_rest_holds_the_load():
    axis = load_axis(EXAMPLE).replace(load_force=500.0)
    ref = ReferenceAxis.from_axis(axis, null_leakage=3e-6)
    pa, pb, bias = rest_equilibrium(ref, ReferenceSeal(**SEAL))
    assert ref.area_a * pa - ref.area_b * pb == pytest.approx(500.0, rel=1e-9)
    assert 0 < pb < pa * 2 and abs(bias) < 0.05
