"""Drift of a cylinder's friction: between two campaigns, and along one campaign's run order.

The thesis saw later runs give lower friction (warm-up) and suspects temperature and seal
wear (Pérez Dorado 2016, ch. 4 and 6). Two questions, answered with the uncertainty the
fits carry:

* :func:`drift` - between two datasheets (or fit output folders) of the same cylinder: per
  coefficient and at a grid of operating points in the common validity range, the change
  ``b - a`` and its z-score ``(b - a) / sqrt(se_a^2 + se_b^2)`` (the two fits are
  independent). ``|z|`` above the two-sided normal quantile of ``level`` (1.96 at 95 %)
  is marked significant. Over a grid of many points a few marks are expected by chance
  even without drift (the points are correlated, so not exactly ``(1 - level)`` of them):
  look at the pattern and the largest ``|z|``.
* :func:`run_order_trend` - within one campaign: the residuals of the points against the
  campaign's own model, against run order (the ``run`` column: the order of
  ``manifest.csv`` or of the file names; or the files' modification times). The trend
  between runs (mean residual of each run against its rank, least squares) and within runs
  (residual against stroke rank, each run's mean removed) with their standard errors.
  A campaign run in order of pressure confounds the between-run trend with pressure,
  which the model has partly absorbed; the within-run trend is free of that.

Temperature is an identification option of its own: :mod:`cylfric.viscosity`.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Sequence

    import pandas as pd
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath

    from .model import FrictionModel

__all__ = [
    "drift",
    "load_fit",
    "run_order_trend",
    "RunOrderTrend",
    "figure_run_order",
]

_ORDERS = ("run", "mtime")


def load_fit(
    source: FrictionModel | dict[str, Any] | StrPath,
) -> tuple[FrictionModel, pd.DataFrame | None, str]:
    """(model, points or None, label) of a datasheet path, a fit output folder, a dict or a
    :class:`~cylfric.model.FrictionModel`. ``points`` is ``points.csv`` beside the datasheet."""
    import pandas as pd

    from .model import FrictionModel

    if isinstance(source, FrictionModel):
        return source, None, "model"
    if isinstance(source, dict):
        return FrictionModel.from_datasheet(source), None, source.get("name", "datasheet")
    path = Path(source)
    if path.is_dir():
        folder, path = path, path / "datasheet.json"
    else:
        folder = path.parent
    if not path.exists():
        raise ValueError(f"{path}: no datasheet; expected a datasheet.json or a fit output folder")
    model = FrictionModel.from_datasheet(path)
    points_path = folder / "points.csv"
    points = pd.read_csv(points_path) if points_path.exists() else None
    label = folder.name if path.name == "datasheet.json" else path.stem
    return model, points, label


def _z(change, se_a, se_b):
    se = np.hypot(np.asarray(se_a, dtype=float), np.asarray(se_b, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(se > 0, change / se, np.nan)
    return se, z


def drift(
    a: StrPath | dict[str, Any] | FrictionModel,
    b: StrPath | dict[str, Any] | FrictionModel,
    *,
    pressures: Sequence[float] | None = None,
    velocities: Sequence[float] | None = None,
    n: int = 5,
    level: float = 0.95,
) -> pd.DataFrame:
    """Change of friction between two fits of the same cylinder, with z-scores.

    Parameters
    ----------
    a, b : path-like, dict or FrictionModel
        The earlier and the later datasheet (or fit output folder).
    pressures : sequence of float, optional
        Operating pressures [Pa]; default ``n`` evenly spaced over the common validity range.
    velocities : sequence of float, optional
        Speeds [m/s]; default ``n`` log-spaced over the common validity range.
    n : int
        Grid size per axis when the points are not given.
    level : float
        Two-sided confidence level of the significance mark [-].

    Returns
    -------
    pandas.DataFrame
        One row per coefficient (``kind`` = ``"parameter"``) and per operating point
        (``kind`` = ``"friction"``): ``quantity``, ``unit``, ``velocity [m/s]``,
        ``pressure [Pa]`` (NaN for coefficients), ``a``, ``b``, ``change``, ``stderr``
        (of the change), ``z [-]`` and ``significant``. SI units (``unit``).
        ``attrs["notes"]`` says which coefficients were left out and why.

    Raises
    ------
    ValueError
        The two datasheets' pressure laws see different pressures (``reference``: chamber
        A, B, their sum, mean or maximum): the same operating pressure is then a different
        state of the cylinder and nothing compares; the message names both and their
        references.

    Notes
    -----
    Coefficients are compared only where they mean the same thing: both datasheets have
    the same friction law (``stribeck``, ``coulomb_viscous``, ``coulomb``) and the
    parameter has the same pressure law (``linear``, ``quadratic``, ...). Otherwise only
    the friction at the operating points is compared (a force at a velocity and an
    operating pressure is the same quantity under any law) and a note says why.
    """
    import pandas as pd

    from .model import ValidityWarning

    if not 0 < level < 1:
        raise ValueError(f"level = {level}: expected 0 < level < 1")
    model_a, _, label_a = load_fit(a)
    model_b, _, label_b = load_fit(b)
    names = (_described(a, model_a, label_a), _described(b, model_b, label_b))
    comparable, notes = _comparable(model_a, model_b, names)
    z_crit = _normal_quantile(0.5 + level / 2)
    rows = []
    for name, pa in model_a.parameters.items():
        pb = model_b.parameters.get(name)
        if pa.value is None or pb is None or pb.value is None or pa.unit != pb.unit:
            continue
        if pa.parameter not in comparable:
            continue
        if pa.parameter in ("sigma_0", "sigma_1"):
            continue  # bristle parameters: assumed in most datasheets, not fitted
        se_a = math.nan if pa.stderr is None else pa.stderr
        se_b = math.nan if pb.stderr is None else pb.stderr
        change = pb.value - pa.value
        se, z = _z(change, se_a, se_b)
        rows.append(
            {
                "kind": "parameter",
                "quantity": name,
                "unit": pa.unit,
                "velocity [m/s]": math.nan,
                "pressure [Pa]": math.nan,
                "a": pa.value,
                "b": pb.value,
                "change": change,
                "stderr": float(se),
                "z [-]": float(z),
            }
        )
    p_grid, v_grid = _common_grid(model_a, model_b, pressures, velocities, n)
    v: np.ndarray
    p: np.ndarray
    v, p = np.meshgrid(v_grid, p_grid, indexing="ij")
    v, p = v.ravel(), p.ravel()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        f_a, f_b = model_a.friction(v, p), model_b.friction(v, p)
        se_a = _friction_se(model_a, v, p)
        se_b = _friction_se(model_b, v, p)
    se, z = _z(f_b - f_a, se_a, se_b)
    for i in range(v.size):
        rows.append(
            {
                "kind": "friction",
                "quantity": "friction",
                "unit": "N",
                "velocity [m/s]": float(v[i]),
                "pressure [Pa]": float(p[i]),
                "a": float(f_a[i]),
                "b": float(f_b[i]),
                "change": float(f_b[i] - f_a[i]),
                "stderr": float(se[i]),
                "z [-]": float(z[i]),
            }
        )
    table = pd.DataFrame.from_records(rows)
    table["significant"] = np.abs(table["z [-]"]) > z_crit
    table.attrs["level"] = level
    table.attrs["z_critical"] = z_crit
    table.attrs["notes"] = notes
    return table


def _described(source, model, label) -> str:
    """How the message names a datasheet: its path as given, else its file, else its label."""
    if isinstance(source, str | Path):
        return str(source)
    return model.source or label


def _comparable(model_a, model_b, names) -> tuple[set, list[str]]:
    """(parameters whose coefficients mean the same in both models, notes on the others);
    ValueError when the pressure references differ (nothing compares then)."""
    first, second = names
    if model_a.reference != model_b.reference:
        raise ValueError(
            f"{first} and {second} have different pressure references ({first}: "
            f"{model_a.reference!r}, {second}: {model_b.reference!r}; the pressure their laws "
            "see: chamber a, b, sum, mean or max): the same operating pressure is a different "
            "state of the cylinder, so neither their coefficients nor their friction at an "
            "operating point compare. Compare datasheets fitted with the same reference"
        )
    if model_a.friction_law != model_b.friction_law:
        return set(), [
            f"friction laws differ ({first}: {model_a.friction_law}, {second}: "
            f"{model_b.friction_law}): their coefficients mean different things, so none is "
            "compared; the friction at the operating points is (a force at a velocity and "
            "pressure is the same quantity under any law)"
        ]
    comparable, notes = set(), []
    for parameter, law_a in model_a.laws.items():
        law_b = model_b.laws.get(parameter)
        if law_a == law_b:
            comparable.add(parameter)
        elif law_a is not None and law_b is not None:
            notes.append(
                f"pressure laws of {parameter} differ ({first}: {law_a}, {second}: {law_b}): "
                "its coefficients are not compared; the friction at the operating points is"
            )
    return comparable, notes


def _friction_se(model, v, p):
    if model.covariance is None:
        return np.full(v.shape, np.nan)
    return model.standard_error(v, p)


def _common_grid(model_a, model_b, pressures, velocities, n):
    if pressures is not None and velocities is not None:
        return np.asarray(pressures, dtype=float), np.abs(np.asarray(velocities, dtype=float))
    va, vb = model_a.validity, model_b.validity
    if va is None or vb is None:
        raise ValueError(
            "a datasheet without validity ranges: give the pressures [Pa] and velocities [m/s]"
        )
    p_lo = max(va["pressure_min"], vb["pressure_min"])
    p_hi = min(va["pressure_max"], vb["pressure_max"])
    v_lo = max(va["velocity_min"], vb["velocity_min"])
    v_hi = min(va["velocity_max"], vb["velocity_max"])
    if p_lo > p_hi or v_lo > v_hi or v_hi <= 0:
        raise ValueError(
            f"the two datasheets' validity ranges do not overlap (pressures "
            f"{va['pressure_min'] / 1e5:.4g}-{va['pressure_max'] / 1e5:.4g} and "
            f"{vb['pressure_min'] / 1e5:.4g}-{vb['pressure_max'] / 1e5:.4g} bar, speeds "
            f"{va['velocity_min'] * 1e3:.4g}-{va['velocity_max'] * 1e3:.4g} and "
            f"{vb['velocity_min'] * 1e3:.4g}-{vb['velocity_max'] * 1e3:.4g} mm/s); "
            "give the operating points"
        )
    if pressures is None:
        pressures = np.linspace(p_lo, p_hi, n) if p_hi > p_lo else np.array([p_lo])
    if velocities is None:
        velocities = np.geomspace(max(v_lo, 1e-6), v_hi, n) if v_hi > v_lo else np.array([v_hi])
    return np.asarray(pressures, dtype=float), np.abs(np.asarray(velocities, dtype=float))


@dataclass(frozen=True)
class RunOrderTrend:
    """Friction residuals against run order in one campaign (see :func:`run_order_trend`).

    Attributes
    ----------
    points : pandas.DataFrame
        The points used, with ``order [-]`` (run rank), ``stroke order [-]`` (rank in its
        run) and ``residual [N]`` (measured minus the model).
    runs : pandas.DataFrame
        Per run: ``order [-]``, ``file``, ``residual [N]`` (mean), ``n [-]``.
    between_slope, between_stderr : float
        Trend of the runs' mean residual [N per run] and its standard error (NaN with
        fewer than 3 runs).
    within_slope, within_stderr : float
        Trend of the residual along the strokes of a run [N per stroke] (the mean of each
        run and direction removed) and its standard error (NaN when runs have a single stroke).
    order : str
        ``"run"`` or ``"mtime"``.
    """

    points: pd.DataFrame
    runs: pd.DataFrame
    between_slope: float
    between_stderr: float
    within_slope: float
    within_stderr: float
    order: str

    def summary(self) -> str:
        """One line per trend with the slope, its standard error and the z-score."""
        lines = []
        for what, slope, se, unit in (
            ("between runs", self.between_slope, self.between_stderr, "N per run"),
            ("within runs", self.within_slope, self.within_stderr, "N per stroke"),
        ):
            if math.isfinite(slope) and math.isfinite(se) and se > 0:
                lines.append(f"{what}: {slope:+.4g} ± {se:.2g} {unit} (z = {slope / se:+.2f})")
            else:
                lines.append(f"{what}: not estimable")
        return "\n".join(lines)


def _ols_slope(x: ArrayLike, y: ArrayLike) -> tuple[float, float]:
    """Least-squares slope of y on x and its standard error (NaN when not estimable)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    sxx = float(np.sum((x - x.mean()) ** 2)) if x.size else 0.0
    if x.size < 3 or sxx == 0:
        return math.nan, math.nan
    slope = float(np.sum((x - x.mean()) * (y - y.mean())) / sxx)
    resid = y - y.mean() - slope * (x - x.mean())
    return slope, math.sqrt(float(np.sum(resid**2)) / (x.size - 2) / sxx)


def run_order_trend(
    points: pd.DataFrame,
    model: FrictionModel,
    *,
    order: Literal["run", "mtime"] = "run",
    campaign: StrPath | None = None,
) -> RunOrderTrend:
    """Residual friction against run order, between and within runs.

    Parameters
    ----------
    points : pandas.DataFrame
        A campaign's points table (``points.csv``: ``run``, ``file``, ``velocity [m/s]``,
        ``pressure [Pa]``, ``friction [N]``, ``window_start [s]``, ``flag``); rows whose
        flag is not ``ok`` or without friction are left out.
    model : FrictionModel
        The campaign's model; residual = measured friction - ``model.friction(|v|, p)``.
    order : {"run", "mtime"}
        Run order: the ``run`` column (manifest or file-name order), or the modification
        time of each file in ``campaign``.
    campaign : path-like, optional
        Campaign folder (needed for ``order="mtime"``).
    """
    import pandas as pd

    from .model import ValidityWarning

    if order not in _ORDERS:
        raise ValueError(f"order = {order!r}: unknown; valid: {list(_ORDERS)}")
    needed = {"run", "file", "velocity [m/s]", "pressure [Pa]", "friction [N]"}
    missing = needed - set(points.columns)
    if missing:
        raise ValueError(f"points table: missing columns {sorted(missing)}; expected points.csv")
    table = points.copy()
    if "flag" in table:
        table = table[table["flag"] == "ok"]
    table = table[np.isfinite(table["friction [N]"]) & np.isfinite(table["velocity [m/s]"])]
    if table.empty:
        raise ValueError("points table: no usable point (flag ok, finite friction)")
    if order == "mtime":
        if campaign is None:
            raise ValueError("order = 'mtime' needs the campaign folder of the raw files")
        times = {}
        for file in table["file"].unique():
            path = Path(campaign) / Path(file).name
            if not path.exists():
                raise ValueError(f"{path}: run file not found for order = 'mtime'")
            times[file] = path.stat().st_mtime
        key = table["file"].map(times)
    else:
        key = table["run"]
    table["order [-]"] = key.rank(method="dense").astype(int) - 1
    sort = ["order [-]"] + (["window_start [s]"] if "window_start [s]" in table else [])
    table = table.sort_values(sort, kind="stable")
    table["stroke order [-]"] = table.groupby("order [-]").cumcount()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        table["residual [N]"] = table["friction [N]"] - model.friction(
            np.abs(table["velocity [m/s]"].to_numpy()), table["pressure [Pa]"].to_numpy()
        )
    runs = (
        table.groupby("order [-]")
        .agg(file=("file", "first"), residual=("residual [N]", "mean"), n=("run", "size"))
        .reset_index()
        .rename(columns={"residual": "residual [N]", "n": "n [-]"})
    )
    between = _ols_slope(runs["order [-]"], runs["residual [N]"])
    # each run's (and direction's) own mean removed: only the order within a run remains
    groups = ["order [-]"] + (["direction [-]"] if "direction [-]" in table else [])
    grouped = table.groupby(groups)
    x = table["stroke order [-]"] - grouped["stroke order [-]"].transform("mean")
    y = table["residual [N]"] - grouped["residual [N]"].transform("mean")
    sxx = float(np.sum(x**2))
    dof = len(table) - grouped.ngroups - 1
    if sxx > 0 and dof > 0:
        w_slope = float(np.sum(x * y) / sxx)
        w_se = math.sqrt(float(np.sum((y - w_slope * x) ** 2)) / dof / sxx)
    else:
        w_slope = w_se = math.nan
    return RunOrderTrend(
        pd.DataFrame(table).reset_index(drop=True), runs, *between, w_slope, w_se, order
    )


def figure_run_order(trend: RunOrderTrend, title: str = "") -> Figure:
    """Residual friction [N] against run order (points, run means, between-run trend)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 3.6), layout="constrained")
    ax = fig.subplots()
    pts = trend.points
    position = (
        pts["order [-]"]
        + (pts["stroke order [-]"] + 0.5)
        / (pts.groupby("order [-]")["stroke order [-]"].transform("max") + 1)
        - 0.5
    )
    ax.plot(position, pts["residual [N]"], ".", ms=3, alpha=0.6, label="points (strokes in order)")
    ax.plot(trend.runs["order [-]"], trend.runs["residual [N]"], "o", label="run mean")
    if math.isfinite(trend.between_slope):
        x = trend.runs["order [-]"].to_numpy(dtype=float)
        y = trend.runs["residual [N]"].to_numpy()
        line = y.mean() + trend.between_slope * (x - x.mean())
        ax.plot(
            x,
            line,
            "-",
            label=f"trend {trend.between_slope:+.3g} ± {trend.between_stderr:.2g} N/run",
        )
    ax.axhline(0.0, color="0.5", lw=0.8)
    basis = "file modification time" if trend.order == "mtime" else "run"
    ax.set_xlabel(f"run order [-] ({basis})")
    ax.set_ylabel("measured - model [N]")
    ax.set_title(title or "friction against run order (warm-up)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return fig


def _normal_quantile(q):
    from statistics import NormalDist

    return NormalDist().inv_cdf(q)


def write_drift(table: pd.DataFrame, out: StrPath) -> Path:
    """Write ``drift.csv`` into ``out`` (atomically) and a JSON summary; returns the CSV path."""
    from ._paths import make_folder
    from .io.writers import atomic_write_text

    out = make_folder(out)  # a symbolic link is refused, not written through
    path = atomic_write_text(out / "drift.csv", table.to_csv(index=False))
    friction = table[table["kind"] == "friction"]
    z = np.abs(friction["z [-]"].to_numpy(dtype=float))
    summary = {
        "level": table.attrs.get("level"),
        "z_critical": table.attrs.get("z_critical"),
        "significant_points": int(friction["significant"].sum()),
        "points": int(len(friction)),
        "max_abs_z": None if np.isnan(z).all() else float(np.nanmax(z)),  # None: no stderr
        "significant_parameters": list(
            table[(table["kind"] == "parameter") & table["significant"]]["quantity"]
        ),
        "notes": list(table.attrs.get("notes", [])),
    }
    atomic_write_text(out / "drift.json", json.dumps(summary, indent=1) + "\n")
    return path
