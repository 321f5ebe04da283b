"""The scatter record every export carries: ``fit.scatter`` and ``quality.lack_of_fit``.

The datasheet states how far a new run or a new session of the seal scatters about the
fitted law (docs/uncertainty.md): the repeatability ``s_r``, the run-to-run ``s_run`` and the
session-to-session ``s_session`` components (relative to the friction level, in % and in N at
``reference_force_N``), the reproducibility ``s_R`` (ISO 5725-2) and the lack-of-fit test.
This module flattens both records into named numbers and texts, so that each export writes
the same fields (a MATLAB struct, Modelica constants, FMU parameters, a CSV table): the
numbers as data, the texts through :mod:`cylfric.escape` by the caller. A datasheet without
the records (an older cylfric) gives ``None``: the exports then say "not computed".
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable

    from cylfric.model import FrictionModel

__all__ = [
    "SCATTER_NUMBERS",
    "LACK_OF_FIT_NUMBERS",
    "scatter_numbers",
    "scatter_texts",
    "lack_of_fit_numbers",
    "lack_of_fit_texts",
    "band_text",
    "summary_lines",
    "scatter_records",
    "NOT_COMPUTED",
]

NOT_COMPUTED = "not computed (the datasheet has no {key} record: an older cylfric)"
"""What an export says for a missing record (``{key}``: ``fit.scatter`` or
``quality.lack_of_fit``)."""

SCATTER_NUMBERS: dict[str, tuple[str, str]] = {
    "reference_force_N": ("N", "friction level at which the std_N values are stated"),
    "sessions": ("1", "sessions (mounts, days) in the fit"),
    "runs": ("1", "runs (files) in the fit"),
    "points": ("1", "points (steady windows) in the fit"),
    "repeatability_percent": ("%", "repeatability s_r (ISO 5725-2): scatter within a run"),
    "repeatability_N": ("N", "repeatability s_r at reference_force_N"),
    "run_percent": ("%", "run-to-run scatter s_run on the same mount"),
    "run_N": ("N", "run-to-run scatter s_run at reference_force_N"),
    "session_percent": ("%", "session-to-session scatter s_session (seal remounted, new day)"),
    "session_N": ("N", "session-to-session scatter s_session at reference_force_N"),
    "session_prior_percent": ("%", "stated prior of the between-session scatter s_L"),
    "between_session_percent": (
        "%",
        "between-session scatter of a level s_L = sqrt(s_run^2 + s_session^2)",
    ),
    "reproducibility_percent": (
        "%",
        "reproducibility s_R = sqrt(s_r^2 + s_L^2) (ISO 5725-2): a new session's scatter",
    ),
    "reproducibility_N": ("N", "reproducibility s_R at reference_force_N"),
    "residual_std_N": ("N", "residual standard deviation of the fit s_res"),
    "residual_absolute_N": (
        "N",
        "absolute part s_a of the residual scatter s(F)^2 = s_a^2 + (s_b F)^2",
    ),
    "residual_relative_percent": (
        "%",
        "relative part s_b of the residual scatter s(F)^2 = s_a^2 + (s_b F)^2",
    ),
}
"""Flat name -> (unit, meaning) of the numbers of ``fit.scatter`` (the order exports use)."""

LACK_OF_FIT_NUMBERS: dict[str, tuple[str, str]] = {
    "statistic": ("1", "test statistic"),
    "dof_1": ("1", "degrees of freedom of the lack of fit (F test)"),
    "dof_2": ("1", "degrees of freedom of the pure error (F test)"),
    "p_value": ("1", "p-value"),
    "significant": ("1", "1 when the law does not fit the data at alpha = 0.05, else 0"),
    "rms_lack_N": ("N", "RMS of the lack-of-fit component"),
}
"""Flat name -> (unit, meaning) of the numbers of ``quality.lack_of_fit``."""


def _finite(value: Any) -> float | None:
    if value is None or isinstance(value, bool):
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def scatter_numbers(model: FrictionModel) -> dict[str, float] | None:
    """The numbers of ``fit.scatter`` by flat name (:data:`SCATTER_NUMBERS`), or None.

    Values as the datasheet states them: percentages [%] of the friction level, forces [N],
    counts [-]; a field the record does not carry is left out.
    """
    record = model.scatter
    if not record:
        return None
    components = record.get("components") or {}
    out: dict[str, float | None] = {
        "reference_force_N": _finite(record.get("reference_force_N")),
        "sessions": _finite(record.get("sessions")),
        "runs": _finite(record.get("runs")),
        "points": _finite(record.get("points")),
    }
    for name in ("repeatability", "run", "session"):
        component = components.get(name) or {}
        out[f"{name}_percent"] = _finite(component.get("std_percent"))
        out[f"{name}_N"] = _finite(component.get("std_N"))
    session = components.get("session") or {}
    out["session_prior_percent"] = _finite(session.get("prior_percent"))
    out["between_session_percent"] = _finite(session.get("between_percent"))
    total = record.get("reproducibility") or {}
    out["reproducibility_percent"] = _finite(total.get("std_percent"))
    out["reproducibility_N"] = _finite(total.get("std_N"))
    out["residual_std_N"] = _finite(model.statistics.get("residual_std"))
    shape = record.get("residual_function") or {}
    out["residual_absolute_N"] = _finite(shape.get("absolute_std_N"))
    out["residual_relative_percent"] = _finite(shape.get("relative_std_percent"))
    return {key: value for key in SCATTER_NUMBERS if (value := out.get(key)) is not None}


def scatter_texts(model: FrictionModel) -> dict[str, str] | None:
    """The texts of ``fit.scatter`` (raw user text: escape it for the target), or None.

    ``method``, ``repeatability_source``, ``run_source``, ``session_source`` and, when the
    record carries one, ``session_prior_basis``.
    """
    record = model.scatter
    if not record:
        return None
    components = record.get("components") or {}
    out = {"method": str(record.get("method", "not stated"))}
    for name in ("repeatability", "run", "session"):
        out[f"{name}_source"] = str((components.get(name) or {}).get("source", "not stated"))
    basis = (components.get("session") or {}).get("prior_basis")
    if basis is not None:
        out["session_prior_basis"] = str(basis)
    return out


def lack_of_fit_numbers(model: FrictionModel) -> dict[str, float] | None:
    """The numbers of ``quality.lack_of_fit`` by flat name (:data:`LACK_OF_FIT_NUMBERS`)."""
    record = model.lack_of_fit
    if not record:
        return None
    dof = record.get("dof") or [None, None]
    out = {
        "statistic": _finite(record.get("statistic")),
        "dof_1": _finite(dof[0]) if len(dof) == 2 else None,
        "dof_2": _finite(dof[1]) if len(dof) == 2 else None,
        "p_value": _finite(record.get("p_value")),
        "significant": None if "significant" not in record else float(bool(record["significant"])),
        "rms_lack_N": _finite(record.get("rms_lack_N")),
    }
    return {key: value for key in LACK_OF_FIT_NUMBERS if (value := out.get(key)) is not None}


def lack_of_fit_texts(model: FrictionModel) -> dict[str, str] | None:
    """``test`` and ``action`` of ``quality.lack_of_fit`` (raw user text), or None."""
    record = model.lack_of_fit
    if not record:
        return None
    return {
        "test": str(record.get("test", "not stated")),
        "action": str(record.get("action", "not stated")),
    }


def scatter_records(model: FrictionModel) -> tuple[tuple[str, str, Any, Any, Any], ...]:
    """``(name, datasheet key, numbers, texts, number table)`` of the two records, in the
    order every export writes them: ``scatter`` (fit.scatter) and ``lack_of_fit``
    (quality.lack_of_fit); numbers and texts None where the datasheet has no such record."""
    return (
        ("scatter", "fit.scatter", scatter_numbers(model), scatter_texts(model), SCATTER_NUMBERS),
        (
            "lack_of_fit",
            "quality.lack_of_fit",
            lack_of_fit_numbers(model),
            lack_of_fit_texts(model),
            LACK_OF_FIT_NUMBERS,
        ),
    )


def band_text(model: FrictionModel) -> str:
    """One line (ASCII) on how to form a band for a new session from the exported numbers."""
    if model.scatter is None:
        return (
            "Bands for a new run or session: not computed (this datasheet has no fit.scatter "
            "record); refit the campaign with this cylfric to get them (docs/uncertainty.md)."
        )
    return (
        "Band for a new session (seal remounted, another day), level 95 %: "
        "F +/- k sqrt(se^2 + (s F)^2) with F the model's friction [N], "
        "s^2 = s_r^2 + s_L^2 + (s_L^2 - s_run^2)/n (n the sessions fitted: the fitted law "
        "carries what every run of its sessions shared, over n), se the standard error of "
        "the mean curve [N] (cylfric FrictionModel.standard_error) and k = 1.96 (about: the "
        "Student-t quantile; cylfric's FrictionModel.prediction_band(v, p, scope='session') "
        "gives it exactly); for a new run on the same mount s = sqrt(s_r^2 + s_run^2), se the "
        "model-based (not cluster-robust) standard error "
        "(FrictionModel.standard_error(robust=False)) and k the internally studentised "
        "residual's quantile on the residual variance's degrees of freedom nu "
        "(fit.scatter.residual_variance.dof in the datasheet: about 1.96 for many, 1.65 for "
        "nu = 3); never narrower than k sqrt(se^2 + s_a^2 + (s_b F)^2), the residual "
        "scatter at the level F (residual_absolute_N, residual_relative_percent; s_res at "
        "every level where they are missing) (docs/uncertainty.md)."
    )


def _percent(value: float | None) -> str:
    return "?" if value is None else f"{value:.3g} %"


def summary_lines(model: FrictionModel, user: Callable[[str], str] = str) -> list[str]:
    """Lines of text for comments and READMEs: the scatter record, the lack-of-fit verdict
    and how to form a band.

    ``user`` is applied to each piece of user text (method, sources, the prior's basis, the
    test's name and action): pass the target's escaper (e.g.
    :func:`cylfric.escape.markdown_text`); the rest is fixed ASCII text and numbers. Without
    it (``str``) the lines hold raw user text: escape each whole line for the target.
    """
    numbers = scatter_numbers(model)
    texts = scatter_texts(model)
    if texts is not None:
        texts = {key: user(value) for key, value in texts.items()}
    lines = [user(line) for line in model.assumptions()]  # the dynamic parameters' status
    if numbers is None or texts is None:
        lines.append("Scatter components: " + NOT_COMPUTED.format(key="fit.scatter") + ".")
    else:
        level = numbers.get("reference_force_N")
        at = "" if level is None else f" (at {level:.4g} N)"
        lines.append(
            f"Scatter components{at}, relative to the friction level: repeatability s_r "
            f"{_percent(numbers.get('repeatability_percent'))}, run-to-run s_run "
            f"{_percent(numbers.get('run_percent'))}, session s_session "
            f"{_percent(numbers.get('session_percent'))} (source: {texts['session_source']}); "
            f"reproducibility s_R {_percent(numbers.get('reproducibility_percent'))} "
            "(ISO 5725-2)."
        )
        prior = _percent(numbers.get("session_prior_percent"))
        basis = texts.get("session_prior_basis", "basis not stated")
        if texts["session_source"] == user("prior"):
            lines.append(
                "ASSUMPTION: one session cannot show the between-session scatter; it is the "
                f"stated prior of {prior} of the level (pooled with the runs' scatter): {basis}."
            )
        elif "prior" in texts["session_source"]:  # estimated+prior
            lines.append(
                f"The between-session scatter pools the estimate with a stated prior of {prior} "
                f"of the level: {basis}."
            )
        lines.append(f"Method: {texts['method']}.")
    verdict = lack_of_fit_texts(model)
    if verdict is not None:
        verdict = {key: user(value) for key, value in verdict.items()}
    lof = lack_of_fit_numbers(model) or {}
    if verdict is None:
        lines.append("Lack of fit: " + NOT_COMPUTED.format(key="quality.lack_of_fit") + ".")
    else:
        said = "significant" if lof.get("significant") else "not significant"
        p_value = lof.get("p_value")
        lines.append(
            f"Lack of fit ({verdict['test']}): {said} at alpha 0.05"
            + ("" if p_value is None else f" (p = {p_value:.3g})")
            + f"; {verdict['action']}."
        )
    lines.append(band_text(model))
    return lines
