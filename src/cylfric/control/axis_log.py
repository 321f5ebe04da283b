"""A logged identification motion of a virtual axis (for :mod:`cylfric.identify.axis_identify`).

:func:`identification_reference` is the motion docs/dynamic_parameters.md asks a user to log
on the real axis (a small sine around one position, then a slow move and back, 10 s);
:func:`virtual_axis_log` runs it in the closed loop of :mod:`.loop` (PI with feedforward, no
compensator) on a plant whose friction, sigma_0 included, is known, and returns what the
axis's sensors would log: the position quantised (1 um by default) with noise, the chamber
pressures with transducer noise, and the valve command. The loop itself feeds back the
plant's exact position (the compiled loop has no sensor model); the noise and quantisation
are the log's.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..identify.axis_identify import AxisLog
from .axis import DEFAULT_AXIS, Axis
from .loop import LoopRun, PlantFriction, Reference, simulate_loop

if TYPE_CHECKING:
    from cylfric.model import FrictionModel

__all__ = ["identification_reference", "virtual_axis_log"]


def _smoothstep(u: np.ndarray) -> np.ndarray:
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def identification_reference(
    axis: Axis = DEFAULT_AXIS,
    *,
    amplitude: float = 8e-6,
    frequency: float = 1.0,
    cycles: int = 4,
    travel: float = 1e-3,
    duration: float = 10.0,
) -> Reference:
    """The identification motion from the axis's start position.

    0.3 s at rest; a sine of ``amplitude`` [m] at ``frequency`` [Hz] for ``cycles``
    periods (presliding: the force stays below breakaway), then one second of a sine of
    half the amplitude at five times the frequency (bristle damping); then a smooth move of
    ``travel`` [m] over 2 s (about 0.75 ``travel`` per second at its peak), a hold, and back
    (gross sliding and two breakaways). ``duration`` [s] at most 10 s by design.
    """
    if not (amplitude > 0 and frequency > 0 and cycles >= 1 and duration > 0):
        raise ValueError("amplitude, frequency, cycles and duration must be > 0")
    t = np.arange(0.0, duration + 0.5 * axis.sample_time, axis.sample_time)
    x = np.zeros_like(t)
    start = 0.3
    stop = start + cycles / frequency
    slow = (t >= start) & (t < stop)
    x[slow] = amplitude * np.sin(2 * math.pi * frequency * (t[slow] - start))
    fast = (t >= stop) & (t < stop + 1.0)
    x[fast] = 0.5 * amplitude * np.sin(2 * math.pi * 5 * frequency * (t[fast] - stop))
    ramp = stop + 1.2
    rest = max(duration - ramp - 4.0, 0.2)
    x += travel * (_smoothstep((t - ramp) / 2.0) - _smoothstep((t - ramp - 2.0 - rest) / 1.8))
    position = axis.start_position + x
    return Reference(t, position, np.gradient(position, axis.sample_time), "identification")


def virtual_axis_log(
    plant: FrictionModel,
    axis: Axis = DEFAULT_AXIS,
    *,
    datasheet: FrictionModel | None = None,
    reference: Reference | None = None,
    seed: int = 0,
    position_resolution: float = 1e-6,
    position_noise: float = 0.2e-6,
    pressure_noise: float = 0.05e5,
) -> tuple[AxisLog, LoopRun]:
    """Log of the identification motion on a virtual axis whose friction is ``plant``.

    Parameters
    ----------
    plant : FrictionModel
        The axis's true friction (its sigma_0 [N/m] and sigma_1 [N*s/m] are the truth).
    axis : Axis
    datasheet : FrictionModel, optional
        What the controller is tuned with (default: ``plant``); no compensator runs.
    reference : Reference, optional
        Default :func:`identification_reference`.
    seed : int
        Noise stream.
    position_resolution : float
        Position quantisation step [m] (0: none).
    position_noise : float
        Standard deviation of the position noise before quantisation [m].
    pressure_noise : float
        Standard deviation of each pressure transducer's noise [Pa].

    Returns
    -------
    (AxisLog, LoopRun)
        The log (what the sensors read) and the run (the truth, ``run.outputs``).
    """
    reference = reference or identification_reference(axis)
    run = simulate_loop(
        datasheet or plant,
        "none",
        axis=axis,
        reference=reference,
        plant=PlantFriction(name="axis", model=plant),
    )
    rng = np.random.default_rng(seed)
    out = run.outputs
    n = out.shape[0]
    position = out[:, 0] + rng.normal(0.0, position_noise, n)
    if position_resolution > 0:
        position = np.round(position / position_resolution) * position_resolution
    log = AxisLog(
        time=reference.time.copy(),
        position=position,
        pressure_a=out[:, 2] + rng.normal(0.0, pressure_noise, n),
        pressure_b=out[:, 3] + rng.normal(0.0, pressure_noise, n),
        command=out[:, 4].copy(),
        source=f"virtual axis (seed {seed})",
    )
    return log, run
