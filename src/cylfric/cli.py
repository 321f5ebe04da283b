"""The ``cylfric`` command line (typer + rich). No physics here: calls into the library.

Exit codes: 0 success, 2 bad input (one line naming the file and the problem),
1 unexpected error (rerun with ``--debug`` for the traceback).
"""

from __future__ import annotations

import sys

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from . import __version__
from .friction import params_at_pressure, stribeck
from .friction.literature import THESIS_2016

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="cylfric: pressure-dependent friction of hydraulic cylinders.",
)
console = Console()
err_console = Console(stderr=True)
STATE = {"debug": False}


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


def thesis_table() -> Table:
    """The thesis model (eq. 4.1-4.3, alpha = 1, v_r = 10 mm/s) as friction [N] vs v and p."""
    pressures_bar = [0.1, 20.7, 55, 83, 124, 159]
    speeds_mm_s = [1, 2, 5, 10, 25, 50, 100, 135]
    table = Table(title="Thesis model F_f [N] (eq. 2.7 with eq. 4.1-4.3)")
    table.add_column("v [mm/s]", justify="right")
    for p in pressures_bar:
        table.add_column(f"{p:g} bar", justify="right")
    params = params_at_pressure(np.array(pressures_bar) * 1e5, THESIS_2016.coefficients)
    for v in speeds_mm_s:
        forces = stribeck(v * 1e-3, **params)
        table.add_row(f"{v:g}", *(f"{f:.1f}" for f in forces))
    return table


@app.command()
def demo():
    """Show the thesis' pressure-dependent friction model."""
    console.print(thesis_table())


def main() -> None:
    """Console-script entry point with the project's exit-code contract."""
    try:
        app(standalone_mode=True)
    except SystemExit:
        raise
    except Exception as exc:  # pragma: no cover - exercised through subprocess tests
        if STATE["debug"]:
            raise
        err_console.print(f"[red]error:[/red] unexpected {type(exc).__name__}: {exc}")
        err_console.print("rerun with --debug for the traceback")
        sys.exit(1)
