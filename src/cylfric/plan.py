"""The standard test plan: which (pressure, speed) runs identify the friction model best.

A campaign is a list of runs; each run drives the rod down and up the stroke at one speed
and one pressure, and the extraction turns it into one friction value per direction whose
offset-free mean is ``(F_up - F_down) / 2`` (:mod:`cylfric.steady_state`). Around a model
``theta`` (the thesis law by default, or a datasheet), a run at (v, p) contributes
``j j^T / s^2`` to the information matrix of the coefficients, where ``j`` is the
sensitivity of the friction to each coefficient (:meth:`FrictionModel.jacobian`) and
``s`` the standard error of the run's friction (:class:`WindowNoise`). The plan of N runs
maximises ``det(M)``, ``M = sum j j^T / s^2`` (D-optimal: the smallest joint confidence
region of the coefficients) over a candidate grid of log-spaced speeds and evenly spaced
pressures, by a greedy start and Fedorov exchange; its predicted covariance is ``M^-1``
(first order, with the fit weighted by the window standard errors as
:func:`cylfric.identify.identify` does).

Examples
--------
>>> from cylfric.plan import WindowNoise, predicted_uncertainty
>>> from cylfric.model import FrictionModel
>>> noise = WindowNoise((0.001, 0.1), (0.02, 0.08))    # [m/s], [N]
>>> speeds = [0.001, 0.003, 0.01, 0.03, 0.1]             # [m/s]
>>> u = predicted_uncertainty(FrictionModel(), speeds * 2, [1e4] * 5 + [159e5] * 5, noise)
>>> len(u.names), round(u.stderr["F_c.intercept"], 3)     # 8 coefficients; [N]
(8, 0.093)
"""

from __future__ import annotations

import base64
import html
import io
import math
import tempfile
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .io.writers import atomic_write_bytes, atomic_write_text
from .model import STEADY_PARAMETERS, FrictionModel, engineering_unit

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence
    from pathlib import Path
    from typing import Any

    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath

    from .simulate.bench import BenchSettings

__all__ = [
    "WindowNoise",
    "Uncertainty",
    "TestPlan",
    "predicted_uncertainty",
    "d_optimal",
    "make_plan",
    "grid_uncertainty",
    "compare",
    "candidate_grid",
    "OPERATING_POINTS",
]

OPERATING_POINTS = (
    (0.002, 55e5),
    (0.010, 103e5),
    (0.025, 80e5),
    (0.100, 159e5),
    (0.005, 20e5),
    (0.050, 5e5),
)
"""(velocity [m/s], pressure [Pa]) where the plan reports the band width: the six points of
the band-calibration study in the README (2 mm/s at 55 bar, ..., 50 mm/s at 5 bar)."""

BAND_LEVEL = 0.95
_Z95 = 1.959963984540054  # normal quantile of 0.975 (a plan has no residual dof yet)


@dataclass(frozen=True)
class WindowNoise:
    """Standard error of a window's mean friction [N] against speed [m/s].

    Interpolated linearly in log-log between the calibration speeds and held constant
    beyond them. The friction of a run, the mean of its two directions, has the standard
    error ``sem / sqrt(2)`` (:meth:`run_std`).

    Attributes
    ----------
    speeds : tuple of float
        Calibration speeds [m/s], increasing.
    sem : tuple of float
        Root-mean-square standard error ``friction_std / sqrt(n)`` of the windows at each
        speed [N].
    source : str
        Where the calibration came from.
    """

    speeds: tuple
    sem: tuple
    source: str = "given"

    def __post_init__(self) -> None:
        v, s = np.asarray(self.speeds, float), np.asarray(self.sem, float)
        if v.ndim != 1 or v.shape != s.shape or v.size < 1:
            raise ValueError("WindowNoise needs equally long, non-empty speeds [m/s] and sem [N]")
        if not (np.all(v > 0) and np.all(np.diff(v) > 0)):
            raise ValueError(f"WindowNoise speeds {self.speeds} must be > 0 m/s and increasing")
        if not (np.all(s > 0) and np.all(np.isfinite(s))):
            raise ValueError(f"WindowNoise sem {self.sem} must be finite and > 0 N")

    def __call__(self, speed: ArrayLike) -> np.ndarray:
        """Standard error of one window's mean friction [N] at ``speed`` [m/s]."""
        logv = np.log(np.abs(np.asarray(speed, dtype=float)))
        return np.exp(np.interp(logv, np.log(self.speeds), np.log(self.sem)))

    def run_std(self, speed: ArrayLike) -> np.ndarray:
        """Standard error of a run's friction [N] (mean of the two directions)."""
        return self(speed) / math.sqrt(2.0)

    @classmethod
    def from_points(
        cls, points: pd.DataFrame, *, source: str = "points table", relative: float = 0.1
    ) -> WindowNoise:
        """Calibrate from a points table (``points.csv`` of a fit, or an extraction).

        Uses the ``ok`` windows: ``friction_std [N] / sqrt(n [-])`` grouped by speed
        (speeds within ``relative`` of each other form one group), root mean square per
        group.
        """
        needed = {"velocity [m/s]", "friction_std [N]", "n [-]"}
        missing = needed - set(points.columns)
        if missing:
            raise ValueError(
                f"{source}: the points table lacks {sorted(missing)}; expected the columns of "
                "points.csv written by cylfric fit"
            )
        used = points[points["flag"].eq("ok")] if "flag" in points else points
        speed = used["velocity [m/s]"].abs().to_numpy(float)
        sem = (used["friction_std [N]"] / np.sqrt(used["n [-]"])).to_numpy(float)
        good = np.isfinite(sem) & (sem > 0) & (speed > 0)
        speed, sem = speed[good], sem[good]
        if speed.size == 0:
            raise ValueError(f"{source}: no usable window (flag ok, friction_std > 0, n > 0)")
        order = np.argsort(speed)
        speed, sem = speed[order], sem[order]
        group = np.concatenate(([0], np.cumsum(np.diff(speed) > relative * speed[1:])))
        speeds = [float(np.exp(np.mean(np.log(speed[group == g])))) for g in np.unique(group)]
        rms = [float(np.sqrt(np.mean(sem[group == g] ** 2))) for g in np.unique(group)]
        return cls(tuple(speeds), tuple(rms), source)

    @classmethod
    def from_bench(
        cls,
        settings: BenchSettings | None = None,
        *,
        speeds: ArrayLike | None = None,
        pressure_bar: float = 80.0,
        seeds: int = 2,
        progress: Callable[..., Any] | None = None,
    ) -> WindowNoise:
        """Calibrate on the virtual bench: pilot runs through the extraction.

        Runs the bench (``settings``: force noise, sampling, stroke) at ``speeds`` [m/s] and
        one pressure [bar], ``seeds`` times, extracts the windows as ``cylfric fit`` does,
        and calibrates with :meth:`from_points`. The window length (and so the error) is
        what the extraction keeps, not the nominal stroke: at 1 mm/s the settled window is
        a fraction of the stroke.
        """
        from .simulate.bench import BenchSettings, generate_campaign
        from .steady_state import extract_campaign

        s = settings or BenchSettings()
        speeds = np.geomspace(1e-3, 0.135, 9) if speeds is None else np.asarray(speeds, float)
        frames = []
        for seed in range(seeds):
            pilot = _replace(
                s,
                points=tuple((pressure_bar, round(v * 1e3, 6)) for v in speeds),
                seed=s.seed + 1000 + seed,
            )
            with tempfile.TemporaryDirectory(prefix="cylfric-pilot-") as folder:
                generate_campaign(folder, pilot, progress=progress)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    frames.append(extract_campaign(folder).points)
        return cls.from_points(
            pd.concat(frames),
            source=f"virtual bench pilot: {len(speeds)} speeds at {pressure_bar:g} bar, "
            f"{seeds} seed(s), force noise {s.force_noise:g} N",
        )


def _replace(settings, **changes):
    from dataclasses import replace

    return replace(settings, **changes)


def _names(model: FrictionModel, fixed=()):
    fixed = set(fixed)
    return [
        n
        for n in model.varying
        if n.partition(".")[0] in STEADY_PARAMETERS
        and n not in fixed
        and n.partition(".")[0] not in fixed
    ]


def _information_rows(model, velocity, pressure, noise, names):
    """Rows ``j / s`` [-]: each run's sensitivities over its friction's standard error."""
    velocity = np.asarray(velocity, dtype=float)
    jac = model.jacobian(np.abs(velocity), np.asarray(pressure, dtype=float), names)
    return jac / noise.run_std(velocity)[..., None]


@dataclass(frozen=True)
class Uncertainty:
    """Predicted uncertainty of a plan (SI).

    Attributes
    ----------
    names : tuple of str
        Coefficients (``"F_c.slope"``), in the order of ``covariance``.
    covariance : ndarray
        ``M^-1`` [SI units of the coefficients, squared].
    stderr : dict
        Coefficient -> standard error [SI].
    band : pandas.DataFrame
        ``velocity [m/s]``, ``pressure [Pa]``, ``friction [N]``, ``stderr [N]`` and
        ``half_width [N]`` (95 % band of the mean friction) at the operating points.
    log_det : float
        ``log det M`` with the coefficients in SI [-] (the D criterion).
    """

    names: tuple
    covariance: np.ndarray
    stderr: dict
    band: pd.DataFrame
    log_det: float

    def table(self) -> pd.DataFrame:
        """Standard errors in engineering units: ``coefficient``, ``stderr``, ``unit``."""
        rows = []
        for name in self.names:
            unit, k = engineering_unit(name)
            rows.append({"coefficient": name, "stderr": self.stderr[name] * k, "unit": unit})
        return pd.DataFrame(rows)


def predicted_uncertainty(
    model: FrictionModel,
    velocity: ArrayLike,
    pressure: ArrayLike,
    noise: WindowNoise,
    *,
    fixed: Iterable[str] = (),
    operating_points: Sequence[tuple[float, float]] = OPERATING_POINTS,
) -> Uncertainty:
    """Covariance of the coefficients that runs at (velocity [m/s], pressure [Pa]) would give.

    ``cov = (J^T W J)^-1`` with ``W = diag(1 / s_run^2)`` (:meth:`WindowNoise.run_std`),
    the first-order covariance of the weighted least-squares fit. Coefficients in
    ``fixed`` (``"alpha"``, ``"v_r"``) are held. Raises ValueError when the runs cannot
    identify the coefficients (singular information matrix).
    """
    names = _names(model, fixed)
    rows = _information_rows(model, velocity, pressure, noise, names)
    info = rows.T @ rows
    scale = np.sqrt(np.diag(info))
    if np.any(scale == 0):
        blind = [n for n, s in zip(names, scale, strict=True) if s == 0]
        raise ValueError(f"the runs carry no information on {blind}")
    scaled = info / np.outer(scale, scale)
    sign, logdet = np.linalg.slogdet(scaled)
    if sign <= 0 or np.linalg.cond(scaled) > 1e12:
        raise ValueError(
            f"{len(rows)} run(s) cannot identify the {len(names)} coefficients {names}: "
            "too few distinct speeds or pressures"
        )
    cov = np.linalg.inv(scaled) / np.outer(scale, scale)
    stderr = dict(zip(names, np.sqrt(np.diag(cov)).tolist(), strict=True))
    v_op = np.array([v for v, _ in operating_points], dtype=float)
    p_op = np.array([p for _, p in operating_points], dtype=float)
    jac = model.jacobian(v_op, p_op, names)
    se = np.sqrt(np.einsum("ij,jk,ik->i", jac, cov, jac))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        friction = model.friction(v_op, p_op)
    band = pd.DataFrame(
        {
            "velocity [m/s]": v_op,
            "pressure [Pa]": p_op,
            "friction [N]": friction,
            "stderr [N]": se,
            "half_width [N]": _Z95 * se,
        }
    )
    return Uncertainty(tuple(names), cov, stderr, band, float(logdet + 2 * np.log(scale).sum()))


MAX_CANDIDATES = 20_000
"""Most candidate runs (pressures x speeds) a plan is chosen from: the exchange holds a few
(runs x candidates) arrays (3,000 x 3,000 candidates had taken 2.7 GB, then MemoryError);
the default grid has 225."""
MAX_RUNS = 5_000
"""Most runs a plan may have (the thesis grid has 270)."""


def _check_size(n_pressures: int, n_speeds: int, runs: int | None = None) -> None:
    """ValueError naming the grid or the run count when a plan would not fit in memory or
    time (:data:`MAX_CANDIDATES`, :data:`MAX_RUNS`)."""
    if not (n_pressures >= 1 and n_speeds >= 2):
        raise ValueError(
            f"candidate grid {n_pressures} pressures x {n_speeds} speeds: expected at least "
            "1 pressure and 2 speeds (--candidate-pressures, --candidate-speeds)"
        )
    if n_pressures * n_speeds > MAX_CANDIDATES:
        raise ValueError(
            f"candidate grid {n_pressures} pressures x {n_speeds} speeds = "
            f"{n_pressures * n_speeds:,} candidates; at most {MAX_CANDIDATES:,} (the default "
            "is 9 x 25): choose smaller --candidate-pressures and --candidate-speeds"
        )
    if runs is not None and not 1 <= runs <= MAX_RUNS:
        raise ValueError(f"{runs:,} runs: expected 1 to {MAX_RUNS:,} runs (--runs)")


def candidate_grid(
    pressure_range: tuple[float, float],
    speed_range: tuple[float, float],
    *,
    n_pressures: int = 9,
    n_speeds: int = 25,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate runs: ``n_pressures`` evenly spaced pressures [Pa] x ``n_speeds`` log-spaced
    speeds [m/s] over the ranges (rounded to 0.1 bar and 0.01 mm/s)."""
    _check_size(n_pressures, n_speeds)
    p_lo, p_hi = pressure_range
    v_lo, v_hi = speed_range
    if not (0 <= p_lo <= p_hi and math.isfinite(p_hi)):
        raise ValueError(f"pressure range {p_lo}-{p_hi} Pa: expected 0 <= low <= high")
    if not (0 < v_lo < v_hi and math.isfinite(v_hi)):
        raise ValueError(f"speed range {v_lo}-{v_hi} m/s: expected 0 < low < high")
    pressures = np.unique(np.round(np.linspace(p_lo, p_hi, max(n_pressures, 1)) / 1e4) * 1e4)
    speeds = np.unique(np.round(np.geomspace(v_lo, v_hi, n_speeds) * 1e5) / 1e5)
    return pressures, speeds


def d_optimal(
    rows: np.ndarray,
    runs: int,
    *,
    max_repeats: int = 1,
    start: Sequence[int] | None = None,
    max_sweeps: int = 200,
) -> np.ndarray:
    """Indices of ``runs`` rows (with repeats) maximising ``det(sum r r^T)`` (D-optimal).

    ``rows`` is the (candidates, k) matrix of information rows ``j / s``. A greedy start
    (each step adds the candidate of largest prediction variance ``r^T M^-1 r``, with a
    small ridge while ``M`` is singular), then Fedorov exchange: the best swap of a design
    run for a candidate while it raises ``det M`` by more than 1e-9 relative. Each
    candidate is used at most ``max_repeats`` times.
    """
    rows = np.asarray(rows, dtype=float)
    n_cand, k = rows.shape
    if runs < k:
        raise ValueError(f"{runs} runs cannot identify {k} coefficients; plan at least {k} runs")
    if runs > n_cand * max_repeats:
        raise ValueError(
            f"{runs} runs exceed the {n_cand} candidates x {max_repeats} repeat(s); allow "
            "more repeats or a finer candidate grid"
        )
    scale = np.sqrt((rows**2).sum(axis=0))
    scale[scale == 0] = 1.0
    x = rows / scale
    count = np.zeros(n_cand, dtype=int)
    design: list[int] = [] if start is None else list(start)
    for index in design:
        count[index] += 1
    ridge = 1e-8 * np.eye(k)
    while len(design) < runs:
        m = x[design].T @ x[design] + ridge if design else ridge
        minv = np.linalg.inv(m)
        d = np.einsum("ij,jk,ik->i", x, minv, x)
        d[count >= max_repeats] = -np.inf
        best = int(np.argmax(d))
        design.append(best)
        count[best] += 1
    chosen = np.array(design)
    for _ in range(max_sweeps):
        m = x[chosen].T @ x[chosen]
        minv = np.linalg.pinv(m)
        d_all = np.einsum("ij,jk,ik->i", x, minv, x)
        cross = x[chosen] @ minv @ x.T  # (runs, candidates)
        d_in = d_all[chosen][:, None]
        gain = (1 + d_all[None, :]) * (1 - d_in) + cross**2 - 1  # det ratio - 1
        gain[:, count >= max_repeats] = -np.inf
        i, j = np.unravel_index(np.argmax(gain), gain.shape)
        if gain[i, j] <= 1e-9:
            break
        count[chosen[i]] -= 1
        count[j] += 1
        chosen[i] = j
    return chosen


@dataclass
class TestPlan:
    """A test plan: runs in order and their predicted uncertainty.

    Attributes
    ----------
    runs : pandas.DataFrame
        ``run``, ``pressure [Pa]``, ``velocity [m/s]``, ``stroke [m]``,
        ``sample_interval [s]``, ``notes``; in run order (pressure levels ascending, speeds
        in a seeded random order within a level, which keeps warm-up drift from lining up
        with speed).
    uncertainty : Uncertainty
        Predicted uncertainty of the plan.
    noise : WindowNoise
        The noise model it was designed with.
    model : FrictionModel
        The model the design is optimal for.
    candidates : tuple of ndarray
        (pressures [Pa], speeds [m/s]) of the candidate grid.
    """

    __test__ = False  # not a pytest test class

    runs: pd.DataFrame
    uncertainty: Uncertainty
    noise: WindowNoise
    model: FrictionModel
    candidates: tuple
    settings: object = None
    notes: list = field(default_factory=list)

    @property
    def points(self) -> tuple:
        """((pressure [bar], speed [mm/s]), ...) in run order, for ``BenchSettings(points=)``."""
        return tuple(
            (round(p / 1e5, 6), round(v * 1e3, 6))
            for p, v in zip(self.runs["pressure [Pa]"], self.runs["velocity [m/s]"], strict=True)
        )

    def sheet(self) -> pd.DataFrame:
        """The printable test sheet in engineering units, in run order."""
        return pd.DataFrame(
            {
                "run": self.runs["run"],
                "pressure [bar]": (self.runs["pressure [Pa]"] / 1e5).round(2),
                "speed [mm/s]": (self.runs["velocity [m/s]"] * 1e3).round(3),
                "stroke [mm]": (self.runs["stroke [m]"] * 1e3).round(1),
                "sample interval [ms]": (self.runs["sample_interval [s]"] * 1e3).round(1),
                "notes": self.runs["notes"],
            }
        )

    def figure(self) -> Figure:
        """The design in the (v, p) plane: candidates, chosen runs (repeats by size)."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=(7, 4.5), constrained_layout=True)
        ax = fig.add_subplot()
        pressures, speeds = self.candidates
        vv, pp = np.meshgrid(speeds * 1e3, pressures / 1e5)
        ax.scatter(vv.ravel(), pp.ravel(), s=6, color="0.75", label="candidates")
        pts = pd.Series(self.points).value_counts()
        ax.scatter(
            [v for _, v in pts.index],
            [p for p, _ in pts.index],
            s=40 * pts.to_numpy(),
            color="C0",
            label=f"plan: {len(self.runs)} runs",
            zorder=3,
        )
        ax.set_xscale("log")
        ax.set_xlabel("speed [mm/s]")
        ax.set_ylabel("pressure [bar]")
        ax.set_title("D-optimal test plan (each run: descend and ascend)")
        ax.legend(loc="upper left", bbox_to_anchor=(1, 1))
        return fig

    def write(self, out: StrPath) -> dict[str, Path]:
        """Write ``plan.csv``, ``uncertainty.csv``, ``plan.png``/``.svg`` and ``plan.html``
        into the folder ``out`` (created; a symbolic link is refused, see
        :func:`cylfric._paths.refuse_link`)."""
        from ._paths import make_folder

        out = make_folder(out)
        sheet = self.sheet()
        files = {"csv": atomic_write_text(out / "plan.csv", sheet.to_csv(index=False))}
        table = self.uncertainty.table()
        files["uncertainty"] = atomic_write_text(out / "uncertainty.csv", table.to_csv(index=False))
        fig = self.figure()
        png, svg = io.BytesIO(), io.BytesIO()
        fig.savefig(png, format="png", dpi=110)
        fig.savefig(svg, format="svg")
        files["png"] = atomic_write_bytes(out / "plan.png", png.getvalue())
        files["svg"] = atomic_write_bytes(out / "plan.svg", svg.getvalue())
        files["html"] = atomic_write_text(out / "plan.html", self.html(png.getvalue()))
        return files

    def html(self, png: bytes) -> str:
        """Self-contained HTML: the run table, the design figure, the predicted uncertainty."""
        band = self.uncertainty.band
        band_rows = pd.DataFrame(
            {
                "speed [mm/s]": band["velocity [m/s]"] * 1e3,
                "pressure [bar]": band["pressure [Pa]"] / 1e5,
                "friction [N]": band["friction [N]"].round(2),
                "95 % band half-width [N]": band["half_width [N]"].round(4),
            }
        )
        se = self.uncertainty.table()
        se["stderr"] = se["stderr"].map(lambda x: f"{x:.3g}")
        img = base64.b64encode(png).decode("ascii")
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in self.notes)
        return (
            "<!DOCTYPE html><html><head><meta charset='utf-8'><title>cylfric test plan</title>"
            "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
            "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 8px;"
            "text-align:right}@media print{img{max-width:100%}}</style></head><body>"
            f"<h1>Friction test plan: {len(self.runs)} runs</h1>"
            "<p>Each run: both chambers at the pressure, descend the stroke and ascend it at "
            "the constant speed (thesis ch. 3). Tick each run when done; note anything "
            "unusual.</p>"
            + _html_table(self.sheet().assign(done=""))
            + f"<h2>Design</h2><img src='data:image/png;base64,{img}' alt='design'>"
            f"<h2>Predicted standard errors</h2><p>Noise model: {html.escape(self.noise.source)}"
            "</p>"
            + _html_table(se)
            + "<h2>95 % band of the mean friction at operating points</h2>"
            + _html_table(band_rows)
            + (f"<h2>Notes</h2><ul>{notes}</ul>" if notes else "")
            + "</body></html>"
        )


def _html_table(frame: pd.DataFrame) -> str:
    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in row) + "</tr>"
        for row in frame.itertuples(index=False)
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def make_plan(
    pressure_range: tuple[float, float],
    speed_range: tuple[float, float],
    runs: int,
    *,
    model: FrictionModel | None = None,
    noise: WindowNoise | None = None,
    settings: BenchSettings | None = None,
    fixed: Iterable[str] = (),
    n_pressures: int = 9,
    n_speeds: int = 25,
    max_repeats: int = 1,
    seed: int = 0,
) -> TestPlan:
    """Design a D-optimal test plan of ``runs`` runs.

    Parameters
    ----------
    pressure_range : (float, float)
        Lowest and highest pressure [Pa].
    speed_range : (float, float)
        Lowest and highest speed [m/s]; every candidate must be realisable on the bench
        (stroke and sample budget of ``settings``).
    runs : int
        Number of runs (each: descend and ascend).
    model : FrictionModel, optional
        Model the design is optimal for (default: the thesis law).
    noise : WindowNoise, optional
        Standard error of the windows against speed (default: calibrated on the virtual
        bench with ``settings``, :meth:`WindowNoise.from_bench`).
    settings : BenchSettings, optional
        The bench: stroke, sampling, force noise (default: the thesis bench).
    fixed : iterable of str
        Coefficients to be held in the fit (``"alpha"``, ``"v_r"``).
    n_pressures, n_speeds : int
        Candidate grid size (pressures evenly spaced, speeds log-spaced).
    max_repeats : int
        How often one candidate may be run (1: no replicates).
    seed : int
        Seed of the speed order within each pressure level.
    """
    from .simulate.bench import BenchSettings, run_plan

    _check_size(n_pressures, n_speeds, int(runs))
    settings = settings or BenchSettings()
    model = model or FrictionModel()
    pressures, speeds = candidate_grid(
        pressure_range, speed_range, n_pressures=n_pressures, n_speeds=n_speeds
    )
    for v in (speeds[0], speeds[-1]):
        run_plan(v, settings)  # raises when a speed is not realisable on the bench
    if noise is None:
        noise = WindowNoise.from_bench(settings, speeds=np.geomspace(speeds[0], speeds[-1], 9))
    pp, vv = (a.ravel() for a in np.meshgrid(pressures, speeds, indexing="ij"))
    names = _names(model, fixed)
    rows = _information_rows(model, vv, pp, noise, names)
    chosen = d_optimal(rows, int(runs), max_repeats=max_repeats)
    rng = np.random.default_rng(seed)
    shuffled: list[int] = []
    for p in np.unique(pp[chosen]):
        at = chosen[pp[chosen] == p]
        shuffled.extend(rng.permutation(at))
    order = np.array(shuffled)
    table = _run_table(pp[order], vv[order], settings)
    uncertainty = predicted_uncertainty(
        model, table["velocity [m/s]"], table["pressure [Pa]"], noise, fixed=fixed
    )
    notes = [
        f"D-optimal for {len(names)} coefficients ({', '.join(names)}) of the "
        f"{model.friction_law} law with {model.pressure_law} pressure laws",
        f"candidates: {len(pressures)} pressures x {len(speeds)} log-spaced speeds; "
        f"at most {max_repeats} run(s) per candidate",
    ]
    if len(np.unique(pp[chosen])) < 3:
        notes.append(
            "the plan uses two pressure levels (the laws are linear in pressure): add runs "
            "at a middle pressure to check the linear law"
        )
    return TestPlan(table, uncertainty, noise, model, (pressures, speeds), settings, notes)


def _run_table(pressure, velocity, settings) -> pd.DataFrame:
    from .simulate.bench import run_plan

    rows, last = [], None
    slow = set(np.unique(np.round(velocity * 1e3, 6))[: settings.slow_speed_count])
    for i, (p, v) in enumerate(zip(pressure, velocity, strict=True), start=1):
        stroke, interval, _ = run_plan(v, settings, slow=round(v * 1e3, 6) in slow)
        note = f"set both chambers to {p / 1e5:g} bar" if p != last else ""
        last = p
        rows.append(
            {
                "run": i,
                "pressure [Pa]": float(p),
                "velocity [m/s]": float(v),
                "stroke [m]": stroke,
                "sample_interval [s]": interval,
                "notes": note,
            }
        )
    return pd.DataFrame(rows)


def grid_uncertainty(
    model: FrictionModel,
    pressures: ArrayLike,
    speeds: ArrayLike,
    noise: WindowNoise,
    *,
    fixed: Iterable[str] = (),
) -> Uncertainty:
    """Predicted uncertainty of a full grid: every pressure [Pa] x every speed [m/s]."""
    pp, vv = (a.ravel() for a in np.meshgrid(pressures, speeds, indexing="ij"))
    return predicted_uncertainty(model, vv, pp, noise, fixed=fixed)


def compare(
    first: Uncertainty, second: Uncertainty, labels: tuple[str, str] = ("grid", "plan")
) -> pd.DataFrame:
    """Standard errors of two plans side by side (engineering units) and their ratio."""
    a, b = first.table(), second.table()
    out = a.rename(columns={"stderr": labels[0]})
    out[labels[1]] = b.set_index("coefficient").loc[out["coefficient"], "stderr"].to_numpy()
    out[f"{labels[1]} / {labels[0]}"] = out[labels[1]] / out[labels[0]]
    return out[["coefficient", "unit", labels[0], labels[1], f"{labels[1]} / {labels[0]}"]]
