"""The self-contained HTML report: figures embedded as base64 PNG, works offline."""

from __future__ import annotations

import base64
import html
import math
from typing import TYPE_CHECKING

import pandas as pd

from .._runtable import run_column
from ..escape import html_text
from ..io.writers import atomic_write_text
from .figures import not_identified_line, render_all, save_rendered

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping, Sequence
    from pathlib import Path
    from typing import Any
    from typing import Any as _Results  # identification results, duck-typed: never imported here

    from cylfric._typing import StrPath
    from cylfric.steady_state import Extraction

__all__ = [
    "render_report",
    "write_report",
    "write_report_folder",
    "offset_by_pressure",
    "scatter_html",
]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2rem auto;
max-width:1100px;color:#222;line-height:1.45;padding:0 1rem}
h1{font-size:1.6rem;margin-bottom:.2rem}h2{margin-top:2rem;border-bottom:1px solid #ddd}
table{border-collapse:collapse;font-size:.85rem;margin:.6rem 0}
td,th{border:1px solid #ccc;padding:.25rem .5rem;text-align:right}
th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}
figure{margin:1rem 0}figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.85rem;color:#555}.law{font-family:ui-monospace,monospace;font-size:1rem}
.note{background:#fff7e0;border-left:4px solid #e0a800;padding:.4rem .8rem;margin:.4rem 0}
.muted{color:#777;font-size:.85rem}
pre{white-space:pre-wrap;overflow-wrap:anywhere;max-width:100%;font-size:.8rem;
background:#fafafa;border:1px solid #eee;padding:.5rem}
.law{overflow-wrap:anywhere}.scroll{max-width:100%;overflow-x:auto}
"""


def _table(frame: pd.DataFrame, digits=4) -> str:
    def fmt(x):
        if isinstance(x, float):
            return "" if math.isnan(x) else f"{x:.{digits}g}"
        return html_text(x)

    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    rows = "".join(
        "<tr>" + "".join(f"<td>{fmt(v)}</td>" for v in row) + "</tr>"
        for row in frame.itertuples(index=False)
    )
    table = f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"
    return f"<div class='scroll'>{table}</div>"  # a wide table scrolls, the page does not


def _number(value, digits=3) -> str:
    """A number of a datasheet record as text ('n/a' when missing or not finite)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return "n/a"
    return f"{value:.{digits}g}"


COMPONENT_MEANING = {
    "repeatability": (
        "points of one run about that run's own level (stroke to stroke in one file, the "
        "same conditions): near 0 when each run gives one point per direction, which says "
        "nothing of a re-run"
    ),
    "run": "a run's level about its pressure block's: a file re-run on the same mount",
    "session": (
        "a session's level about the others': the seal remounted, another day (with few "
        "sessions, pooled with the stated prior)"
    ),
    "reproducibility": (
        "all three together: the scatter of one new run in a new session about the law"
    ),
}
"""What each scatter component of ``fit.scatter`` measures, for the report's table."""


def scatter_html(scatter: Mapping[str, Any] | None, lack_of_fit: Mapping[str, Any] | None) -> str:
    """HTML: the scatter components (``fit.scatter``) and the lack-of-fit test
    (``quality.lack_of_fit``) of a datasheet; '' when neither was computed.

    The scatter table gives each component's standard deviation in % of the friction
    level and in N, its source, and the prior's basis where the session component is a
    prior; the lack-of-fit line the test, statistic, degrees of freedom, p-value, verdict
    (at alpha = 0.05) and what the fit did about it.
    """
    if not scatter and not lack_of_fit:
        return ""
    parts = ["<h2>Scatter and lack of fit</h2>"]
    if scatter:
        components = scatter.get("components") or {}
        rows = []
        for name, part in components.items():
            basis = ""
            if "prior" in str(part.get("source", "")):
                prior = _number(part.get("prior_percent"))
                basis = f"prior {prior} %: {part.get('prior_basis') or 'basis not stated'}"
            rows.append(
                {
                    "component": name,
                    "std [%]": _number(part.get("std_percent")),
                    "std [N]": _number(part.get("std_N")),
                    "source": str(part.get("source", "")),
                    "prior basis": basis,
                    "what it measures": COMPONENT_MEANING.get(name, ""),
                }
            )
        total = scatter.get("reproducibility")
        if total:
            rows.append(
                {
                    "component": "reproducibility (ISO 5725-2 s_R)",
                    "std [%]": _number(total.get("std_percent")),
                    "std [N]": _number(total.get("std_N")),
                    "source": "combined",
                    "prior basis": "",
                    "what it measures": COMPONENT_MEANING["reproducibility"],
                }
            )
        counts = ", ".join(
            f"{scatter[k]} {k}"
            for k in ("sessions", "runs", "points")
            if scatter.get(k) is not None
        )
        level = _number(scatter.get("reference_force_N"))
        parts.append(
            f"<p>Scatter components ({html_text(scatter.get('method', 'method not stated'))}; "
            f"{html_text(counts)}); N at the mean fitted friction {level} N.</p>"
        )
        if rows:
            parts.append(_table(pd.DataFrame(rows)))
        shape = scatter.get("residual_function") or {}
        if None not in (shape.get("absolute_std_N"), shape.get("relative_std_percent")):
            parts.append(
                "<p>Residual scatter at the friction level F (the point band's; "
                + html_text(str(shape.get("components", "components not stated")))
                + "): s(F) = sqrt(s_a<sup>2</sup> + (s_b F)<sup>2</sup>), s_a = "
                f"{_number(shape['absolute_std_N'])} N, s_b = "
                f"{_number(shape['relative_std_percent'])} %.</p>"
            )
    if lack_of_fit:
        dof = lack_of_fit.get("dof")
        dof_text = f", dof {dof[0]}, {dof[1]}" if dof else ""
        significant = lack_of_fit.get("significant")
        verdict = (
            "the law does not fit the data (significant at 5 %)"
            if significant
            else "no significant lack of fit at 5 %"
            if significant is not None
            else "verdict not stated"
        )
        lack = lack_of_fit.get("rms_lack_N")
        lack_text = f"; RMS lack of fit {_number(lack)} N" if lack is not None else ""
        line = (
            f"Lack of fit ({lack_of_fit.get('test', 'test not stated')}): statistic "
            f"{_number(lack_of_fit.get('statistic'))}{dof_text}, p = "
            f"{_number(lack_of_fit.get('p_value'), 2)}: {verdict}{lack_text}. "
            f"Action: {lack_of_fit.get('action') or 'none stated'}."
        )
        css = "note" if significant else "muted"
        parts.append(f"<p class='{css}' id='lack-of-fit'>{html_text(line)}</p>")
    return "\n".join(parts)


def _records(sheet, model) -> tuple[Any, Any]:
    """(fit.scatter, quality.lack_of_fit): from the model when it carries them, else from
    the datasheet; None where not computed."""
    scatter = getattr(model, "scatter", None) or (sheet.get("fit") or {}).get("scatter")
    lack = getattr(model, "lack_of_fit", None) or (sheet.get("quality") or {}).get("lack_of_fit")
    return scatter, lack


def render_report(
    sheet: Mapping[str, Any],
    ident: _Results,
    extraction: Extraction,
    figures: Iterable[tuple[str, str, bytes]],
    *,
    title: str = "cylfric friction report",
    excluded: pd.DataFrame | None = None,
    exports: Sequence[Mapping[str, Any]] | None = None,
    dynamic_section: str | None = None,
) -> str:
    """HTML text of the report: datasheet summary, figures, tables, data quality."""
    parts = [
        f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        f"<meta name='viewport' content='width=device-width,initial-scale=1'>"
        f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"
    ]
    parts.append(f"<h1>{html.escape(title)}: {html_text(sheet.get('name', ''))}</h1>")
    parts.append(
        f"<p class='muted'>cylfric {html_text(sheet.get('cylfric_version', ''))}, "
        f"{html_text(sheet.get('created', ''))}; model: steady-state LuGre/Stribeck "
        "law (thesis eq. 2.7) with pressure laws; units N, bar, mm/s.</p>"
    )
    model = ident.model
    parts.append("<h2>Datasheet summary</h2>")
    parts.append("<p class='muted'>Each coefficient ± its standard error.</p>")
    parts += [f"<div class='law'>{html.escape(line)}</div>" for line in model.law_lines()]
    offset = sheet.get("offset")
    fit = sheet["fit"]
    val = sheet["validity"]
    parts.append(
        "<p>RMSE of the global fit: <b>{:.3f} N</b> over {} points. Load-cell offset "
        "(weight, preload or pressure force, whatever the rig has): {}. "
        "Valid for {:.3g}-{:.3g} bar and {:.3g}-{:.3g} mm/s.</p>".format(
            fit["rmse"],
            fit.get("n_points", ""),
            "n/a"
            if offset is None
            else f"<b>{offset:.2f} N</b>"
            + (f" (spread {sheet['offset_std']:.2f} N)" if sheet.get("offset_std") else ""),
            val["pressure_min"] / 1e5,
            val["pressure_max"] / 1e5,
            val["velocity_min"] * 1e3,
            val["velocity_max"] * 1e3,
        )
    )
    parts.append(offset_by_pressure(extraction))
    if model.not_identified:
        line = not_identified_line(model.not_identified, width=10_000)
        parts.append(f"<p class='note' id='not-identified'>{html_text(line)}.</p>")
    dyn = ", ".join(
        f"{name} {status} ({reason})" for name, (status, reason) in model.dynamic_status.items()
    )
    parts.append(f"<p class='muted'>Dynamic (LuGre) parameters: {html_text(dyn)}.</p>")
    for note in sheet.get("notes", []):
        parts.append(f"<p class='note'>{html_text(note)}</p>")
    parts.append(scatter_html(*_records(sheet, model)))
    parts.append("<h2>Figures</h2>")
    for stem, caption, png in figures:
        data = base64.b64encode(png).decode("ascii")
        parts.append(
            f"<figure id='{stem}'><img alt='{html.escape(caption)}' "
            f"src='data:image/png;base64,{data}'><figcaption>{html.escape(caption)}"
            "</figcaption></figure>"
        )
    parts.append("<h2>Fit report</h2>")
    parts.append(f"<pre>{html.escape(model.fit_report(min_correlation=0.3))}</pre>")
    parts.append("<h2>Per-pressure parameters (thesis Table 4.1 layout)</h2>")
    parts.append(_table(_engineering_per_pressure(ident.per_pressure)))
    parts.append("<h2>Pressure laws compared</h2>")
    parts.append(_table(ident.comparison))
    if ident.sensitivity is not None:
        sens = ident.sensitivity.assign(**{"v_r [mm/s]": ident.sensitivity["v_r [m/s]"] * 1e3})
        parts.append("<h2>Sensitivity (thesis Tables 4.2-4.4)</h2>")
        parts.append(_table(sens[["table", "alpha [-]", "v_r [mm/s]", "rmse [N]"]]))
        rec = ident.recommended
        parts.append(
            f"<p>Recommended fixed values (grid minimum): alpha = {rec['alpha']:.3g}, "
            f"v_r = {rec['v_r'] * 1e3:.3g} mm/s, RMSE {rec['rmse']:.3f} N.</p>"
        )
    if dynamic_section:
        parts.append(dynamic_section)
    if exports:
        parts.append(_exports(exports))
    parts.append("<h2>Data quality</h2>")
    if excluded is not None and len(excluded):
        parts.append(
            f"<p class='note'>The data-quality gate left {len(excluded)} run(s) out of the fit "
            "(also in excluded.csv):</p>"
        )
        parts.append(_table(excluded))  # files relative to the campaign folder
    else:
        parts.append("<p>The data-quality gate left no run out.</p>")
    parts.append(_quality(extraction))
    parts.append("</body></html>")
    return "\n".join(parts)


def _exports(exports) -> str:
    """The simulator exports of ``fit --export`` and what the lossy ones lose."""
    lines = ["<h2>Simulator exports</h2>"]
    for item in exports:
        where = html.escape(f"{item['folder']}/")
        if item["loss"] is None:
            lines.append(
                f"<p><b>{html.escape(item['target'])}</b> ({where}): lossless, the full "
                "pressure-dependent LuGre model.</p>"
            )
            continue
        lines.append(
            f"<p><b>{html.escape(item['target'])}</b> ({where}): best-fit parameters of the "
            "simulator's own block over the validity range; difference to this datasheet "
            "(block - cylfric, both directions; loss_*.csv/.txt/.png in that folder):</p>"
        )
        lines.append(_table(pd.DataFrame(item["loss"])))
    return "\n".join(lines)


def _engineering_per_pressure(table):
    if table.empty:
        return table
    out = pd.DataFrame(
        {
            "p [bar]": table["pressure [Pa]"] / 1e5,
            "F_s [N]": table["F_s [N]"],
            "F_c [N]": table["F_c [N]"],
            "sigma_2 [N*s/mm]": table["sigma_2 [N*s/m]"] / 1e3,
            "v_r [mm/s]": table["v_r [m/s]"] * 1e3,
            "alpha [-]": table["alpha [-]"],
            "v_Stribeck [mm/s]": table["stribeck_velocity [m/s]"] * 1e3,
            "RMSE [N]": table["rmse [N]"],
            "n": table["n_points [-]"],
        }
    )
    return out


def offset_by_pressure(extraction: Extraction, t_limit: float = 4.0, smallest: float = 0.5) -> str:
    """HTML: the load-cell offset per pressure level, and whether it changes with pressure.

    Each run with windows in both directions has its own offset (F_up + F_down) / 2 [N]. A
    straight line through them against pressure says whether the offset has a pressure
    dependence (a pressure force on the load cell): when its change over the pressure range
    exceeds ``smallest`` [N] and ``t_limit`` standard errors [-]. '' without an extraction or
    with fewer than two pressure levels.
    """
    import numpy as np

    from ..levels import pressure_levels

    if extraction is None or "offset [N]" not in extraction.points:
        return ""
    pts = extraction.points
    ok = pts[pts["flag"].eq("ok")]
    both = ok.groupby("run")["direction [-]"].nunique() == 2
    runs = ok[ok["run"].isin(both[both].index)].groupby("run")
    table = pd.DataFrame(
        {"pressure": runs["pressure [Pa]"].median(), "offset": runs["offset [N]"].first()}
    ).dropna()
    if len(table) < 3:
        return ""
    labels, levels = pressure_levels(table["pressure"].to_numpy())
    if len(levels) < 2:
        return ""
    p, offset = table["pressure"].to_numpy(), table["offset"].to_numpy()
    design = np.column_stack([np.ones_like(p), p])
    coef, *_ = np.linalg.lstsq(design, offset, rcond=None)
    res = offset - design @ coef
    dof = max(len(p) - 2, 1)
    cov = np.linalg.pinv(design.T @ design) * float(res @ res) / dof
    span = float(p.max() - p.min())
    change, change_se = coef[1] * span, math.sqrt(max(cov[1, 1], 0.0)) * span
    per_level = pd.DataFrame(
        {
            "pressure [bar]": levels / 1e5,
            "offset [N]": [float(np.median(offset[labels == k])) for k in range(len(levels))],
            "runs": [int(np.sum(labels == k)) for k in range(len(levels))],
        }
    )
    if abs(change) > max(smallest, t_limit * change_se):
        verdict = (
            f"The load-cell offset changes with pressure: {coef[1] * 1e5:+.3g} N/bar, "
            f"{change:+.3g} N over {p.min() / 1e5:.3g}-{p.max() / 1e5:.3g} bar (a pressure "
            "force on the load cell that the force balance does not cancel, e.g. unequal "
            "piston areas without both chamber pressures). Each run's own offset is removed; "
            "that removes such a force only as far as the pressure is the same in both "
            "directions of a run: check [cylinder] and [force_balance] in campaign.toml."
        )
    else:
        verdict = (
            "The load-cell offset does not change with pressure beyond its run-to-run "
            f"spread ({change:+.2g} ± {change_se:.2g} N over {p.min() / 1e5:.3g}-"
            f"{p.max() / 1e5:.3g} bar)."
        )
    return f"<p>{html.escape(verdict)}</p>" + _table(per_level)


def _quality(extraction) -> str:
    if extraction is None:
        return "<p>No extraction details.</p>"
    pts = extraction.points
    flags = pts["flag"].value_counts().rename_axis("flag").reset_index(name="windows")
    spikes = int(pts["spikes [-]"].sum()) if "spikes [-]" in pts else 0
    events = sum(run_column(extraction.runs, "events", default=0))
    lines = [
        f"<p>{len(extraction.runs)} files read ({extraction.bytes_read / 1e6:.1f} MB), "
        f"{len(extraction.skipped)} skipped; {len(pts)} stroke windows; {spikes} spike "
        f"samples rejected; {events} status/header lines between data blocks.</p>",
        _table(flags),
    ]
    rejected = pts[~pts["flag"].eq("ok")]
    if len(rejected):
        lines.append("<p>Rejected windows:</p>")
        lines.append(
            _table(
                rejected[["file", "stroke", "direction [-]", "n [-]", "flag"]].assign(
                    file=lambda d: d["file"].map(lambda f: f.split("/")[-1])
                )
            )
        )
    if extraction.skipped:
        lines.append("<p>Skipped files:</p>")
        lines.append(_table(pd.DataFrame(extraction.skipped)))
    return "\n".join(lines)


def write_report(path: StrPath, text: str) -> Path:
    """Write the report atomically."""
    return atomic_write_text(path, text)


def write_report_folder(
    out: Path,
    sheet: Mapping[str, Any],
    ident: _Results,
    extraction: Extraction,
    excluded: pd.DataFrame | None = None,
    *,
    workers: int | None = None,
    exports: Sequence[Mapping[str, Any]] | None = None,
    dynamic: _Results | None = None,
    progress: Callable[[str], object] | None = None,
) -> dict[str, Path]:
    """Draw the figures (PNG, SVG into ``out/figures``) and write ``out/report.html``.

    Returns {output name: path}. ``workers`` (None: the cores this process may use) draw
    the figures (see :func:`~cylfric.report.figures.render_all`). ``exports``: plain
    summaries of the simulator exports (target, folder, files, loss rows) for their section.
    ``dynamic`` (a :class:`~cylfric.identify.dynamic.DynamicIdentification`) adds the
    presliding and breakaway figure and tables. ``progress`` is called with each figure's
    name once drawn.
    """
    from pathlib import Path

    out = Path(out)
    offset = None if extraction is None else extraction.offset
    files, shown = {}, []
    for stem, caption, png, svg in render_all(ident, offset, workers=workers, progress=progress):
        files[f"figure_{stem}"] = save_rendered(out / "figures", stem, png, svg)["png"]
        shown.append((stem, caption, png))
    section = None
    if dynamic is not None:
        from .dynamic import dynamic_html, figure_dynamic
        from .figures import render

        png, svg = render(figure_dynamic(dynamic))
        files["figure_dynamic"] = save_rendered(out / "figures", "dynamic", png, svg)["png"]
        if progress is not None:
            progress("dynamic")
        section = dynamic_html(dynamic, base64.b64encode(png).decode("ascii"), _table)
    files["report"] = write_report(
        out / "report.html",
        render_report(
            sheet,
            ident,
            extraction,
            shown,
            excluded=excluded,
            exports=exports,
            dynamic_section=section,
        ),
    )
    return files
