"""What every ``cylfric`` command shares: the typer app, the consoles, the exit-code
contract (:func:`guarded`), option parsers and the progress bar. No physics here.

Exit codes: 0 success; 2 bad input (one line naming the file and the problem, no
traceback); 1 unexpected error (rerun with ``--debug`` for the traceback).
Unit-bearing options accept units (``10mm/s``, ``55bar``, ``5MPa``); bare numbers are read in
bar, mm/s, s, kg, N/m as each option's help says.
"""

from __future__ import annotations

import functools
import math
import re
import sys
import traceback
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from rich.text import Text

from .._version import __version__
from ..escape import terminal
from ..units import UnitError, parse_quantity

app = typer.Typer(
    add_completion=True,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="cylfric: pressure-dependent friction of hydraulic cylinders.",
)
console = Console(emoji=False)  # ":smile:" in a user's name stays text
err_console = Console(stderr=True, emoji=False)
STATE = {"debug": False}

BAD_INPUT_EXIT = 2
UNEXPECTED_EXIT = 1


class BadInput(ValueError):
    """A command-line value is wrong (exit code 2)."""


def _version(value: bool):
    if value:
        console.print(f"cylfric {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
    debug: bool = typer.Option(False, "--debug", help="Show tracebacks of unexpected errors."),
):
    STATE["debug"] = debug


def guarded(command):
    """Map errors to the exit-code contract: bad input 2 (one line), unexpected 1."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except (typer.Exit, typer.Abort, SystemExit):
            raise
        except ValueError as exc:  # BenchFileError, DatasheetError, UnitError, BadInput, ...
            if STATE["debug"]:
                traceback.print_exc()
            err_console.print(
                terminal(f"error: {exc}", markup=False, multiline=True),
                markup=False,
                highlight=False,
                soft_wrap=True,
            )
            raise typer.Exit(BAD_INPUT_EXIT) from None
        except OSError as exc:  # the file, the action when known, the system's reason
            from .._paths import os_error_message

            if STATE["debug"]:
                traceback.print_exc()
            err_console.print(
                terminal(f"error: {os_error_message(exc)}", markup=False),
                markup=False,
                soft_wrap=True,
            )
            raise typer.Exit(BAD_INPUT_EXIT) from None
        except Exception as exc:  # noqa: BLE001 - the contract: never a bare traceback
            if STATE["debug"]:
                traceback.print_exc()
            err_console.print(
                terminal(f"error: unexpected {type(exc).__name__}: {exc}", markup=False),
                markup=False,
                soft_wrap=True,
            )
            err_console.print("rerun with --debug for the traceback")
            raise typer.Exit(UNEXPECTED_EXIT) from None

    return wrapper


def _numbers(text: str, dimension: str, unit: str) -> list[float]:
    """``"10,55,159"`` or ``"1MPa,5MPa"`` -> SI floats (bare numbers in ``unit``)."""
    try:
        return [
            parse_quantity(part, dimension, default_unit=unit)
            for part in text.split(",")
            if part.strip()
        ]
    except UnitError as exc:
        raise BadInput(f"{text!r}: {exc}") from None


def _fixed(options: list[str]) -> dict:
    """``alpha=1``, ``v_r=10mm/s``, ``F_c=70N``, ``sigma_2=0.34N*s/mm`` -> SI dict."""
    dims = {
        "alpha": ("dimensionless", "-"),
        "v_r": ("velocity", "mm/s"),
        "F_c": ("force", "N"),
        "F_s": ("force", "N"),
        "sigma_2": ("damping", "N*s/mm"),
    }
    out = {}
    # 'alpha=1,v_r=10mm/s': split at commas that start a NAME= (not at decimal commas)
    items = [part for option in options for part in re.split(r",(?=\s*[A-Za-z_]\w*\s*=)", option)]
    for item in items:
        name, _, value = item.partition("=")
        name = name.strip()
        if name not in dims or not value:
            raise BadInput(
                f"--fix {item!r}: expected NAME=VALUE with NAME one of "
                f"{sorted(dims)} (e.g. --fix alpha=1 --fix v_r=10mm/s)"
            )
        dim, unit = dims[name]
        try:
            out[name] = parse_quantity(value, dim, default_unit=unit)
        except UnitError as exc:
            raise BadInput(f"--fix {item!r}: {exc}") from None
        _check_fixed(item, name, out[name], unit)
    if out.get("F_s", math.inf) < out.get("F_c", 0.0):
        raise BadInput(
            f"--fix F_s={out['F_s']:g}N is below --fix F_c={out['F_c']:g}N; expected "
            "F_s >= F_c (the static friction is at least the Coulomb friction)"
        )
    return out


def _check_fixed(item: str, name: str, value: float, unit: str):
    """Refuse a held value the model cannot have (v_r = 0, alpha < 0.2, F_c < 0, NaN)."""
    from ..model.names import PARAMETER_BOUNDS
    from ..units import from_si

    low, high = PARAMETER_BOUNDS[name]
    if math.isfinite(value) and low <= value <= high and (value > 0 or name != "v_r"):
        return
    shown = unit if unit != "-" else ""
    expected = f"{from_si(low, unit):g}" + (
        f" to {from_si(high, unit):g} {shown}" if math.isfinite(high) else f" {shown} or more"
    )
    raise BadInput(
        f"--fix {item!r}: {name} = {from_si(value, unit):g} {shown} is out of range; expected "
        f"{expected.strip()}".replace("  ", " ")
    )


class _ThreadlessProgress(Progress):
    """A rich progress bar redrawn by ``advance`` (at most 10 times a second), not by a thread.

    rich's own refresh thread would keep the process from forking its second extraction
    worker and its figure worker (they fork only in a single-threaded process).
    """

    def advance(self, task_id, advance=1):
        super().advance(task_id, advance)
        now = self.get_time()
        if now - getattr(self, "_drawn", 0.0) >= 0.1 or self.finished:
            self._drawn = now
            self.refresh()


class _RateColumn(ProgressColumn):
    """Items per second (``unit`` a field of the task: ``add_task(..., unit="runs")``), from
    rich's estimate over the last 30 s; blank for the first second and when finished."""

    def render(self, task) -> Text:
        speed = task.finished_speed or task.speed
        if speed is None or task.elapsed is None or task.elapsed < 1.0:
            return Text("")
        unit = task.fields.get("unit", "")
        return Text(f"{speed:,.0f} {unit}/s".replace("  ", " "), style="progress.data.speed")


def _progress():
    return _ThreadlessProgress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        _RateColumn(),
        TimeElapsedColumn(),
        TextColumn("eta"),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
        auto_refresh=False,
        disable=not err_console.is_terminal,
    )


def _summary_table(sheet: dict, title="Friction datasheet") -> Table:
    from ..model import FrictionModel

    model = FrictionModel.from_datasheet(sheet)
    table = Table(title=title, show_header=False)
    table.add_column("", style="bold")
    table.add_column("")
    for line in model.law_lines():
        name, sep, rest = line.partition(" = ")
        if not sep:
            name, _, rest = line.partition(": ")
        table.add_row(terminal(name), terminal(rest))
    fit = sheet["fit"]
    if fit.get("rmse") is not None:
        table.add_row("RMSE", f"{fit['rmse']:.3f} N over {fit.get('n_points', '?')} points")
    offset = sheet.get("offset")
    table.add_row("load-cell offset", "n/a" if offset is None else f"{offset:.2f} N")
    val = sheet["validity"]
    if val is not None:
        table.add_row(
            "valid for",
            f"{val['pressure_min'] / 1e5:.3g}-{val['pressure_max'] / 1e5:.3g} "
            f"bar, {val['velocity_min'] * 1e3:.3g}-"
            f"{val['velocity_max'] * 1e3:.3g} mm/s",
        )
    for name, (status, reason) in model.dynamic_status.items():
        value, _, unit = (
            model.parameters[name].engineering()
            if name in model.parameters
            else (
                None,
                None,
                "",
            )
        )
        text = f"{value:.4g} {unit}" if value is not None else "pressure dependent"
        table.add_row(name, terminal(f"{text} ({status}: {reason})"))
    table.add_row("method", terminal(fit["method"]))
    return table


_NUMBER = re.compile(r"[-+]?(\d[\d.,]*|\.\d+)([eE][-+]?\d+)?")
"""A number as the tables show it (``70.18``, ``-3.2e-05``, ``1.5-7``: ranges are split)."""


def _numeric(text: str) -> bool:
    parts = [p for p in re.split(r"\s*(?:±|\+/-|(?<=\d)-(?=\d)| )\s*", text.strip()) if p]
    return bool(parts) and all(_NUMBER.fullmatch(p) or p in ("-", "n/a") for p in parts)


def print_table(table: Table) -> None:
    """Print ``table`` without ever cutting a number: columns of numbers do not wrap and keep
    their full width, text columns wrap (at most 20 characters kept together), and the table
    is printed wider than the terminal when it needs to be."""
    from rich.measure import Measurement

    for column in table.columns:
        cells = [str(c) for c in column.cells]
        header = str(column.header)
        if cells and all(_numeric(c) for c in cells if c.strip()):
            column.no_wrap = True
            column.min_width = max(len(c) for c in [*cells, header])
        else:
            words = [w for c in [*cells, header] for w in c.split()]
            column.min_width = min(20, max((len(w) for w in words), default=1))
    measure = Measurement.get(console, console.options.update_width(10_000), table)
    if measure.minimum > console.width:
        # the natural width when it is not absurd, else the least that keeps every number
        # (with a little room: rich's minimum can leave the last column no width at all)
        natural = measure.maximum <= max(2 * console.width, 160)
        width = measure.maximum if natural else measure.minimum + 2 * len(table.columns)
        saved = console._width  # rich lays a table out by the console's own width
        console.width = width
        try:
            console.print(table, crop=False)
        finally:
            console._width = saved
    else:
        console.print(table)


def print_json(document: object) -> None:
    """``document`` as JSON on standard output (``--json``): plain numbers in SI unless a
    key names another unit, NaN as null, no markup or colour."""
    import json

    sys.stdout.write(json.dumps(_plain(document), indent=1, allow_nan=False) + "\n")
    sys.stdout.flush()


def _plain(value: object) -> object:
    """JSON-ready: numpy scalars as numbers, NaN/inf as None, paths as text."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "item") and not isinstance(value, str | bytes):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


def model_document(model) -> dict:
    """A FrictionModel for ``--json``: its laws as text and every coefficient in SI with its
    unit, standard error, pressure law and status; the validity ranges in SI."""
    table = model.to_pandas()
    parameters = {
        name: {
            "law": row["law"],
            "value": row["value"],
            "stderr": row["stderr"],
            "unit": row["unit"],
            "status": row["status"],
        }
        for name, row in table.iterrows()
    }
    return {
        "name": model.record.get("name"),
        "friction_law": model.friction_law,
        "pressure_reference": model.reference,
        "laws": model.law_lines(),
        "parameters": parameters,
        "validity": dict(model.validity) if model.validity is not None else None,
        "rmse [N]": model.statistics.get("rmse"),
    }


JSON_HELP = "Print a JSON document on standard output instead of tables (for scripts)."

# public names for the command modules
progress_bar = _progress
numbers = _numbers
fixed_parameters = _fixed
summary_table = _summary_table

__all__ = [
    "app",
    "console",
    "err_console",
    "guarded",
    "BadInput",
    "progress_bar",
    "numbers",
    "fixed_parameters",
    "summary_table",
    "print_table",
    "print_json",
    "JSON_HELP",
    "model_document",
]
