"""Runs at different oil temperatures, identified as one campaign at a reference temperature.

:func:`walther_viscosity` (ASTM D341 for mineral oils, from two points of the oil's data
sheet) and :func:`viscosity_corrected`, which maps each point's speed to the speed with the
same Hersey number (thesis eq. 2.8) at a reference temperature, so that runs made at
different oil temperatures can be identified as one campaign at that temperature:
``identify(viscosity_corrected(points, oil=..., ...))``. :func:`correct_campaign` does it for
``cylfric fit`` from ``campaign.toml [oil]`` and the runs' oil temperatures
(``manifest.csv``), and says what it did.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import pandas as pd
    from numpy.typing import ArrayLike

    from ._typing import OilPoints
    from .io.campaign import OilSettings

__all__ = [
    "walther_viscosity",
    "viscosity_corrected",
    "correct_campaign",
    "ViscosityCorrection",
    "VISCOSITY_RULE",
]


@overload
def walther_viscosity(temperature: float, oil: OilPoints) -> float: ...


@overload
def walther_viscosity(temperature: np.ndarray, oil: OilPoints) -> np.ndarray: ...


@overload
def walther_viscosity(temperature: ArrayLike, oil: OilPoints) -> np.ndarray | float: ...


def walther_viscosity(temperature: ArrayLike, oil: OilPoints) -> np.ndarray | float:
    """Kinematic viscosity [m^2/s] of a mineral oil by the Walther equation (ASTM D341).

    ``log10(log10(nu + 0.7)) = A - B log10(T)`` with ``nu`` in mm^2/s (cSt) and ``T`` in K;
    ``A`` and ``B`` from the two points of ``oil``. Valid for ``nu`` >= 2 mm^2/s (the
    standard adds terms below) and for mineral oils; interpolate rather than extrapolate.

    Parameters
    ----------
    temperature : float or array_like
        Oil temperature [K].
    oil : ((float, float), (float, float))
        Two (temperature [K], kinematic viscosity [m^2/s]) points of the oil's data sheet,
        e.g. ``((313.15, 46e-6), (373.15, 6.8e-6))`` for an ISO VG 46 oil of viscosity
        index about 100 (46 and 6.8 mm^2/s at 40 and 100 degC).

    Examples
    --------
    >>> oil = ((313.15, 46e-6), (373.15, 6.8e-6))
    >>> round(walther_viscosity(313.15, oil) * 1e6, 6)    # [mm^2/s] at 40 degC
    46.0
    """
    (t1, nu1), (t2, nu2) = oil
    if not (t1 > 0 and t2 > 0 and t1 != t2 and nu1 > 0 and nu2 > 0):
        raise ValueError(
            f"oil = {oil!r}: expected two (temperature [K], viscosity [m^2/s]) points at "
            "different positive temperatures"
        )
    if min(nu1, nu2) < 2e-6:
        raise ValueError(
            f"oil viscosities {nu1 * 1e6:g} and {nu2 * 1e6:g} mm^2/s: the Walther form of "
            "ASTM D341 holds from 2 mm^2/s (viscosities are in m^2/s: 46 cSt = 46e-6)"
        )
    z1 = np.log10(np.log10(nu1 * 1e6 + 0.7))
    z2 = np.log10(np.log10(nu2 * 1e6 + 0.7))
    slope = (z1 - z2) / (np.log10(t2) - np.log10(t1))  # B
    intercept = z1 + slope * np.log10(t1)  # A
    t = np.asarray(temperature, dtype=float)
    if np.any(~np.isfinite(t)) or np.any(t <= 0):
        raise ValueError(f"temperature {temperature!r}: expected positive kelvin values")
    nu = 10.0 ** (10.0 ** (intercept - slope * np.log10(t))) - 0.7  # [mm^2/s]
    return nu * 1e-6 if np.ndim(nu) else float(nu) * 1e-6


def viscosity_corrected(
    points: pd.DataFrame,
    *,
    oil: OilPoints,
    reference_temperature: float,
    temperature: float | None = None,
) -> pd.DataFrame:
    """Points with their speeds mapped to a reference oil temperature (same Hersey number).

    The lubrication regime of a seal, and so the Stribeck curve, depends on the Hersey
    number ``|v| mu / (F_N / L)`` (thesis eq. 2.8). At the same pressure (same load per
    length) a point measured at speed ``v`` with viscosity ``nu(T)`` behaves as a point at
    ``v nu(T) / nu(T_ref)`` at the reference temperature. Kinematic viscosities are used
    for the ratio (the density of a mineral oil changes by about 0.07 %/K, neglected).

    Parameters
    ----------
    points : pandas.DataFrame
        A points table (``velocity [m/s]``; ``temperature [K]`` unless ``temperature`` is
        given).
    oil : pair of (temperature [K], viscosity [m^2/s])
        See :func:`walther_viscosity`.
    reference_temperature : float
        Temperature the corrected campaign represents [K].
    temperature : float, optional
        One oil temperature for every point [K] (campaign metadata), instead of the
        ``temperature [K]`` column.

    Returns
    -------
    pandas.DataFrame
        A copy with ``velocity [m/s]`` replaced by the equivalent speed, the measured one
        in ``velocity measured [m/s]`` and ``temperature [K]`` filled in.
    """
    from .friction import hersey_number

    table = points.copy()
    if temperature is not None:
        table["temperature [K]"] = float(temperature)
    if "temperature [K]" not in table:
        raise ValueError(
            "points table: no 'temperature [K]' column and no temperature given; "
            "expected the oil temperature of each point [K]"
        )
    t = table["temperature [K]"].to_numpy(dtype=float)
    for name, values in (("temperature [K]", t), ("reference_temperature", reference_temperature)):
        values = np.atleast_1d(np.asarray(values, dtype=float))
        if np.any(~np.isfinite(values)) or np.any(values < 200) or np.any(values > 450):
            raise ValueError(
                f"{name}: values outside 200-450 K; temperatures are in kelvin (40 degC = 313.15 K)"
            )
    velocity = table["velocity [m/s]"].to_numpy(dtype=float)
    nu = walther_viscosity(t, oil)
    nu_ref = walther_viscosity(reference_temperature, oil)
    # equal Hersey number (eq. 2.8) at equal load per length: |v_eq| nu_ref = |v| nu(T);
    # windows without a speed (NaN, flagged by the extraction) stay NaN
    nu = np.broadcast_to(nu, velocity.shape)
    finite = np.isfinite(velocity)
    speed = np.full(velocity.shape, np.nan)
    speed[finite] = hersey_number(velocity[finite], nu[finite], 1.0) / nu_ref
    table["velocity measured [m/s]"] = velocity
    table["velocity [m/s]"] = np.sign(velocity) * speed
    return table


VISCOSITY_RULE = (
    "equal Hersey number (thesis eq. 2.8) at equal load per length: each point's speed v at "
    "oil temperature T is identified as v nu(T) / nu(T_ref), kinematic viscosities nu by the "
    "Walther equation (ASTM D341) through the oil's two data-sheet points"
)
"""The rule of the viscosity correction, as the datasheet records it."""


@dataclass(frozen=True)
class ViscosityCorrection:
    """What :func:`correct_campaign` did.

    Attributes
    ----------
    points : pandas.DataFrame
        The points, corrected (``velocity [m/s]`` at the reference temperature,
        ``velocity measured [m/s]``, ``temperature [K]``) or as given.
    runs : list of dict
        The extraction's runs, nominal ``velocity [m/s]`` scaled alike when corrected.
    record : dict or None
        The datasheet's ``fit.viscosity_correction`` (rule, oil points, reference
        temperature [K], temperatures [K] and speed ratios [-] met); None when not corrected.
    note : str or None
        One line for the datasheet notes, the summary and the report.
    """

    points: object
    runs: Sequence
    record: dict | None
    note: str | None


def _celsius(kelvin) -> str:
    return f"{kelvin - 273.15:.4g} degC"


def _without_oil(
    unchanged: ViscosityCorrection, listed: np.ndarray | None, *, enabled: bool | None
) -> ViscosityCorrection:
    """No ``[oil]`` table: raise when the correction was asked for, else the points
    unchanged, with a note when the runs carry oil temperatures [K] (``listed``)."""
    if enabled:
        raise ValueError(
            "--viscosity-correction: campaign.toml has no [oil] table; expected "
            '[oil] viscosity_40C = "46 mm2/s", viscosity_100C = "6.8 mm2/s"'
        )
    if listed is None or not np.isfinite(listed).any():
        return unchanged
    t = listed[np.isfinite(listed)]
    return replace(
        unchanged,
        note=f"the runs carry oil temperatures ({_celsius(t.min())} to {_celsius(t.max())}, "
        "manifest.csv) but campaign.toml has no [oil] table: identified at the measured "
        "speeds without viscosity correction; add [oil] viscosity_40C and viscosity_100C "
        "to correct, or --no-viscosity-correction to silence this note",
    )


def _check_every_run(points: pd.DataFrame, temperature: np.ndarray) -> None:
    """Refuse points of which some have an oil temperature [K] and others none."""
    missing = sorted({Path(f).name for f in points.loc[~np.isfinite(temperature), "file"]})
    if missing:
        manifest = Path(points["file"].iloc[0]).parent / "manifest.csv"
        raise ValueError(
            f"{manifest}: no oil temperature for {len(missing)} run(s) "
            f"({', '.join(missing[:3])}{', ...' if len(missing) > 3 else ''}) while others "
            "have one; expected a temperature for every run, an [oil] temperature for the "
            "rest, or --no-viscosity-correction"
        )


def _scaled_runs(runs: Sequence[Mapping[str, Any]], per_run: dict) -> list[dict]:
    """Copies of ``runs`` with the nominal ``velocity [m/s]`` of each run in ``per_run``
    multiplied by its speed ratio [-]."""
    new_runs = []
    for info in runs:
        info = dict(info)
        if info.get("run") in per_run:
            info["velocity [m/s]"] = info.get("velocity [m/s]", math.nan) * per_run[info["run"]]
        new_runs.append(info)
    return new_runs


def correct_campaign(
    points: pd.DataFrame,
    runs: Sequence[Mapping[str, Any]],
    oil: OilSettings | None,
    *,
    enabled: bool | None = None,
) -> ViscosityCorrection:
    """Map a campaign's points to the oil's reference temperature, or say why not.

    Parameters
    ----------
    points : pandas.DataFrame
        Points table of the extraction (a ``temperature [K]`` column from ``manifest.csv``
        when the runs carry oil temperatures).
    runs : list of dict
        The extraction's runs (``run``, nominal ``velocity [m/s]``).
    oil : cylfric.io.campaign.OilSettings or None
        ``campaign.toml [oil]``: the two data-sheet viscosities, the reference temperature
        [K] and a campaign-wide oil temperature [K] for runs without their own.
    enabled : bool or None
        None (default): correct when both ``[oil]`` and temperatures are there, else a note
        says which is missing. True: correct or raise. False: do not correct (a note says
        so when there was something to correct).

    Returns
    -------
    ViscosityCorrection

    Raises
    ------
    ValueError
        Correction asked for (``enabled=True``) without ``[oil]`` or temperatures; some
        runs with a temperature and others without (and no campaign-wide one).
    """
    unchanged = ViscosityCorrection(points, runs, None, None)  # not copied: a RunTable stays one
    column = "temperature [K]"
    listed = points[column].to_numpy(dtype=float) if column in points else None
    has_listed = listed is not None and bool(np.isfinite(listed).any())
    if enabled is False:
        if oil is None and not has_listed:
            return unchanged
        return replace(
            unchanged,
            note="viscosity correction turned off (--no-viscosity-correction): identified at "
            "the measured speeds, whatever the oil temperature of each run",
        )
    if oil is None:
        return _without_oil(unchanged, listed, enabled=enabled)
    temperature = listed if listed is not None else np.full(len(points), np.nan)
    sources = ["manifest.csv"] if has_listed else []
    if oil.temperature is not None and not np.isfinite(temperature).all():
        temperature = np.where(np.isfinite(temperature), temperature, oil.temperature)
        sources.append("campaign.toml [oil] temperature")
    if not np.isfinite(temperature).any():
        if enabled:
            raise ValueError(
                f"--viscosity-correction: {oil.source} has [oil] but no run has an oil "
                "temperature; expected a temperature_C column in manifest.csv or [oil] "
                'temperature = "45 degC"'
            )
        return replace(
            unchanged,
            note=f"{oil.source} has [oil] but no run has an oil temperature (no temperature_C "
            "column in manifest.csv, no [oil] temperature): identified at the measured speeds "
            "without viscosity correction",
        )
    _check_every_run(points, temperature)
    table = points.copy()
    table[column] = temperature
    corrected = viscosity_corrected(
        table, oil=oil.points, reference_temperature=oil.reference_temperature
    )
    nu_ref = walther_viscosity(oil.reference_temperature, oil.points)
    ratio = walther_viscosity(temperature, oil.points) / nu_ref
    new_runs = _scaled_runs(runs, dict(zip(table["run"], ratio, strict=True)))
    (t40, nu40), (t100, nu100) = oil.points
    record = {
        "rule": VISCOSITY_RULE,
        "oil": {
            "temperature": [t40, t100],
            "viscosity": [nu40, nu100],
            "source": oil.source,
        },
        "reference_temperature": oil.reference_temperature,
        "temperature_min": float(temperature.min()),
        "temperature_max": float(temperature.max()),
        "temperature_source": " and ".join(sources),
        "speed_ratio_min": float(ratio.min()),
        "speed_ratio_max": float(ratio.max()),
    }
    outside = temperature.min() < t40 or temperature.max() > t100
    note = (
        f"viscosity correction: runs at {_celsius(temperature.min())} to "
        f"{_celsius(temperature.max())} identified as at {_celsius(oil.reference_temperature)} "
        f"(equal Hersey number, eq. 2.8; Walther viscosities through {nu40 * 1e6:g} and "
        f"{nu100 * 1e6:g} mm2/s; speeds scaled by {ratio.min():.3g} to {ratio.max():.3g}): "
        f"the datasheet holds at {_celsius(oil.reference_temperature)}"
        + ("; the Walther line is extrapolated outside 40-100 degC" if outside else "")
    )
    return ViscosityCorrection(corrected, new_runs, record, note)
