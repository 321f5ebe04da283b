"""``cylfric fit-field`` (friction in service from machine logs) and ``cylfric generate-field``
(the virtual field bench). Thin: parse, call :func:`cylfric.identify.field.fit_field`, write."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import BadInput, _plain, app, console, guarded

FIT_JSON = "field.json"
TABLES = {
    "bands": "friction_bands.csv",
    "cross_check": "cross_check.csv",
    "days": "trend.csv",
    "changes": "changes.csv",
}
FIGURES = ("load.png", "friction.png", "mass.png", "force.png", "trend.png")
REPORT = "report.html"
LOAD_CSV = "load_curves.csv"
DATASHEET_CSV = "datasheet_comparison.csv"


@app.command("fit-field")
@guarded
def fit_field_command(
    logs: list[Path] = typer.Argument(
        ..., help="Machine logs: text with units in the header, .mat v5 or v7.3 (never modified)."
    ),
    config: Path = typer.Option(
        ..., "--config", "-c", help="field.toml: cylinder, columns, sensors (docs/field.md)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
    as_json: bool = typer.Option(False, "--json", help="Print field.json instead of a summary."),
    datasheet: Path = typer.Option(
        None,
        "--datasheet",
        help="A seal datasheet (datasheet.json of this cylinder's size): compare the "
        "in-service friction with it at the machine's operating points.",
    ),
):
    """Friction of a cylinder in service, from its machine's own logs (no load cell).

    Piston force from the chamber pressures; per log a load curve over position and an
    effective mass; a Coulomb + viscous law (pressure slope where identifiable) with bands
    cluster-robust by stroke; a model-free cross-check pairing extension and retraction;
    the friction level per day and a change test. Writes field.json, CSV tables, figures
    and report.html into OUT.
    """
    _run(logs, config, out, as_json, datasheet)


@app.command("generate-field")
@guarded
def generate_field_command(
    out: Path = typer.Argument(..., help="Folder for the logs, field.toml and truth.json."),
    days: int = typer.Option(2, "--days", min=1, help="Days of logs."),
    logs_per_day: int = typer.Option(2, "--logs-per-day", min=1, help="Logs per day."),
    duration: float = typer.Option(600.0, "--duration", min=10.0, help="Seconds per log."),
    rise: float = typer.Option(
        0.0, "--rise", help="Friction rise per day after the first, in % (15 = +15 %)."
    ),
    counterbalance: bool = typer.Option(
        False, "--counterbalance", help="Pressure A measured on the valve side of a CBV."
    ),
    fmt: str = typer.Option("csv", "--format", help="csv, mat (v5) or mat73 (v7.3/HDF5)."),
    seed: int = typer.Option(0, "--seed", help="Random seed."),
):
    """Write a virtual field campaign: a boom crane's logs at 100 Hz with the truth."""
    from ..simulate.field_bench import FieldSettings, generate_field

    if fmt not in ("csv", "mat", "mat73"):
        raise BadInput(f"--format {fmt!r}; valid: csv, mat, mat73")
    from .._paths import make_folder

    make_folder(out, "OUT")
    settings = FieldSettings(counterbalance=counterbalance, seed=seed)
    scales = tuple((1 + rise / 100) ** d for d in range(days))
    generate_field(
        out,
        settings,
        days=days,
        logs_per_day=logs_per_day,
        duration=duration,
        friction_scales=scales,
        fmt=fmt,
    )
    console.print(
        terminal(
            f"wrote {days * logs_per_day} logs, field.toml, truth.json to {out}", markup=False
        ),
        markup=False,
    )


def _run(logs, config, out, as_json, datasheet=None) -> None:
    import json
    import warnings

    from .._paths import refuse_link
    from ..identify.field import fit_field
    from ..io.fieldlog import load_field_config, read_field_logs
    from ..io.writers import atomic_write_bytes, atomic_write_text

    if not config.is_file():
        raise BadInput(f"--config {config}: no such file")
    refuse_link(out)
    if out.exists() and not out.is_dir():
        raise BadInput(f"--out {out}: exists and is not a folder")
    from .. import _outfolder

    _outfolder.check_reusable(out)  # before the fit: the folder is replaced whole
    inputs = {p.resolve() for p in [*logs, config]}
    names = [FIT_JSON, LOAD_CSV, DATASHEET_CSV, REPORT, *TABLES.values(), *FIGURES]
    clash = [n for n in names if (out / n).resolve() in inputs]
    if clash:
        raise BadInput(f"--out {out}: writing {clash[0]} would overwrite an input file")
    if datasheet is not None and not datasheet.is_file():
        raise BadInput(f"--datasheet {datasheet}: no such file")
    settings = load_field_config(config)
    sheet_model = None
    if datasheet is not None:
        from ..model import FrictionModel

        sheet_model = FrictionModel.from_datasheet(datasheet)
    try:
        records = read_field_logs(logs, settings)
    except ImportError as exc:
        raise BadInput(str(exc)) from None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = fit_field(records, settings)
    document = {
        "format": "cylfric field fit",
        "version": 1,
        "units": "SI: N, N*s/m, N/Pa, kg, m, m/s, Pa",
        "config": str(config),
        "cylinder": {
            "bore [m]": settings.bore,
            "rod [m]": settings.rod,
            "orientation": settings.orientation,
            "sensors": dict(settings.sensors),
        },
        "logs": [
            {"file": str(p), "day": r.day, "kind": r.metadata["kind"]}
            for p, r in zip(logs, records, strict=True)
        ],
        **fit.to_dict(),
        "datasheet": None,
        "warnings": list(dict.fromkeys(str(w.message) for w in caught)),
    }
    comparison = None
    if sheet_model is not None:
        from ..identify.field import compare_datasheet

        comparison = compare_datasheet(fit, sheet_model)
        document["datasheet"] = {"file": str(datasheet), **comparison}
    text = json.dumps(_plain(document), indent=2, allow_nan=False)
    figures = _figures(fit)

    def write(folder: Path) -> None:  # the staging folder, swapped in whole
        atomic_write_text(folder / FIT_JSON, text + "\n")
        tables = {
            "bands": fit.bands,
            "cross_check": fit.cross_check,
            "days": fit.days,
            "changes": fit.changes,
        }
        for key, rows in tables.items():
            atomic_write_text(folder / TABLES[key], _csv_rows(rows))
        atomic_write_text(folder / LOAD_CSV, _curves_csv(fit))
        if comparison is not None:
            atomic_write_text(folder / DATASHEET_CSV, _csv_rows(comparison["points"]))
        for name, png in figures.items():
            atomic_write_bytes(folder / name, png)
        atomic_write_text(folder / REPORT, _report(fit, document, list(figures)))

    from .. import _outfolder

    _outfolder.staged(out, write)  # an out holding files cylfric did not write: refused
    if as_json:
        console.print_json(text)
    else:
        _summary(fit, out)
        if comparison is not None:
            console.print(
                terminal(f"against the datasheet: {comparison['verdict']}", markup=False),
                markup=False,
            )


def _csv_rows(rows) -> str:
    import csv
    import io

    buffer = io.StringIO()
    if not rows:
        return ""
    keys = list(rows[0])
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(keys)
    for row in rows:
        writer.writerow(
            [
                "; ".join(map(str, row[k]))
                if isinstance(row[k], list)
                else (f"{row[k]:.9g}" if isinstance(row[k], float) else row[k])
                for k in keys
            ]
        )
    return buffer.getvalue()


def _curves_csv(fit) -> str:
    lines = ["log,position [m],load [N],load band [N],mass [kg],mass band [kg]"]
    for load, mass in zip(fit.loads, fit.masses, strict=True):
        for i, x in enumerate(load["position [m]"]):
            lines.append(
                f'"{load["log"]}",{x:.6g},{load["load [N]"][i]:.6g},{load["band [N]"][i]:.4g},'
                f"{mass['mass [kg]'][i]:.6g},{mass['band [kg]'][i]:.4g}"
            )
    return "\n".join(lines) + "\n"


def _png(fig) -> bytes:
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return buffer.getvalue()


def _curves_figure(curves, quantity: str, ylabel: str, title: str):
    """One log's curve against rod position per line, with its band: the load [N] or the
    effective mass [kg] of ``fit.loads`` / ``fit.masses``, drawn in kN or t (``1e-3``)."""
    import numpy as np
    from matplotlib.figure import Figure

    from ..escape import plot_text

    unit = quantity.split("[")[1].rstrip("]")  # "N" or "kg": the band's key carries it too
    fig = Figure(figsize=(7, 4.5))
    ax = fig.add_subplot()
    for curve in curves:
        x = 1e3 * np.array(curve["position [m]"])
        y = 1e-3 * np.array(curve[quantity])
        b = 1e-3 * np.array(curve[f"band [{unit}]"])
        ax.plot(x, y, label=plot_text(curve["log"]))
        ax.fill_between(x, y - b, y + b, alpha=0.3)
    ax.set(xlabel="rod position [mm]", ylabel=ylabel, title=title)
    ax.legend(fontsize=7)
    fig.subplots_adjust(left=0.12, right=0.97, top=0.92, bottom=0.12)
    return fig


def _figures(fit) -> dict[str, bytes]:
    import numpy as np
    from matplotlib.figure import Figure

    from ..escape import plot_text

    out: dict[str, bytes] = {}
    if not fit.identified:
        return out
    for name, curves, quantity, ylabel, title in (
        ("load.png", fit.loads, "load [N]", "external load [kN]", "Load against position"),
        ("mass.png", fit.masses, "mass [kg]", "effective mass [t]", "Reflected mass"),
    ):
        out[name] = _png(_curves_figure(curves, quantity, ylabel, title))

    fig = Figure(figsize=(7, 4.5))
    ax = fig.add_subplot()
    speeds = [c["speed [m/s]"] for c in fit.cross_check] or [fit.reference_speed]
    v = np.linspace(0.5 * min(speeds), 1.2 * max(speeds), 100)
    f, half = fit.friction_band(v)
    ax.plot(1e3 * v, f, "k", label="model (extension; retraction mirrored)")
    ax.fill_between(
        1e3 * v, f - half, f + half, color="0.7", alpha=0.5, label=f"{100 * fit.level:.0f} % band"
    )
    if fit.cross_check:
        ax.errorbar(
            [1e3 * c["speed [m/s]"] for c in fit.cross_check],
            [c["friction [N]"] for c in fit.cross_check],
            yerr=[1.96 * c["stderr [N]"] for c in fit.cross_check],
            fmt="o",
            label="cross-check (F_ext - F_ret)/2",
        )
    ax.set(xlabel="speed [mm/s]", ylabel="friction [N]", title="Friction against speed")
    ax.legend(fontsize=7)
    fig.subplots_adjust(left=0.12, right=0.97, top=0.92, bottom=0.12)
    out["friction.png"] = _png(fig)

    if fit.force_check:
        fig = Figure(figsize=(6, 5))
        ax = fig.add_subplot()
        measured = 1e-3 * np.array(fit.force_check["measured [N]"])
        predicted = 1e-3 * np.array(fit.force_check["predicted [N]"])
        ax.plot(measured, predicted, ".", ms=2, alpha=0.4)
        lims = [min(measured.min(), predicted.min()), max(measured.max(), predicted.max())]
        ax.plot(lims, lims, "k", lw=0.8)
        ax.set(
            xlabel="measured piston force p_A A_A - p_B A_B [kN]",
            ylabel="predicted force [kN]",
            title=f"Measured against predicted (RMS {fit.rmse:.3g} N)",
        )
        fig.subplots_adjust(left=0.14, right=0.97, top=0.92, bottom=0.12)
        out["force.png"] = _png(fig)

    fig = Figure(figsize=(7, 4.5))
    ax = fig.add_subplot()
    if fit.days:
        k = np.arange(len(fit.days))
        ax.errorbar(
            k,
            [d["friction [N]"] for d in fit.days],
            yerr=[d["band [N]"] for d in fit.days],
            fmt="o-",
        )
        ax.set_xticks(k, [plot_text(d["day"]) for d in fit.days], rotation=30, fontsize=7)
    ax.set(
        ylabel="friction level [N]",
        title=f"Friction per day at {1e3 * fit.reference_speed:.3g} mm/s",
    )
    fig.subplots_adjust(left=0.12, right=0.97, top=0.92, bottom=0.2)
    out["trend.png"] = _png(fig)
    return out


def _report(fit, document, figures) -> str:
    from ..escape import html_text as h

    def table(rows):
        if not rows:
            return "<p>none</p>"
        keys = list(rows[0])
        head = "".join(f"<th>{h(k)}</th>" for k in keys)
        body = "".join(
            "<tr>"
            + "".join(
                f"<td>{h(f'{r[k]:.5g}' if isinstance(r[k], float) else str(r[k]))}</td>"
                for k in keys
            )
            + "</tr>"
            for r in rows
        )
        return f"<table><tr>{head}</tr>{body}</table>"

    law = document["friction"]["parameters"]
    law_rows = [
        {
            "parameter": k,
            "value": v["value"] if v["value"] is not None else "-",
            "stderr": v["stderr"] if v["stderr"] is not None else "-",
            "unit": v["unit"],
            "status": v["status"],
        }
        for k, v in law.items()
    ]
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>cylfric field fit</title>",
        "<style>body{font-family:sans-serif;max-width:60em;margin:auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}</style></head><body>",
        "<h1>Friction in service</h1>",
        f"<p>{len(document['logs'])} logs; friction law F = sign(v) (F_c + k_p p) + F_v v</p>",
        table(law_rows),
        f"<p>direction asymmetry: {h(fit.status['asymmetry'])}</p>",
        "<h2>Flags</h2>" + ("".join(f"<p>{h(f)}</p>" for f in fit.flags) or "<p>none</p>"),
        "<h2>Friction at the speed bands</h2>",
        table(fit.bands),
        "<h2>Model-free cross-check</h2>",
        table(fit.cross_check),
        "<h2>Against the datasheet</h2>",
        (
            f"<p>{h(str(document['datasheet']['verdict']))}</p>"
            + table(document["datasheet"]["points"])
            if document.get("datasheet")
            else "<p>no datasheet given</p>"
        ),
        "<h2>Trend per day</h2>",
        table(fit.days),
        f"<p>between-day scatter: {h(str(fit.reproducibility.get('source', '-')))}</p>",
        table(fit.changes),
        *[f"<p><img src='{h(name)}' alt='{h(name)}'></p>" for name in figures],
        "<h2>Notes</h2>" + ("".join(f"<p>{h(n)}</p>" for n in fit.notes) or "<p>none</p>"),
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"


SUMMARY_UNITS = {"F_c": ("N", 1.0), "F_v": ("N*s/mm", 1e-3), "k_p": ("N/bar", 1e5)}
"""The summary's engineering units and factors from SI (N, N*s/m, N/Pa): field.json is SI."""


def _summary(fit, out) -> None:
    for name, (unit, factor) in SUMMARY_UNITS.items():
        value, se = fit.parameters[name], fit.stderr[name]
        if value is None:
            console.print(terminal(f"{name}: {fit.status[name]}", markup=False), markup=False)
        else:
            shown = f"{name} = {value * factor:.5g} ± {se * factor:.2g} {unit}"
            console.print(terminal(shown, markup=False), markup=False)
    for c in fit.cross_check:
        console.print(
            f"cross-check at {1e3 * c['speed [m/s]']:.3g} mm/s: {c['friction [N]']:.4g} ± "
            f"{c['stderr [N]']:.2g} N (model {c['model [N]']:.4g} N)"
        )
    for change in fit.changes:
        mark = "CHANGE" if change["significant"] else "no change"
        console.print(
            terminal(
                f"{change['from']} -> {change['to']}: {change['change [%]']:+.3g} % "
                f"(z = {change['z [-]']:.3g}) {mark}",
                markup=False,
            ),
            markup=False,
        )
    for flag in fit.flags:
        console.print(terminal(f"flag: {flag}", markup=False), markup=False)
    console.print(
        terminal(f"wrote {out / FIT_JSON}, tables, figures, {REPORT}", markup=False), markup=False
    )
