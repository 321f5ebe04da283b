"""``cylfric generate`` and ``simulate``: the virtual test bench and the simulator."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from ..escape import plot_text, terminal
from ..units import parse_quantity
from .common import BadInput, _numbers, _progress, app, console, err_console, guarded

if TYPE_CHECKING:
    from collections.abc import Callable


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
    clean: bool = typer.Option(
        False,
        "--clean",
        help="A clean bench (cylfric's bench before issue 22): no run, pressure or session "
        "scatter, warm-up, start-up transients, load-cell offset or quantisation.",
    ),
    sessions: int = typer.Option(
        1, "--sessions", help="Sessions (remounts), each a full pass of the runs: s1_..., s2_..."
    ),
    session_seed: int = typer.Option(
        None, "--session-seed", help="Seed of the session effects (default: --seed)."
    ),
    run_seed: int = typer.Option(
        None, "--run-seed", help="Seed of the run-to-run effects (default: --seed)."
    ),
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
    """Virtual test bench: write a campaign of raw files and manifest.csv.

    By default the bench is as rough as a real rig (levels measured on the shared Zillen
    data, see docs/simulation.md): run, pressure-block and session scatter, warm-up drift,
    start-up transients, a load-cell offset and quantisation; manifest.csv then names each
    run's session and its true friction multiplier. --clean writes the earlier clean bench.
    """
    from .._paths import refuse_link

    refuse_link(out_dir, "OUT_DIR")  # a symbolic link is refused, not written through
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())) and not force:
        raise BadInput(
            f"{out_dir} is not empty; generate writes raw files and manifest.csv that would "
            "overwrite what is there: choose an empty folder or add --force"
        )
    from ..simulate.bench import TESTS, BenchSettings, DynamicTestSettings, generate_campaign

    chosen = [t.strip() for t in tests.split(",") if t.strip()]
    chosen = list(TESTS) if chosen == ["all"] else chosen
    unknown = [t for t in chosen if t not in TESTS]
    if unknown or not chosen:
        raise BadInput(
            f"--tests {tests!r}: unknown test(s) {unknown}; valid: {', '.join(TESTS)}, all"
        )
    if sessions < 1:
        raise BadInput(f"--sessions {sessions}: expected a whole number >= 1")
    if clean and sessions > 1:
        raise BadInput("--clean writes one session (the earlier bench); drop --sessions")
    kwargs: dict[str, Any] = {
        "seed": seed,
        "sessions": sessions,
        "session_seed": session_seed,
        "run_seed": run_seed,
        "decimal_comma": decimal_comma,
        "pressure_channel": pressure_channel,
    }
    if pressures:
        kwargs["pressures_bar"] = tuple(p / 1e5 for p in _numbers(pressures, "pressure", "bar"))
    if speeds:
        kwargs["speeds_mm_s"] = tuple(v * 1e3 for v in _numbers(speeds, "velocity", "mm/s"))
    if any(v <= 0 for v in kwargs.get("speeds_mm_s", (1,))):
        raise BadInput("--speeds must be > 0")
    if any(p < 0 for p in kwargs.get("pressures_bar", (0,))):
        raise BadInput("--pressures must be >= 0")
    settings = BenchSettings.clean(**kwargs) if clean else BenchSettings(**kwargs)
    n = len(settings.pressures_bar) * len(settings.speeds_mm_s) * ("constant-velocity" in chosen)
    n *= settings.sessions
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

OUTPUT_STEP = 1e-3
"""Output interval of ``cylfric simulate`` [s]."""

CLI_PEAK_BYTES_PER_SAMPLE = 256
"""Peak memory of ``cylfric simulate`` [bytes per output sample] above the process after a
1 s run, measured (issue 23) with ``/usr/bin/time -v`` (maximum resident set size) in fresh
processes at 300 s and 1000 s of the default spring drive, as the slope between them: the
simulation, its figure (a line of every sample in three axes, PNG and SVG) and simulation.csv
written in blocks of :data:`CSV_ROWS` rows; see :func:`_csv_blocks`."""

CSV_ROWS = 100_000
"""Rows of simulation.csv formatted at a time (the file is never held whole in memory)."""


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
        help="Refuse (exit 2) before allocating when the estimated peak memory would exceed "
        "this many GiB (samples every 1 ms x 256 bytes measured: 1 GiB is about 70 min "
        "simulated).",
    ),
):
    """Simulate a cylinder with dynamic LuGre friction; writes simulation.csv and a figure.

    Outputs every 1 ms; the peak memory is estimated before the run and a simulation above
    --max-output-gib (default 1 GiB) is refused with exit 2: shorten --duration or raise
    the limit.
    """
    import numpy as np

    from .._atomic import atomic_write_chunks
    from ..friction.literature import LITERATURE
    from ..model import FrictionModel
    from ..report.figures import save_figure
    from ..simulate import (
        AppliedForce,
        Cylinder,
        PositionServo,
        PrescribedMotion,
        SpringPull,
    )
    from ..simulate import simulate as run_simulation

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
    _check_peak(duration, t_end, max_output_gib)
    from .._paths import make_folder, refuse_link

    refuse_link(out)  # before the simulation: a symbolic link is refused, not written through
    params = friction.params_at(friction.operating_pressure(p))
    drives: dict[
        str, Callable[[], PrescribedMotion | AppliedForce | SpringPull | PositionServo]
    ] = {
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
                dt=OUTPUT_STEP,
                max_output_bytes=max_output_gib * 2**30,
            )
        except ValueError as exc:  # e.g. a law extrapolated below 0 outside its validity
            named = str(exc).startswith(model) or not Path(model).is_file()
            raise BadInput(str(exc) if named else f"{model}: {exc}") from None
    for note in dict.fromkeys(str(w.message) for w in caught):
        console.print(f"[yellow]note:[/yellow] {terminal(note)}")
    assumed = friction.assumptions()
    for line in assumed:
        err_console.print(f"[yellow]note:[/yellow] {terminal(line)}", highlight=False)
    make_folder(out)
    atomic_write_chunks(out / "simulation.csv", _csv_blocks(result))
    import json

    from .._atomic import atomic_write_text

    atomic_write_text(
        out / "simulation.json",
        json.dumps(
            {
                "model": model,
                "drive": drive,
                "pressure [bar]": p / 1e5,
                "duration [s]": t_end,
                "mass [kg]": m,
                "assumptions": assumed,
            },
            indent=2,
        )
        + "\n",
    )
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 7), constrained_layout=True)
    result.plot(ax=axes)
    fig.suptitle(plot_text(f"{drive} at {p / 1e5:g} bar ({model})"))
    if assumed:
        footnote = "sigma_0, sigma_1 assumed, not identified (simulation.json)"
        fig.text(0.01, 0.0, footnote, fontsize=7)
    save_figure(fig, out, "simulation")
    f = result.outputs["friction_force"]
    console.print(
        terminal(
            f"{drive}: {result.time.size} samples over {t_end:g} s; friction {f.min():.1f} to "
            f"{f.max():.1f} N; wrote {out / 'simulation.csv'} and simulation.png/svg"
        )
    )


def _check_peak(duration: str, t_end: float, max_output_gib: float):
    """Refuse (exit 2), before anything is allocated, a simulation whose estimated peak
    memory (:data:`CLI_PEAK_BYTES_PER_SAMPLE` per output sample) exceeds the limit."""
    if not max_output_gib > 0:
        raise BadInput(f"--max-output-gib {max_output_gib:g}: expected a size > 0 GiB")
    ratio = t_end / OUTPUT_STEP
    samples = ratio + 1 if math.isfinite(ratio) else math.inf
    peak = samples * CLI_PEAK_BYTES_PER_SAMPLE
    if peak > max_output_gib * 2**30:
        raise BadInput(
            f"--duration {duration}: {samples:.4g} samples every {OUTPUT_STEP * 1e3:g} ms would "
            f"take about {peak / 2**30:.3g} GiB of memory at its peak ({CLI_PEAK_BYTES_PER_SAMPLE}"
            f" bytes measured per sample), above the limit of {max_output_gib:.3g} GiB; shorten "
            "--duration or raise the limit with --max-output-gib"
        )


def _csv_blocks(result):
    """simulation.csv as bytes, :data:`CSV_ROWS` rows at a time (the columns of
    ``result.to_pandas()``, the same text)."""
    import pandas as pd

    from ..simulate.result import UNITS

    columns = {"time [s]": result.time}
    for name, values in {**result.states, **result.outputs}.items():
        columns[f"{name} [{UNITS.get(name, '-')}]"] = values
    for start in range(0, result.time.size, CSV_ROWS):
        block = pd.DataFrame({k: v[start : start + CSV_ROWS] for k, v in columns.items()})
        yield block.to_csv(index=False, header=start == 0).encode("utf-8")
