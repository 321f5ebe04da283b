"""Sensitivity of the whole model to alpha and v_r (thesis 4.1.1-4.1.2, Tables 4.2-4.4).

At fixed ``alpha`` and ``v_r`` the pressure-dependent model is linear in the remaining six
coefficients, so every grid point is one linear least-squares solve: the RMSE ("SME",
eq. 4.4) of the whole model refit with alpha and v_r held.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np
import pandas as pd
from scipy.optimize import minimize

from ..model import FrictionModel
from .stribeck_fit import design_columns, grid_rss, near_minimum, solve_linear

if TYPE_CHECKING:
    from typing import Any

    from numpy.typing import ArrayLike

__all__ = [
    "rmse_at",
    "refit_at",
    "sensitivity_grid",
    "sensitivity_refits",
    "thesis_tables",
    "THESIS_ALPHAS",
    "THESIS_V_R",
]

THESIS_ALPHAS = (0.5, 0.77, 0.8, 1.0, 1.5, 2.0)
"""alpha values of thesis Tables 4.2 and 4.3 [-]."""
THESIS_V_R = (0.005, 0.00743, 0.010, 0.015)
"""v_r values of thesis Table 4.4 [m/s]; Tables 4.2/4.3 use 7.43 and 10 mm/s."""


def rmse_at(
    velocity: ArrayLike, pressure: ArrayLike, friction: ArrayLike, v_r: float, alpha: float
) -> float:
    """RMSE [N] of the linear-law model refit at fixed ``v_r`` [m/s] and ``alpha`` [-]."""
    speed = np.abs(np.asarray(velocity, dtype=float))
    p_bar = np.asarray(pressure, dtype=float) / 1e5
    force = np.asarray(friction, dtype=float)
    a = design_columns(speed, p_bar, v_r, alpha)
    coef = solve_linear(a, force)
    return float(np.sqrt(np.mean((a @ coef - force) ** 2)))


def refit_at(
    velocity: ArrayLike,
    pressure: ArrayLike,
    friction: ArrayLike,
    v_r: float,
    alpha: float,
    *,
    reference: str = "mean",
) -> tuple[FrictionModel, float]:
    """The linear-law model refit with ``v_r`` [m/s] and ``alpha`` [-] held: (model, RMSE [N]).

    The six pressure-law coefficients of F_c, F_s and sigma_2 come from one linear
    least-squares solve (the model is linear in them at fixed v_r and alpha).
    """
    speed = np.abs(np.asarray(velocity, dtype=float))
    p_bar = np.asarray(pressure, dtype=float) / 1e5
    force = np.asarray(friction, dtype=float)
    a = design_columns(speed, p_bar, v_r, alpha)
    coef = solve_linear(a, force)
    rmse = float(np.sqrt(np.mean((a @ coef - force) ** 2)))
    coefficients = {
        par: {"intercept": float(coef[2 * j]), "slope": float(coef[2 * j + 1]) / 1e5}
        for j, par in enumerate(("F_c", "F_s", "sigma_2"))
    }
    model = FrictionModel(
        {**coefficients, "v_r": float(v_r), "alpha": float(alpha)},
        reference=reference,
        fixed=("v_r", "alpha"),
        statistics={"rmse": rmse, "n_points": int(force.size)},
        provenance={"method": "linear least squares at fixed v_r and alpha (sensitivity)"},
    )
    return model, rmse


def sensitivity_refits(
    velocity: ArrayLike, pressure: ArrayLike, friction: ArrayLike, *, reference: str = "mean"
) -> list[dict[str, Any]]:
    """The refits of thesis Figs. 4.4-4.12: a list of dicts ``panel``, ``alpha [-]``,
    ``v_r [m/s]``, ``rmse [N]``, ``model`` (:class:`~cylfric.model.FrictionModel`).

    Panel ``"alpha"``: alpha in :data:`THESIS_ALPHAS` at v_r = 10 mm/s (Figs. 4.4-4.9);
    panel ``"v_r"``: v_r in :data:`THESIS_V_R` at alpha = 1 (Figs. 4.10-4.12 and 4.7).
    """
    cases = [("alpha", a, 0.010) for a in THESIS_ALPHAS] + [("v_r", 1.0, v) for v in THESIS_V_R]
    out = []
    for panel, alpha, v_r in cases:
        model, rmse = refit_at(velocity, pressure, friction, v_r, alpha, reference=reference)
        out.append(
            {"panel": panel, "alpha [-]": alpha, "v_r [m/s]": v_r, "rmse [N]": rmse, "model": model}
        )
    return out


def sensitivity_grid(
    velocity: ArrayLike,
    pressure: ArrayLike,
    friction: ArrayLike,
    *,
    alphas: ArrayLike | None = None,
    v_rs: ArrayLike | None = None,
) -> tuple[pd.DataFrame, dict[str, float]]:
    """RMSE over a grid of alpha and v_r, and the recommended fixed values.

    Returns a DataFrame with columns ``alpha [-]``, ``v_r [m/s]``, ``rmse [N]``, and the
    minimum as a dict ``{"alpha", "v_r", "rmse"}``: the best grid node refined by a local
    Nelder-Mead search in (log v_r, alpha).
    """
    speed = np.abs(np.asarray(velocity, dtype=float))
    alphas = np.linspace(0.4, 2.5, 22) if alphas is None else np.asarray(alphas, dtype=float)
    v_rs = (
        np.geomspace(max(speed.min(), 1e-4), max(speed.max(), 1e-3), 30)
        if v_rs is None
        else np.asarray(v_rs, dtype=float)
    )
    nodes = [(a, v) for a in alphas for v in v_rs]
    force = np.asarray(friction, dtype=float)
    # all nodes screened at once; those near the minimum solved again one by one, so the
    # minimum and the refinement's start are those of solving every node with rmse_at
    rss, trusted = grid_rss(
        speed,
        np.asarray(pressure, dtype=float) / 1e5,
        force,
        [v for _, v in nodes],
        [a for a, _ in nodes],
    )
    exact = near_minimum(rss, trusted, force)
    rows = [
        {
            "alpha [-]": a,
            "v_r [m/s]": v,
            "rmse [N]": rmse_at(velocity, pressure, friction, v, a)
            if again
            else float(np.sqrt(r / force.size)),
        }
        for (a, v), r, again in zip(nodes, rss, exact, strict=True)
    ]
    table = pd.DataFrame(rows)
    # the row of the smallest rmse (idxmin: a label of the RangeIndex); all-float columns
    best = cast("pd.Series[float]", table.loc[cast("int", table["rmse [N]"].idxmin())])

    def objective(x):
        return rmse_at(velocity, pressure, friction, float(np.exp(x[0])), float(x[1]))

    local = minimize(
        objective,
        [np.log(best["v_r [m/s]"]), best["alpha [-]"]],
        method="Nelder-Mead",
        options={"xatol": 1e-4, "fatol": 1e-9},
    )
    if local.fun < best["rmse [N]"] and 0.1 < local.x[1] < 10:
        return table, {
            "alpha": float(local.x[1]),
            "v_r": float(np.exp(local.x[0])),
            "rmse": float(local.fun),
        }
    return table, {
        "alpha": float(best["alpha [-]"]),
        "v_r": float(best["v_r [m/s]"]),
        "rmse": float(best["rmse [N]"]),
    }


def thesis_tables(velocity: ArrayLike, pressure: ArrayLike, friction: ArrayLike) -> pd.DataFrame:
    """Tables 4.2-4.4 layout: one row per (table, alpha, v_r) with the RMSE [N].

    ``table`` is ``"4.2"`` (alpha varies, v_r = 7.43 mm/s), ``"4.3"`` (alpha varies,
    v_r = 10 mm/s) or ``"4.4"`` (v_r varies, alpha = 1).
    """
    rows = []
    for table, v_r in (("4.2", 0.00743), ("4.3", 0.010)):
        for alpha in THESIS_ALPHAS:
            rows.append(
                {
                    "table": table,
                    "alpha [-]": alpha,
                    "v_r [m/s]": v_r,
                    "rmse [N]": rmse_at(velocity, pressure, friction, v_r, alpha),
                }
            )
    for v_r in THESIS_V_R:
        rows.append(
            {
                "table": "4.4",
                "alpha [-]": 1.0,
                "v_r [m/s]": v_r,
                "rmse [N]": rmse_at(velocity, pressure, friction, v_r, 1.0),
            }
        )
    return pd.DataFrame(rows)
