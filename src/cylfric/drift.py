"""Drift of a cylinder's friction: between two campaigns, and along one campaign's run order.

The thesis saw later runs give lower friction (warm-up) and suspects temperature and seal
wear (Pérez Dorado 2016, ch. 4 and 6). Two questions, answered with the uncertainty the
fits carry:

* :func:`drift` - between two datasheets (or fit output folders) of the same cylinder: per
  coefficient and at a grid of operating points in the common validity range, the change
  ``b - a`` and its z-score ``(b - a) / sqrt(u_a^2 + u_b^2)`` (the two fits are
  independent), judged against the scope that applies. Two datasheets of *different
  sessions* (remounted, reconnected, another day): ``u^2`` is each fit's standard error
  plus what its sessions' offsets leave in its curve (``fit.scatter``: the session
  component over the sessions fitted, and the runs' offsets where the fit's covariance does
  not hold them), so a change must exceed the reproducibility (ISO 5725-6 sec. 4.2.3: the
  critical difference of two laboratories' results); the quantile is Student-t's on the
  session components' degrees of freedom. Two datasheets of the *same session* (the same
  session names): ``u`` is each fit's standard error (repeatability), the quantile the
  normal one. Over a grid of many points a few marks are expected by chance even without
  drift: the verdict is one joint test of the coefficients' changes (Wald, F on the
  session dof), or, when the coefficients do not compare, the largest ``|z|`` against a
  Bonferroni quantile.
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
    "DRIFT_SCOPES",
    "drift",
    "load_fit",
    "run_order_trend",
    "RunOrderTrend",
    "figure_run_order",
]

_ORDERS = ("run", "mtime")

DRIFT_SCOPES = ("auto", "session", "repeatability")
"""Scopes :func:`drift` judges a change against: ``"session"`` (the datasheets are of
different sessions: reproducibility), ``"repeatability"`` (the same session: the fits'
standard errors), ``"auto"`` (the same session when both datasheets name the same sessions,
else different sessions; the fits' standard errors when a datasheet has no scatter record)."""


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


def fit_labels(*sources: FrictionModel | dict[str, Any] | StrPath) -> list[str]:
    """Each fit's label for titles and file names: the datasheet's ``name`` (else the fit
    folder's or the file's name), made distinct (the folder's name, else ``-a``, ``-b``, ...
    added to a name two fits share) and safe as a file name (letters, digits, ``. _ -``)."""
    names, fallbacks = [], []
    for source in sources:
        model, _, fallback = load_fit(source)
        name = model.record.get("name") if isinstance(model.record.get("name"), str) else None
        names.append(_safe(name or fallback))
        fallbacks.append(_safe(fallback))
    labels = list(names)
    for i, name in enumerate(names):
        if names.count(name) > 1:
            labels[i] = name if fallbacks[i] == name else f"{name}_{fallbacks[i]}"
    shared = [labels.count(label) > 1 for label in labels]
    return [
        f"{label}-{chr(ord('a') + i)}" if twice else label
        for i, (label, twice) in enumerate(zip(labels, shared, strict=True))
    ]


def _safe(text: str) -> str:
    """``text`` as a file-name part: other characters than letters, digits, ``. _ -`` as _."""
    cleaned = "".join(ch if ch.isascii() and (ch.isalnum() or ch in "._-") else "_" for ch in text)
    return cleaned.strip(".")[:LABEL_LENGTH] or "fit"


LABEL_LENGTH = 80
"""Longest label [characters]: a file name (``run_order_<label>.svg``) stays well below the
file systems' 255 bytes, whatever the datasheet's name."""


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
    scope: str = "auto",
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
    scope : {"auto", "session", "repeatability"}
        What the change is judged against (:data:`DRIFT_SCOPES`): ``"session"`` the
        between-session scatter each datasheet states (``fit.scatter``), ``"repeatability"``
        the fits' standard errors only; ``"auto"``: the same session when both datasheets
        name the same sessions, else different sessions.

    Returns
    -------
    pandas.DataFrame
        One row per coefficient (``kind`` = ``"parameter"``) and per operating point
        (``kind`` = ``"friction"``): ``quantity``, ``unit``, ``velocity [m/s]``,
        ``pressure [Pa]`` (NaN for coefficients), ``a``, ``b``, ``change``, ``stderr``
        (of the change, in the scope's sense), ``z [-]`` and ``significant``. SI units
        (``unit``). A Coulomb law on both sides (no speed dependence) gets one speed per
        pressure. ``attrs``: ``notes`` (which coefficients were left out and why),
        ``scope`` and ``scope_reason``, ``level``, ``z_critical``, ``dof``, ``verdict``
        (``significant``, ``test``, ``statistic``, ``critical``, ``p_value``).

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
    if scope not in DRIFT_SCOPES:
        raise ValueError(f"scope = {scope!r}: unknown; valid: {list(DRIFT_SCOPES)}")
    model_a, _, label_a = load_fit(a)
    model_b, _, label_b = load_fit(b)
    names = (_described(a, model_a, label_a), _described(b, model_b, label_b))
    comparable, notes = _comparable(model_a, model_b, names)
    scope, reason = _scope(model_a, model_b, scope, names)
    between = {
        "a": _session_covariance(model_a) if scope == "session" else None,
        "b": _session_covariance(model_b) if scope == "session" else None,
    }
    dof = math.inf
    if scope == "session":  # the session components' dof: the smaller of the two
        dof = min(_session_dof(model_a), _session_dof(model_b))
    z_crit = _quantile(0.5 + level / 2, dof)
    rows = []
    for name, pa in model_a.parameters.items():
        pb = model_b.parameters.get(name)
        if pa.value is None or pb is None or pb.value is None or pa.unit != pb.unit:
            continue
        if pa.parameter not in comparable:
            continue
        if pa.parameter in ("sigma_0", "sigma_1"):
            continue  # bristle parameters: assumed in most datasheets, not fitted
        se_a = _parameter_se(model_a, name, pa.stderr, between["a"])
        se_b = _parameter_se(model_b, name, pb.stderr, between["b"])
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
    if velocities is None and v_grid.size > 1 and _speed_free(model_a) and _speed_free(model_b):
        # no speed dependence on either side: one speed (the geometric middle) per pressure
        v_grid = np.array([math.sqrt(v_grid[0] * v_grid[-1])])
    v: np.ndarray
    p: np.ndarray
    v, p = np.meshgrid(v_grid, p_grid, indexing="ij")
    v, p = v.ravel(), p.ravel()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        f_a, f_b = model_a.friction(v, p), model_b.friction(v, p)
        se_a = _friction_se(model_a, v, p, between["a"])
        se_b = _friction_se(model_b, v, p, between["b"])
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
    table.attrs["dof"] = None if math.isinf(dof) else dof
    table.attrs["scope"] = scope
    table.attrs["scope_reason"] = reason
    table.attrs["verdict"] = _verdict(model_a, model_b, comparable, between, table, level, dof)
    table.attrs["notes"] = notes
    return table


SCOPE_WORDS = {
    "session": (
        "reproducibility: the datasheets are of different sessions; each fit's standard error "
        "and what its sessions' offsets leave in its curve (fit.scatter)"
    ),
    "repeatability": "repeatability: each fit's standard error only (the same session)",
}
"""What each scope of :func:`drift` judges a change against, as the outputs say it."""


def _scope(model_a, model_b, scope: str, names) -> tuple[str, str]:
    """(scope, why) of a comparison: ``"session"`` or ``"repeatability"``."""
    sessions = [tuple((m.scatter or {}).get("session_names") or ()) for m in (model_a, model_b)]
    missing = [name for name, m in zip(names, (model_a, model_b), strict=True) if not m.scatter]
    if scope == "session":
        if missing:
            raise ValueError(
                f"{missing[0]}: no scatter components (fit.scatter: a datasheet of an older "
                "cylfric or a hand-made model), so the between-session scatter is not known; "
                "refit the campaign, or compare with scope 'repeatability'"
            )
        return "session", "asked for (scope 'session')"
    if scope == "repeatability":
        return "repeatability", "asked for (scope 'repeatability')"
    if missing:
        return "repeatability", (
            f"{missing[0]} has no scatter components (fit.scatter), so the between-session "
            "scatter is not known: judged against the fits' standard errors only"
        )
    if sessions[0] and sessions[0] == sessions[1]:
        return "repeatability", (
            f"both datasheets are of session(s) {', '.join(sessions[0])} (the campaigns' "
            "session names): the same session; give scope 'session' if they are not"
        )
    files = [_run_files(m) for m in (model_a, model_b)]
    if not (sessions[0] and sessions[1]) and files[0] and files[0] == files[1]:
        return "repeatability", (
            f"both datasheets are of the same {len(files[0])} run files (by name): the same "
            "session; give scope 'session' if they are not"
        )
    said = [", ".join(s) if s else "not named" for s in sessions]
    return "session", (
        f"different sessions (sessions {said[0]} and {said[1]}); give scope 'repeatability' "
        "for two fits of the same session"
    )


def _run_files(model) -> tuple[str, ...]:
    """The names of the run files a datasheet was fitted to (``fit.source.files``), sorted."""
    files = ((model.record.get("fit") or {}).get("source") or {}).get("files") or []
    return tuple(sorted(str(f.get("name")) for f in files if isinstance(f, dict)))


def _session_parts(model) -> tuple[float, float, int]:
    """(run, session, sessions) of a fit's scatter: the relative s.d. of its runs' offsets
    that its covariance does not hold (0 when the covariance is cluster-robust by run: it
    holds them), of its sessions' shared offset, and the number of sessions fitted."""
    c = model.scatter["components"]
    run = c["run"]["std_percent"] / 100.0 if model.influence is None else 0.0
    return run, c["session"]["std_percent"] / 100.0, max(int(model.scatter.get("sessions") or 1), 1)


def _session_covariance(model) -> np.ndarray | None:
    """Coefficient covariance [covariance names] of what a fit's sessions (and its runs, where
    the covariance does not hold them) leave in its curve: the sessions' shared offset over
    the sessions fitted, each level's runs' offsets averaged, spread over the law
    (:func:`cylfric.model.core.level_offset_covariance`); without the levels, one offset
    shared by every level (the level-scaling coefficients F_c, F_s, sigma_2 in proportion)."""
    from .model.core import level_offset_covariance

    if model.covariance is None:
        return None
    run, session, sessions = _session_parts(model)
    covariance = level_offset_covariance(model, run=run, session=session, sessions=sessions)
    if covariance is not None:
        return covariance
    names = model.covariance[0]
    values = np.array(
        [
            model.parameters[n].value if n.partition(".")[0] in ("F_c", "F_s", "sigma_2") else 0.0
            for n in names
        ],
        dtype=float,
    )
    return np.outer(values, values) * (run**2 + session**2 / sessions)


def _session_dof(model) -> float:
    """Degrees of freedom [-] of a fit's between-session scatter (prior and estimate)."""
    dof = model.scatter["components"]["session"].get("dof")
    return float(dof) if dof else math.inf


def _parameter_se(model, name, stderr, between) -> float:
    """Standard error [SI] of coefficient ``name`` in the comparison's scope."""
    se = math.nan if stderr is None else float(stderr)
    if between is None or model.covariance is None or name not in model.covariance[0]:
        return se
    i = list(model.covariance[0]).index(name)
    return math.sqrt((0.0 if math.isnan(se) else se**2) + max(float(between[i, i]), 0.0))


def _speed_free(model) -> bool:
    """Whether the model's friction does not depend on the speed (a Coulomb law)."""
    return model.friction_law == "coulomb"


def _quantile(q: float, dof: float) -> float:
    """Student-t quantile on ``dof`` [-] (normal for infinite dof)."""
    if math.isinf(dof):
        return _normal_quantile(q)
    from scipy.stats import t

    return float(t.ppf(q, dof))


def _verdict(model_a, model_b, comparable, between, table, level, dof) -> dict[str, Any]:
    """One test of the whole change: Wald on the comparable coefficients (chi-square, or F on
    the session dof), else the largest friction |z| against a Bonferroni quantile."""
    from scipy import stats

    names = _joint_names(model_a, model_b, comparable)
    if names:
        index_a = [list(model_a.covariance[0]).index(n) for n in names]
        index_b = [list(model_b.covariance[0]).index(n) for n in names]
        cov = (
            model_a.covariance[1][np.ix_(index_a, index_a)]
            + model_b.covariance[1][np.ix_(index_b, index_b)]
        )
        for side, index in (("a", index_a), ("b", index_b)):
            if between[side] is not None:
                cov = cov + between[side][np.ix_(index, index)]
        delta = np.array([model_b.parameters[n].value - model_a.parameters[n].value for n in names])
        scale = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
        scaled = cov / np.outer(scale, scale)
        statistic = float(delta / scale @ np.linalg.pinv(scaled) @ (delta / scale))
        k = len(names)
        if math.isinf(dof):
            p_value = float(stats.chi2.sf(statistic, k))
            critical = float(stats.chi2.ppf(level, k))
            test = f"Wald chi-square on {k} coefficients ({', '.join(names)})"
        else:
            p_value = float(stats.f.sf(statistic / k, k, dof))
            critical = float(k * stats.f.ppf(level, k, dof))
            test = f"Wald F on {k} coefficients ({', '.join(names)}), {dof:.3g} session dof"
        return {
            "significant": bool(statistic > critical),
            "test": test,
            "statistic": statistic,
            "critical": critical,
            "p_value": p_value,
        }
    friction = table[table["kind"] == "friction"]
    z = np.abs(friction["z [-]"].to_numpy(dtype=float))
    m = max(int(np.isfinite(z).sum()), 1)
    critical = _quantile(1.0 - (1.0 - level) / (2 * m), dof)
    largest = float(np.nanmax(z)) if np.isfinite(z).any() else math.nan
    return {
        "significant": bool(largest > critical),
        "test": f"largest |z| of {m} operating points against Bonferroni's quantile",
        "statistic": largest,
        "critical": critical,
        "p_value": None,
    }


def _joint_names(model_a, model_b, comparable) -> list[str]:
    """Coefficients both fits estimated (in both covariances) that mean the same in both."""
    if model_a.covariance is None or model_b.covariance is None:
        return []
    names_b = set(model_b.covariance[0])
    return [
        n
        for n in model_a.covariance[0]
        if n in names_b
        and n.partition(".")[0] in comparable
        and n.partition(".")[0] not in ("sigma_0", "sigma_1")
        and model_a.parameters[n].value is not None
        and model_b.parameters[n].value is not None
    ]


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


def _friction_se(model, v, p, between=None):
    """Standard error [N] of a fit's friction at (v [m/s], p [Pa]) in the comparison's scope:
    the fit's own, plus its sessions' offsets (``between``, a coefficient covariance)."""
    if model.covariance is None:
        return np.full(v.shape, np.nan)
    se = model.standard_error(v, p)
    if between is None:
        return se
    jac = model._jacobian(v, p)
    extra = np.einsum("...i,ij,...j->...", jac, between, jac)
    return np.sqrt(se**2 + np.clip(extra, 0.0, None))


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
    from .escape import csv_frame

    path = atomic_write_text(out / "drift.csv", csv_frame(table).to_csv(index=False))
    friction = table[table["kind"] == "friction"]
    z = np.abs(friction["z [-]"].to_numpy(dtype=float))
    summary = {
        "scope": table.attrs.get("scope"),
        "judged_against": SCOPE_WORDS.get(table.attrs.get("scope", ""), None),
        "scope_reason": table.attrs.get("scope_reason"),
        "verdict": table.attrs.get("verdict"),
        "level": table.attrs.get("level"),
        "z_critical": table.attrs.get("z_critical"),
        "dof": table.attrs.get("dof"),
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
