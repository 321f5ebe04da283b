"""``cylfric inspect FILE|FOLDER``: what cylfric read from a run file or a campaign.

The columns and their units (as read and as converted), the force balance applied, the
nominal pressure and speed with their sources, the strokes and steady windows, and what
the data-quality gate says; with ``--out``, one PNG per run file of its raw traces with the
windows shaded (:func:`cylfric.report.inspect.figure_run`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.table import Table

from ..escape import terminal
from .common import JSON_HELP, app, console, guarded, print_json, print_table

if TYPE_CHECKING:
    from ..inspect import Inspection, RunInspection


def _value(value: float, scale: float, unit: str) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value / scale:.4g} {unit}"


def _columns_table(run: RunInspection) -> Table:
    table = Table(title=terminal(f"Columns of {run.name}"))
    for title in ("column", "unit read", "taken for", "converted to", "factor", "range"):
        table.add_column(terminal(title), justify="left")
    for c in run.columns:
        table.add_row(
            terminal(c.name),
            terminal(c.unit or "-"),
            terminal(c.quantity or "kept as read (not used)"),
            terminal(c.key),
            f"{c.factor:g}",
            f"{c.minimum:.4g} to {c.maximum:.4g} {terminal(c.si_unit)}",
        )
    return table


def _balance_table(run: RunInspection) -> Table:
    table = Table(title="Force balance applied (eq. 3.1: F_f sign(v) + W = the terms below)")
    for title in ("term", "as applied", "from"):
        table.add_column(title)
    for term in run.force_balance:
        value = term["value"] + ("" if term["applied"] else "  [not applied]")
        table.add_row(terminal(term["term"]), terminal(value), terminal(term["set_in"]))
    if run.windows is not None:
        table.add_row("weight offset W", _value(run.offset, 1.0, "N"), terminal(run.offset_from))
    return table


def _nominal_table(run: RunInspection) -> Table:
    table = Table(title="Nominal pressure and speed (the value used, then every source)")
    for title in ("quantity", "used", "from", "all sources"):
        table.add_column(title)
    for quantity, scale, unit in (("pressure", 1e5, "bar"), ("velocity", 1e-3, "mm/s")):
        used = run.pressure if quantity == "pressure" else run.velocity
        found = run.nominal.get(quantity, {})
        sources = "; ".join(
            f"{source}: {_value(v, scale, unit)} ({where})" for source, (v, where) in found.items()
        )
        source = run.source.get(quantity, "none")
        if quantity == "pressure" and run.pressure_measured:
            source += " (the points' pressure is the pressure column, measured)"
        if quantity == "velocity" and not math.isfinite(used):
            source = "none: the windows use the 90th percentile of |v| as the speed"
        table.add_row(
            "speed" if quantity == "velocity" else quantity,
            _value(used, scale, unit),
            terminal(source),
            terminal(sources or "-"),
        )
    return table


def _windows_table(run: RunInspection) -> Table:
    table = Table(title=terminal(f"Strokes and steady windows of {run.name} (the points of a fit)"))
    titles = (
        "stroke",
        "dir",
        "stroke [s]",
        "window [s]",
        "n",
        "speed [mm/s]",
        "pressure [bar]",
        "force [N]",
        "friction [N]",
        "flag",
    )
    for title in titles:
        table.add_column(terminal(title), justify="right")
    assert run.windows is not None
    for row in run.windows.to_dict("records"):
        start, end = row["window_start [s]"], row["window_end [s]"]
        span = f"{start:.3f}-{end:.3f}" if math.isfinite(start) else "-"
        a, b = row["stroke_start [s]"], row["stroke_end [s]"]
        table.add_row(
            str(row["stroke"]),
            "ext" if row["direction [-]"] > 0 else "ret",
            f"{a:.3f}-{b:.3f}" if math.isfinite(a) else "-",
            span,
            str(row["n [-]"]),
            _value(row["velocity [m/s]"], 1e-3, ""),
            _value(row["pressure [Pa]"], 1e5, ""),
            _value(row["force [N]"], 1.0, ""),
            _value(row["friction [N]"], 1.0, ""),
            terminal(row["flag"]),
        )
    return table


def _runs_table(found: Inspection) -> Table:
    table = Table(title=terminal(f"Runs of {found.campaign.folder}"))
    for title in (
        "file",
        "pressure [bar]",
        "from",
        "speed [mm/s]",
        "from",
        "strokes",
        "ok",
        "offset [N]",
        "gate",
    ):
        table.add_column(terminal(title))
    for run in found.runs:
        source = run.source.get("pressure", "none")
        if run.pressure_measured and run.windows is not None and len(run.windows):
            median = float(run.windows["pressure [Pa]"].median())
            source += f"; points: measured column (median {median / 1e5:.4g} bar)"
        table.add_row(
            terminal(run.name),
            _value(run.pressure, 1e5, ""),
            terminal(source),
            _value(run.velocity, 1e-3, ""),
            terminal(run.source.get("velocity", "-")),
            str(run.strokes),
            str(run.usable),
            _value(run.offset, 1.0, ""),
            terminal(run.verdict),
        )
    return table


def _print(found: Inspection, single: bool) -> None:
    campaign = found.campaign
    console.print(terminal(f"campaign: {campaign.folder}", markup=False), markup=False)
    console.print(terminal(f"configuration: {found.config_source}", markup=False), markup=False)
    readable = [run for run in found.runs if not run.error and run.columns]
    if readable:
        first = readable[0]
        print_table(_columns_table(first))
        print_table(_balance_table(first))
        layout = [(c.name, c.unit) for c in first.columns]
        other = [run.name for run in readable if [(c.name, c.unit) for c in run.columns] != layout]
        if other:
            shown = ", ".join(other[:5]) + (" ..." if len(other) > 5 else "")
            console.print(
                terminal(
                    f"{len(other)} run(s) have other columns or units than {first.name}: "
                    f"{shown} (cylfric inspect FILE shows a file's own)",
                    markup=False,
                ),
                markup=False,
            )
    if single:
        run = found.runs[0]
        if run.columns:
            print_table(_nominal_table(run))
        if run.windows is not None:
            print_table(_windows_table(run))
        console.print(
            terminal(f"quality gate: {run.verdict}", markup=False, multiline=True), markup=False
        )
    else:
        print_table(_runs_table(found))
        for name in campaign.unlisted:
            console.print(terminal(f"not read (not in manifest.csv): {name}", markup=False))
        for copy in campaign.duplicates:
            console.print(terminal(f"not read: {copy.file}: {copy.reason}", markup=False))
    for note in found.gate.notes:
        console.print(terminal(note, markup=False), markup=False)


def _figure_name(name: str) -> str:
    """A run's figure file name in OUT: its path in the campaign, '/' as '__', and .png."""
    return name.replace("/", "__") + ".png"


def _draw(run: RunInspection, out: Path) -> Path | None:
    from .._paths import inside
    from ..report.inspect import figure_run, save_png

    traces = run.traces
    if traces is None or run.windows is None:
        return None
    fig = figure_run(
        traces["time [s]"],
        traces["velocity [m/s]"],
        traces["force [N]"],
        run.windows.to_dict("records"),
        position=traces["position [m]"],
        stroke=traces["stroke [-]"],
        offset=run.offset,
        title=run.name,
        nominal_speed=run.velocity,
    )
    run.traces = None  # drawn: the signals are let go
    return save_png(fig, inside(out, _figure_name(run.name), what="figure name"))


@app.command("inspect")
@guarded
def inspect_command(
    target: Path = typer.Argument(
        ..., help="A run file (in its campaign folder) or a campaign folder (never modified)."
    ),
    out: Path = typer.Option(
        None,
        "--out",
        "-o",
        help="Folder for one PNG per run file: the raw traces with the windows shaded "
        "(without it: the tables only).",
    ),
    config: Path = typer.Option(
        None,
        "--config",
        exists=True,
        dir_okay=False,
        help="campaign.toml to use instead of the campaign folder's (as for fit).",
    ),
    glob: str = typer.Option(
        None, "--glob", help="Which files are runs, e.g. '*.txt' (default: campaign.toml)."
    ),
    no_gate: bool = typer.Option(
        False, "--no-gate", help="Skip the quality gate (it reads the whole campaign)."
    ),
    json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Show what cylfric read: columns and units, force balance, nominal values, strokes,
    steady windows and the quality gate's verdict, for one run file or a whole campaign."""
    from .._paths import make_folder, refuse_link
    from ..inspect import inspect

    folder = None if out is None else refuse_link(out)  # a link refused before any reading
    figures: list[Path] = []

    def draw(run: RunInspection) -> None:
        if folder is not None:
            if not figures:
                make_folder(folder)
            written = _draw(run, folder)
            if written is not None:
                figures.append(written)

    inspection = inspect(
        target, config=config, glob=glob, gate=not no_gate, traces=folder is not None, each=draw
    )
    found = inspection.runs
    if json_output:
        print_json({**inspection.document(), "figures": figures})
    else:
        _print(inspection, single=target.is_file())
        if folder is not None:
            console.print(
                terminal(f"{len(figures)} figure(s) in {folder}", markup=False), markup=False
            )
    bad = inspection.unreadable
    if bad:
        more = f" ({len(bad)} of {len(found)} files unreadable)" if len(found) > 1 else ""
        raise ValueError(bad[0].error + more)
