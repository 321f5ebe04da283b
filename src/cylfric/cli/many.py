"""``cylfric fit-many``: every campaign folder under a root fitted in parallel on Dask."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from ..options import FitOptions
from .common import (
    JSON_HELP,
    BadInput,
    console,
    fixed_parameters,
    guarded,
    print_json,
    print_table,
    progress_bar,
)


def register(app: typer.Typer) -> None:
    """Add ``cylfric fit-many`` to the app."""

    @app.command("fit-many")
    @guarded
    def fit_many_command(
        root: Path = typer.Argument(..., help="Folder of campaign folders (never modified)."),
        out: Path = typer.Option(
            Path("cylfric-many"), "--out", "-o", help="Output folder: one folder per campaign."
        ),
        catalog: Path = typer.Option(
            None, "--catalog", help="SQLite catalogue to add every fitted datasheet to."
        ),
        scheduler: str = typer.Option(
            None,
            "--scheduler",
            help="Dask distributed scheduler address (tcp://host:8786), 'local-cluster' or "
            "'serial' (default: local worker processes).",
        ),
        workers: int = typer.Option(
            None, "--workers", "-j", help="Local worker processes (default: the cores)."
        ),
        fix: list[str] = typer.Option(
            [], "--fix", help="Hold parameters in every fit: --fix alpha=1,v_r=10mm/s."
        ),
        pressure_law: str = typer.Option(
            "linear", "--pressure-law", "--law", help="linear, quadratic or exponential."
        ),
        per_direction: bool = typer.Option(
            False, "--per-direction", help="Also fit extension and retraction separately."
        ),
        skip_bad: bool = typer.Option(False, "--skip-bad", help="Skip unreadable files."),
        no_report: bool = typer.Option(False, "--no-report", help="No figures or report.html."),
        glob: str = typer.Option(None, "--glob", help="Which files are runs, e.g. '*.txt'."),
        strict: bool = typer.Option(
            False, "--strict", help="A campaign with runs the quality gate flags fails."
        ),
        viscosity_correction: bool = typer.Option(
            None,
            "--viscosity-correction/--no-viscosity-correction",
            help="As for cylfric fit (default: on where campaign.toml has [oil] and the runs "
            "temperatures).",
        ),
        json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
    ):
        """Fit every campaign folder under ROOT in parallel; OUT/fit_many.csv says how each went.

        Exit 0 when at least one campaign was fitted, 2 when all failed.
        """
        if not root.is_dir():
            raise BadInput(f"{root}: not a folder; expected a folder of campaign folders")
        if workers is not None and workers < 1:
            raise BadInput(f"--workers {workers}: expected at least 1")
        options = FitOptions(
            fixed=fixed_parameters(list(fix)),
            pressure_law=pressure_law,
            per_direction=per_direction,
            skip_bad=skip_bad,
            report=not no_report,
            glob=glob,
            strict=strict,
            viscosity_correction=viscosity_correction,
        )
        from ..many import find_campaigns, fit_many

        total = len(find_campaigns(root, exclude=[out]))  # a few ms
        from rich.table import Table
        from rich.text import Text

        with progress_bar() as progress:
            task = progress.add_task("fitting campaigns", total=total)
            result = fit_many(
                root,
                out,
                options,
                workers=workers,
                scheduler=scheduler,
                catalog=catalog,
                progress=lambda _: progress.advance(task),
            )
        if json_output:
            print_json(
                {
                    "out": out,
                    "scheduler": result.scheduler,
                    "seconds [s]": result.seconds,
                    "succeeded": result.succeeded,
                    "campaigns": result.rows,
                }
            )
            if result.succeeded == 0:
                raise typer.Exit(2)
            return
        table = Table(title=f"fit-many: {result.succeeded} of {len(result.rows)} fitted")
        for column in ("campaign", "status", "runs", "excluded", "seconds", "reason"):
            table.add_column(column)
        for row in result.rows:  # plain dicts: this process needs no pandas
            runs, excluded, seconds = (
                row.get(k) for k in ("runs [-]", "excluded [-]", "seconds [s]")
            )
            reason, catalogued = row.get("reason") or "", row.get("catalog") or ""
            table.add_row(
                terminal(row["campaign"]),
                "[green]ok[/green]" if row["status"] == "ok" else "[red]failed[/red]",
                "" if runs is None else str(int(runs)),
                "" if excluded is None else str(int(excluded)),
                "" if seconds is None else f"{seconds:.1f}",
                Text(
                    terminal(
                        reason + (f" (catalogue: {catalogued})" if catalogued else ""), markup=False
                    )
                ),
            )
        print_table(table)
        console.print(
            terminal(
                f"{result.scheduler}: {result.seconds:.1f} s; summary in {out / 'fit_many.csv'}"
            )
        )
        if result.succeeded == 0:
            raise typer.Exit(2)
