"""The ``cylfric`` command line (typer + rich). No physics here: it calls the library.

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
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from . import __version__
from .escape import terminal
from .options import FitOptions
from .units import UnitError, parse_quantity

if TYPE_CHECKING:
    from .pipeline import FitOutputs

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
            from ._paths import os_error_message

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
    from .model.core import PARAMETER_BOUNDS
    from .units import from_si

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


def _progress():
    return _ThreadlessProgress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=err_console,
        transient=True,
        auto_refresh=False,
        disable=not err_console.is_terminal,
    )


def _summary_table(sheet: dict, title="Friction datasheet") -> Table:
    from .model import FrictionModel

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


def run_fit(
    campaign: Path, out: Path, options: FitOptions | None = None, *, quiet: bool = False
) -> FitOutputs:
    """Shared by ``fit`` and ``demo``: the pipeline with a progress bar and a summary."""
    from .io.campaign import Campaign, check_glob
    from .pipeline import fit_campaign

    options = options or FitOptions()
    if options.glob is not None:
        check_glob(options.glob, campaign, key="--glob")
    opened = Campaign.open(campaign, options.glob)  # read once, passed down to every step
    n_files = len(opened.steady_runs)  # the bar counts these (not presliding/breakaway tests)
    progress = _progress()
    task = progress.add_task(terminal(f"reading {campaign.name}"), total=n_files)
    # warnings reach the user once, as the notes printed below (not as Python's own lines)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        progress.start()
        try:
            result = fit_campaign(
                opened,
                out,
                options,
                progress=lambda _: progress.advance(task),
                after_extraction=progress.stop,
            )
        finally:
            progress.stop()
    if not quiet:
        console.print(_summary_table(result.datasheet))
        skipped = result.extraction.skipped
        if skipped:
            console.print(f"[yellow]{len(skipped)} file(s) skipped[/yellow] (see skipped.csv):")
            for item in skipped[:10]:
                console.print(terminal(f"  {item['reason']}", markup=False), markup=False)
        excluded = result.excluded
        if excluded is not None and len(excluded):
            console.print(f"[yellow]{len(excluded)} run(s) excluded[/yellow] (see excluded.csv):")
            for _, item in excluded.head(10).iterrows():
                console.print(
                    terminal(f"  {item['file']}: {item['reason']}", markup=False), markup=False
                )
        for note in result.identification.notes:
            console.print(f"[yellow]note:[/yellow] {terminal(note)}")
        for exported in result.exports.values():
            console.print(
                terminal(exported.summary(), markup=False, multiline=True),
                markup=False,
                highlight=False,
            )
        opened = f"; open {out / 'report.html'}" if options.report else ""
        console.print(terminal(f"outputs in {out}{opened}", markup=False), markup=False)
    return result


@app.command()
@guarded
def fit(
    campaign: Path = typer.Argument(..., help="Folder of raw bench files (never modified)."),
    out: Path = typer.Option(Path("cylfric-out"), "--out", "-o", help="Output folder."),
    fix: list[str] = typer.Option(
        [], "--fix", help="Hold parameters: --fix alpha=1,v_r=10mm/s (or repeat --fix)."
    ),
    pressure_law: str = typer.Option(
        "linear",
        "--pressure-law",
        "--law",
        help="Pressure law of F_c, F_s, sigma_2: linear, quadratic, exponential.",
    ),
    per_direction: bool = typer.Option(
        False, "--per-direction", help="Also fit extension and retraction separately."
    ),
    skip_bad: bool = typer.Option(False, "--skip-bad", help="Skip unreadable files."),
    no_report: bool = typer.Option(False, "--no-report", help="No figures or report.html."),
    glob: str = typer.Option(
        None, "--glob", help="Which files are runs, e.g. '*.txt' (default: campaign.toml)."
    ),
    strict: bool = typer.Option(
        False, "--strict", help="Stop (exit 2) instead of excluding runs the quality gate flags."
    ),
    export: str = typer.Option(
        None,
        "--export",
        help="Also export to simulators into OUT/export/<target>: e.g. fmu,simscape "
        "(fmu, modelica, simscape, hopsan, matlab).",
    ),
    viscosity_correction: bool = typer.Option(
        None,
        "--viscosity-correction/--no-viscosity-correction",
        help="Identify at campaign.toml [oil] reference_temperature, each run's speeds "
        "mapped by its oil viscosity (default: on when [oil] and run temperatures are given).",
    ),
):
    """Raw bench files -> datasheet.json, tables, figures and report.html."""
    if not campaign.is_dir():
        raise BadInput(f"{campaign}: not a folder; expected a campaign folder of run files")
    targets: list[str] = []
    if export is not None:
        from .export import parse_targets, resolve

        try:
            targets = parse_targets(export)
            for target in targets:  # fail before the fit, not after it
                resolve(target)
        except (ValueError, ImportError) as exc:
            raise BadInput(f"--export {export!r}: {exc}") from None
    options = FitOptions(
        fixed=_fixed(list(fix)),
        pressure_law=pressure_law,
        per_direction=per_direction,
        skip_bad=skip_bad,
        report=not no_report,
        glob=glob,
        strict=strict,
        export=tuple(targets),
        viscosity_correction=viscosity_correction,
    )
    run_fit(campaign, out, options)


THESIS_VALUES = {
    "F_c": (70.2, 0.5, "N"),
    "F_s": (112.9, 0.6, "N"),
    "sigma_2": (0.34, 8e-4, "N*s/mm"),
}


@app.command()
@guarded
def demo(
    out: Path = typer.Option(Path("cylfric-demo"), "--out", "-o", help="Output folder."),
    seed: int = typer.Option(0, "--seed", help="Seed of the virtual campaign."),
):
    """Generate the thesis' virtual campaign (10 pressures x 27 speeds) and fit it.

    Writes the raw files to OUT/campaign (regenerated on every run) and the fit to OUT/fit.
    """
    from ._paths import refuse_link
    from .simulate.bench import BenchSettings, generate_campaign

    refuse_link(out)  # a symbolic link is refused (exit 2), not written through
    settings = BenchSettings(seed=seed)
    campaign = out / "campaign"
    n = len(settings.pressures_bar) * len(settings.speeds_mm_s)
    with _progress() as progress:
        task = progress.add_task("virtual bench", total=n)
        generate_campaign(campaign, settings, progress=lambda _: progress.advance(task))
    console.print(terminal(f"virtual campaign: {n} files in {campaign}"))
    result = run_fit(campaign, out / "fit", FitOptions(), quiet=True)
    sheet = result.datasheet
    console.print(_summary_table(sheet, "Recovered from the virtual campaign"))
    table = Table(title="Recovered against the thesis (eq. 4.1-4.3, alpha, v_r; p in bar)")
    for col in ("parameter", "thesis", "recovered"):
        table.add_column(col, justify="right")
    params = sheet["parameters"]
    for name, (a, b, unit) in THESIS_VALUES.items():
        k = 1e-3 if name == "sigma_2" else 1.0
        c = params[name]
        table.add_row(
            name,
            f"{a:g} + {b:g} p {unit}",
            f"{c['intercept'] * k:.4g} + {c['slope'] * k * 1e5:.3g} p {unit}",
        )
    table.add_row("alpha", "1", f"{params['alpha']:.3f}")
    table.add_row("v_r", "10 mm/s", f"{params['v_r'] * 1e3:.2f} mm/s")
    table.add_row("offset", f"{35.67 / 2:.2f} N (35.67 N up-down)", f"{sheet['offset']:.2f} N")
    console.print(table)
    console.print(terminal(f"report: {out / 'fit' / 'report.html'}"))


@app.command()
@guarded
def show(datasheet: Path = typer.Argument(..., help="A datasheet.json file.")):
    """Summarise a datasheet."""
    from .datasheet import read_datasheet
    from .model import FrictionModel

    sheet = read_datasheet(datasheet)
    title = terminal(f"Friction datasheet {sheet.get('name', '')}")
    console.print(_summary_table(sheet, title))
    report = FrictionModel.from_datasheet(sheet).fit_report(min_correlation=0.3)
    console.print(terminal(report, markup=False, multiline=True), markup=False, highlight=False)
    rows = sheet.get("per_pressure", [])
    if rows:
        table = Table(title="Per pressure (thesis Table 4.1 layout)")
        for col in (
            "p [bar]",
            "F_s [N]",
            "F_c [N]",
            "sigma_2 [N*s/mm]",
            "v_Stribeck [mm/s]",
            "RMSE [N]",
            "n",
        ):
            table.add_column(terminal(col), justify="right")  # "[bar]" is not rich markup
        for r in rows:
            vs = r.get("stribeck_velocity")
            table.add_row(
                f"{r['pressure'] / 1e5:.3g}",
                "-" if r["F_s"] is None else f"{r['F_s']:.1f}",
                f"{r['F_c']:.1f}",
                "-" if r["sigma_2"] is None else f"{r['sigma_2'] / 1e3:.3f}",
                "-" if vs is None else f"{vs * 1e3:.1f}",
                f"{r['rmse']:.2f}",
                str(r["n_points"]),
            )
        console.print(table)


@app.command()
@guarded
def generate(
    out_dir: Path = typer.Argument(..., help="Folder to write the campaign into."),
    pressures: str = typer.Option(
        None, "--pressures", help="Pressures, bar or with units (default: the thesis' 10 levels)."
    ),
    speeds: str = typer.Option(
        None, "--speeds", help="Speeds, mm/s or with units (default: 27 speeds 1-135 mm/s)."
    ),
    seed: int = typer.Option(0, "--seed", help="Random seed (deterministic output)."),
    decimal_comma: bool = typer.Option(False, "--decimal-comma", help="Write 0,017 not 0.017."),
    pressure_channel: bool = typer.Option(
        False, "--pressure-channel", help="Add a measured pressure column."
    ),
    force: bool = typer.Option(
        False, "--force", help="Write into a folder that already holds files (overwriting)."
    ),
    tests: str = typer.Option(
        "constant-velocity",
        "--tests",
        help="Tests to write, comma-separated: constant-velocity, presliding, breakaway "
        "(force-controlled, for sigma_0 and sigma_1), or all.",
    ),
):
    """Virtual test bench: write a campaign of raw files and manifest.csv."""
    from ._paths import refuse_link

    refuse_link(out_dir, "OUT_DIR")  # a symbolic link is refused, not written through
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())) and not force:
        raise BadInput(
            f"{out_dir} is not empty; generate writes raw files and manifest.csv that would "
            "overwrite what is there: choose an empty folder or add --force"
        )
    from .simulate.bench import TESTS, BenchSettings, DynamicTestSettings, generate_campaign

    chosen = [t.strip() for t in tests.split(",") if t.strip()]
    chosen = list(TESTS) if chosen == ["all"] else chosen
    unknown = [t for t in chosen if t not in TESTS]
    if unknown or not chosen:
        raise BadInput(
            f"--tests {tests!r}: unknown test(s) {unknown}; valid: {', '.join(TESTS)}, all"
        )
    kwargs = {"seed": seed, "decimal_comma": decimal_comma, "pressure_channel": pressure_channel}
    if pressures:
        kwargs["pressures_bar"] = tuple(p / 1e5 for p in _numbers(pressures, "pressure", "bar"))
    if speeds:
        kwargs["speeds_mm_s"] = tuple(v * 1e3 for v in _numbers(speeds, "velocity", "mm/s"))
    if any(v <= 0 for v in kwargs.get("speeds_mm_s", (1,))):
        raise BadInput("--speeds must be > 0")
    if any(p < 0 for p in kwargs.get("pressures_bar", (0,))):
        raise BadInput("--pressures must be >= 0")
    settings = BenchSettings(**kwargs)
    n = len(settings.pressures_bar) * len(settings.speeds_mm_s) * ("constant-velocity" in chosen)
    rates = len(DynamicTestSettings().breakaway_rates)
    n += len(settings.pressures_bar) * (("presliding" in chosen) + rates * ("breakaway" in chosen))
    with _progress() as progress:
        task = progress.add_task("virtual bench", total=n)
        info = generate_campaign(
            out_dir, settings, progress=lambda _: progress.advance(task), tests=chosen
        )
    console.print(
        terminal(
            f"wrote {len(info['files'])} files and manifest.csv to {out_dir} "
            f"({info['steps']:.3g} simulated steps)"
        )
    )


DRIVES = ("spring", "sine", "ramp-force", "servo-step")


@app.command()
@guarded
def simulate(
    model: str = typer.Argument(
        ..., help="A datasheet.json or a literature set name (thesis_2016, thesis_2016_revised)."
    ),
    out: Path = typer.Option(Path("cylfric-sim"), "--out", "-o", help="Output folder."),
    drive: str = typer.Option("spring", "--drive", help=f"One of {', '.join(DRIVES)}."),
    pressure: str = typer.Option("50bar", "--pressure", help="Chamber pressure (bar)."),
    speed: str = typer.Option("5mm/s", "--speed", help="Spring speed or sine amplitude."),
    duration: str = typer.Option("10s", "--duration", help="Simulated time."),
    mass: str = typer.Option("10kg", "--mass", help="Moving mass."),
    stiffness: str = typer.Option("2e4", "--stiffness", help="Spring or servo stiffness (N/m)."),
    sigma_0: str = typer.Option(
        None,
        "--sigma-0",
        help="Bristle stiffness (N/m); default: the model's (sigma_1 = sqrt(sigma_0 m) then).",
    ),
    max_output_gib: float = typer.Option(
        1.0,
        "--max-output-gib",
        help="Refuse (exit 2) before allocating when the outputs would exceed this many GiB "
        "(samples every 1 ms x 8 signals x 8 bytes: 1 GiB is about 4.6 h simulated).",
    ),
):
    """Simulate a cylinder with dynamic LuGre friction; writes simulation.csv and a figure.

    Outputs every 1 ms; their size is estimated before the run and a simulation above
    --max-output-gib (default 1 GiB) is refused with exit 2: shorten --duration or raise
    the limit.
    """
    import numpy as np

    from .friction.literature import LITERATURE
    from .io.writers import atomic_write_text
    from .model import FrictionModel
    from .report.figures import save_figure
    from .simulate import (
        AppliedForce,
        Cylinder,
        PositionServo,
        PrescribedMotion,
        SpringPull,
    )
    from .simulate import simulate as run_simulation

    if Path(model).is_file():
        friction = FrictionModel.from_datasheet(model)
    elif model in LITERATURE and LITERATURE[model].coefficients:
        friction = FrictionModel(dict(LITERATURE[model].coefficients))
    else:
        sets = sorted(k for k, s in LITERATURE.items() if s.coefficients)
        raise BadInput(f"{model!r}: not a datasheet file nor a literature set; valid sets: {sets}")
    p = parse_quantity(pressure, "pressure", "bar")
    v = parse_quantity(speed, "velocity", "mm/s")
    t_end = parse_quantity(duration, "time", "s")
    m = parse_quantity(mass, "mass", "kg")
    k = parse_quantity(stiffness, "stiffness", "N/m")
    if drive not in DRIVES:
        raise BadInput(f"--drive {drive!r}: expected one of {list(DRIVES)}")
    if sigma_0 is not None:
        s0 = parse_quantity(sigma_0, "stiffness", "N/m")
        if not s0 > 0:
            raise BadInput("--sigma-0 must be > 0")
        friction = friction.replace(sigma_0=s0, sigma_1=math.sqrt(s0 * m))
    if not (m > 0 and k > 0 and t_end > 0):
        raise BadInput("--mass, --stiffness and --duration must be > 0")
    from ._paths import make_folder, refuse_link

    refuse_link(out)  # before the simulation: a symbolic link is refused, not written through
    params = friction.params_at(friction.operating_pressure(p))
    drives = {
        "spring": lambda: SpringPull(k, v),
        "sine": lambda: PrescribedMotion(lambda t: v * np.sin(2 * np.pi * t)),
        "ramp-force": lambda: AppliedForce(lambda t: 2 * params["F_s"] * t / t_end),
        "servo-step": lambda: PositionServo(
            lambda t: 0.01 * (t > 0.1), kp=k, kd=2 * math.sqrt(k * m), ki=k
        ),
    }
    # warnings reach the user once each, as notes (not as Python's own lines with a path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = run_simulation(
                Cylinder(m),
                friction,
                drives[drive](),
                t_end,
                pressure_a=p,
                max_output_bytes=max_output_gib * 2**30,
            )
        except ValueError as exc:  # e.g. a law extrapolated below 0 outside its validity
            named = str(exc).startswith(model) or not Path(model).is_file()
            raise BadInput(str(exc) if named else f"{model}: {exc}") from None
    for note in dict.fromkeys(str(w.message) for w in caught):
        console.print(f"[yellow]note:[/yellow] {terminal(note)}")
    frame = result.to_pandas()
    make_folder(out)
    atomic_write_text(out / "simulation.csv", frame.to_csv(index=False))
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 7), constrained_layout=True)
    result.plot(ax=axes)
    fig.suptitle(f"{drive} at {p / 1e5:g} bar ({model})")
    save_figure(fig, out, "simulation")
    f = result.outputs["friction_force"]
    console.print(
        terminal(
            f"{drive}: {len(frame)} samples over {t_end:g} s; friction {f.min():.1f} to "
            f"{f.max():.1f} N; wrote {out / 'simulation.csv'} and simulation.png/svg"
        )
    )


# public names for the command modules in cylfric/commands/
progress_bar = _progress
numbers = _numbers
fixed_parameters = _fixed


def _register_commands() -> None:
    from .commands import register_all

    register_all(app)


_register_commands()


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except SystemExit:
        raise
    except Exception as exc:  # pragma: no cover - typer's own failures
        err_console.print(
            terminal(f"error: unexpected {type(exc).__name__}: {exc}", markup=False),
            markup=False,
        )
        err_console.print("rerun with --debug for the traceback")
        sys.exit(UNEXPECTED_EXIT)


def console_main() -> None:
    """The ``cylfric`` command (console script): :func:`main`, then a quick exit.

    Once the command is done (its outputs written and closed), its objects are frozen (the
    final collections skip them), the exit handlers run and the process ends with the
    command's exit code without tearing down the interpreter's modules (numba, scipy, pandas:
    about 0.3 s of a ``cylfric fit`` together). With threads of its own still running it
    exits the usual way, still frozen. :func:`main` itself, for use in-process, does neither.
    """
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code
    _freeze_for_exit()
    _exit_now(code)


def _exit_now(code):
    """End the process with ``code`` as SystemExit would, skipping the interpreter's
    teardown when no other non-daemon thread runs; exit handlers and stream flushes first."""
    import atexit
    import contextlib
    import os
    import threading

    if code is None:
        status = 0
    elif isinstance(code, int):
        status = code
    else:  # SystemExit("message"): printed, exit status 1
        print(code, file=sys.stderr)
        status = 1
    main_thread = threading.main_thread()
    if any(t is not main_thread and not t.daemon for t in threading.enumerate()):
        sys.exit(status)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # a closed pipe (cylfric ... | head)
            stream.flush()
    os._exit(status)


def _freeze_for_exit():
    """Spare the interpreter's last garbage collections over everything numba, scipy and
    pandas loaded (0.2 s of a `cylfric fit` on 144 files, measured): the command's work is
    done and written, so its objects move to the permanent generation, which the collector
    skips; exit handlers still run."""
    import gc

    gc.freeze()


__all__ = ["app", "main", "console_main", "run_fit"]
