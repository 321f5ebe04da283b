"""``cylfric plan``: the standard test procedure, a D-optimal plan of runs with its uncertainty."""

from __future__ import annotations

import re
from pathlib import Path

import typer

from ..escape import terminal
from .common import BadInput, console, guarded, print_table, progress_bar


def _range(text: str, dimension: str, unit: str, option: str) -> tuple[float, float]:
    """``"0-160bar"``, ``"1-150mm/s"``, ``"1mm/s-0.15m/s"`` -> (low, high) in SI."""
    from ..units import UnitError, parse_quantity

    parts = re.split(r"(?<![eE])-", text.strip())
    if len(parts) != 2 or not all(p.strip() for p in parts):
        raise BadInput(f"{option} {text!r}: expected LOW-HIGH, e.g. {option} 0-160bar")
    low, high = (p.strip() for p in parts)
    suffix = re.sub(r"^[0-9.eE+]+", "", high).strip()
    if re.fullmatch(r"[0-9.eE+]+", low) and suffix:
        low += suffix  # "0-160bar": the low end takes the unit of the high end
    try:
        lo = parse_quantity(low, dimension, default_unit=unit)
        hi = parse_quantity(high, dimension, default_unit=unit)
    except UnitError as exc:
        raise BadInput(f"{option} {text!r}: {exc}") from None
    if not lo < hi:
        raise BadInput(f"{option} {text!r}: the low end must be below the high end")
    return lo, hi


def register(app: typer.Typer) -> None:
    """Add ``cylfric plan`` to the app."""

    @app.command()
    @guarded
    def plan(
        pressures: str = typer.Option(
            "0.1-159bar", "--pressures", help="Pressure range, e.g. 0-160bar (bare numbers: bar)."
        ),
        speeds: str = typer.Option(
            "1-135mm/s", "--speeds", help="Speed range, e.g. 1-150mm/s (bare numbers: mm/s)."
        ),
        runs: int = typer.Option(90, "--runs", help="Number of runs (each: descend and ascend)."),
        model: Path = typer.Option(
            None, "--model", help="Datasheet the design is optimal for (default: thesis law)."
        ),
        out: Path = typer.Option(Path("cylfric-plan"), "--out", "-o", help="Output folder."),
        fix: str = typer.Option(
            "",
            "--fix",
            help="Coefficients the fit will hold (names only): --fix alpha,v_r.",
        ),
        noise_from: Path = typer.Option(
            None,
            "--noise-from",
            help="points.csv of an earlier fit: window noise against speed from it "
            "(default: calibrated on the virtual bench).",
        ),
        repeats: int = typer.Option(1, "--repeats", help="Runs allowed per candidate point."),
        n_pressures: int = typer.Option(9, "--candidate-pressures", help="Candidate pressures."),
        n_speeds: int = typer.Option(25, "--candidate-speeds", help="Candidate speeds (log)."),
        seed: int = typer.Option(0, "--seed", help="Seed of the speed order within a level."),
        compare_grid: bool = typer.Option(
            False,
            "--compare-thesis-grid",
            help="Also predict the thesis' 27 x 10 grid and write the two side by side.",
        ),
    ):
        """A D-optimal test plan: runs in order (plan.csv, plan.html) and its uncertainty."""
        from .._paths import refuse_link

        refuse_link(out)  # before the design: a symbolic link is refused, not written through
        p_range, v_range, fixed = _checked_design(pressures, speeds, runs, repeats, fix)

        from ..model import FrictionModel
        from ..plan import make_plan
        from ..simulate.bench import BenchSettings

        friction = FrictionModel.from_datasheet(model) if model is not None else FrictionModel()
        settings = BenchSettings()
        noise = _window_noise(noise_from, v_range, settings, widen_to_thesis=compare_grid)
        result = make_plan(
            p_range,
            v_range,
            runs,
            model=friction,
            noise=noise,
            settings=settings,
            fixed=fixed,
            n_pressures=n_pressures,
            n_speeds=n_speeds,
            max_repeats=repeats,
            seed=seed,
        )
        files = result.write(out)
        table = result.uncertainty.table()
        title = f"Predicted standard errors of a {runs}-run plan"
        if compare_grid:
            table = _compare_thesis_grid(friction, noise, fixed, result, runs, out, files)
            title = f"Predicted standard errors: thesis grid (270 runs) and a {runs}-run plan"
        _print_plan(result, table, title, runs, noise, files)


FIXABLE = {"F_c", "F_s", "sigma_2", "v_r", "alpha"}
"""Coefficients ``--fix`` may hold."""


def _checked_design(
    pressures: str, speeds: str, runs: int, repeats: int, fix: str
) -> tuple[tuple[float, float], tuple[float, float], tuple[str, ...]]:
    """The pressure range [Pa], the speed range [m/s] and the held coefficients, checked."""
    p_range = _range(pressures, "pressure", "bar", "--pressures")
    v_range = _range(speeds, "velocity", "mm/s", "--speeds")
    if not v_range[0] > 0:
        raise BadInput(
            f"--speeds {speeds!r}: the lowest speed must be > 0 (candidate speeds are "
            "log-spaced), e.g. --speeds 1-150mm/s"
        )
    if not p_range[0] >= 0:
        raise BadInput(f"--pressures {pressures!r}: pressures must be >= 0")
    if runs < 1 or repeats < 1:
        raise BadInput("--runs and --repeats must be >= 1")
    fixed = tuple(n.strip() for n in fix.split(",") if n.strip())
    if set(fixed) - FIXABLE:
        raise BadInput(
            f"--fix {fix!r}: expected names among {sorted(FIXABLE)} (no values: a held "
            "coefficient drops out of the design whatever its value)"
        )
    return p_range, v_range, fixed


def _window_noise(noise_from: Path | None, v_range, settings, *, widen_to_thesis: bool):
    """Window noise against speed: from an earlier fit's points.csv, else a bench pilot.

    The pilot runs 9 log-spaced speeds over ``v_range`` [m/s], widened to the thesis
    speeds when the plan is to be compared with the thesis grid.
    """
    import numpy as np

    from ..plan import WindowNoise
    from ..simulate.bench import THESIS_SPEEDS_MM_S, run_plan

    if noise_from is not None:
        import pandas as pd

        if not noise_from.is_file():
            raise BadInput(f"--noise-from {noise_from}: not a file; expected a points.csv")
        return WindowNoise.from_points(pd.read_csv(noise_from), source=str(noise_from))
    speeds_pilot = np.geomspace(v_range[0], v_range[1], 9)
    if widen_to_thesis:
        speeds_pilot = np.geomspace(
            min(v_range[0], THESIS_SPEEDS_MM_S[0] * 1e-3),
            max(v_range[1], THESIS_SPEEDS_MM_S[-1] * 1e-3),
            9,
        )
    for v in (speeds_pilot[0], speeds_pilot[-1]):
        run_plan(v, settings)
    with progress_bar() as progress:
        task = progress.add_task("noise pilot on the virtual bench", total=2 * 9)
        return WindowNoise.from_bench(
            settings, speeds=speeds_pilot, progress=lambda _: progress.advance(task)
        )


def _compare_thesis_grid(friction, noise, fixed, result, runs: int, out: Path, files: dict):
    """The plan's standard errors beside the thesis' 27 x 10 grid's; writes comparison.csv."""
    import numpy as np

    from ..io.writers import atomic_write_text
    from ..plan import compare, grid_uncertainty
    from ..simulate.bench import THESIS_PRESSURES_BAR, THESIS_SPEEDS_MM_S

    grid = grid_uncertainty(
        friction,
        np.array(THESIS_PRESSURES_BAR) * 1e5,
        np.array(THESIS_SPEEDS_MM_S) * 1e-3,
        noise,
        fixed=fixed,
    )
    table = compare(grid, result.uncertainty, labels=("27 x 10 grid", f"{runs}-run plan"))
    files["comparison"] = atomic_write_text(out / "comparison.csv", table.to_csv(index=False))
    return table


def _print_plan(result, table, title: str, runs: int, noise, files: dict) -> None:
    """The standard-error table, the plan's size, its notes and where the test sheet is."""
    from rich.table import Table

    shown = Table(title=title)
    for column in table.columns:
        shown.add_column(terminal(column), justify="right")
    for row in table.itertuples(index=False):
        shown.add_row(*(f"{x:.3g}" if isinstance(x, float) else terminal(x) for x in row))
    print_table(shown)
    levels = result.runs["pressure [Pa]"].nunique()
    console.print(
        f"{runs} runs at {levels} pressure level(s) and "
        f"{result.runs['velocity [m/s]'].nunique()} speed(s); noise: {terminal(noise.source)}"
    )
    for note in result.notes[2:]:
        console.print(f"[yellow]note:[/yellow] {terminal(note)}")
    console.print(terminal(f"test sheet: {files['csv']} and {files['html']}"))
