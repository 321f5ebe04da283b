"""Text views of a friction model: the pressure laws with ± and an lmfit-style fit report.

Engineering units throughout (N, bar, mm/s, N*s/mm), as the thesis and its users write them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS
from .names import DYNAMIC_PARAMETERS, STEADY_PARAMETERS

if TYPE_CHECKING:
    import pandas as pd

    from .core import FrictionModel, Parameter

__all__ = ["law_lines", "fit_report", "format_value", "parameter_table", "html_summary"]


def format_value(value: float | None, stderr: float | None = None, digits: int = 4) -> str:
    """``"70.18 ± 0.021"``: the value to ``digits`` significant digits, stderr to two."""
    if value is None:
        return "n/a"
    text = f"{value:.{digits}g}"
    if stderr is not None and math.isfinite(stderr) and stderr > 0:
        text += f" ± {stderr:.2g}"
    return text


def _term(model, name):
    p = model.parameters[name]
    value, stderr, unit = p.engineering()
    text = format_value(value, stderr if p.vary else None)
    return text + ("" if p.vary else " (fixed)"), unit


def law_lines(model: FrictionModel) -> list[str]:
    """The steady-state laws in engineering units with standard errors, one line each.

    ``F_c(p) = 70.18 ± 0.021 N + 0.5 ± 0.00021 N/bar * p``; parameters not identified say so.
    """
    lines = []
    for name in ("F_c", "F_s", "sigma_2"):
        law = model.laws[name]
        if law is None:
            lines.append(f"{name}: not identified ({model.not_identified.get(name, '')})")
            continue
        if law == "constant":
            text, unit = _term(model, name)
            lines.append(f"{name} = {text} {unit}")
            continue
        terms = {c: _term(model, f"{name}.{c}") for c in PRESSURE_LAW_COEFFICIENTS[law]}
        text = f"{name}(p) = ({terms['intercept'][0]}) {terms['intercept'][1]}"
        if "slope" in terms:
            text += f" + ({terms['slope'][0]}) {terms['slope'][1]} * p"
        if "curvature" in terms:
            text += f" + ({terms['curvature'][0]}) {terms['curvature'][1]} * p^2"
        if "amplitude" in terms:
            text += (
                f" + ({terms['amplitude'][0]}) {terms['amplitude'][1]}"
                f" * (exp(({terms['rate'][0]}) {terms['rate'][1]} * p) - 1)"
            )
        lines.append(text)
    shape = []
    for name in ("v_r", "alpha"):
        if model.laws[name] is None:
            continue
        text, unit = _term(model, name)
        shape.append(f"{name} = {text}" + ("" if unit == "-" else f" {unit}"))
    if shape:
        lines.append(", ".join(shape))
    return lines


REPORT_WIDTH = 100
"""Longest line of :func:`fit_report` [characters]: longer ones wrap with a hanging indent,
so the report fits a terminal and the HTML report's page."""


def _wrapped(line: str, width: int = REPORT_WIDTH) -> str:
    """``line`` wrapped at ``width`` characters, continuation lines indented 4 more."""
    import textwrap

    if len(line) <= width:
        return line
    indent = " " * (len(line) - len(line.lstrip()) + 4)
    return textwrap.fill(line, width, subsequent_indent=indent, break_on_hyphens=False)


def fit_report(model: FrictionModel, *, min_correlation: float = 0.1) -> str:
    """lmfit-style report: model, fit statistics, variables ± stderr, correlations, dynamics.

    No line is longer than :data:`REPORT_WIDTH` characters (longer ones wrap).
    """
    lines = ["[[Model]]"]
    lines.append(
        f"    {model.friction_law} friction law; pressure laws: "
        + ", ".join(f"{n} {model.laws[n]}" for n in STEADY_PARAMETERS if model.laws[n])
        + f"; operating pressure: {model.reference} of the chambers"
    )
    if model.provenance.get("method"):
        lines.append(f"    method: {model.provenance['method']}")
    lines += _statistics_lines(model.statistics)
    lines.append("[[Variables]]")
    width = max(len(n) for n in model.parameters)
    for p in model.parameters.values():
        if p.parameter not in DYNAMIC_PARAMETERS:
            lines.append(_variable_line(model, p, width))
    lines += _correlation_lines(model, min_correlation)
    lines += _dynamic_lines(model)
    if model.validity is not None:
        val = model.validity
        lines.append("[[Validity]]")
        lines.append(
            f"    {val['pressure_min'] / 1e5:.4g}-{val['pressure_max'] / 1e5:.4g} bar, "
            f"{val['velocity_min'] * 1e3:.4g}-{val['velocity_max'] * 1e3:.4g} mm/s"
        )
    return "\n".join(_wrapped(line) for line in lines)


_STATISTICS_LABELS = (
    ("n_points", "# data points", ""),
    ("n_variables", "# variables", ""),
    ("rmse", "RMSE", " N"),
    ("residual_std", "residual std", " N"),
    ("dof", "degrees of freedom", ""),
    ("aic", "Akaike info crit", ""),
    ("bic", "Bayesian info crit", ""),
)
"""(key in ``model.statistics``, label, unit) of the report's [[Fit Statistics]] lines."""


def _statistics_lines(stats: Mapping[str, Any]) -> list[str]:
    """The [[Fit Statistics]] section (empty without statistics); RMSE and std in N."""
    if not stats:
        return []
    lines = ["[[Fit Statistics]]"]
    for key, label, unit in _STATISTICS_LABELS:
        if stats.get(key) is not None:
            value = stats[key]
            text = f"{value:d}" if isinstance(value, int) else f"{value:.5g}"
            if key == "dof":
                unit = _dof_meaning(stats)
            lines.append(f"    {label:20s} = {text}{unit}")
    return lines


def _dof_meaning(stats: Mapping[str, Any]) -> str:
    """What the degrees of freedom count: points - variables, or (standard errors clustered
    by run, CR2) runs - variables."""
    n, k, dof = stats.get("n_points"), stats.get("n_variables"), stats.get("dof")
    if n is None or k is None or dof is None:
        return ""
    if dof == n - k:
        return " (data points - variables)"
    return (
        f" (runs - variables = {dof + k} - {k}: the standard errors are clustered by run, "
        "whose points share its level)"
    )


def _variable_line(model: FrictionModel, p: Parameter, width: int) -> str:
    """One [[Variables]] line: value +/- stderr (relative %) in engineering units."""
    if p.value is None:
        reason = model.not_identified.get(p.parameter, "")
        return f"    {p.name:{width}s}:  not identified ({reason})"
    value, stderr, unit = p.engineering()
    if not p.vary:
        return f"    {p.name:{width}s}:  {value:.6g} {unit} (fixed)"
    text = f"    {p.name:{width}s}:  {value:.6g}"
    if stderr is not None:
        rel = abs(stderr / value) * 100 if value else math.inf
        text += f" +/- {stderr:.3g}" + (f" ({rel:.2f}%)" if math.isfinite(rel) else "")
    return text + f" {unit}"


def _correlation_lines(model: FrictionModel, min_correlation: float) -> list[str]:
    """The [[Correlations]] section: pairs with |C| >= ``min_correlation`` [-], largest first."""
    correlations = model.correlations()
    if correlations is None:
        return []
    names, corr = correlations
    pairs = [
        (abs(corr[i, j]), names[i], names[j], corr[i, j])
        for i in range(len(names))
        for j in range(i + 1, len(names))
        if abs(corr[i, j]) >= min_correlation
    ]
    lines = [f"[[Correlations]] (unreported correlations are < {min_correlation:.3f})"]
    for _, a, b, c in sorted(pairs, reverse=True):
        lines.append(f"    C({a}, {b}) = {c:+.4f}")
    return lines


def _dynamic_lines(model: FrictionModel) -> list[str]:
    """The [[Dynamic]] section: each dynamic parameter, its pressure law and its status."""
    lines = ["[[Dynamic]]"]
    for name in DYNAMIC_PARAMETERS:
        status, reason = model.dynamic_status[name]
        law = model.laws[name]
        if law == "constant":
            value, _, unit = model.parameters[name].engineering()
            text = f"{value:.4g} {unit}"
        else:
            text = (
                f"{law} in pressure, "
                + ", ".join(
                    f"{c} {model.parameters[f'{name}.{c}'].value:.4g}"
                    for c in PRESSURE_LAW_COEFFICIENTS[law]
                )
                + " (SI)"
            )
        lines.append(f"    {name:8s} = {text} ({status}: {reason})")
    return lines


PARAMETER_COLUMNS = (
    "law",
    "value",
    "stderr",
    "unit",
    "value (engineering)",
    "stderr (engineering)",
    "unit (engineering)",
    "vary",
    "status",
)
"""Columns of :func:`parameter_table`."""


def parameter_table(model: FrictionModel) -> pd.DataFrame:
    """The model's coefficients as a DataFrame, one row each (index: ``"F_c.slope"``, ...).

    Columns: ``law`` (the parameter's pressure law), ``value`` and ``stderr`` in SI with
    ``unit``, the same in engineering units (N, bar, mm/s, N*s/mm), ``vary`` (False: held
    fixed) and ``status`` (``identified``, ``fixed``, ``assumed`` or ``not identified: ...``).
    """
    import pandas as pd

    rows = {}
    for p in model.parameters.values():
        value, stderr, unit = p.engineering()
        dynamic = model.dynamic_status.get(p.parameter)
        if p.value is None:
            status = f"not identified: {model.not_identified.get(p.parameter, '')}".rstrip(": ")
        elif dynamic is not None:
            status = dynamic[0]
        else:
            status = "identified" if p.vary else "fixed"
        rows[p.name] = (
            model.laws.get(p.parameter),
            p.value,
            p.stderr,
            p.unit,
            value,
            stderr,
            unit,
            p.vary,
            status,
        )
    frame = pd.DataFrame.from_dict(rows, orient="index", columns=list(PARAMETER_COLUMNS))
    frame.index.name = "parameter"
    return frame


def html_summary(model: FrictionModel, title: str = "FrictionModel") -> str:
    """HTML for a notebook: the laws, a table of coefficients with units and standard
    errors in engineering units, the operating-pressure rule and the validity ranges."""
    import html

    from ..escape import html_text

    head = (
        f"<b>{html.escape(title)}</b>: {html_text(model.friction_law)} friction law, "
        f"operating pressure: {html_text(model.reference)} of the chamber pressures"
    )
    name = model.record.get("name")
    if name:
        head += f" &middot; datasheet <code>{html_text(name)}</code>"
    laws = "".join(f"<div><code>{html_text(line)}</code></div>" for line in law_lines(model))
    cells = []
    for p in model.parameters.values():
        value, stderr, unit = p.engineering()
        if p.value is None:
            reason = model.not_identified.get(p.parameter, "")
            shown, error = "not identified", html_text(reason)
        else:
            shown = f"{value:.6g}"
            error = "fixed" if not p.vary else ("" if stderr is None else f"{stderr:.3g}")
        dynamic = model.dynamic_status.get(p.parameter)
        if dynamic is not None and p.value is not None:
            error = (error + " " if error else "") + f"({html_text(dynamic[0])})"
        cells.append(
            f"<tr><td style='text-align:left'><code>{html_text(p.name)}</code></td>"
            f"<td>{shown}</td><td>{error}</td><td style='text-align:left'>"
            f"{html_text(unit)}</td></tr>"
        )
    table = (
        "<table><thead><tr><th>parameter</th><th>value</th><th>std. error</th>"
        "<th>unit</th></tr></thead><tbody>" + "".join(cells) + "</tbody></table>"
    )
    validity = ""
    if model.validity is not None:
        val = model.validity
        validity = (
            f"<div>valid for {val['pressure_min'] / 1e5:.4g}-{val['pressure_max'] / 1e5:.4g} "
            f"bar, {val['velocity_min'] * 1e3:.4g}-{val['velocity_max'] * 1e3:.4g} mm/s</div>"
        )
    return f"<div>{head}</div>{laws}{table}{validity}"
