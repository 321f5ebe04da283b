"""Tracking metrics of one closed-loop run (SI; the names carry the unit).

- ``rms_error_m``, ``max_error_m``: RMS and maximum of ``|x_ref - x|`` over the run;
- ``reversal_error_m``: the mean over the reference's reversals (sign changes of the
  reference velocity) of the largest ``|x_ref - x|`` within ``REVERSAL_WINDOW`` after each;
- ``steady_state_error_m``: mean ``|x_ref - x|`` over the samples where the reference has
  rested for more than ``SETTLE`` (None when it never rests, e.g. a sine);
- ``hunting_amplitude_m``, ``hunting_period_s``: half the peak-to-peak error and the mean
  period between its zero-mean upward crossings over the same resting samples (a limit
  cycle; None without rests or without two crossings);
- ``control_effort_rms``: RMS of the valve command [-]; ``control_travel_1_s``: the total
  variation of the command per second [1/s] (wear of the valve).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["tracking_metrics", "REVERSAL_WINDOW", "SETTLE"]

REVERSAL_WINDOW = 0.5
"""Time after a reversal searched for its error [s]."""
SETTLE = 0.5
"""Rest of the reference before its samples count as steady state [s]."""


def _reversals(velocity: np.ndarray) -> np.ndarray:
    sign = np.sign(velocity)
    moving = np.nonzero(sign != 0)[0]
    if moving.size < 2:
        return np.array([], dtype=int)
    s = sign[moving]
    return moving[1:][s[1:] != s[:-1]]


def tracking_metrics(
    time: np.ndarray,
    reference: np.ndarray,
    ref_velocity: np.ndarray,
    position: np.ndarray,
    command: np.ndarray,
) -> dict:
    """The metrics (see the module notes) of one run sampled at ``time`` [s]."""
    error = reference - position
    dt = float(time[1] - time[0])
    window = int(round(REVERSAL_WINDOW / dt))
    peaks = [np.abs(error[i : i + window]).max() for i in _reversals(ref_velocity)]
    rest = np.zeros(len(time), dtype=bool)
    still = np.r_[False, np.diff(reference) == 0] & (ref_velocity == 0)
    run = 0
    for i, flag in enumerate(still):
        run = run + 1 if flag else 0
        rest[i] = run * dt > SETTLE
    metrics: dict = {
        "rms_error_m": float(np.sqrt(np.mean(error**2))),
        "max_error_m": float(np.abs(error).max()),
        "reversal_error_m": float(np.mean(peaks)) if peaks else None,
        "reversals": len(peaks),
        "steady_state_error_m": float(np.mean(np.abs(error[rest]))) if rest.any() else None,
        "hunting_amplitude_m": None,
        "hunting_period_s": None,
        "control_effort_rms": float(np.sqrt(np.mean(command**2))),
        "control_travel_1_s": float(np.abs(np.diff(command)).sum() / (time[-1] - time[0])),
    }
    if rest.any():
        starts = np.nonzero(np.diff(np.r_[0, rest.astype(int)]) == 1)[0]
        ends = np.nonzero(np.diff(np.r_[rest.astype(int), 0]) == -1)[0]
        amplitudes, periods = [], []
        for a, b in zip(starts, ends, strict=True):
            part = error[a : b + 1]
            if part.size < 3:
                continue
            amplitudes.append(0.5 * float(part.max() - part.min()))
            centred = part - part.mean()
            up = np.nonzero((centred[:-1] < 0) & (centred[1:] >= 0))[0]
            if up.size >= 2:
                periods.append(float(np.mean(np.diff(up))) * dt)
        if amplitudes:
            metrics["hunting_amplitude_m"] = float(np.mean(amplitudes))
        if periods:
            metrics["hunting_period_s"] = float(np.mean(periods))
    for key, value in metrics.items():
        if isinstance(value, float) and not math.isfinite(value):
            metrics[key] = None
    return metrics
