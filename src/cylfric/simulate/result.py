"""The result of a simulation (python-control's TimeResponseData pattern)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

UNITS = {
    "position": "m",
    "velocity": "m/s",
    "z": "m",
    "friction_force": "N",
    "drive_force": "N",
    "pressure_a": "Pa",
    "pressure_b": "Pa",
}


@dataclass(frozen=True)
class SimulationResult:
    """Time response of a simulated cylinder.

    Attributes
    ----------
    time : ndarray
        Sample times [s].
    states : dict of ndarray
        ``position`` [m], ``velocity`` [m/s], ``z`` bristle deflection [m].
    outputs : dict of ndarray
        ``friction_force`` [N] (positive in the direction of motion), ``drive_force`` [N]
        (force of the drive on the rod), ``pressure_a``, ``pressure_b`` [Pa].
    info : dict
        Integrator details (method, steps, iterations, ...).
    """

    time: np.ndarray
    states: dict
    outputs: dict
    info: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """A DataFrame with one column per signal, named with its unit (``"time [s]"``)."""
        import pandas as pd

        columns = {"time [s]": self.time}
        for name, values in {**self.states, **self.outputs}.items():
            columns[f"{name} [{UNITS.get(name, '-')}]"] = values
        return pd.DataFrame(columns)

    def plot(self, ax: np.ndarray | None = None) -> np.ndarray:
        """Plot position, velocity and friction force against time (see :mod:`.plotting`)."""
        from .plotting import plot_result

        return plot_result(self, ax=ax)
