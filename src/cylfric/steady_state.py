"""Force balance and steady-state extraction: from a run to friction points (thesis ch. 3).

Force balance (eq. 3.1/3.2), with the signs of the rig from the campaign configuration::

    F_f sign(v) = A_a p_a - A_b p_b + s_lc F_l - m x''

In the thesis rig (equal areas, equal pressures, inertia negligible at constant speed) the
load cell reads the friction directly. The load cell also carries a constant weight offset
``W``; per run it is ``(F_up + F_down) / 2`` and the friction ``(F_up - F_down) / 2``.

Windows follow ``pvlib.clearsky.detect_clearsky``: every threshold is a keyword with its
unit, and :func:`find_windows` can return its intermediate components.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.ndimage import median_filter
from scipy.signal import savgol_filter

from .io.campaign import CampaignConfig, discover_runs, load_config, read_run
from .io.text import BenchFileError

__all__ = [
    "friction_signal",
    "smoothed_velocity",
    "find_windows",
    "extract_points",
    "extract_campaign",
    "Extraction",
    "POINT_COLUMNS",
]

POINT_COLUMNS = [
    "run",
    "file",
    "stroke",
    "direction [-]",
    "pressure [Pa]",
    "pressure_std [Pa]",
    "velocity [m/s]",
    "velocity_std [m/s]",
    "force [N]",
    "friction [N]",
    "friction_std [N]",
    "n [-]",
    "window_start [s]",
    "window_end [s]",
    "spikes [-]",
    "offset [N]",
    "flag",
]
"""Columns of the points table. ``force`` is the mean force-balance signal (with the offset),
``friction`` the friction magnitude after removing the run's offset, ``flag`` is ``"ok"``,
``"short_window"``, ``"unsettled"`` or ``"no_offset"``."""


def friction_signal(data: pd.DataFrame, config: CampaignConfig, velocity=None) -> np.ndarray:
    """``F_f sign(v)`` plus the weight offset, from eq. 3.1 [N].

    Uses ``force [N]``, the pressure columns (``pressure_a``/``pressure_b``, or ``pressure``
    for both chambers) with the areas of ``config``, and the inertia term when
    ``config.moving_mass`` > 0 (``velocity`` [m/s] then needed).
    """
    if "force [N]" not in data:
        raise ValueError(f"no force column; found {list(data.columns)}")
    signal = config.load_cell_sign * data["force [N]"].to_numpy()
    pa = data.get("pressure_a [Pa]", data.get("pressure [Pa]"))
    pb = data.get("pressure_b [Pa]", data.get("pressure [Pa]"))
    if config.area_a and pa is not None:
        signal = signal + config.area_a * pa.to_numpy()
    if config.area_b and pb is not None:
        signal = signal - config.area_b * pb.to_numpy()
    if config.moving_mass:
        acceleration = np.gradient(velocity, data["time [s]"].to_numpy())
        signal = signal - config.moving_mass * acceleration
    return signal


def smoothed_velocity(time, position, *, window=0.2, sign=1.0):
    """Velocity [m/s] by a Savitzky-Golay derivative over ``window`` [s] (quadratic)."""
    dt = float(np.median(np.diff(time)))
    if not dt > 0:
        raise ValueError("time must increase; found a non-increasing time column")
    n = max(5, int(round(window / dt)) | 1)
    n = min(n, (len(time) - 1) | 1 if len(time) % 2 == 0 else len(time))
    if n < 3:
        return sign * np.gradient(position, time)
    return sign * savgol_filter(position, n, 2, deriv=1, delta=dt)


@dataclass
class _Window:
    stroke: int
    direction: int
    start: int
    stop: int  # exclusive
    flag: str


def find_windows(
    time,
    velocity,
    force,
    *,
    nominal_speed=math.nan,
    moving_fraction=0.3,
    settle_tolerance=0.02,
    min_samples=10,
    trim_sigma=4.0,
    trim_floor=1.0,
    median_window=9,
    method="auto",
    skip_start=10,
    skip_end=10,
    return_components=False,
):
    """Constant-velocity windows of each stroke.

    Parameters
    ----------
    time : ndarray
        [s].
    velocity : ndarray
        Smoothed velocity [m/s] (> 0 extension).
    force : ndarray
        Force-balance signal [N].
    nominal_speed : float
        Nominal speed [m/s] if known (else the 90th percentile of |v|).
    moving_fraction : float
        A sample belongs to a stroke when |v| > moving_fraction * speed [-].
    settle_tolerance : float
        Settled when |v - v_stroke| <= settle_tolerance * |v_stroke| [-].
    min_samples : int
        Shorter windows are flagged ``"short_window"``.
    trim_sigma, trim_floor : float
        Ends whose rolling-median force departs from the window's centre by more than
        max(trim_sigma * robust sigma of the rolling median, trim_floor [N]) are trimmed
        (end-of-stroke cushioning).
    median_window : int
        Samples of the rolling median [-].
    method : {"auto", "fixed-index"}
        ``"fixed-index"`` is the thesis rule: drop ``skip_start`` samples at the start and
        ``skip_end`` at the end of each stroke (10, 10: with two strokes, 20 around the
        reversal).
    return_components : bool
        Also return a dict of intermediate arrays (``moving``, ``settled``, ``stroke``).

    Returns
    -------
    list of _Window (and dict of components)
    """
    speed_ref = nominal_speed if nominal_speed > 0 else float(np.percentile(np.abs(velocity), 90))
    if not speed_ref > 0:
        windows = []
        return (windows, {}) if return_components else windows
    moving = np.abs(velocity) > moving_fraction * speed_ref
    direction = np.sign(velocity) * moving
    change = np.flatnonzero(np.diff(direction) != 0) + 1
    bounds = np.concatenate(([0], change, [len(velocity)]))
    stroke_id = np.full(len(velocity), -1)
    settled_all = np.zeros(len(velocity), dtype=bool)
    windows = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        d = int(direction[a])
        if d == 0 or b - a < 3:
            continue
        k = len(windows)
        stroke_id[a:b] = k
        if method == "fixed-index":
            start, stop = a + skip_start, b - skip_end
            flag = "ok" if stop - start >= min_samples else "short_window"
            windows.append(_Window(k, d, start, max(start, stop), flag))
            continue
        v = velocity[a:b]
        v_stroke = float(np.median(v))
        settled = np.abs(v - v_stroke) <= settle_tolerance * abs(v_stroke)
        settled_all[a:b] = settled
        start, stop = _longest_true(settled)
        if stop - start < min_samples:
            windows.append(
                _Window(k, d, a + start, a + stop, "unsettled" if stop == start else "short_window")
            )
            continue
        start, stop = _trim_by_force(
            force[a + start : a + stop], trim_sigma, trim_floor, median_window, a + start
        )
        flag = "ok" if stop - start >= min_samples else "short_window"
        windows.append(_Window(k, d, start, stop, flag))
    if return_components:
        return windows, {"moving": moving, "settled": settled_all, "stroke": stroke_id}
    return windows


def _longest_true(mask):
    if not mask.any():
        return 0, 0
    padded = np.concatenate(([False], mask, [False]))
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    starts, stops = edges[::2], edges[1::2]
    i = int(np.argmax(stops - starts))
    return int(starts[i]), int(stops[i])


def _trim_by_force(force, trim_sigma, trim_floor, median_window, offset):
    """Trim ends where the rolling median of the force leaves the centre level."""
    n = len(force)
    w = min(median_window, max(1, n // 3) | 1)
    rolling = median_filter(force, size=w, mode="nearest")
    centre = rolling[n // 4 : n - n // 4] if n >= 8 else rolling
    level = np.median(centre)
    spread = 1.4826 * np.median(np.abs(force - np.median(force))) / math.sqrt(w)
    limit = max(trim_sigma * spread, trim_floor)
    inside = np.abs(rolling - level) <= limit
    mid = n // 2
    lo = mid
    while lo > 0 and inside[lo - 1]:
        lo -= 1
    hi = mid
    while hi < n and inside[hi]:
        hi += 1
    return offset + lo, offset + hi


def extract_points(
    data: pd.DataFrame,
    metadata: dict,
    config: CampaignConfig | None = None,
    *,
    run=0,
    spike_sigma=5.0,
    velocity_window=0.2,
    **window_options,
):
    """Friction points of one run: one row per stroke window (columns :data:`POINT_COLUMNS`).

    Spikes (|F - median| > spike_sigma robust sigmas) are dropped from each window and
    counted. The run offset ``(F_up + F_down)/2`` uses the ok windows of both directions;
    a run with one direction only gets NaN offset and the flag ``"no_offset"`` until the
    campaign offset is applied by :func:`extract_campaign`.
    """
    config = config or CampaignConfig()
    options = {**config.extraction, **window_options}
    file = metadata.get("file", "")
    time = data["time [s]"].to_numpy()
    if "velocity [m/s]" in data:
        velocity = config.position_sign * data["velocity [m/s]"].to_numpy()
    elif "position [m]" in data:
        velocity = smoothed_velocity(
            time, data["position [m]"].to_numpy(), window=velocity_window, sign=config.position_sign
        )
    else:
        raise BenchFileError(
            file,
            "no position or velocity column; expected one named "
            "Displacement/Position/Weg or Velocity",
        )
    force = friction_signal(data, config, velocity)
    nominal_speed = abs(metadata.get("velocity", math.nan))
    windows = find_windows(time, velocity, force, nominal_speed=nominal_speed, **options)
    pressure_col = data.get("pressure [Pa]", data.get("pressure_a [Pa]"))
    rows = []
    for w in windows:
        sl = slice(w.start, w.stop)
        f = force[sl]
        if w.stop > w.start:
            med = np.median(f)
            sigma = 1.4826 * np.median(np.abs(f - med)) or np.std(f)
            keep = np.abs(f - med) <= spike_sigma * sigma if sigma > 0 else np.ones(f.size, bool)
        else:
            keep = np.zeros(0, bool)
        if pressure_col is not None and w.stop > w.start:
            p = pressure_col.to_numpy()[sl]
            p_mean, p_std = float(np.mean(p)), float(np.std(p))
        else:
            p_mean, p_std = float(metadata.get("pressure", math.nan)), 0.0
        n = int(keep.sum())
        rows.append(
            {
                "run": run,
                "file": file,
                "stroke": w.stroke,
                "direction [-]": w.direction,
                "pressure [Pa]": p_mean,
                "pressure_std [Pa]": p_std,
                "velocity [m/s]": float(np.mean(velocity[sl][keep])) if n else math.nan,
                "velocity_std [m/s]": float(np.std(velocity[sl][keep])) if n else math.nan,
                "force [N]": float(np.mean(f[keep])) if n else math.nan,
                "friction_std [N]": float(np.std(f[keep])) if n else math.nan,
                "n [-]": n,
                "window_start [s]": float(time[w.start]) if n else math.nan,
                "window_end [s]": float(time[w.stop - 1]) if n else math.nan,
                "spikes [-]": int(keep.size - n),
                "flag": w.flag,
            }
        )
    points = pd.DataFrame(
        rows, columns=[c for c in POINT_COLUMNS if c not in ("friction [N]", "offset [N]")]
    )
    if math.isnan(metadata.get("pressure", math.nan)) and pressure_col is None:
        raise BenchFileError(
            file,
            "no pressure for this run; expected manifest.csv, a "
            "'Pressure: 55 bar' header line, a file-name token such as "
            "55bar, or a pressure column",
        )
    for key, value in metadata.get("extra", {}).items():
        points[key] = value
    return _apply_offset(points)


def _apply_offset(points: pd.DataFrame, campaign_offset=None) -> pd.DataFrame:
    ok = points["flag"].eq("ok")
    up = points.loc[ok & (points["direction [-]"] > 0), "force [N]"]
    down = points.loc[ok & (points["direction [-]"] < 0), "force [N]"]
    if len(up) and len(down):
        offset = 0.5 * (up.mean() + down.mean())
    elif campaign_offset is not None:
        offset = campaign_offset
    else:
        offset = math.nan
    points = points.copy()
    points["offset [N]"] = offset
    points["friction [N]"] = points["direction [-]"] * (points["force [N]"] - offset)
    if math.isnan(offset):
        points.loc[ok, "flag"] = "no_offset"
    return points[[c for c in POINT_COLUMNS] + [c for c in points if c not in POINT_COLUMNS]]


@dataclass
class Extraction:
    """Points of a campaign and what happened on the way.

    Attributes
    ----------
    points : pandas.DataFrame
        Columns :data:`POINT_COLUMNS` (+ extra metadata such as ``seal``).
    skipped : list of dict
        ``file`` and ``reason`` of the files skipped with ``skip_bad``.
    offset : float
        Campaign weight offset, median of the run offsets [N].
    offset_std : float
        Spread (standard deviation) of the run offsets [N].
    runs : list of dict
        Per run: file, rows, segments, pressure/velocity sources, events.
    bytes_read : int
        Size of the files read [bytes].
    """

    points: pd.DataFrame
    skipped: list = field(default_factory=list)
    offset: float = math.nan
    offset_std: float = math.nan
    runs: list = field(default_factory=list)
    bytes_read: int = 0

    @property
    def usable(self) -> pd.DataFrame:
        """The points flagged ``"ok"``."""
        return self.points[self.points["flag"].eq("ok")]


def extract_campaign(
    folder, config: CampaignConfig | None = None, *, skip_bad=False, progress=None, **options
) -> Extraction:
    """Read every run of a campaign folder and extract its friction points.

    Files are read one at a time (memory does not grow with the number of files).
    By default the first bad file raises :class:`~cylfric.io.BenchFileError`; with
    ``skip_bad`` it is listed in ``Extraction.skipped`` with the reason and the rest goes on.
    ``progress`` is called with each file name. Input files are never modified.
    """
    config = config or load_config(folder)
    infos = discover_runs(folder, config)
    frames, skipped, runs = [], [], []
    total = 0
    for index, info in enumerate(infos):
        try:
            data, metadata = read_run(info, config)
            points = extract_points(data, metadata, config, run=index, **options)
        except BenchFileError as exc:
            if not skip_bad:
                raise
            skipped.append({"file": str(info.path), "reason": str(exc)})
        else:
            frames.append(points)
            runs.append(
                {
                    "file": str(info.path),
                    "rows": metadata["rows"],
                    "segments": metadata.get("segments", 1),
                    "source": metadata["source"],
                    "events": len(metadata.get("events", [])),
                }
            )
        total += info.path.stat().st_size
        if progress is not None:
            progress(info.path.name)
    if not frames:
        raise BenchFileError(folder, "no run could be read; see the skipped files")
    points = pd.concat(frames, ignore_index=True)
    run_offsets = points.groupby("run")["offset [N]"].first().dropna()
    offset = float(run_offsets.median()) if len(run_offsets) else math.nan
    offset_std = float(run_offsets.std()) if len(run_offsets) > 1 else math.nan
    if points["flag"].eq("no_offset").any() and not math.isnan(offset):
        fixed = []
        for _, group in points.groupby("run", sort=False):
            if group["flag"].eq("no_offset").any():
                group = group.assign(flag=group["flag"].replace("no_offset", "ok"))
                group = _apply_offset(group, campaign_offset=offset)
            fixed.append(group)
        points = pd.concat(fixed, ignore_index=True)
    return Extraction(points, skipped, offset, offset_std, runs, total)
