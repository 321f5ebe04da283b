"""``cylfric fit``, ``demo`` and ``show``: a campaign folder to a datasheet, and back to text."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.table import Table

from ..escape import terminal
from ..options import FitOptions
from .common import (
    JSON_HELP,
    BadInput,
    _fixed,
    _progress,
    _summary_table,
    app,
    console,
    guarded,
    model_document,
    print_json,
    print_table,
)

if TYPE_CHECKING:
    from ..pipeline import FitOutputs

__all__ = ["run_fit"]


def run_fit(
    campaign: Path, out: Path, options: FitOptions | None = None, *, quiet: bool = False
) -> FitOutputs:
    """Shared by ``fit`` and ``demo``: the pipeline with a progress bar and a summary
    (``quiet``: no summary)."""
    from ..io.campaign import Campaign, check_glob
    from ..pipeline import fit_campaign

    options = options or FitOptions()
    if options.glob is not None:
        check_glob(options.glob, campaign, key="--glob")
    opened = Campaign.open(campaign, options.glob)  # read once, passed down to every step
    n_files = len(opened.steady_runs)  # the bar counts these (not presliding/breakaway tests)
    progress = _progress()
    task = progress.add_task(terminal(f"reading {campaign.name}"), total=n_files)

    def step(description: str, total: int):
        """A new bar for a later step of the fit (the earlier ones hidden); its advance."""
        for earlier in progress.task_ids:
            progress.update(earlier, visible=False)
        shown = progress.add_task(terminal(description), total=total)
        progress.start()
        progress.refresh()
        return lambda _: progress.advance(shown)

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
                step=step,
            )
        finally:
            progress.stop()
    if not quiet:
        print_table(_summary_table(result.datasheet))
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
        shown = f"; open {out / 'report.html'}" if options.report else ""
        console.print(terminal(f"outputs in {out}{shown}", markup=False), markup=False)
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
    json_output: bool = typer.Option(
        False, "--json", help=JSON_HELP + " The outputs are written as without it."
    ),
):
    """Raw bench files -> datasheet.json, tables, figures and report.html."""
    if not campaign.is_dir():
        raise BadInput(f"{campaign}: not a folder; expected a campaign folder of run files")
    targets: list[str] = []
    if export is not None:
        from ..export import parse_targets, resolve

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
    result = run_fit(campaign, out, options, quiet=json_output)
    if json_output:
        excluded = result.excluded
        print_json(
            {
                "out": out,
                "datasheet": out / "datasheet.json",
                **model_document(result.identification.model),
                "skipped": list(result.extraction.skipped),
                "excluded": [] if excluded is None else excluded.to_dict("records"),
                "notes": list(result.identification.notes),
                "exports": {k: list(v.files) for k, v in result.exports.items()},
            }
        )


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
    from .._paths import refuse_link
    from ..simulate.bench import BenchSettings, generate_campaign

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
    print_table(_summary_table(sheet, "Recovered from the virtual campaign"))
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
    print_table(table)
    console.print(terminal(f"report: {out / 'fit' / 'report.html'}"))


@app.command()
@guarded
def show(
    datasheet: Path = typer.Argument(..., help="A datasheet.json file."),
    json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Summarise a datasheet."""
    from ..datasheet import read_datasheet
    from ..model import FrictionModel

    sheet = read_datasheet(datasheet)
    if json_output:
        document = model_document(FrictionModel.from_datasheet(sheet))
        print_json({"datasheet": datasheet, **document, "per_pressure": sheet.get("per_pressure")})
        return
    title = terminal(f"Friction datasheet {sheet.get('name', '')}")
    print_table(_summary_table(sheet, title))
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
        print_table(table)
