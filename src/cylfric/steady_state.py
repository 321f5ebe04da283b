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
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._parallel import cores, start
from ._runtable import RunTable
from .friction.pressure import PRESSURE_REFERENCES, REFERENCE_CHAMBERS, operating_pressure
from .io.campaign import Campaign, CampaignConfig, read_run
from .io.text import BenchFileError

if TYPE_CHECKING:  # pandas is imported once the points are collected: reading needs none
    import pandas as pd

__all__ = [
    "friction_signal",
    "smoothed_velocity",
    "find_windows",
    "extract_points",
    "extract_campaign",
    "read_chunk",
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
``"short_window"``, ``"unsettled"`` or ``"no_offset"``. ``pressure`` is the pressure the laws
see: the chamber pressures combined by the campaign's pressure reference
(:func:`operating_pressure_signal`; a single-acting cylinder's working chamber)."""


def friction_signal(data, config: CampaignConfig, velocity=None) -> np.ndarray:
    """``F_f sign(v)`` plus the weight offset, from eq. 3.1 [N].

    ``data`` is a DataFrame or a dict of arrays. Uses ``force [N]`` (none with
    ``config.force_source == "pressures"``: a rig without a load cell), the pressure columns
    (``pressure_a``/``pressure_b``, or ``pressure`` for both chambers) with the areas of
    ``config``, and the inertia term when
    ``config.moving_mass`` > 0 (``velocity`` [m/s] then needed).
    """
    pa = data.get("pressure_a [Pa]", data.get("pressure [Pa]"))
    pb = data.get("pressure_b [Pa]", data.get("pressure [Pa]"))
    if config.force_source == "pressures":  # no load cell: the chambers drive the rod
        needed = [
            name
            for name, area, p in (("a", config.area_a, pa), ("b", config.area_b, pb))
            if area and p is None
        ]
        if needed:
            raise ValueError(
                f"force from the chamber pressures needs a pressure_{needed[0]} column (or one "
                f"pressure column for both chambers); found {list(data)}"
            )
        signal = np.zeros(len(np.asarray(data["time [s]"])))
    elif "force [N]" not in data:
        raise ValueError(
            f"no force column; found {list(data)} (a rig without a load cell: "
            '[force_balance] force = "pressures" in campaign.toml)'
        )
    else:
        signal = config.load_cell_sign * np.asarray(data["force [N]"])
    if config.area_a and pa is not None:
        signal = signal + config.area_a * np.asarray(pa)
    if config.area_b and pb is not None:
        signal = signal - config.area_b * np.asarray(pb)
    if config.moving_mass:
        acceleration = np.gradient(velocity, np.asarray(data["time [s]"]))
        signal = signal - config.moving_mass * acceleration
    return signal


def chamber_signals(data) -> dict:
    """The chamber pressures a file measures [Pa]: ``{"a": array, "b": array}``.

    ``pressure_a [Pa]`` and ``pressure_b [Pa]`` are the chambers; a single ``pressure [Pa]``
    column is the pressure of both (a rig that holds both chambers at one pressure, or the
    working chamber of a single-acting cylinder). A chamber the file does not measure is
    left out.
    """
    common = data.get("pressure [Pa]")
    found = {
        "a": data.get("pressure_a [Pa]", common),
        "b": data.get("pressure_b [Pa]", common),
    }
    return {chamber: np.asarray(p) for chamber, p in found.items() if p is not None}


def operating_pressure_signal(data, config: CampaignConfig, file="") -> np.ndarray | None:
    """The pressure the laws see [Pa], from the file's chamber pressures by the campaign's
    reference (``config.pressure_basis``); None when the file measures no pressure.

    Raises
    ------
    BenchFileError
        The reference needs a chamber the file does not measure (e.g. ``"mean"`` with a
        ``pressure_a`` column only): the message names the file, the rule, who stated it and
        what to write in campaign.toml.
    """
    chambers = chamber_signals(data)
    if not chambers:
        return None
    basis = config.pressure_basis
    rule = basis["rule"]
    missing = [c for c in REFERENCE_CHAMBERS[rule] if c not in chambers]
    if missing:
        has = ", ".join(f"pressure_{c}" for c in sorted(chambers))
        raise BenchFileError(
            file,
            f'the pressure reference "{rule}" ({basis["stated_by"]}) needs the pressure of '
            f"chamber {missing[0].upper()}, but this file measures only {has}; state which "
            "pressure the laws see in campaign.toml, e.g. [cylinder] pressure_reference = "
            f'"{sorted(chambers)[0]}" (or kind = "single-acting" for a cylinder with one '
            "working chamber)",
        )
    pa = chambers["a"] if "a" in chambers else chambers["b"]  # a rule of chamber B: unused
    pb = chambers.get("b", pa)
    return np.asarray(operating_pressure(pa, pb, reference=rule), dtype=float)


def smoothed_velocity(time, position, *, window=0.2, sign=1.0, dt=None):
    """Velocity [m/s] by a Savitzky-Golay derivative over ``window`` [s] (quadratic).

    ``dt`` is the median time step [s] when the caller has it (else computed from ``time``).
    """
    from ._filters import convolve_nearest, median  # with numba, on first use (see io.text)

    if dt is None:
        dt = median(np.diff(time))
    if not dt > 0:
        raise ValueError("time must increase; found a non-increasing time column")
    n = max(5, int(round(window / dt)) | 1)
    n = min(n, (len(time) - 1) | 1 if len(time) % 2 == 0 else len(time))
    if n < 3:
        return sign * np.gradient(position, time)
    # Savitzky-Golay first derivative, quadratic over n samples: for an odd window its
    # kernel is the least-squares slope k / (dt sum k^2), k = -m..m; this is what
    # scipy.signal.savgol_filter(position, n, 2, deriv=1, delta=dt, mode="nearest") computes
    # (scipy.signal is not imported: it loads scipy.stats)
    k = np.arange(n // 2, -(n // 2) - 1, -1, dtype=float)  # reversed: convolution
    return sign * convolve_nearest(position, k / (dt * float(k @ k)))


WINDOW_METHODS = ("auto", "fixed-index")
"""Window methods of :func:`find_windows`."""


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
    settle_sigma=3.0,
    settle_force_tolerance=0.005,
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
    settle_sigma, settle_force_tolerance : float
        Force settling at the start of each window (a start-up transient: the pressures of a
        valve-driven axis build up after the speed has settled): the window starts once a
        rolling mean of the force (over a twentieth of the window) has entered and stays
        within max(settle_sigma * its own spread over the window's second half,
        settle_force_tolerance * |final level|) of the final level, the median of the second
        half (the settling time of IEC 60050-351-45-24: the time after which the response
        stays within a stated band around its final value) [-].
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
    if method not in WINDOW_METHODS:
        raise ValueError(f"unknown window method {method!r}; valid: {list(WINDOW_METHODS)}")
    speed_ref = nominal_speed if nominal_speed > 0 else float(np.percentile(np.abs(velocity), 90))
    if not speed_ref > 0:
        windows: list[_Window] = []
        return (windows, {}) if return_components else windows
    from ._filters import stroke_window

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
        settled, start, stop, cut = stroke_window(
            velocity[a:b],
            force[a:b],
            velocity_tolerance=settle_tolerance,
            min_samples=min_samples,
            median_window=median_window,
            settle_sigma=settle_sigma,
            settle_tolerance=settle_force_tolerance,
            trim_sigma=trim_sigma,
            trim_floor=trim_floor,
            spike_sigma=SPIKE_SIGMA,
        )
        settled_all[a:b] = settled
        if cut is None:
            windows.append(
                _Window(k, d, a + start, a + stop, "unsettled" if stop == start else "short_window")
            )
            continue
        first, lo, hi = cut
        start, stop = a + start + first + lo, a + start + first + hi
        flag = "ok" if stop - start >= min_samples else "short_window"
        windows.append(_Window(k, d, start, stop, flag))
    if return_components:
        return windows, {"moving": moving, "settled": settled_all, "stroke": stroke_id}
    return windows


SPIKE_SIGMA = 5.0
"""Samples further than this many robust sigmas from the rolling median of the force are
spikes: left out of the cushion trimming's rolling mean (:func:`find_windows`) [-]."""


def extract_points(
    data: pd.DataFrame, metadata: dict, config: CampaignConfig | None = None, *, run=0, **options
) -> pd.DataFrame:
    """Friction points of one run: one row per stroke window (columns :data:`POINT_COLUMNS`).

    ``data`` is a DataFrame (:func:`cylfric.io.read_bench_text`) or a dict of arrays.

    Spikes (|F - median| > ``spike_sigma`` robust sigmas, default 5) are dropped from each
    window and counted. The run offset ``(F_up + F_down)/2`` uses the ok windows of both
    directions; a run with one direction only gets NaN offset and the flag ``"no_offset"``
    until :func:`extract_campaign` applies the campaign offset. Other keywords go to
    :func:`find_windows` (``velocity_window`` [s] to the velocity smoothing).
    """
    config = config or CampaignConfig()
    rows = _offset_rows(
        _point_rows(data, metadata, config, run, extraction_options(config, options)),
        config=config,
    )
    import pandas as pd

    return pd.DataFrame(rows, columns=_columns(rows))


def _columns(rows):
    known = set(POINT_COLUMNS)
    extra = {k: None for row in rows for k in row if k not in known}  # every run's labels
    return POINT_COLUMNS + list(extra)


def extraction_options(config: CampaignConfig, options: dict) -> dict:
    """Merge ``campaign.toml [extraction]`` with keyword options; unknown names raise.

    Valid names: the keywords of :func:`find_windows` (thresholds with their units),
    ``spike_sigma`` [-] and ``velocity_window`` [s].
    """
    import inspect

    merged = {**config.extraction, **options}
    fixed = {"time", "velocity", "force", "nominal_speed", "return_components"}
    valid = {p for p in inspect.signature(find_windows).parameters if p not in fixed}
    valid |= {"spike_sigma", "velocity_window"}
    unknown = sorted(set(merged) - valid)
    if unknown:
        where = config.source or "extraction options"
        raise BenchFileError(
            where, f"unknown extraction option(s) {unknown}; valid: {sorted(valid)}"
        )
    return merged


def _window_speed(time, position, velocity, window, keep):
    """Mean velocity of a window [m/s]: the slope of position against time (least squares).

    Exact at constant velocity, and free of the smoothing filter's bias near the window
    edges (the filtered velocity read 0.05-0.08 % low on the short windows of fast strokes).
    Without a position column: the mean of the velocity column over the kept samples.
    """
    if position is None or window.stop - window.start < 3:
        return _mean(velocity[window.start : window.stop][keep])
    t = time[window.start : window.stop]
    x = position[window.start : window.stop]
    t = t - _mean(t)
    return float(np.dot(t, x - _mean(x)) / np.dot(t, t))


_sum = np.add.reduce


def _mean(x) -> float:
    """``x.mean()`` of a non-empty 1-D float array, the same value (numpy's pairwise sum,
    divided by the count) without the Python wrapper of ``ndarray.mean``."""
    return float(_sum(x) / x.size)


def _mean_std(x) -> tuple[float, float]:
    """``(x.mean(), x.std())`` of a non-empty 1-D float array, the same values (numpy's
    ``_var``: the deviations from the mean squared and summed pairwise, divided by the
    count; its square root) with the mean computed once."""
    mean = _sum(x) / x.size
    deviation = x - mean
    return float(mean), math.sqrt(_sum(deviation * deviation) / x.size)


def _point_rows(data, metadata, config, run, options, balance=None):
    """Point rows of one run; ``balance``, when a list, gets per row the mean pressure term
    of the force balance over its window, ``A_a p_a - A_b p_b`` [N] (NaN without one)."""
    options = dict(options)
    spike_sigma = options.pop("spike_sigma", 5.0)
    velocity_window = options.pop("velocity_window", 0.2)
    file = metadata.get("file", "")
    if "time [s]" not in data:
        raise BenchFileError(
            file,
            "no time column; expected one named Time/Zeit/Tid (with a unit, e.g. 'Time [s]'), "
            'or [columns] time = "..." in campaign.toml',
        )
    from ._filters import median, median_and_deviation

    time = np.asarray(data["time [s]"])
    dt = median(np.diff(time)) if time.size >= 2 else math.nan  # the time step [s]
    if not dt > 0:
        raise BenchFileError(file, "the time column does not increase; expected time in s rising")
    for name, values in data.items():
        values = np.asarray(values)
        if values.dtype.kind == "f" and not np.all(np.isfinite(values)):
            row = int(np.flatnonzero(~np.isfinite(values))[0])
            raise BenchFileError(
                file,
                f"column {name!r} holds {values[row]} at data row {row + 1}; expected "
                "finite numbers",
            )
    if "velocity [m/s]" in data:
        velocity = config.position_sign * np.asarray(data["velocity [m/s]"])
    elif "position [m]" in data:
        velocity = smoothed_velocity(
            time,
            np.asarray(data["position [m]"]),
            window=velocity_window,
            sign=config.position_sign,
            dt=dt,
        )
    else:
        raise BenchFileError(
            file,
            "no position or velocity column; expected one named "
            "Displacement/Position/Weg or Velocity",
        )
    try:
        force = friction_signal(data, config, velocity)
    except ValueError as exc:
        raise BenchFileError(file, str(exc)) from None
    position = (
        config.position_sign * np.asarray(data["position [m]"]) if "position [m]" in data else None
    )
    pressure = operating_pressure_signal(data, config, file)
    pressure_force = _pressure_force(data, config) if balance is not None else None
    if math.isnan(metadata.get("pressure", math.nan)) and pressure is None:
        listed = metadata.get("manifest_line")
        manifest = (
            f"a pressure_bar value in manifest.csv (line {listed} gives none)"
            if listed is not None
            else "manifest.csv"
        )
        raise BenchFileError(
            file,
            f"no pressure for this run; expected {manifest}, a "
            "'Pressure: 55 bar' header line, a file-name token such as "
            "55bar, or a pressure column",
        )
    nominal_speed = abs(metadata.get("velocity", math.nan))
    windows = find_windows(time, velocity, force, nominal_speed=nominal_speed, **options)
    nominal_pressure: float | None = None
    extra = metadata.get("extra", {})
    rows = []
    nan = math.nan
    for w in windows:
        f = force[w.start : w.stop]
        v = velocity[w.start : w.stop]
        keep = np.zeros(0, bool)
        if f.size:
            med, deviation = median_and_deviation(f)
            sigma = 1.4826 * deviation or float(np.std(f))
            keep = np.abs(f - med) <= spike_sigma * sigma if sigma > 0 else np.ones(f.size, bool)
        n = int(keep.sum())
        if n < f.size:  # spikes left out (with none, the window as it is: the same values)
            f, v = f[keep], v[keep]
        if pressure is not None and n:
            p = pressure[w.start : w.stop]
            p = p[keep] if n < p.size else p
            p_mean, p_std = _mean_std(p)
        else:  # the nominal pressure is the chambers' (both, or the working one)
            if nominal_pressure is None:
                nominal = np.asarray(float(metadata.get("pressure", math.nan)))
                reference = PRESSURE_REFERENCES[config.pressure_reference]
                nominal_pressure = float(reference(nominal, nominal))
            p_mean, p_std = nominal_pressure, 0.0
        f_mean = f_std = v_std = nan
        if n:
            f_mean, f_std = _mean_std(f)
            v_std = _mean_std(v)[1]
        if balance is not None:  # 0 N: the balance adds no pressure term
            term = 0.0 if n else nan
            if pressure_force is not None and n:
                window = pressure_force[w.start : w.stop]
                term = _mean(window[keep] if n < window.size else window)
            balance.append(term)
        rows.append(
            {
                "run": run,
                "file": file,
                "stroke": w.stroke,
                "direction [-]": w.direction,
                "pressure [Pa]": p_mean,
                "pressure_std [Pa]": p_std,
                "velocity [m/s]": _window_speed(time, position, velocity, w, keep) if n else nan,
                "velocity_std [m/s]": v_std,
                "force [N]": f_mean,
                "friction [N]": nan,
                "friction_std [N]": f_std,
                "n [-]": n,
                "window_start [s]": float(time[w.start]) if n else nan,
                "window_end [s]": float(time[w.stop - 1]) if n else nan,
                "spikes [-]": int(keep.size - n),
                "offset [N]": nan,
                "flag": w.flag if n else ("unsettled" if w.flag == "ok" else w.flag),
                **extra,
            }
        )
    return rows


def _pressure_force(data, config: CampaignConfig) -> np.ndarray | None:
    """The pressure term of the force balance (eq. 3.1), ``A_a p_a - A_b p_b`` [N], as
    :func:`friction_signal` adds it; None when it adds none (no areas, no pressure column)."""
    pa = data.get("pressure_a [Pa]", data.get("pressure [Pa]"))
    pb = data.get("pressure_b [Pa]", data.get("pressure [Pa]"))
    term = None
    if config.area_a and pa is not None:
        term = config.area_a * np.asarray(pa, dtype=float)
    if config.area_b and pb is not None:
        term = (0.0 if term is None else term) - config.area_b * np.asarray(pb, dtype=float)
    return term


def _run_balance(rows, terms) -> float:
    """The run's pressure term of the force balance as its offset sees it [N]: the mean of
    the ok windows' terms of each direction, averaged over the directions it has (0 N
    without an ok window or without a pressure term; a number, so that summaries compare
    equal)."""
    means = []
    for direction in (1, -1):
        values = [
            t
            for r, t in zip(rows, terms, strict=True)
            if r["flag"] in ("ok", "no_offset")
            and r["direction [-]"] * direction > 0
            and not math.isnan(t)
        ]
        if values:
            means.append(float(np.mean(values)))
    return float(np.mean(means)) if means else 0.0  # (no window: nothing to balance)


def _offset_rows(rows, campaign_offset=None, config=None):
    """Set the run offset (F_up + F_down)/2 and the friction magnitude of every row.

    A rig without a load cell (``config.force_source == "pressures"``) has no weight offset
    to remove: its offset is 0 N. (F_up + F_down)/2 would also take away the real asymmetry
    of its friction: on a valve-driven axis the two directions run at different pressures.
    """
    if config is not None and config.force_source == "pressures":
        campaign_offset, rows_up_down = 0.0, False
    else:
        rows_up_down = True
    up = [r["force [N]"] for r in rows if r["flag"] == "ok" and r["direction [-]"] > 0]
    down = [r["force [N]"] for r in rows if r["flag"] == "ok" and r["direction [-]"] < 0]
    if up and down and rows_up_down:
        offset = 0.5 * (float(np.mean(up)) + float(np.mean(down)))
    elif campaign_offset is not None:
        offset = campaign_offset
    else:
        offset = math.nan
    for r in rows:
        r["offset [N]"] = offset
        r["friction [N]"] = r["direction [-]"] * (r["force [N]"] - offset)
        if math.isnan(offset) and r["flag"] == "ok":
            r["flag"] = "no_offset"
    return rows


@dataclass
class Extraction:
    """Points of a campaign and what happened on the way.

    Attributes
    ----------
    points : pandas.DataFrame
        Columns :data:`POINT_COLUMNS` (+ extra metadata such as ``seal``), and ``session``
        (the run's session, :func:`cylfric.io.campaign.session_of`; None when the campaign
        does not say).
    skipped : list of dict
        ``file`` and ``reason`` of the files skipped with ``skip_bad``.
    offset : float
        Campaign weight offset, median of the run offsets [N].
    offset_std : float
        Spread (standard deviation) of the run offsets [N].
    runs : list of dict
        Per run: ``file``, ``run`` (index in the points table), nominal ``pressure [Pa]``
        and ``velocity [m/s]`` (NaN when unknown), rows, segments, ``source`` (where the
        nominal values came from), ``nominal`` (every value found, per source: manifest,
        campaign.toml name_pattern, header, file name), ``pressure measured`` (the file has
        a pressure column), events.
    unlisted : list of str
        Files of the folder that ``manifest.csv`` does not list (not read), relative to
        the campaign folder.
    bytes_read : int
        Size of the files read [bytes].
    folder : str or None
        The campaign folder (file names in excluded.csv are relative to it).
    config : CampaignConfig or None
        The campaign's configuration the points were extracted with (the force balance's
        areas and signs, the pressure reference): the data-quality gate checks the points
        against it (:mod:`cylfric.quality.plausibility`). None: not known.
    """

    points: pd.DataFrame
    skipped: list = field(default_factory=list)
    offset: float = math.nan
    offset_std: float = math.nan
    runs: list = field(default_factory=list)
    bytes_read: int = 0
    unlisted: list = field(default_factory=list)
    folder: str | None = None
    config: CampaignConfig | None = None

    @property
    def usable(self) -> pd.DataFrame:
        """The points flagged ``"ok"``."""
        return self.points[self.points["flag"].eq("ok")]


PARALLEL_MIN_FILES = 16
"""Fewest files for which :func:`extract_campaign` reads on a pool of processes
(:func:`cylfric._parallel.run`); fewer are read here, one after another."""

TWO_READERS_MIN_FILES = 300
"""Fewest files for which the extraction's pool has more than one reader. Below it one
forked reader loads the compiled reader (about 0.3 s) and reads the files (about 2 ms each)
while ``cylfric fit`` imports the identification (about 0.55 s); a second reader pays its
own load, or this process's (serial, before the fork), only once it halves about 0.3 s of
reading: some 300 files. Measured (``cylfric fit --no-report``, medians of 5-7 alternating
runs, the other core idle / busy): 144 files one reader 1.36 / 1.63 s, two 1.60 / 1.80 s;
480 files one reader 2.71 / 3.10 s, two 2.37 / 2.88 s."""


def start_extraction(
    folder: Campaign | str | os.PathLike[str],
    config: CampaignConfig | None = None,
    *,
    skip_bad=False,
    progress=None,
    workers=None,
    exclude=(),
    scheduler=None,
    **options,
) -> PendingExtraction:
    """Start reading every run of a campaign folder; ``.result()`` gives the
    :class:`Extraction` (see :func:`extract_campaign`).

    With a pool (``workers`` >= 2 and at least ``PARALLEL_MIN_FILES`` files) the first file
    is read here and the workers start on the rest at once, so the caller can go on with
    other work (``cylfric fit`` imports the identification meanwhile); else the files are
    read when ``.result()`` is called. With ``scheduler`` (a Dask distributed scheduler
    address, ``"tcp://host:8786"``) the files are read by the cluster's workers instead
    (``workers`` is not used): see :func:`read_chunk`.
    """
    campaign = _open_campaign(folder, config)
    config = campaign.config
    options = extraction_options(config, options)
    excluded = set(exclude)
    infos = [i for i in campaign.runs if i.path.name not in excluded]
    if not infos:
        raise BenchFileError(
            campaign.folder,
            "no constant-velocity runs (only presliding/breakaway tests); the steady-state "
            "fit needs constant-velocity runs",
        )

    if scheduler is not None:
        return _start_on_cluster(campaign, infos, options, scheduler, skip_bad, progress)

    def one(index):
        return _read_one(infos[index], index, config, options)

    workers, pooled, one_reader, head = _readers(len(infos), workers)
    first = [_pack([one(i) for i in range(head)])] if head else []
    if progress is not None:
        for i in range(head):
            progress(infos[i].path.name)
    size = chunk_size(len(infos) - head, workers)
    chunks = [range(lo, min(lo + size, len(infos))) for lo in range(head, len(infos), size)]

    def report(index, _result=None):
        if progress is not None:
            for i in chunks[index]:
                progress(infos[i].path.name)

    pending = start(
        lambda c: _pack([one(i) for i in chunks[c]]),
        len(chunks),
        workers=workers if pooled else 1,
        done=report,
        background=one_reader,
    )
    return PendingExtraction(campaign, infos, first, pending, skip_bad)


def _start_on_cluster(campaign, infos, options, scheduler, skip_bad, progress):
    """The files read on the Dask cluster at ``scheduler``: tasks of consecutive files
    (:func:`chunk_size` for the cluster's threads), each :func:`read_chunk` on a worker."""
    from ._parallel import ClusterPending, connect

    client = connect(scheduler)
    try:
        n = len(infos)
        size = chunk_size(n, sum(client.nthreads().values()))
        chunks = [range(lo, min(lo + size, n)) for lo in range(0, n, size)]
        here = os.getcwd()

        def report(index, _result=None):
            if progress is not None:
                for i in chunks[index]:
                    progress(infos[i].path.name)

        tasks = [(campaign.config, options, [(i, infos[i]) for i in c], here) for c in chunks]
        pending = ClusterPending(client, read_chunk, tasks, done=report)
    except BaseException:
        client.close()
        raise
    return PendingExtraction(campaign, infos, [], pending, skip_bad)


def read_chunk(
    config: CampaignConfig, options: dict, runs: list, here: str | os.PathLike[str]
) -> tuple:
    """Read the runs of one task on a Dask worker: the packed table of their points,
    summaries and errors (:func:`_pack`), as the local pool returns it.

    ``runs`` are (run index, :class:`~cylfric.io.campaign.RunInfo`) pairs (file names and
    nominal values, not the data: the worker reads the files), ``options`` those of
    :func:`extraction_options`. A relative path is read under ``here`` (the submitting
    process's working folder) and reported as given, so the points name the files as a
    local fit does. The worker must see the files at that path (a shared file system).
    """
    results = []
    for index, info in runs:
        where = info.replace(
            path=Path(here, info.path),
            manifest=None if info.manifest is None else Path(here, info.manifest),
        )
        rows, summary, error = _read_one(where, index, config, options)
        read, shown = str(where.path), str(info.path)
        if read != shown:
            for row in rows or ():
                if row.get("file") == read:
                    row["file"] = shown
            if summary is not None:
                summary["file"] = shown
            if error is not None and error.path == read:
                error = BenchFileError(shown, error.message, error.line)
        results.append((rows, summary, error))
    return _pack(results)


def _open_campaign(
    folder: Campaign | str | os.PathLike[str], config: CampaignConfig | None
) -> Campaign:
    """``folder`` when it is a :class:`Campaign` (then ``config`` must be None), else the
    campaign opened from that folder with ``config``."""
    if not isinstance(folder, Campaign):
        return Campaign.open(folder, config=config)
    if config is not None:
        raise ValueError(
            "config comes with the Campaign (Campaign.open(folder, config=...)); "
            "pass config=None with a Campaign"
        )
    return folder


def _read_one(info, index: int, config: CampaignConfig, options: dict) -> tuple:
    """(point rows, summary, None) of one run file, or (None, None, the BenchFileError)."""
    try:
        data, metadata = read_run(info, config)
        terms: list[float] = []
        rows = _offset_rows(
            _point_rows(data, metadata, config, index, dict(options), terms), config=config
        )
    except BenchFileError as exc:
        return None, None, exc
    units = metadata.get("units", {})
    summary = {
        "file": str(info.path),
        "run": index,
        "pressure [Pa]": metadata["pressure"],
        "velocity [m/s]": metadata["velocity"],
        "rows": metadata["rows"],
        "segments": metadata.get("segments", 1),
        "source": metadata["source"],
        "nominal": metadata.get("nominal", {}),
        "pressure measured": "pressure [Pa]" in data or "pressure_a [Pa]" in data,
        "events": len(metadata.get("events", [])),
        "sha256": metadata.get("sha256"),
        "pressure force [N]": _run_balance(rows, terms),
        "units": {
            quantity: str(unit)
            for quantity, unit in units.items()
            if quantity in ("force", "pressure", "pressure_a", "pressure_b", "position")
        },
    }
    return rows, summary, None


def _readers(n: int, workers: int | None) -> tuple[int, bool, bool, int]:
    """How ``n`` files are read: (workers, pooled, one background reader, files read here
    first) for ``workers`` asked (None: the cores this process may use,
    :func:`cylfric._parallel.cores`)."""
    workers = cores() if workers is None else workers
    pooled = workers >= 2 and n >= PARALLEL_MIN_FILES
    # below TWO_READERS_MIN_FILES one forked reader loads the compiled reader and reads
    # every file while this process imports the identification; from it on, the first file
    # is read here (loading the compiled reader once: the workers forked for the rest
    # inherit it instead of each loading it again) and ``workers`` readers share the rest
    one_reader = pooled and n < TWO_READERS_MIN_FILES
    head = 1 if pooled and not one_reader else 0
    if one_reader:
        workers = 1
    elif pooled:  # each reader's share at least half TWO_READERS_MIN_FILES (many cores)
        workers = min(workers, n // (TWO_READERS_MIN_FILES // 2))
    return workers, pooled, one_reader, head


CHUNK_FILES = 64
"""Most run files in one task of the extraction's pool: a task's files are read one after
another by one worker and their points come back as one table of arrays (one pickle per
task, not per file)."""


def chunk_size(n: int, workers: int) -> int:
    """Files per task when ``n`` files are read by ``workers`` processes [-]: about 8 tasks
    per worker (the last ones balance the load), at most :data:`CHUNK_FILES` files each."""
    return max(1, min(CHUNK_FILES, -(-n // (8 * max(workers, 1)))))


def _column(values: list):
    """A column of point rows as a numpy array when all values are floats (float64) or all
    are ints (int64), else the list as it is (pandas infers its type as from the rows)."""
    kinds = {type(v) for v in values}
    if values and kinds <= {float, np.float64}:
        return np.array(values, dtype=np.float64)
    if kinds == {int}:
        return np.array(values, dtype=np.int64)
    return values


def _pack(results: list) -> tuple:
    """The results (rows, summary, error) of consecutive files -> (points, summaries,
    errors), the points as one table of arrays (a dict of columns: one pickle of
    a few arrays instead of a dict per point); rows whose keys differ (a run with labels the
    others lack) stay a list of rows."""
    rows = [r for file_rows, _, _ in results if file_rows is not None for r in file_rows]
    summaries = RunTable.from_dicts([summary for _, summary, _ in results])
    errors = [error for _, _, error in results]
    keys = _columns(rows)
    if all(len(r) == len(keys) for r in rows):
        return {key: _column([r[key] for r in rows]) for key in keys}, summaries, errors
    return rows, summaries, errors


class PendingExtraction:
    """A campaign's reading, started by :func:`start_extraction`."""

    def __init__(self, campaign, infos, first, pending, skip_bad) -> None:
        self.campaign = campaign
        self.files = tuple(info.path.name for info in infos)
        self._infos, self._first, self._pending, self._skip_bad = infos, first, pending, skip_bad

    def close(self) -> None:
        """Stop reading (the files being read are finished, the rest dropped)."""
        self._pending.close()

    def result(self) -> Extraction:
        """Wait for the files and build the :class:`Extraction` (bad files raise here)."""
        from ._parallel import release_free_memory

        extraction = _finish(
            self.campaign, self._infos, self._first + self._pending.results(), self._skip_bad
        )
        release_free_memory()  # the workers' packed results, unpacked into the Extraction
        return extraction


def extract_campaign(
    folder: Campaign | str | os.PathLike[str],
    config: CampaignConfig | None = None,
    *,
    skip_bad=False,
    progress=None,
    workers=None,
    exclude=(),
    scheduler=None,
    **options,
) -> Extraction:
    """Read every run of a campaign folder and extract its friction points.

    Files are read one at a time per core (memory does not grow with the number of files:
    only each run's points are kept). By default the first bad file raises
    :class:`~cylfric.io.BenchFileError`; with ``skip_bad`` it is listed in
    ``Extraction.skipped`` with the reason and the rest goes on. ``progress`` is called with
    each file name as it is done. ``workers`` (default: the cores this process may use,
    :func:`cylfric._parallel.cores`): with 2 or more, and at least
    ``PARALLEL_MIN_FILES`` files, the files are read on a pool of forked processes (one
    reader below ``TWO_READERS_MIN_FILES``, started before this process's other work)
    (:func:`cylfric._parallel.run`; the per-file work is small numpy calls that hold the
    GIL, so threads would not help), else here, one after another; the result is the same
    either way; with ``scheduler`` (a Dask scheduler address) the files are read by that
    cluster's workers (:func:`start_extraction`). ``exclude``
    names files of the campaign that are not constant-velocity runs (the presliding and
    breakaway tests, identified by :mod:`cylfric.identify.dynamic`); they are not read here.
    Input files are never modified.

    ``folder`` is a campaign folder (read with ``config``, default its campaign.toml) or a
    :class:`~cylfric.io.campaign.Campaign` already opened (with its own configuration:
    then ``config`` must be None), whose campaign.toml and manifest.csv are not read again.
    """
    return start_extraction(
        folder,
        config,
        skip_bad=skip_bad,
        progress=progress,
        workers=workers,
        exclude=exclude,
        scheduler=scheduler,
        **options,
    ).result()


def _finish(campaign, infos, packs, skip_bad) -> Extraction:
    """The packed results of the files (:func:`_pack`, in file order) -> the
    :class:`Extraction`."""
    skipped, read = [], []
    total = 0
    index = 0
    for _, summaries, errors in packs:
        read.append(summaries.select([error is None for error in errors]))
        for error in errors:
            info = infos[index]
            index += 1
            if error is not None:
                if not skip_bad:
                    raise BenchFileError(
                        error.path,
                        str(error).split(": ", 1)[-1] + " (to skip such files: --skip-bad)",
                        error.line,
                    ) from None
                skipped.append({"file": str(info.path), "reason": str(error)})
            total += _file_bytes(info.path)
    runs = RunTable.join(read)  # the summaries as columns, not 30 objects a run
    if not runs:
        reasons = "; ".join(item["reason"] for item in skipped[:3])
        raise BenchFileError(
            campaign.folder,
            f"none of the {len(skipped)} run file(s) could be read; the first: {reasons}",
        )
    columns = _join([points for points, *_ in packs])
    if columns is None:  # runs with different labels: as rows
        rows = [r for points, *_ in packs for r in _rows_of(points)]
        return _finish_rows(campaign, rows, skipped, runs, total)
    return _finish_columns(campaign, columns, skipped, runs, total)


def _file_bytes(path) -> int:
    """Size of a regular file [bytes]; 0 for anything else or a file gone (one stat: this
    runs once per file after the reading, on one core)."""
    try:
        status = os.stat(path)
    except OSError:
        return 0
    return status.st_size if stat.S_ISREG(status.st_mode) else 0


def _rows_of(points) -> list:
    """A pack's points as a list of row dicts."""
    if isinstance(points, list):
        return points
    keys = list(points)
    n = len(points[keys[0]]) if keys else 0
    return [{key: _item(points[key][i]) for key in keys} for i in range(n)]


def _item(value):
    return value.item() if isinstance(value, np.generic) else value


def _join(packs: list) -> dict | None:
    """The columns of packs with the same keys, joined (None: keys differ, or rows)."""
    tables = [p for p in packs if not (isinstance(p, list) and not p)]  # no points: skip
    if not tables or any(isinstance(p, list) for p in tables):
        return None if tables else {}
    keys = list(tables[0])
    if any(list(t) != keys for t in tables):
        return None
    joined: dict[str, Any] = {}
    for key in keys:
        parts = [t[key] for t in tables]
        if all(isinstance(x, np.ndarray) for x in parts) and len({x.dtype for x in parts}) == 1:
            joined[key] = np.concatenate(parts)
        else:
            joined[key] = [_item(v) for x in parts for v in x]
    return joined


def _campaign_offset(run_offsets) -> tuple[float, float]:
    offset = float(np.median(run_offsets)) if len(run_offsets) else math.nan
    offset_std = float(np.std(run_offsets, ddof=1)) if len(run_offsets) > 1 else math.nan
    return offset, offset_std


def _finish_columns(campaign, columns, skipped, runs, total) -> Extraction:
    """The points as columns (one array per column) -> the :class:`Extraction` (the same
    table as :func:`_finish_rows` builds from the rows)."""
    import pandas as pd

    if not columns:
        points = pd.DataFrame(columns=POINT_COLUMNS)
        offset = offset_std = math.nan
    else:
        run = np.asarray(columns["run"])
        first = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])  # each run's first row
        offsets = np.asarray(columns["offset [N]"], dtype=float)[first]
        offset, offset_std = _campaign_offset(offsets[~np.isnan(offsets)])
        flags = columns["flag"]
        if not math.isnan(offset):
            stops = np.r_[first[1:], len(run)]
            for a, b in zip(first, stops, strict=True):
                if any(flags[i] == "no_offset" for i in range(a, b)):
                    _reoffset(columns, a, b, offset)
        points = pd.DataFrame(columns, columns=list(columns))
    return _extraction(campaign, points, skipped, offset, offset_std, runs, total)


def _extraction(campaign, points, skipped, offset, offset_std, runs, total) -> Extraction:
    """The :class:`Extraction` of a points table (with its ``session`` column, None where the
    campaign does not say)."""
    if "session" not in points:  # the label column every points table has (None: not said)
        points["session"] = None
    return Extraction(
        points,
        skipped,
        offset,
        offset_std,
        runs,
        total,
        list(campaign.unlisted),
        str(campaign.folder),
        getattr(campaign, "config", None),
    )


def _reoffset(columns, a, b, offset) -> None:
    """Rows a..b-1 (one run without its own offset) at the campaign offset, in place."""
    rows = [{key: _item(columns[key][i]) for key in columns} for i in range(a, b)]
    for r in rows:
        r["flag"] = "ok" if r["flag"] == "no_offset" else r["flag"]
    _offset_rows(rows, campaign_offset=offset)
    for i, r in zip(range(a, b), rows, strict=True):
        for key in ("offset [N]", "friction [N]", "flag"):
            columns[key][i] = r[key]


def _finish_rows(campaign, rows, skipped, runs, total) -> Extraction:
    """The points as rows (labels that differ between runs) -> the :class:`Extraction`."""
    per_run: dict = {}
    for r in rows:
        per_run.setdefault(r["run"], []).append(r)
    run_offsets = [
        run_rows[0]["offset [N]"]
        for run_rows in per_run.values()
        if not math.isnan(run_rows[0]["offset [N]"])
    ]
    offset, offset_std = _campaign_offset(run_offsets)
    if not math.isnan(offset):
        for run_rows in per_run.values():
            if any(r["flag"] == "no_offset" for r in run_rows):
                for r in run_rows:
                    r["flag"] = "ok" if r["flag"] == "no_offset" else r["flag"]
                _offset_rows(run_rows, campaign_offset=offset)
    import pandas as pd

    points = (
        pd.DataFrame(rows, columns=_columns(rows)) if rows else pd.DataFrame(columns=POINT_COLUMNS)
    )
    return _extraction(campaign, points, skipped, offset, offset_std, runs, total)
