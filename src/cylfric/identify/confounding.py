"""Confounding of the pressure laws with the direction of motion or the speed.

On a valve-driven axis the chamber pressures are set by the valve and the friction, not by
the experimenter: extension runs at one pressure and retraction at another, whatever the
speed. A pressure slope fitted to such data is the pressure effect plus the difference
between the directions, and the data cannot tell the two apart, however small the slope's
standard error in a model without a direction term.

The criterion is the variance inflation factor of the pressure in the design
``[1, p, direction, |v|]`` (Kutner, Nachtsheim, Neter & Li, *Applied Linear Statistical
Models*, 5th ed., 2005, sec. 10.5: a VIF above 10 signals multicollinearity that makes a
coefficient's estimate unreliable; computed as
:func:`statsmodels.stats.outliers_influence.variance_inflation_factor` defines it, with
numpy: importing statsmodels would load scipy.stats into every fit). ``VIF = 1/(1 - R^2)``
of the pressure regressed on the other columns, so the slope's standard error with a
direction (and speed) term beside it is ``sqrt(VIF)`` times the one without; with the two
directions at disjoint pressures and no spread within a direction it is infinite.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["VIF_LIMIT", "Confounding", "pressure_confounding"]

VIF_LIMIT = 10.0
"""Variance inflation factor [-] above which the pressure slope is confounded (Kutner et al.
2005, sec. 10.5)."""

CRITERION = (
    "variance inflation factor of the pressure in the design [1, p, direction, |v|] above "
    f"{VIF_LIMIT:g} (Kutner et al., Applied Linear Statistical Models, 2005, sec. 10.5; "
    "VIF = 1/(1 - R^2) of p on the other columns)"
)


@dataclass(frozen=True)
class Confounding:
    """What ties the pressure of a points table to the direction or the speed.

    Attributes
    ----------
    vif : float
        Variance inflation factor of the pressure given direction and speed [-] (inf when
        the pressure is an exact combination of them).
    r2_direction, r2_speed : float
        Share of the pressure's variance the direction alone, the speed alone, explain [-].
    by_direction : dict
        ``"extension"``/``"retraction"`` -> (lowest, highest) pressure [Pa] of its points.
    overlap : bool
        Whether the two directions' pressure ranges overlap.
    confounded : bool
        ``vif > VIF_LIMIT``.
    tied_to : str
        ``"direction"``, ``"speed"`` or ``"direction and speed"`` (what explains the pressure).
    """

    vif: float
    r2_direction: float
    r2_speed: float
    by_direction: dict
    overlap: bool
    confounded: bool
    tied_to: str

    def reason(self) -> str:
        """Why the pressure slopes are not identified, in words."""
        ranges = "; ".join(
            f"{name} at {lo / 1e5:.3g}-{hi / 1e5:.3g} bar"
            for name, (lo, hi) in self.by_direction.items()
        )
        vif = "infinite" if not math.isfinite(self.vif) else f"{self.vif:.3g}"
        return (
            f"confounded: the pressure is tied to the {self.tied_to} ({ranges}; variance "
            f"inflation factor {vif} > {VIF_LIMIT:g}), so a pressure slope cannot be told "
            f"from a {'direction' if 'direction' in self.tied_to else 'speed'} effect"
        )

    def record(self, parameters) -> dict:
        """The datasheet's ``fit.confounding`` record."""
        return {
            "criterion": CRITERION,
            "vif": self.vif if math.isfinite(self.vif) else None,
            "r2_direction": self.r2_direction,
            "r2_speed": self.r2_speed,
            "pressure_by_direction_Pa": {k: list(v) for k, v in self.by_direction.items()},
            "overlap": self.overlap,
            "confounded": self.confounded,
            "tied_to": self.tied_to,
            "not_identified": list(parameters),
            "identifiable": "the friction of each direction at its own pressures and speeds: "
            "the fitted law reproduces them there; its pressure slopes mix the pressure "
            "effect with the "
            + self.tied_to
            + " effect and hold on the rig's own operating path only",
        }


def _r2(y, x):
    design = np.column_stack([np.ones_like(y), x])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    res = y - design @ coef
    total = float(((y - y.mean()) ** 2).sum())
    return 1.0 - float(res @ res) / total if total > 0 else 1.0


def pressure_confounding(points) -> Confounding | None:
    """The confounding of the pressure with the direction and speed of ``points``.

    ``points`` has ``pressure [Pa]``, ``velocity [m/s]`` and ``direction [-]`` (else the sign
    of the velocity). Returns None when the question does not arise: a single direction, or
    a pressure that does not vary (no slope to identify).
    """
    p = points["pressure [Pa]"].to_numpy(float)
    v = points["velocity [m/s]"].to_numpy(float)
    d = points["direction [-]"].to_numpy(float) if "direction [-]" in points else np.sign(v)
    if p.size < 4 or np.ptp(p) <= max(0.5e5, 0.02 * float(np.abs(p).max())):
        return None
    if not ((d > 0).any() and (d < 0).any()):
        return None
    speed = np.abs(v)
    columns = [np.ones_like(p), (p - p.mean()) / p.std(), d]
    if np.ptp(speed) > 0:
        columns.append((speed - speed.mean()) / speed.std())
    r2 = _r2(columns[1], np.column_stack(columns[2:]))
    vif = 1.0 / (1.0 - r2) if r2 < 1.0 - 1e-12 else math.inf
    r2_direction = _r2(p, d)
    r2_speed = _r2(p, speed) if np.ptp(speed) > 0 else 0.0
    by_direction = {
        name: (float(p[d == sign].min()), float(p[d == sign].max()))
        for name, sign in (("extension", 1), ("retraction", -1))
    }
    (lo_e, hi_e), (lo_r, hi_r) = by_direction.values()
    overlap = lo_e <= hi_r and lo_r <= hi_e
    if r2_direction >= 0.5 and r2_speed >= 0.5:
        tied = "direction and speed"
    elif r2_speed > r2_direction:
        tied = "speed"
    else:
        tied = "direction"
    return Confounding(
        vif=vif,
        r2_direction=r2_direction,
        r2_speed=r2_speed,
        by_direction=by_direction,
        overlap=overlap,
        confounded=vif > VIF_LIMIT,
        tied_to=tied,
    )
