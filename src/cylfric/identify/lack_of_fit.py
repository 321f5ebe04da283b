"""Lack of fit of a friction law: the pure-error F test, or a runs test without replicates.

Where replicates exist (several observations at one operating point: the same direction,
pressure level and speed level), the classical pure-error F test (Draper & Smith, *Applied
Regression Analysis*, 3rd ed., sec. 2.1): the residual sum of squares splits into pure error
(observations about their operating point's mean) and lack of fit (the operating points'
means about the law),

    F = (SS_lof / (G - p)) / (SS_pe / (N - G)),

with G operating points, N observations, p fitted coefficients. When several runs share an
operating point, the observations are the runs' means (a run's strokes share its offset and
level, so they are not independent replicates); otherwise the points themselves.

Without replicates, the Wald-Wolfowitz runs test of the residuals' signs in the order of the
fitted values (Wald & Wolfowitz 1940; statsmodels ``runstest_1samp``): a curved truth under a
straight law gives long runs of one sign.

What a significant result does to the bands (docs/uncertainty.md): nothing is added. The
lack of fit is already in the residual scatter of the point band and in the run component of
the run and session bands (a level off the law is a run off the law); adding it again double
counts (on the real repeatability data, 3.4x the ideal band). The datasheet flags it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["ALPHA", "lack_of_fit", "operating_points"]

ALPHA = 0.05
"""Significance level of the lack-of-fit test [-]."""

SPEED_STEP = 0.1
"""Relative step [-] beyond which a speed starts a new speed level."""

ACTION_SIGNIFICANT = (
    "flagged: the law misses the data beyond their scatter; the lack of fit is already in "
    "the point band's residual scatter and in the run component of the run and session bands, "
    "so it is not added a second time (docs/uncertainty.md)"
)
ACTION_NONE = "none: the law fits within the data's scatter"


def _speed_levels(speed: np.ndarray) -> np.ndarray:
    """Labels of speed levels [-]: sorted speeds, a new level beyond SPEED_STEP relative."""
    order = np.argsort(speed)
    labels = np.empty(speed.size, dtype=int)
    level, start = -1, -math.inf
    for i in order:
        if speed[i] > start * (1 + SPEED_STEP) or level < 0:
            level, start = level + 1, speed[i]
        labels[i] = level
    return labels


def operating_points(points: pd.DataFrame) -> np.ndarray:
    """Label [-] of each point's operating point: direction x pressure level x speed level."""
    from ..levels import pressure_levels

    pressure_labels, _ = pressure_levels(points["pressure [Pa]"])
    speed = np.abs(points["velocity [m/s]"].to_numpy(dtype=float))
    direction = (
        np.sign(points["direction [-]"].to_numpy(dtype=float))
        if "direction [-]" in points
        else np.zeros(len(points))
    )
    keys = pd.DataFrame(
        {"d": direction, "p": np.asarray(pressure_labels), "v": _speed_levels(speed)}
    )
    return keys.groupby(["d", "p", "v"], sort=False).ngroup().to_numpy()


def lack_of_fit(
    points: pd.DataFrame, residuals: np.ndarray, n_parameters: int, *, alpha: float = ALPHA
) -> dict[str, Any] | None:
    """The ``quality.lack_of_fit`` record of a fit, or None when no test applies.

    Parameters
    ----------
    points : pandas.DataFrame
        The fitted points: ``pressure [Pa]``, ``velocity [m/s]``, optionally ``direction [-]``
        and ``run``.
    residuals : array
        Measured minus fitted friction at each point [N].
    n_parameters : int
        Fitted coefficients of the law [-].
    alpha : float
        Significance level [-].
    """
    residuals = np.asarray(residuals, dtype=float)
    groups = operating_points(points)
    frame = pd.DataFrame({"g": groups, "e": residuals})
    if "run" in points:
        frame["run"] = points["run"].astype(str).to_numpy()
        runs_per_group = frame.groupby("g")["run"].nunique()
        if (runs_per_group >= 2).any():  # replicate runs: each run's mean is one observation
            frame = frame.groupby(["g", "run"], as_index=False).agg(e=("e", "mean"))
    n, g = len(frame), int(frame["g"].nunique())
    if n - g >= 1 and g - n_parameters >= 1:
        means = frame.groupby("g")["e"].transform("mean").to_numpy()
        e = frame["e"].to_numpy()
        ss_pe = float(np.sum((e - means) ** 2))
        ss_lof = float(np.sum(e**2)) - ss_pe
        dof = (g - n_parameters, n - g)
        if ss_pe <= 0:
            return None
        from scipy.special import fdtrc  # the F distribution's survival function

        statistic = (max(ss_lof, 0.0) / dof[0]) / (ss_pe / dof[1])
        p_value = float(fdtrc(dof[0], dof[1], statistic))
        test, rms = "pure-error F", math.sqrt(max(ss_lof, 0.0) / n)
        dof_list: list[int] | None = [int(dof[0]), int(dof[1])]
    elif len(residuals) >= 10:
        fitted_order = np.argsort(points["friction [N]"].to_numpy(dtype=float) - residuals)
        statistic, p_value = runs_test(residuals[fitted_order])
        test, rms, dof_list = (
            "Wald-Wolfowitz runs test (residual signs by fitted value)",
            None,
            None,
        )
    else:
        return None
    significant = bool(p_value < alpha)
    return {
        "test": test,
        "statistic": float(statistic),
        "dof": dof_list,
        "p_value": p_value,
        "significant": significant,
        "rms_lack_N": rms,
        "action": ACTION_SIGNIFICANT if significant else ACTION_NONE,
    }


def runs_test(values: np.ndarray) -> tuple[float, float]:
    """Wald-Wolfowitz runs test of the signs of ``values`` (``>= 0`` against ``< 0``):
    (z statistic, two-sided p-value), with the continuity correction of 0.5 below 50 values
    (SAS; as statsmodels ``runstest_1samp(x, cutoff=0, correction=True)``, which it equals,
    tests/test_scatter.py, without importing statsmodels into every fit)."""
    signs = np.asarray(values) >= 0.0
    n = signs.size
    n_runs = 1 + int(np.count_nonzero(signs[1:] != signs[:-1]))
    if n_runs == 1:  # all of one sign: the binomial probability of one run
        p_one = 1.0 / 2.0 ** (min(n, 1024) - 1)
        return -_normal_isf(p_one), 2.0 * p_one
    n_pos = int(np.count_nonzero(signs))
    npn = float(n_pos * (n - n_pos))
    mean = 2.0 * npn / n + 1.0
    std = math.sqrt(2.0 * npn * (2.0 * npn - n) / n**2 / (n - 1.0))
    excess = n_runs - mean
    if n < 50:
        excess = excess - 0.5 if excess > 0.5 else excess + 0.5 if excess < 0.5 else 0.0
    z = excess / std
    return z, math.erfc(abs(z) / math.sqrt(2.0))


def _normal_isf(q: float) -> float:
    from statistics import NormalDist

    return NormalDist().inv_cdf(1.0 - q)
