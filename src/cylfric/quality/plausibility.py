"""Physical checks of a campaign's points against its recipe: the force balance and the units.

The data-quality gate (:func:`cylfric.quality.assess`) calls these with the extraction,
whose :attr:`~cylfric.steady_state.Extraction.config` says the areas, the signs and the
pressure reference the points were formed with. Two checks (issue 39 item 2, issue 43
item 2):

- :func:`check_force_balance`: the force balance (eq. 3.1) is checked, not assumed. A run's
  offset ``(F_up + F_down) / 2`` holds what does not change sign with the motion: the weight,
  a preload, and any pressure force the balance failed to cancel. With the right
  ``load_cell_sign`` the load cell's reading of the pressure force cancels the balance's
  ``A_a p_a - A_b p_b``; with the wrong one the two add, and the offset follows the pressure
  force with a slope of 2 (one more chamber area per chamber area). A run's friction that
  follows the pressure force (runs without both directions, whose offset is the campaign's)
  says the same. A friction below 0 in most runs is a wrong ``position_sign`` (or
  ``load_cell_sign`` on a rig whose load cell sees no pressure force). A real seal's friction
  changes with pressure by a few per cent of the pressure force at most (0.014 of it on the
  shared Zillen PK seal, 0.004 on the thesis' hydraulic seals), so a slope of half the
  pressure force is far from both.
- :func:`check_plausibility`: a friction level above the pressure force the cylinder could
  make (the stated areas at the highest pressure) is a unit slip (a force column in kN
  whose unit says MN), not a seal.

Both raise a :class:`~cylfric.quality.QualityError` subclass (a ValueError: exit 2) naming
the files, the keys of campaign.toml and the likely slip, unless ``accept`` is set; then
they return the same text as a note.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._runtable import run_column
from . import QualityError, _relative

if TYPE_CHECKING:
    import pandas as pd

    from ..steady_state import Extraction

__all__ = [
    "ForceBalanceError",
    "ImplausibleDataError",
    "check_force_balance",
    "check_plausibility",
    "ACCEPT_HINT",
]

ACCEPT_HINT = (
    "to fit anyway: cylfric fit --accept-force-balance (FitOptions(accept_force_balance=True))"
)


class ForceBalanceError(QualityError):
    """The points contradict the force balance of campaign.toml (a sign or an area)."""


class ImplausibleDataError(QualityError):
    """The points contradict the cylinder's stated size and pressures (a unit slip)."""


def _runs(extraction: Extraction) -> pd.DataFrame:
    """Per run with ok windows: ``file``, ``pressure`` [Pa] (median of the windows),
    ``friction`` [N] (median), ``offset`` [N] (NaN without windows in both directions),
    ``balance`` [N] (the run's pressure term of the force balance, NaN without one)."""
    import pandas as pd

    points = extraction.points
    ok = points[points["flag"].eq("ok")]
    if ok.empty:
        return pd.DataFrame(columns=["run", "file", "pressure", "friction", "offset", "balance"])
    both = ok.groupby("run")["direction [-]"].nunique() == 2
    table = ok.groupby("run").agg(
        file=("file", "first"),
        pressure=("pressure [Pa]", "median"),
        friction=("friction [N]", "median"),
        offset=("offset [N]", "first"),
    )
    table.loc[~both.reindex(table.index, fill_value=False), "offset"] = math.nan
    balance = dict(
        zip(
            run_column(extraction.runs, "run"),
            run_column(extraction.runs, "pressure force [N]", default=math.nan),
            strict=True,
        )
    )
    table["balance"] = [float(balance.get(run, math.nan)) for run in table.index]
    table["file"] = [_relative(f, extraction) for f in table["file"]]
    return table.reset_index()


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(slope, its standard error) of a straight line through (x, y) [y/x]."""
    design = np.column_stack([np.ones_like(x), x])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    residual = y - design @ coef
    dof = max(len(x) - 2, 1)
    cov = np.linalg.pinv(design.T @ design) * float(residual @ residual) / dof
    return float(coef[1]), math.sqrt(max(float(cov[1, 1]), 0.0))


def _recipe(extraction: Extraction) -> str:
    """The campaign.toml the points were formed with (the ``--config`` recipe or the
    folder's), as a path to name in a message."""
    config = extraction.config
    source = getattr(config, "source", None)
    if source:
        return str(source)
    folder = getattr(extraction, "folder", None)
    return str(Path(folder) / "campaign.toml") if folder else "campaign.toml"


def _signs(extraction: Extraction) -> str:
    """'load_cell_sign = -1 (line 15), position_sign = 1 (not set: the default)'."""
    from ..io.campaign import _line_of

    config = extraction.config
    recipe = _recipe(extraction)
    said = []
    for key in ("load_cell_sign", "position_sign"):
        value = int(getattr(config, key, 1))
        line = _line_of(Path(recipe), key) if Path(recipe).is_file() else None
        where = f"line {line}" if line is not None else "not set: the default"
        said.append(f"{key} = {value} ({where})")
    return ", ".join(said)


def _significant(slope: float, stderr: float, t_limit: float) -> bool:
    return abs(slope) > t_limit * stderr


def _refuse(error: type[QualityError], text: str, accept: bool) -> list[str]:
    if accept:
        return [f"accepted (--accept-force-balance): {text}"]
    raise error(f"{text}; {ACCEPT_HINT}")


def check_force_balance(
    extraction: Extraction,
    *,
    accept: bool = False,
    min_fraction: float = 0.5,
    t_limit: float = 5.0,
    min_runs: int = 3,
    min_span: float = 0.05,
    scale_factor: float = 30.0,
) -> list[str]:
    """Refuse points whose offset or friction follows the pressure force of the balance.

    Parameters
    ----------
    extraction : Extraction
        With its :attr:`~cylfric.steady_state.Extraction.config` (without one nothing is
        checked).
    accept : bool
        Return the findings as notes instead of raising.
    min_fraction : float
        Smallest slope of the offset (or the friction) against the balance's pressure term
        ``A_a p_a - A_b p_b`` that is a wrong balance [-]: a wrong ``load_cell_sign`` gives
        2, a real seal's friction well under 0.05.
    t_limit : float
        The slope must also exceed this many standard errors [-].
    min_runs : int
        Fewest runs for a slope [-].
    min_span : float
        The balance's pressure force must change across the runs by more than this
        fraction of the larger area times the runs' pressure range for a slope [-]: on a
        rig whose chambers cancel (equal areas, equal pressures) it changes only by the
        sensors' noise.
    scale_factor : float
        Runs whose friction is more than this factor off the median run's are left out
        (a file in another force unit: the gate's ``scale`` check lists it) [-].

    Returns
    -------
    list of str
        Notes (only with ``accept``).

    Raises
    ------
    ForceBalanceError
        Naming the finding, the keys ``load_cell_sign`` / ``position_sign`` and the file
        that sets them (or would).
    """
    config = extraction.config
    if config is None:
        return []
    runs = _runs(extraction)
    if not runs.empty:  # a run in another force unit (the scale check's) is no evidence
        level = float(np.median(np.abs(runs["friction"])))
        ratio = np.abs(runs["friction"]) / level if level > 0 else np.ones(len(runs))
        runs = runs[(ratio < scale_factor) & (ratio > 1 / scale_factor)]
    if runs.empty:
        return []
    recipe = _recipe(extraction)
    signs = _signs(extraction)
    flip = {key: -int(getattr(config, key, 1)) for key in ("load_cell_sign", "position_sign")}
    pressure_rig = config.force_source == "pressures"
    area = max(config.area_a, config.area_b)

    def spans(frame) -> bool:
        """Whether the balance's pressure force changes across the runs of ``frame`` by
        more than ``min_span`` of what their pressures' range makes on the larger area
        (else it changes by the pressure sensors' noise only, which the offset shares:
        equal areas at equal pressures)."""
        if len(frame) < min_runs:
            return False
        reach = area * float(np.ptp(frame["pressure"]))
        return reach > 0 and float(np.ptp(frame["balance"])) > min_span * reach

    # 1. the offset follows the pressure force: the load cell's sign adds it instead of
    #    cancelling it (a load-cell rig with the chambers in the balance)
    if not pressure_rig:
        with_offset = runs.dropna(subset=["offset", "balance"])
        if spans(with_offset):
            x = with_offset["balance"].to_numpy(float)
            slope, stderr = _line(x, with_offset["offset"].to_numpy(float))
            if abs(slope) > min_fraction and _significant(slope, stderr, t_limit):
                positive = float(np.median(runs["friction"])) > 0
                if 1.5 < slope < 2.5:
                    cause = (
                        "the load cell's reading of the pressure force adds to the balance's "
                        "A_a p_a - A_b p_b instead of cancelling it: load_cell_sign has the "
                        "wrong sign"
                        + (
                            ", and so has position_sign (the two wrong signs cancel in the "
                            "friction's sign, not in its level)"
                            if positive
                            else ""
                        )
                    )
                    keys = (
                        f"load_cell_sign = {flip['load_cell_sign']} and position_sign = "
                        f"{flip['position_sign']}"
                        if positive
                        else f"load_cell_sign = {flip['load_cell_sign']}"
                    )
                else:
                    cause = (
                        "the balance's pressure term does not match the load cell's: the "
                        "signs (load_cell_sign, position_sign) or the areas ([cylinder] bore, "
                        "rod, kind) are wrong"
                    )
                    keys = "load_cell_sign, position_sign (and check bore, rod, kind)"
                per_bar = _per_bar(slope, x, with_offset["pressure"].to_numpy(float))
                return _refuse(
                    ForceBalanceError,
                    f"{recipe}: the force balance contradicts the data: the runs' load-cell "
                    f"offset (F_up + F_down)/2 follows the balance's pressure force "
                    f"A_a p_a - A_b p_b with a slope of {slope:.3g} (+/- {stderr:.2g}; "
                    f"{per_bar}), where a right balance leaves at most a few per cent "
                    f"(the seal's own pressure dependence): {cause}. Set {keys} in "
                    f"[force_balance] of {recipe} (now {signs})",
                    accept,
                )
        # 2. a run's friction follows the pressure force (runs without both directions)
        with_balance = runs.dropna(subset=["balance"])
        if spans(with_balance):
            x = with_balance["balance"].to_numpy(float)
            slope, stderr = _line(x, with_balance["friction"].to_numpy(float))
            if abs(slope) > min_fraction and _significant(slope, stderr, t_limit):
                return _refuse(
                    ForceBalanceError,
                    f"{recipe}: the force balance contradicts the data: the runs' friction "
                    f"follows the balance's pressure force A_a p_a - A_b p_b with a slope of "
                    f"{slope:.3g} (+/- {stderr:.2g}), where a seal's friction changes by a "
                    "few per cent of it at most: the pressure force is counted twice "
                    "(load_cell_sign) or not cancelled (the areas). Check load_cell_sign, "
                    f"position_sign in [force_balance] and bore, rod, kind in [cylinder] of "
                    f"{recipe} (now {signs})",
                    accept,
                )
    # 3. the friction is below 0 in most runs: the motion's sign is the opposite
    negative = runs["friction"] < 0
    if negative.mean() > 0.5 and float(np.median(runs["friction"])) < 0:
        files = ", ".join(str(f) for f in runs.loc[negative, "file"].head(3))
        balanced = runs.dropna(subset=["offset", "balance"])
        if pressure_rig:
            advice = f"position_sign = {flip['position_sign']} (or swap the chambers' columns)"
        elif spans(balanced):
            # the offset does not follow the pressure force: the load cell's sign cancels
            # it, so the position's sign is the wrong one
            advice = f"position_sign = {flip['position_sign']} (the load cell's sign cancels "
            advice += "the pressure force, so the position's is the wrong one)"
        else:
            advice = (
                f"position_sign = {flip['position_sign']} (the position's sign), or "
                f"load_cell_sign = {flip['load_cell_sign']} when the position is right"
            )
        return _refuse(
            ForceBalanceError,
            f"{recipe}: the force balance contradicts the data: the friction is below 0 N in "
            f"{int(negative.sum())} of {len(runs)} runs (median {np.median(runs['friction']):.4g}"
            f" N; {files}): the force opposes a motion of the opposite sign. Set {advice} in "
            f"[force_balance] of {recipe} (now {signs})",
            accept,
        )
    return []


def _per_bar(slope: float, balance: np.ndarray, pressure: np.ndarray) -> str:
    """The slope in N/bar against the points' pressure, beside the balance's own [words]."""
    if np.ptp(pressure) > 0:
        area, _ = _line(pressure, balance)  # the balance's pressure force per pascal [m^2]
        return f"{slope * area * 1e5:+.3g} N/bar against the balance's {area * 1e5:.3g} N/bar"
    return "one pressure"


FORCE_UNITS = {"mN": 1e-3, "N": 1.0, "daN": 10.0, "kN": 1e3, "MN": 1e6, "GN": 1e9}
"""Force units by their factor to N, for naming a unit slip."""


def _force_slip(unit: str | None, ratio: float) -> str:
    """The likely slip of a force column whose values are ``ratio`` times too large."""
    factor = FORCE_UNITS.get(unit or "", None)
    steps = round(math.log10(ratio) / 3) if ratio > 0 else 0
    steps = max(steps, 1)
    if factor is not None:
        meant = factor / 10 ** (3 * steps)
        names = [name for name, f in FORCE_UNITS.items() if math.isclose(f, meant)]
        if names:
            return (
                f"x{10 ** (3 * steps):g}: the values are probably in {names[0]} while the "
                f"unit says {unit}; correct the force unit in the files' unit row (or "
                "[columns] units in campaign.toml)"
            )
    return (
        f"about x{10 ** (3 * steps):g}: check the force column's unit (N or kN) in the files' "
        "unit row (or [columns] units in campaign.toml)"
    )


def check_plausibility(
    extraction: Extraction,
    runs: pd.DataFrame | None = None,
    *,
    accept: bool = False,
    margin: float = 1.0,
    min_fraction: float = 0.0,
) -> list[str]:
    """Refuse a friction level above the pressure force the cylinder could make.

    The largest pressure force is ``max(A_a, A_b)`` (the stated bore, rod and kind) times
    the highest chamber pressure of the campaign: the points' highest pressure, doubled for
    the references that are a mean or a single chamber of a double-acting cylinder (the other
    chamber may hold more). A seal's friction is a few per cent of it; a run above
    ``margin`` times it is a unit slip (a force column in kN whose unit says MN: x1000).

    Parameters
    ----------
    extraction : Extraction
        With its config (without areas nothing is checked).
    runs : DataFrame, optional
        ``run``, ``file``, ``friction`` [N], ``pressure`` [Pa] of the runs to check (default:
        every run with ok windows).
    accept : bool
        Return the finding as a note instead of raising.
    margin : float
        Fraction of the largest pressure force a friction may reach [-].
    min_fraction : float
        Refuse only when more than this fraction of the runs is above it [-] (0: any run;
        the gate first asks for a majority, before its ``scale`` check lists single runs
        in another unit, then for any of the runs it keeps).

    Raises
    ------
    ImplausibleDataError
        Naming the runs, the force unit their files state and the likely slip.
    """
    config = extraction.config
    if config is None:
        return []
    area = max(config.area_a, config.area_b)
    if not area > 0:
        return []
    table = _runs(extraction) if runs is None else runs
    table = table.dropna(subset=["friction", "pressure"])
    if table.empty:
        return []
    rule = config.pressure_reference
    single = config.pressure_basis.get("kind") == "single-acting"
    factor = 1.0 if rule in ("sum", "max") or single else 2.0
    p_max = factor * float(table["pressure"].max())
    if not p_max > 0:
        return []
    capacity = area * p_max
    high = table[table["friction"].abs() > margin * capacity]
    if high.empty or len(high) <= min_fraction * len(table):
        return []
    units = dict(
        zip(
            run_column(extraction.runs, "run"),
            run_column(extraction.runs, "units", "force", default=None),
            strict=True,
        )
    )
    first = high.iloc[0]
    unit = units.get(first["run"])
    ratio = float(abs(first["friction"]) / capacity)
    files = ", ".join(str(f) for f in high["file"].head(3)) + (", ..." if len(high) > 3 else "")
    text = (
        f"{extraction.folder or 'the campaign'}: the friction of {len(high)} of {len(table)} "
        f"runs ({files}) is above the pressure force the cylinder could make: "
        f"{first['friction']:.4g} N against {capacity:.4g} N (the stated area "
        f"{area * 1e6:.4g} mm^2 times {p_max / 1e5:.4g} bar, the highest chamber pressure; "
        f"{_recipe(extraction)}); the force unit the file states: "
        f"{unit or 'none (campaign.toml [columns] units)'}; likely slip "
        f"{_force_slip(unit, ratio * 100)}"
    )
    if accept:
        return [f"accepted (--accept-force-balance): {text}"]
    raise ImplausibleDataError(f"{text}; {ACCEPT_HINT}")
