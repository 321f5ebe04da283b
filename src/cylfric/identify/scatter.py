"""Scatter components of a fit: repeatability, run-to-run and session-to-session (issue 22).

:func:`scatter_components` fits a linear mixed model by REML (statsmodels ``MixedLM``) to
the *relative* residuals of the points about the fitted law, ``r = (F_meas - F_model) /
F_model``: a random intercept per session, a variance component per run inside its session,
and the residual, so that

    r_{s,k,i} = mu + b_s + c_{s,k} + e_{s,k,i},
    b_s ~ N(0, s_session^2),  c_{s,k} ~ N(0, s_run^2),  e ~ N(0, s_r^2)

(Pinheiro & Bates 2000, ch. 2; ISO 5725-2:2019 sec. 7 for the names: ``s_r`` the
repeatability, ``s_R = sqrt(s_r^2 + s_L^2)`` the reproducibility, ``s_L^2`` the
between-"laboratory" part, here between sessions: ``s_L^2 = s_run^2 + s_session^2``).

One session cannot show its own offset: the between-session part ``s_L`` is then a stated
prior, :data:`SESSION_PRIOR`, calibrated on the shared real repeatability data (Zillen et
al. 2021, three sessions of one O-ring). From two sessions on, the estimate and the prior are
pooled by their evidence, a scaled-inverse-chi-square prior updated by the estimate
(Gelman et al., *Bayesian Data Analysis*, 3rd ed., sec. 3.3 / 5.7), the estimate from ``n``
sessions on ``n - 1`` degrees of freedom (n sessions are n draws of the session effects,
however many runs each holds):

    s_L^2 = (nu0 P^2 + (n - 1) s_hat_L^2) / (nu0 + n - 1),   dof nu0 + n - 1

so that two or three sessions that happen to agree move the prior by their weight only, and
with many sessions the estimate decides. ``s_L`` is never below the run-to-run part
the data show (a variance component is not negative), and the session component is what
``s_L`` adds to it: ``s_session^2 = s_L^2 - s_run^2``.

On a rig that measures one file per pressure per session, the run-to-run component and a
session-by-pressure interaction cannot be told apart: both are "this run's level is off the
law". The run component then carries them, and the lack of the law's fit too (a level off a
straight line is a run off the law); see docs/uncertainty.md.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import pandas as pd

__all__ = [
    "SESSION_PRIOR",
    "scatter_components",
    "relative_residuals",
    "scatter_note",
    "residual_strata",
    "residual_function",
    "SESSION_KINDS",
    "session_kinds",
]

SESSION_PRIOR: dict[str, Any] = {
    "std_percent": 14.0,
    "dof": 8,
    "basis": (
        "between-session scatter of a level mean s_L (run and session components together) "
        "on the shared real repeatability data (Zillen et al. 2021, TU Delft, O-ring of bore "
        "25.7 mm, three sessions x 1/3/5/7 bar): standard deviations of the three sessions' "
        "level means 9/12/14/19 % of the level, RMS 14 %, 8 degrees of freedom (3 sessions "
        "x 4 pressures); leave-one-session-out coverage in docs/uncertainty.md"
    ),
}
"""The stated prior of the between-session scatter of a level mean, relative [%], with its
degrees of freedom ``nu0`` [-] and basis (docs/uncertainty.md)."""

SESSION_KINDS: dict[str, str] = {
    "rerun": "re-run on the same mount (nothing taken apart)",
    "reconnect": "rig reconnected (hoses, sensors, controller), seal left mounted",
    "remount": "seal or cylinder taken out and mounted again",
    "rig": "another rig (or another cylinder of the same design)",
}
"""The kinds of session a campaign may state (manifest.csv column ``session_kind``, or a
``session_kind`` group of ``name_pattern``), least to most changed; the datasheet says which
kinds the session band has seen (``fit.scatter.session_kinds``)."""

_KIND_ALIASES = {
    "rerun": "rerun",
    "reconnect": "reconnect",
    "reconnected": "reconnect",
    "remount": "remount",
    "remounted": "remount",
    "rig": "rig",
    "anotherrig": "rig",
    "otherrig": "rig",
}

METHOD = (
    "linear mixed model, REML (statsmodels MixedLM): relative residuals about the fitted "
    "law; session random intercept, run variance component, residual = repeatability "
    "(ISO 5725-2 s_r, s_R)"
)

METHOD_ONE_SESSION = (
    "one-way analysis of variance of the runs (ISO 5725-2 sec. 7.4, the runs as groups; "
    "for one session it is what REML gives on balanced data, without its iterations): "
    "relative residuals about the fitted law; run variance component, residual = "
    "repeatability (ISO 5725-2 s_r, s_R)"
)

MIN_FORCE = 1e-6
"""Smallest model friction [N] a relative residual is taken at."""


def relative_residuals(points: pd.DataFrame, fitted: np.ndarray) -> pd.DataFrame:
    """The table the mixed model sees: ``r`` [-], ``run`` and ``session`` labels.

    ``fitted`` is the model friction [N] at each point. Points without a run get one run
    each (no replicate); without a session column, one session ``"1"``.
    """
    measured = points["friction [N]"].to_numpy(dtype=float)
    fitted = np.asarray(fitted, dtype=float)
    keep = np.isfinite(measured) & np.isfinite(fitted) & (np.abs(fitted) > MIN_FORCE)
    run = points["run"] if "run" in points else pd.Series(np.arange(len(points)))
    session = (
        points["session"]
        if "session" in points
        else pd.Series([None] * len(points), index=points.index)
    )
    session = session.where(session.notna(), "(none)").astype(str)
    table = pd.DataFrame(
        {
            "r": (measured - fitted) / fitted,
            "run": run.astype(str).to_numpy(),
            "session": session.to_numpy(),
            "fitted": fitted,
        }
    )[keep]
    table["run"] = table["session"] + "/" + table["run"]  # a run is inside its session
    return table.reset_index(drop=True)


def _reml(model):
    """REML fit of a MixedLM, by the optimisers statsmodels offers in turn (a variance at its
    zero bound can make the gradient's matrix singular for one and not another)."""
    error: Exception | None = None
    for method in ("lbfgs", "powell", "nm"):
        try:
            return model.fit(reml=True, method=method)
        except (np.linalg.LinAlgError, ValueError) as exc:
            error = exc
    raise ValueError(f"the mixed model of the scatter could not be fitted ({error})")


def _one_way(table: pd.DataFrame) -> tuple[float, float, float]:
    """(0, s_run^2, s_r^2) [-] of one session's relative residuals by the one-way analysis of
    variance of ISO 5725-2 (sec. 7.4.4-7.4.5; unbalanced groups: n-bar = (N - sum n_i^2 / N)
    / (p - 1)); a negative run component is set to 0 as the standard says."""
    grouped = table.groupby("run", sort=False)["r"]
    n = grouped.count().to_numpy(dtype=float)
    means = grouped.mean().to_numpy()
    variances = grouped.var(ddof=1).fillna(0.0).to_numpy()
    total, groups = float(n.sum()), len(n)
    within = float(np.sum((n - 1) * variances) / max(total - groups, 1))
    grand = float(np.sum(n * means) / total)
    between = float(np.sum(n * (means - grand) ** 2) / max(groups - 1, 1))
    n_bar = (total - float(np.sum(n**2)) / total) / max(groups - 1, 1)
    run_var = max((between - within) / n_bar, 0.0) if n_bar > 0 else 0.0
    return 0.0, run_var, within


def _mixed_model(table: pd.DataFrame, sessions: int) -> tuple[float, float, float]:
    """(s_session^2, s_run^2, s_r^2) [-] of the relative residuals by REML (one session: the
    one-way analysis of variance, :func:`_one_way`)."""
    if sessions < 2:
        return _one_way(table)
    from statsmodels.regression.mixed_linear_model import MixedLM

    endog = table["r"].to_numpy()
    exog = np.ones((len(table), 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # boundary (zero) variances: statsmodels warns
        groups = table["session"].to_numpy()
        runs = {  # each session's run indicators (its own runs only)
            g: pd.get_dummies(table.loc[groups == g, "run"]).to_numpy(dtype=float)
            for g in pd.unique(groups)
        }
        model = MixedLM(
            endog,
            exog,
            groups=groups,
            exog_re=np.ones((len(table), 1)),
            exog_vc={"run": runs},
        )
        fit = _reml(model)
        session_var = float(np.asarray(fit.cov_re)[0, 0])
        run_var = float(fit.vcomp[0]) if len(fit.vcomp) else 0.0
    residual_var = float(fit.scale)
    values = (max(session_var, 0.0), max(run_var, 0.0), max(residual_var, 0.0))
    if not all(math.isfinite(v) for v in values):
        raise ValueError("the mixed model of the scatter did not converge")
    return values


def _component(std, reference, source, dof, **more):
    return {
        "std_percent": 100.0 * std,
        "std_N": std * reference,
        "source": source,
        "dof": dof,
        **more,
    }


def scatter_components(
    points: pd.DataFrame,
    fitted: np.ndarray,
    *,
    n_parameters: int = 1,
    prior: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The ``fit.scatter`` record: repeatability, run and session scatter of a fit.

    Parameters
    ----------
    points : pandas.DataFrame
        The points the law was fitted to: ``friction [N]``, ``run`` and, when the campaign
        says, ``session``.
    fitted : array
        The fitted law's friction at each point [N].
    n_parameters : int
        Coefficients of the fitted law [-] (the run means' degrees of freedom about it).
    prior : dict, optional
        ``std_percent`` [%], ``dof`` [-] and ``basis`` of the between-session scatter;
        default :data:`SESSION_PRIOR`.

    Returns
    -------
    dict
        ``method``, ``relative``, ``sessions``, ``runs``, ``points``,
        ``reference_force_N`` [N], ``components`` (``repeatability``, ``run``, ``session``:
        ``std_percent`` [%], ``std_N`` [N] at the reference force, ``source``, ``dof``),
        ``reproducibility`` (``std_percent``, ``std_N``): docs/uncertainty.md.
    """
    prior = dict(SESSION_PRIOR if prior is None else prior)
    table = relative_residuals(points, fitted)
    if len(table) < 3:
        raise ValueError(f"{len(table)} points are too few for the scatter components")
    sessions = int(table["session"].nunique())
    runs = int(table["run"].nunique())
    reference = float(np.mean(np.abs(table["fitted"])))
    if runs >= 2:
        session_var, run_var, repeat_var = _mixed_model(table, sessions)
        run_source = "estimated"
    else:
        session_var, run_var = 0.0, 0.0
        repeat_var = float(np.var(table["r"], ddof=1))
        run_source = "not estimable (one run)"
    repeat_dof = max(len(table) - runs, 1)
    run_dof = max(runs - sessions - (n_parameters - 1 if sessions == 1 else 0), 1)
    prior_var = (prior["std_percent"] / 100.0) ** 2
    nu0 = float(prior["dof"])
    estimated_session = math.sqrt(session_var) if sessions >= 2 else None
    if sessions >= 2:
        # s_hat_L^2 = s_session^2 + s_run^2 from n sessions: n - 1 degrees of freedom (the
        # runs' many dof are of the run-to-run part only; an earlier version took their
        # Satterthwaite dof, and three agreeing sessions outweighed the prior)
        estimate = session_var + run_var
        nu = float(sessions - 1)
        between = (nu0 * prior_var + nu * estimate) / (nu0 + nu)
        between_dof = nu0 + nu
        source = "estimated+prior"
    else:  # one session shows nothing of the others: the prior (raised below to its runs')
        between, between_dof, source = prior_var, nu0, "prior"
    between = max(between, run_var)  # s_L never below the run-to-run part the data show
    session_var = between - run_var
    repeat, run, session = (math.sqrt(v) for v in (repeat_var, run_var, session_var))
    reproducibility = math.sqrt(repeat_var + between)
    kinds = session_kinds(points)
    return {
        "method": METHOD if sessions >= 2 else METHOD_ONE_SESSION,
        "relative": True,
        "sessions": sessions,
        "runs": runs,
        "points": int(len(table)),
        "reference_force_N": reference,
        "components": {
            "repeatability": _component(repeat, reference, "estimated", repeat_dof),
            "run": _component(run, reference, run_source, run_dof),
            "session": _component(
                session,
                reference,
                source,
                between_dof,
                prior_percent=float(prior["std_percent"]),
                prior_dof=nu0,
                prior_basis=str(prior["basis"]),
                between_percent=100.0 * math.sqrt(between),
                estimated_percent=(
                    None if estimated_session is None else 100.0 * estimated_session
                ),
            ),
        },
        "reproducibility": {
            "std_percent": 100.0 * reproducibility,
            "std_N": reproducibility * reference,
        },
        "session_names": sorted(set(table["session"]) - {"(none)"}),
        "session_kinds": kinds,
        "levels": _levels(points),
    }


def session_kinds(points: pd.DataFrame) -> dict[str, Any]:
    """Which kinds of session (:data:`SESSION_KINDS`) the fitted points hold.

    Read from the points' ``session_kind`` column (manifest.csv or a ``name_pattern`` group);
    each session must state one kind. Returns ``sessions`` (kind -> number of sessions; an
    unstated kind is ``"unstated"``) and ``seen`` (the stated kinds, least to most changed).
    Raises ValueError naming the session for an unknown kind or two kinds in one session.
    """
    session = (
        points["session"].where(points["session"].notna(), "(none)").astype(str)
        if "session" in points
        else pd.Series("(none)", index=points.index)
    )
    if "session_kind" not in points:
        stated = pd.Series(None, index=points.index, dtype=object)
    else:
        stated = points["session_kind"]
    counts: dict[str, int] = {}
    for name, group in stated.groupby(session, sort=True, dropna=False):
        values = {str(v).strip() for v in group if v is not None and not pd.isna(v) and str(v)}
        if len(values) > 1:
            raise ValueError(
                f"session {name!r}: session_kind {sorted(values)}; expected one kind per "
                f"session (valid: {list(SESSION_KINDS)})"
            )
        kind = "unstated"
        if values:
            text = values.pop()
            key = "".join(ch for ch in text.lower() if ch.isalnum())
            if key not in _KIND_ALIASES:
                raise ValueError(
                    f"session {name!r}: session_kind {text!r} is unknown; valid: "
                    + "; ".join(f"{k} ({v})" for k, v in SESSION_KINDS.items())
                )
            kind = _KIND_ALIASES[key]
        counts[kind] = counts.get(kind, 0) + 1
    seen = [kind for kind in SESSION_KINDS if kind in counts]
    return {"sessions": counts, "seen": seen}


def _levels(points: pd.DataFrame) -> dict[str, Any] | None:
    """The pressure levels of the fitted points: ``pressure_Pa`` (each level's mean [Pa]) and
    ``runs`` (distinct runs at each level [-]); the bands spread the runs' and the sessions'
    relative offsets over them (:func:`cylfric.model.core.level_offset_covariance`)."""
    if "pressure [Pa]" not in points:
        return None
    table = points[np.isfinite(points["friction [N]"].to_numpy(dtype=float))]
    pressure = table["pressure [Pa]"].to_numpy(dtype=float)
    if "level" in table:
        key = table["level"].to_numpy()
    else:  # the nominal levels as the pressures to 1 kPa
        key = np.round(pressure / 1e3)
    run = table["run"].astype(str).to_numpy() if "run" in table else np.arange(len(table))
    session = table["session"].astype(str).to_numpy() if "session" in table else ["-"] * len(table)
    frame = pd.DataFrame(
        {"key": key, "p": pressure, "run": [f"{s}/{r}" for s, r in zip(session, run, strict=True)]}
    )
    frame = frame[np.isfinite(frame["p"])]
    if frame.empty:
        return None
    grouped = frame.groupby("key", sort=True)
    means = grouped["p"].mean()
    runs = grouped["run"].nunique()
    order = np.argsort(means.to_numpy())
    return {
        "pressure_Pa": [float(x) for x in means.to_numpy()[order]],
        "runs": [int(x) for x in runs.to_numpy()[order]],
    }


def scatter_note(record: dict[str, Any]) -> str:
    """One line for the datasheet's notes: the components and, for a prior, the assumption."""
    c = record["components"]
    text = (
        f"scatter (relative to the friction level, at {record['reference_force_N']:.3g} N): "
        f"repeatability {c['repeatability']['std_percent']:.3g} %, run-to-run "
        f"{c['run']['std_percent']:.3g} %, session {c['session']['std_percent']:.3g} % "
        f"({c['session']['source']}); reproducibility "
        f"{record['reproducibility']['std_percent']:.3g} % (ISO 5725-2)"
    )
    kinds = record.get("session_kinds") or {}
    if kinds.get("seen"):
        text += (
            "; the session band has seen sessions of kind "
            + ", ".join(f"{k} ({kinds['sessions'][k]})" for k in kinds["seen"])
            + (
                f" and {kinds['sessions']['unstated']} of unstated kind"
                if kinds["sessions"].get("unstated")
                else ""
            )
        )
    if c["session"]["source"] == "prior":
        text += (
            f"; ASSUMPTION: one session cannot show the between-session scatter, taken as "
            f"{c['session']['prior_percent']:.3g} % of the level in total (prior: "
            f"{c['session']['prior_basis']}); measure the seal in more sessions to replace it"
        )
    return text


STRATA = ("session", "pressure block", "run", "point")
"""The nested strata of a campaign's residuals, outermost first: the sessions, the runs of one
pressure level in one session, the runs, the points of a run."""

STRATA_METHOD = (
    "nested strata of the residuals (session > pressure block > run > point): each stratum's "
    "sum of squares [N^2] and residual degrees of freedom tr(P_s (I - H)) (H the weighted fit's "
    "hat matrix); the residual variance's degrees of freedom by Satterthwaite (1946), "
    "nu = (sum SS_s)^2 / sum(SS_s^2 / d_s)"
)


def _group_sums(index: np.ndarray, values: np.ndarray, groups: int) -> np.ndarray:
    """Sums of ``values`` (n, ...) over the groups of ``index`` (n,) -> (groups, ...)."""
    out = np.zeros((groups, *values.shape[1:]))
    np.add.at(out, index, values)
    return out


def _label_codes(points: pd.DataFrame, column: str) -> np.ndarray:
    """Each point's group (int, numbered as first seen) by the text of its label in
    ``column`` (None and NaN: labels "None" and "nan"; no column: one group). A numpy
    integer or boolean column is grouped by its values (the same groups, without a string
    per point: the run and level columns); any other by each label's text, one column at a
    time (strings per point and stratum took 16 MB at 40,000 points)."""
    if column not in points:
        return np.zeros(len(points), dtype=np.int64)
    series = points[column]
    if isinstance(series.dtype, np.dtype) and series.dtype.kind in "iub":
        return pd.factorize(series.to_numpy())[0]
    return pd.factorize(np.array([str(v) for v in series.to_numpy(dtype=object)], dtype=object))[0]


def _nested(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """The groups of (outer, inner) pairs, numbered as first seen."""
    return pd.factorize(outer * (int(inner.max(initial=0)) + 1) + inner)[0]


def residual_strata(
    points: pd.DataFrame,
    residuals: np.ndarray,
    jacobian: np.ndarray,
    sigma: np.ndarray | None = None,
) -> dict[str, Any] | None:
    """The degrees of freedom of the residual variance on the campaign's nested design.

    The residuals of a campaign are not independent: the runs of one pressure level in one
    session share that block's offset, the points of a run its run's. A residual variance
    ``s_res^2 = RSS / (N - p)`` then carries fewer degrees of freedom than ``N - p``: with
    four pressure blocks and a law linear in pressure, two block contrasts may carry most of
    the residual sum of squares. Each stratum ``s`` (projector ``P_s``: session means, block
    means within sessions, run means within blocks, points within runs) holds the sum of
    squares ``SS_s = r^T P_s r`` [N^2] on ``d_s = tr(P_s (I - H))`` degrees of freedom, ``H``
    the hat matrix of the weighted least squares fit, ``J (J^T W J)^-1 J^T W`` (Nelder 1965,
    the analysis of variance of a design with several error strata); the residual variance's
    effective degrees of freedom are Satterthwaite's (1946)::

        nu = (sum_s SS_s)^2 / sum_s (SS_s^2 / d_s)    (strata with d_s > 0.5 and SS_s > 0)

    which is ``N - p`` when every stratum scatters alike and the dof of the dominant stratum
    when one does. The bands of new data of the same mount use it
    (:meth:`cylfric.model.FrictionModel.prediction_band`).

    Parameters
    ----------
    points : pandas.DataFrame
        The fitted points: ``run``, and ``level`` (the pressure level's index) and
        ``session`` where the campaign has them.
    residuals : array
        Measured minus fitted friction at each point [N].
    jacobian : array (points x coefficients)
        d friction / d fitted coefficient at each point [N per unit].
    sigma : array, optional
        The weighted fit's standard error of each point [N] (weights ``1 / sigma^2``).

    Returns
    -------
    dict or None
        ``method``, ``strata`` (``name``, ``sum_of_squares_N2`` [N^2], ``dof`` [-]) and
        ``dof`` [-] (None when no stratum has degrees of freedom).
    """
    r = np.asarray(residuals, dtype=float)
    jac = np.asarray(jacobian, dtype=float)
    n = r.size
    if jac.shape[0] != n or n < 2:
        return None
    weight = np.ones(n) if sigma is None else 1.0 / np.asarray(sigma, dtype=float) ** 2

    session = _label_codes(points, "session")
    block = _nested(session, _label_codes(points, "level"))
    run = _nested(block, _label_codes(points, "run"))  # a run inside its block
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    jac = jac / scale
    information = np.linalg.pinv(jac.T @ (jac * weight[:, None]))
    traces, sums = [], []
    for key in (session, block, run):
        index, _ = pd.factorize(key)
        counts = np.bincount(index)
        groups = counts.size
        mean_r = _group_sums(index, r, groups) / counts
        sums.append(float(np.sum(counts * mean_r**2)))  # r^T P r, P the group means
        weighted = _group_sums(index, jac * weight[:, None], groups)
        plain = _group_sums(index, jac, groups) / counts[:, None]
        # tr(P (I - H)) = groups - tr((J^T W J)^-1 (W J)^T P J)
        traces.append(groups - float(np.trace(information @ (weighted.T @ plain))))
    sums.append(float(r @ r))
    traces.append(n - float(np.trace(information @ (jac.T @ (jac * weight[:, None])))))
    squares = np.diff(np.r_[0.0, sums])  # nested: each stratum is the next minus this one
    dof = np.diff(np.r_[0.0, traces])
    parts = [
        (name, float(max(ss, 0.0)), float(max(d, 0.0)))
        for name, ss, d in zip(STRATA, squares, dof, strict=True)
    ]
    strata = [{"name": name, "sum_of_squares_N2": ss, "dof": d} for name, ss, d in parts]
    used = [(ss, d) for _, ss, d in parts if d > 0.5]
    total = sum(ss for ss, _ in used)
    spread = sum(ss**2 / d for ss, d in used if ss > 0)
    nu = total**2 / spread if spread > 0 else None
    return {"method": STRATA_METHOD, "strata": strata, "dof": nu}


FUNCTION_METHOD = (
    "two-component variance function of the residuals s(F)^2 = s_a^2 + (s_b F)^2 (Rocke & "
    "Lorenzato 1995), F the fitted friction: s_a [N] and s_b [-] by the method of moments from "
    "the mean squares of the absolute and the relative residuals on N - p degrees of freedom; "
    "a component estimated negative is set to 0 and the other takes the absolute mean square"
)


def residual_function(
    fitted: np.ndarray, residuals: np.ndarray, n_parameters: int = 1
) -> dict[str, Any] | None:
    """How the residual scatter grows with the friction level: ``s(F)^2 = s_a^2 + (s_b F)^2``.

    One residual standard deviation ``s_res`` [N] for every level over-states the scatter of
    the low levels and under-states the high ones when the scatter is relative (a pressure
    block's offset, a run's, in % of its level), and a purely relative scale would miss the
    absolute part (a load cell's noise and resolution). The two-component model of
    measurement error (Rocke & Lorenzato 1995, *Technometrics* 37, 176-184) holds both. Its
    two variances follow from two moments of the fit's residuals ``e_i`` [N] at the fitted
    friction ``F_i`` [N] (N points, p coefficients)::

        sum e_i^2 / (N - p)         = s_a^2 + s_b^2 mean(F^2)      (= s_res^2)
        sum (e_i / F_i)^2 / (N - p) = s_a^2 mean(F^-2) + s_b^2

    a 2 x 2 linear system (singular only when every level is the same; then ``s_b = 0``). A
    component that comes out negative is 0 and the other takes the absolute mean square
    (``s_a = s_res``, or ``s_b^2 = s_res^2 / mean(F^2)``), so that the function's mean over
    the fitted points is always ``s_res^2``: the bands keep their overall width and take the
    data's shape. Points with ``|F| < 1e-6 N`` are left out of the relative moment.

    Parameters
    ----------
    fitted : array
        The fitted law's friction at each point [N].
    residuals : array
        Measured minus fitted friction at each point [N].
    n_parameters : int
        Coefficients of the fitted law [-].

    Returns
    -------
    dict or None
        ``method``, ``absolute_std_N`` (s_a [N]), ``relative_std_percent`` (100 s_b [%]),
        ``components`` ("absolute and relative", "relative only", "absolute only"); None for
        fewer points than coefficients + 1.
    """
    force = np.abs(np.asarray(fitted, dtype=float))
    e = np.asarray(residuals, dtype=float)
    keep = np.isfinite(force) & np.isfinite(e) & (force > MIN_FORCE)
    force, e = force[keep], e[keep]
    dof = force.size - int(n_parameters)
    if dof < 1:
        return None
    absolute = float(e @ e) / dof
    relative = float(np.sum((e / force) ** 2)) / dof
    u = float(np.mean(force**2))  # mean(F^2) [N^2]
    w = float(np.mean(force**-2.0))  # mean(F^-2) [N^-2]
    det = 1.0 - u * w  # <= 0 (Cauchy-Schwarz), 0 when every level is the same
    a2 = b2 = -1.0
    if abs(det) > 1e-9:
        a2 = (absolute - u * relative) / det
        b2 = (relative - w * absolute) / det
    if a2 >= 0.0 and b2 >= 0.0:
        components = "absolute and relative"
    elif a2 < 0.0 and abs(det) > 1e-9:
        a2, b2, components = 0.0, absolute / u, "relative only"
    else:
        a2, b2, components = absolute, 0.0, "absolute only"
    return {
        "method": FUNCTION_METHOD,
        "absolute_std_N": math.sqrt(a2),
        "relative_std_percent": 100.0 * math.sqrt(b2),
        "components": components,
    }
