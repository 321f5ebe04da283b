"""``cylfric identify-axis LOG``: LuGre sigma_0 and sigma_1 from a logged motion of the axis."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import BadInput, _plain, app, console, guarded

DATASHEET = "datasheet.json"
FIT_JSON = "axis_fit.json"
SIGNALS_CSV = "axis_signals.csv"


@app.command("identify-axis")
@guarded
def identify_axis_command(
    log: Path = typer.Argument(
        ...,
        help="The axis log: a CSV (or bench text) file with units in the header: 'time [s]', "
        "'position [mm]', 'pressure_a [bar]', 'pressure_b [bar]', optionally 'command [-]' "
        "(never modified).",
    ),
    datasheet: Path = typer.Option(
        ..., "--datasheet", "-d", help="The seal's datasheet.json: its steady-state law is kept."
    ),
    axis: Path = typer.Option(
        ..., "--axis", help="axis.toml of the logged axis (areas from bore and rods, mass)."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder (a link is refused)."),
    fit_mass: bool = typer.Option(
        False, "--fit-mass", help="Fit the moving mass too (default: axis.toml's)."
    ),
):
    """Identify sigma_0 and sigma_1 on the axis from a short logged motion (no load cell).

    The piston force comes from the chamber pressures and the areas; sigma_0, sigma_1, a
    force offset and a friction level are fitted to force - m a with the datasheet's
    steady-state law (docs/dynamic_parameters.md says what to log). Writes datasheet.json
    (the datasheet with sigma_0 and sigma_1 "identified" and an axis_fit record with their
    standard errors), axis_fit.json and axis_signals.csv. A log without a presliding regime
    is refused with exit 2 and a message saying what to record.
    """
    _run(log, datasheet, axis, out, fit_mass)


def _check_paths(log: Path, datasheet: Path, axis: Path, out: Path) -> None:
    from .._paths import refuse_link

    for path, what in ((log, "LOG"), (datasheet, "--datasheet"), (axis, "--axis")):
        if not path.is_file():
            raise BadInput(f"{what} {path}: no such file")
    refuse_link(out)
    if out.exists() and not out.is_dir():
        raise BadInput(f"--out {out}: exists and is not a folder")
    inputs = {p.resolve() for p in (log, datasheet, axis)}
    clash = [n for n in (DATASHEET, FIT_JSON, SIGNALS_CSV) if (out / n).resolve() in inputs]
    if clash:
        raise BadInput(f"--out {out}: writing {clash[0]} would overwrite an input file")


def _run(log: Path, datasheet: Path, axis_path: Path, out: Path, fit_mass: bool) -> None:
    import json

    from .._paths import make_folder
    from ..control.axis import load_axis
    from ..identify.axis_identify import axis_log, fit_axis_lugre
    from ..io.text import read_bench_arrays
    from ..io.writers import atomic_write_text
    from ..model import FrictionModel
    from ..model.serialize import validate

    _check_paths(log, datasheet, axis_path, out)
    model = FrictionModel.from_datasheet(datasheet)
    the_axis = load_axis(axis_path)
    data, _ = read_bench_arrays(log)
    record = axis_log(data, source=str(log))
    fit = fit_axis_lugre(record, model, the_axis, fit_mass=fit_mass)
    summary = fit.summary()
    sheet = fit.model.to_datasheet()
    sheet["axis_fit"] = summary
    plain = _plain(sheet)
    assert isinstance(plain, dict)
    sheet = validate(plain, source=f"{out / DATASHEET}")
    make_folder(out)
    atomic_write_text(out / DATASHEET, json.dumps(sheet, indent=2, allow_nan=False) + "\n")
    atomic_write_text(out / FIT_JSON, json.dumps(_plain(summary), indent=2, allow_nan=False) + "\n")
    atomic_write_text(out / SIGNALS_CSV, _csv(fit.signals))
    for line in fit.report().splitlines():
        console.print(terminal(line, markup=False), markup=False)
    console.print(
        terminal(f"wrote {out / DATASHEET}, {FIT_JSON}, {SIGNALS_CSV}", markup=False),
        markup=False,
    )


def _csv(columns: dict) -> str:
    import io

    import numpy as np

    buffer = io.StringIO()
    buffer.write(",".join(f'"{n}"' for n in columns) + "\n")
    np.savetxt(buffer, np.column_stack(list(columns.values())), delimiter=",", fmt="%.9g")
    return buffer.getvalue()
