"""Draw the figures of docs/: the friction phenomena of thesis 2.1.3 and the README figure.

Run: ``.venv/bin/python docs/make_figures.py`` (writes PNGs to docs/img/). The numbers come
from the same functions the tests check (cylfric.simulate.phenomena).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from cylfric.simulate import phenomena  # noqa: E402

IMG = Path(__file__).resolve().parent / "img"


def stick_slip():
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, constrained_layout=True)
    for p_bar in (0.1, 80, 160):
        result, amplitude = phenomena.stick_slip(p_bar * 1e5)
        axes[0].plot(
            result.time,
            result.states["velocity"] * 1e3,
            label=f"{p_bar:g} bar (spring force p-p {amplitude:.1f} N)",
        )
        axes[1].plot(result.time, result.outputs["friction_force"])
    axes[0].set_ylabel("velocity [mm/s]")
    axes[1].set_ylabel("friction force [N]")
    axes[1].set_xlabel("time [s]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Stick-slip: 10 kg pulled through 2e4 N/m at 5 mm/s; it grows with pressure")
    fig.savefig(IMG / "stick_slip.png", dpi=100)


def friction_lag():
    fig, ax = plt.subplots(figsize=(6.5, 4.5), constrained_layout=True)
    for p_bar in (0.1, 100):
        v, f, lag = phenomena.friction_lag(p_bar * 1e5)
        ax.plot(v * 1e3, f, label=f"{p_bar:g} bar (accelerating - decelerating: {lag:.1f} N)")
    ax.set_xlabel("velocity [mm/s]")
    ax.set_ylabel("friction force [N]")
    ax.legend(fontsize=8)
    ax.set_title("Friction lag (hysteresis) under 10 ± 8 mm/s at 5 Hz (thesis Fig. 2.1d)")
    fig.savefig(IMG / "friction_lag.png", dpi=100)


def presliding():
    result, at_peak, estimate = phenomena.presliding(50e5)
    fig, ax = plt.subplots(figsize=(6.5, 4.5), constrained_layout=True)
    ax.plot(result.states["position"] * 1e6, result.outputs["friction_force"])
    ax.set_xlabel("displacement [µm]")
    ax.set_ylabel("friction force [N]")
    ax.set_title(
        f"Presliding at 50 bar: force to 0.5 F_c and back; {at_peak * 1e6:.0f} µm "
        f"(F/sigma_0 = {estimate * 1e6:.0f} µm)",
        fontsize=9,
    )
    fig.savefig(IMG / "presliding.png", dpi=100)


def breakaway():
    rates = np.geomspace(20, 1000, 9)  # faster ramps give no distinct peak (see the docstring)
    fig, ax = plt.subplots(figsize=(6.5, 4.5), constrained_layout=True)
    for p_bar in (0.1, 100):
        forces = [phenomena.breakaway_force(p_bar * 1e5, r) for r in rates]
        ax.plot(rates, forces, "o-", label=f"{p_bar:g} bar")
    ax.set_xscale("log")
    ax.set_xlabel("force rate [N/s]")
    ax.set_ylabel("breakaway force [N]")
    ax.legend()
    ax.set_title("Breakaway force against the rate of the applied force")
    fig.savefig(IMG / "breakaway.png", dpi=100)


def readme_figure():
    from cylfric.pipeline import fit_campaign
    from cylfric.simulate.bench import generate_campaign

    with tempfile.TemporaryDirectory() as tmp:
        generate_campaign(Path(tmp) / "campaign")
        out = fit_campaign(Path(tmp) / "campaign", Path(tmp) / "out")
        shutil.copy(out.files["figure_fit"], IMG / "demo_fit.png")


if __name__ == "__main__":
    IMG.mkdir(exist_ok=True)
    for name in sys.argv[1:] or [
        "stick_slip",
        "friction_lag",
        "presliding",
        "breakaway",
        "readme_figure",
    ]:
        globals()[name]()
        print("drew", name)
