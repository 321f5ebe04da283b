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
    from ..io.campaign import Campaign
    from ..pipeline import FitOutputs, SealOutputs

__all__ = ["run_fit"]


def _open(campaign: Path, options: FitOptions):
    """The campaign, opened once (its --glob checked first) and passed down to every step."""
    from ..io.campaign import Campaign, check_glob

    if options.glob is not None:
        check_glob(options.glob, campaign, key="--glob")
    return Campaign.open(campaign, options.glob, config=options.config)


def _fit_with_progress(campaign: Path, n_files: int, call):
    """``call(progress, after_extraction, step)`` with a progress bar over ``n_files`` run
    files and one for each later step that can take seconds (``step(description, total)``);
    warnings reach the user once, as the notes printed after it (not as Python's lines)."""
    progress = _progress()
    task = progress.add_task(terminal(f"reading {campaign.name}"), total=n_files, unit="runs")

    def step(description: str, total: int):
        """A new bar for a later step of the fit (the earlier ones hidden); its advance."""
        for earlier in progress.task_ids:
            progress.update(earlier, visible=False)
        shown = progress.add_task(terminal(description), total=total)
        progress.start()
        progress.refresh()
        return lambda _: progress.advance(shown)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        progress.start()
        try:
            return call(lambda _: progress.advance(task), progress.stop, step)
        finally:
            progress.stop()


def run_fit(
    campaign: Path,
    out: Path,
    options: FitOptions | None = None,
    *,
    quiet: bool = False,
    seal: str | None = None,
    opened: Campaign | None = None,
) -> FitOutputs:
    """Shared by ``fit`` and ``demo``: the pipeline with a progress bar and a summary
    (``quiet``: no summary); ``seal`` fits only that seal's runs into ``out``."""
    from ..pipeline import fit_campaign

    options = options or FitOptions()
    opened = opened or _open(campaign, options)
    chosen = opened.for_seal(seal) if seal is not None else opened  # an unknown seal: exit 2
    result = _fit_with_progress(
        campaign,
        len(chosen.steady_runs),  # the bar counts these (not presliding/breakaway tests)
        lambda progress, stop, step: fit_campaign(
            opened, out, options, seal=seal, progress=progress, after_extraction=stop, step=step
        ),
    )
    if not quiet:
        print_table(_summary_table(result.datasheet))
        _print_outcome(result)
        shown = f"; open {out / 'report.html'}" if options.report else ""
        console.print(terminal(f"outputs in {out}{shown}", markup=False), markup=False)
    return result


def _print_outcome(result: FitOutputs, seal: str | None = None) -> None:
    """The files skipped and excluded, the notes and the exports of one fit (of ``seal``)."""
    where = "" if seal is None else f"{seal}/"
    label = "" if seal is None else terminal(f"seal {seal}: ")
    skipped = result.extraction.skipped
    if skipped:
        console.print(
            f"{label}[yellow]{len(skipped)} file(s) skipped[/yellow] "
            f"(see {terminal(where)}skipped.csv):"
        )
        for item in skipped[:10]:
            console.print(terminal(f"  {item['reason']}", markup=False), markup=False)
    excluded = result.excluded
    if excluded is not None and len(excluded):
        console.print(
            f"{label}[yellow]{len(excluded)} run(s) excluded[/yellow] "
            f"(see {terminal(where)}excluded.csv):"
        )
        for _, item in excluded.head(10).iterrows():
            console.print(
                terminal(f"  {item['file']}: {item['reason']}", markup=False), markup=False
            )
    for note in result.identification.notes:
        console.print(f"{label}[yellow]note:[/yellow] {terminal(note)}")
    for exported in result.exports.values():
        console.print(
            terminal(exported.summary(), markup=False, multiline=True),
            markup=False,
            highlight=False,
        )


def run_seals(
    campaign: Path, out: Path, options: FitOptions, opened: Campaign, *, quiet: bool = False
) -> SealOutputs:
    """``fit`` of a campaign with several seals: one fit per seal into OUT/<seal>/, the
    summary table printed (``quiet``: not) and written as OUT/seals.csv."""
    from ..pipeline import fit_seals

    result = _fit_with_progress(
        campaign,
        len(opened.steady_runs),
        lambda progress, stop, step: fit_seals(
            opened, out, options, progress=progress, after_extraction=stop, step=step
        ),
    )
    if not quiet:
        names = ", ".join(result.seals)
        console.print(
            terminal(f"{len(result.seals)} seals, one model each: {names}", markup=False),
            markup=False,
        )
        print_table(_seals_table(result.summary))
        for name, fitted in result.seals.items():
            _print_outcome(fitted, name)
        shown = " and report.html" if options.report else ""
        console.print(
            terminal(f"outputs in {out}/<seal>/: datasheet.json{shown}", markup=False),
            markup=False,
        )
    return result


def _seals_table(summary) -> Table:
    """The seals summary (:data:`cylfric.pipeline.SEAL_COLUMNS`) as printed: ranges in one
    column each, every name escaped."""
    table = Table(title="One datasheet per seal (OUT/<seal>/; the table: seals.csv)")
    columns = {
        "seal": ("seal",),
        "runs": ("runs [-]",),
        "points": ("points [-]",),
        "excluded": ("excluded [-]",),
        "friction law": ("friction law",),
        "pressure [bar]": ("pressure min [bar]", "pressure max [bar]"),
        "speed [mm/s]": ("speed min [mm/s]", "speed max [mm/s]"),
        "F_c [N] at min-max pressure": ("F_c at pressure min [N]", "F_c at pressure max [N]"),
        "RMSE [N]": ("RMSE [N]",),
    }
    for title in columns:
        text = title in ("seal", "friction law")
        table.add_column(terminal(title), justify="left" if text else "right")
    for row in summary.to_dict("records"):
        table.add_row(*("-".join(_cell(row[key]) for key in keys) for keys in columns.values()))
    return table


def _cell(value) -> str:
    """A cell of the seals table: text escaped, numbers to 4 significant digits."""
    import math

    if isinstance(value, str):
        return terminal(value)
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


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
    config: Path = typer.Option(
        None,
        "--config",
        exists=True,
        dir_okay=False,
        help="campaign.toml to use instead of DIR/campaign.toml (the data folder stays untouched).",
    ),
    strict: bool = typer.Option(
        False, "--strict", help="Stop (exit 2) instead of excluding runs the quality gate flags."
    ),
    accept_force_balance: bool = typer.Option(
        False,
        "--accept-force-balance",
        help="Fit even when the force balance or the units look contradicted (offset or "
        "friction following the pressure force, friction above p*A): notes, not exit 2.",
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
    seal: str = typer.Option(
        None,
        "--seal",
        help="Fit only this seal's runs, into OUT (a campaign of several seals, labelled by "
        "a 'seal' group of name_pattern or a manifest.csv 'seal' column, is otherwise "
        "fitted seal by seal into OUT/<seal>/ with the summary OUT/seals.csv).",
    ),
    scheduler: str = typer.Option(
        None,
        "--scheduler",
        help="Read the run files on a Dask distributed cluster (tcp://host:8786); the files "
        "must be at the same path on every worker (a shared file system).",
    ),
    json_output: bool = typer.Option(
        False, "--json", help=JSON_HELP + " The outputs are written as without it."
    ),
):
    """Raw bench files -> datasheet.json, tables, figures and report.html.

    One model per seal: a folder of several seals gives OUT/<seal>/datasheet.json and
    report for each and the table OUT/seals.csv; --seal NAME fits one into OUT.
    """
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
        config=None if config is None else str(config),
        strict=strict,
        accept_force_balance=accept_force_balance,
        export=tuple(targets),
        viscosity_correction=viscosity_correction,
        scheduler=scheduler,
    )
    opened = _open(campaign, options)
    if seal is None and len(opened.seals) > 1:
        seals = run_seals(campaign, out, options, opened, quiet=json_output)
        if json_output:
            print_json(_seals_document(out, seals))
        return
    result = run_fit(campaign, out, options, quiet=json_output, seal=seal, opened=opened)
    if json_output:
        excluded = result.excluded
        print_json(
            {
                "out": out,
                "datasheet": out / "datasheet.json",
                **model_document(result.model),
                "skipped": list(result.extraction.skipped),
                "excluded": [] if excluded is None else excluded.to_dict("records"),
                "notes": list(result.identification.notes),
                "exports": {k: list(v.files) for k, v in result.exports.items()},
            }
        )


def _seals_document(out: Path, seals: SealOutputs) -> dict:
    """``fit --json`` of a campaign of several seals: the summary rows and, per seal, its
    datasheet, model, files skipped and excluded, and notes."""
    rows = seals.summary.to_dict("records")
    document: dict = {"out": out, "summary": seals.files["seals"], "seals": {}}
    for row, (name, result) in zip(rows, seals.seals.items(), strict=True):
        excluded = result.excluded
        document["seals"][name] = {
            "out": result.out,
            "datasheet": result.out / "datasheet.json",
            "summary": row,
            **model_document(result.model),
            "skipped": list(result.extraction.skipped),
            "excluded": [] if excluded is None else excluded.to_dict("records"),
            "notes": list(result.identification.notes),
            "exports": {k: list(v.files) for k, v in result.exports.items()},
        }
    return document


THESIS_VALUES = {
    "F_c": (70.2, 0.5, "N"),
    "F_s": (112.9, 0.6, "N"),
    "sigma_2": (0.34, 8e-4, "N*s/mm"),
}


def _demo_table(sheet: dict, truth: dict, clean: bool) -> Table:
    """The thesis law, this campaign's truth (the law x its runs' multipliers) and the fit."""
    title = "Recovered against the truth (eq. 4.1-4.3, alpha, v_r; p in bar)"
    table = Table(title=title)
    columns = ("parameter", "bench law (thesis)", "this campaign's truth", "recovered")
    for col in columns if not clean else (columns[0], columns[1], columns[3]):
        table.add_column(col, justify="right")
    params = sheet["parameters"]
    for name, (a, b, unit) in THESIS_VALUES.items():
        k = 1e-3 if name == "sigma_2" else 1.0
        c = params[name]
        row = [name, f"{a:g} + {b:g} p {unit}"]
        if not clean:
            ta, tb = truth["campaign_law"][name]
            row.append(f"{ta * k:.4g} + {tb * k * 1e5:.3g} p {unit}")
        fitted = (
            "not identified"
            if c is None
            else f"{c['intercept'] * k:.4g} + {c['slope'] * k * 1e5:.3g} p {unit}"
        )
        table.add_row(*row, fitted)

    def scalar(value, scale=1.0, digits=3):
        return "not identified" if value is None else f"{value * scale:.{digits}f}"

    truth_cell = [] if clean else ["(not drawn)"]
    table.add_row("alpha", "1", *truth_cell, scalar(params["alpha"]))
    table.add_row("v_r", "10 mm/s", *truth_cell, f"{scalar(params['v_r'], 1e3, 2)} mm/s")
    offsets = ", ".join(f"{o:.2f}" for o in truth["offset"])
    offset_truth = [] if clean else [f"{offsets} N"]
    table.add_row(
        "offset", f"{35.67 / 2:.2f} N (35.67 N up-down)", *offset_truth, f"{sheet['offset']:.2f} N"
    )
    return table


def _demo_truth_lines(truth: dict, clean: bool) -> list[str]:
    """The multipliers the bench drew and how often the fit's bands hold the truth."""
    m = truth["multipliers"]
    level = f"{truth['level']:.0%}"
    runs, inside = truth["runs"], round(truth["run_band_coverage"] * truth["runs"])
    lines = []
    if not clean:
        sessions = ", ".join(f"{s:.3f}" for s in m["session"])
        lines.append(
            "the bench's multipliers of the law (session x pressure block x run x warm-up): "
            f"session {sessions}; pressure blocks {m['pressure_block'][0]:.2f}-"
            f"{m['pressure_block'][1]:.2f}; runs {m['run'][0]:.2f}-{m['run'][1]:.2f}; warm-up "
            f"{m['warmup'][0]:.2f}-{m['warmup'][1]:.2f}; in all {m['total'][0]:.2f}-"
            f"{m['total'][1]:.2f} (manifest.csv, column friction_scale)"
        )
    lines.append(
        f"the {level} band of a new run holds the true friction of {inside} of {runs} runs "
        f"({truth['run_band_coverage']:.1%}); the band of a new session holds the bench's law "
        f"at {truth['session_band_coverage']:.1%} of the runs' speeds and pressures"
    )
    return lines


@app.command()
@guarded
def demo(
    out: Path = typer.Option(Path("cylfric-demo"), "--out", "-o", help="Output folder."),
    seed: int = typer.Option(0, "--seed", help="Seed of the virtual campaign."),
    clean: bool = typer.Option(
        False, "--clean", help="The clean virtual bench (no rig scatter, drift or transients)."
    ),
):
    """Generate the thesis' virtual campaign (10 pressures x 27 speeds) and fit it.

    Writes the raw files to OUT/campaign (regenerated on every run) and the fit to OUT/fit.
    The bench is as rough as a real rig unless --clean: its friction is the thesis law times
    each run's drawn multiplier (OUT/campaign/manifest.csv, column friction_scale).
    """
    from .._paths import refuse_link
    from ..simulate.bench import BenchSettings, generate_campaign, truth_check

    refuse_link(out)  # a symbolic link is refused (exit 2), not written through
    settings = BenchSettings.clean(seed=seed) if clean else BenchSettings(seed=seed)
    campaign = out / "campaign"
    n = len(settings.pressures_bar) * len(settings.speeds_mm_s)
    with _progress() as progress:
        task = progress.add_task("virtual bench", total=n)
        generate_campaign(campaign, settings, progress=lambda _: progress.advance(task))
    rough = "" if clean else " (rough bench: the truth is the thesis law x each run's multiplier)"
    console.print(terminal(f"virtual campaign: {n} files in {campaign}{rough}"))
    result = run_fit(campaign, out / "fit", FitOptions(), quiet=True)
    sheet = result.datasheet
    print_table(_summary_table(sheet, "Recovered from the virtual campaign"))
    truth = truth_check(result.model, settings)
    print_table(_demo_table(sheet, truth, clean))
    for line in _demo_truth_lines(truth, clean):
        console.print(terminal(line, markup=False), markup=False)
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
                "-" if r.get("F_c") is None else f"{r['F_c']:.1f}",
                "-" if r["sigma_2"] is None else f"{r['sigma_2'] / 1e3:.3f}",
                "-" if vs is None else f"{vs * 1e3:.1f}",
                "-" if r.get("rmse") is None else f"{r['rmse']:.2f}",
                str(r["n_points"]),
            )
        print_table(table)
