"""Figures of simulation results (matplotlib; engineering units on the axes)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from .result import SimulationResult


def plot_result(result: SimulationResult, ax: np.ndarray | None = None) -> np.ndarray:
    """Position [mm], velocity [mm/s] and friction [N] against time [s]; returns the axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(3, 1, sharex=True, figsize=(8, 7), constrained_layout=True)
    t = result.time
    ax[0].plot(t, result.states["position"] * 1e3)
    ax[0].set_ylabel("position [mm]")
    ax[1].plot(t, result.states["velocity"] * 1e3)
    ax[1].set_ylabel("velocity [mm/s]")
    ax[2].plot(t, result.outputs["friction_force"])
    ax[2].set_ylabel("friction force [N]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.grid(True, alpha=0.3)
    return ax
