"""``cylfric fit-motion``: friction identification from any logged motion (IDIM-LS)."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import BadInput, _plain, console, guarded, print_table

SIGNALS_CSV = "motion_signals.csv"
FIT_JSON = "motion_fit.json"
FIGURE = "motion_fit.png"
VALIDATION_FIGURE = "motion_validation.png"


def register(app) -> None:
    """Add ``fit-motion`` to the ``cylfric`` app."""

    @app.command("fit-motion")
    @guarded
    def fit_motion_command(
        record: Path = typer.Argument(
            ..., help="Motion record: a .mat file or a bench text file (never modified)."
        ),
        config: Path = typer.Option(
            ..., "--config", "-c", help="motion.toml naming the signals (see docs/motion.md)."
        ),
        out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
        per_direction: bool = typer.Option(
            False, "--per-direction", help="Split F_v and F_c by the direction of motion."
        ),
        validate: Path = typer.Option(
            None,
            "--validate",
            help="A second record: replay the identified model in the [validation] servo loop.",
        ),
        accept_implausible: bool = typer.Option(
            False,
            "--accept-implausible",
            help="Write a fit the plausibility gates flag (a unit off by 1000, a negative "
            "mass, friction above the recorded forces) instead of stopping with exit 2; the "
            "flags go into motion_fit.json.",
        ),
    ):
        """Identify mass, viscous and Coulomb friction and offset from a motion record.

        IDIM-LS as in the EMPS benchmark: zero-phase low-pass of the position, central
        differences, decimated regression, least squares; then, when pressures are recorded,
        a refinement to the pressure-dependent Stribeck model. Writes motion_fit.json,
        motion_signals.csv and motion_fit.png (datasheet.json for a refined model).

        Refused with exit 2, nothing written: a used signal holding NaN or inf (the message
        names the channel, the sample and, in a text record, the line), and a fit the
        plausibility gates flag (stroke over 20 m or speed over 20 m/s: a position in mm read
        as m; a negative mass or one the record's forces and accelerations cannot support;
        friction above the largest recorded force). Fix the units (motion.toml [units], the
        record's header) or give --accept-implausible to write it with its flags.
        """
        _run(record, config, out, per_direction, validate, accept_implausible)


def _check_paths(record: Path, config: Path, validate: Path | None, out: Path) -> None:
    """Refuse missing inputs, an ``--out`` that is a link or a file, and an output that
    would overwrite an input (exit 2, nothing written)."""
    from .._paths import refuse_link

    for path, what in ((record, "RECORD"), (config, "--config")) + (
        ((validate, "--validate"),) if validate is not None else ()
    ):
        if not path.is_file():
            raise BadInput(f"{what} {path}: no such file")
    refuse_link(out)  # a symbolic link is refused (exit 2), not written through
    if out.exists() and not out.is_dir():
        raise BadInput(f"--out {out}: exists and is not a folder")
    inputs = {p.resolve() for p in (record, config, validate) if p is not None}
    outputs = (FIT_JSON, SIGNALS_CSV, FIGURE, VALIDATION_FIGURE, "datasheet.json")
    clash = [name for name in outputs if (out / name).resolve() in inputs]
    if clash:
        raise BadInput(f"--out {out}: writing {clash[0]} would overwrite an input file")


def _run(record, config, out, per_direction, validate, accept_implausible=False):
    import hashlib
    import json
    import warnings

    from .._paths import make_folder
    from ..identify.motion import fit_motion
    from ..io.motion_config import load_motion_config, read_motion_record
    from ..io.writers import atomic_write_bytes, atomic_write_text

    _check_paths(record, config, validate, out)
    settings = load_motion_config(config)
    data = read_motion_record(record, settings)
    # warnings reach the user once each, as notes (not as Python's own lines with a path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = fit_motion(data, settings, per_direction=per_direction)
    for note in dict.fromkeys(str(w.message) for w in caught):
        console.print(terminal(f"note: {note}", markup=False), markup=False)
    if fit.flags and not accept_implausible:
        listed = "; ".join(flag.summary() for flag in fit.flags)
        hints = " ".join(dict.fromkeys(flag.hint for flag in fit.flags))
        raise BadInput(
            f"{record}: implausible fit, nothing written: {listed}. {hints} To write it "
            "anyway, with these flags in motion_fit.json, give --accept-implausible."
        )
    replay = None
    if validate is not None:
        from ..identify.motion_validation import validate_on_record

        replay = validate_on_record(fit, validate, settings)
    document = {
        "format": "cylfric motion fit",
        "version": 1,
        "units": "SI: kg, N, N*s/m, m, s, Pa; relative errors as fractions [-] and in %",
        "record": {
            "file": str(record),
            "sha256": hashlib.sha256(record.read_bytes()).hexdigest(),
            "samples": int(data.time.size),
            "signals": dict(settings.signals),
            "force_scale": data.force_scale,
        },
        "config": str(config),
        **fit.to_dict(),
        "validation": None,
    }
    if replay is not None:
        document["validation"] = {"record": str(validate), **replay.to_dict()}
    jobs = {FIGURE: ("fit", _fit_figure_data(fit))}
    if replay is not None:
        jobs[VALIDATION_FIGURE] = ("validation", _validation_figure_data(replay))
    make_folder(out)
    refined = fit.refinement.model if fit.refinement is not None else None
    if refined is not None:
        sheet = refined.to_datasheet()
        text = json.dumps(_plain(sheet), indent=2, allow_nan=False)
        atomic_write_text(out / "datasheet.json", text + "\n")
    # valid JSON: a non-finite value (a parameter the record does not determine) is null
    text = json.dumps(_plain(document), indent=2, allow_nan=False)
    atomic_write_text(out / FIT_JSON, text + "\n")
    atomic_write_text(out / SIGNALS_CSV, _csv(fit.signals))
    for name, png in _draw_all(jobs).items():
        atomic_write_bytes(out / name, png)
    _print_summary(fit, replay, out)


def _csv(columns: dict) -> str:
    import io

    import numpy as np

    buffer = io.StringIO()
    names = list(columns)
    buffer.write(",".join(f'"{n}"' for n in names) + "\n")
    np.savetxt(buffer, np.column_stack([columns[n] for n in names]), delimiter=",", fmt="%.9g")
    return buffer.getvalue()


def _draw_all(jobs: dict) -> dict:
    drawers = {"fit": _draw_fit, "validation": _draw_validation}
    return {name: drawers[kind](data) for name, (kind, data) in jobs.items()}


def _png(fig) -> bytes:
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def _fit_figure_data(fit) -> dict:
    """Plain arrays for :func:`_draw_fit` (the child imports no cylfric modules)."""
    import numpy as np

    s = fit.signals
    v = s["velocity [m/s]"]
    speed = np.linspace(v.min(), v.max(), 400)
    return {
        "time": s["time [s]"],
        "force": s["force [N]"],
        "predicted": s["predicted force [N]"],
        "velocity": v,
        "friction": s["force [N]"]
        - fit.parameters["mass"] * s["acceleration [m/s^2]"]
        - fit.parameters["offset"],
        "speed": speed,
        "model": fit.predict(speed, 0 * speed) - fit.parameters["offset"],
        "relative_error": fit.relative_error,
    }


def _draw_fit(d) -> bytes:
    """Measured against predicted force over time, and the friction against velocity."""
    from matplotlib.figure import Figure

    t, F, P = d["time"], d["force"], d["predicted"]
    fig = Figure(figsize=(9, 6.5))  # a fixed layout: constrained layout doubles the time
    grid = fig.add_gridspec(
        2,
        2,
        height_ratios=(1.4, 1),
        left=0.08,
        right=0.98,
        top=0.95,
        bottom=0.08,
        hspace=0.3,
        wspace=0.25,
    )
    top = fig.add_subplot(grid[0, :])
    top.plot(t, F, lw=0.8, label="measured")
    top.plot(t, P, lw=0.8, label="predicted (IDIM-LS)")
    top.plot(t, F - P, lw=0.6, color="0.4", label="residual")
    top.set(xlabel="time [s]", ylabel="force [N]")
    top.set_title(f"relative force error {100 * d['relative_error']:.2f} %")
    top.legend(loc="upper right", fontsize=8)
    left = fig.add_subplot(grid[1, 0])
    left.plot(
        1e3 * d["velocity"], d["friction"], ".", ms=1.5, alpha=0.4, label="force - mass*a - offset"
    )
    left.plot(1e3 * d["speed"], d["model"], "k", lw=1.2, label="identified friction")
    left.set(xlabel="velocity [mm/s]", ylabel="friction force [N]")
    left.legend(loc="upper left", fontsize=7)
    right = fig.add_subplot(grid[1, 1])
    right.plot(F, P, ".", ms=1.5, alpha=0.4)
    lims = [min(F.min(), P.min()), max(F.max(), P.max())]
    right.plot(lims, lims, "k", lw=0.8)
    right.set(xlabel="measured force [N]", ylabel="predicted force [N]")
    return _png(fig)


def _validation_figure_data(replay) -> dict:
    return {
        "time": replay.time,
        "measured_position": replay.measured_position,
        "position": replay.position,
        "measured_force": replay.measured_force,
        "force": replay.force,
        "errors": dict(replay.errors),
    }


def _draw_validation(d) -> bytes:
    from matplotlib.figure import Figure

    t = d["time"]
    fig = Figure(figsize=(9, 7.5))
    fig.subplots_adjust(left=0.09, right=0.98, top=0.95, bottom=0.07, hspace=0.12)
    axes = fig.subplots(3, 1, sharex=True, height_ratios=(1, 0.7, 1))
    axes[0].plot(t, 1e3 * d["measured_position"], lw=0.8, label="measured (filtered)")
    axes[0].plot(t, 1e3 * d["position"], lw=0.8, ls="--", label="simulated")
    axes[0].set(ylabel="position [mm]")
    axes[0].set_title(
        f"closed-loop replay: position error {100 * d['errors']['position']:.3g} %, "
        f"force error {100 * d['errors']['force']:.3g} %"
    )
    axes[0].legend(fontsize=8)
    axes[1].plot(t, 1e6 * (d["position"] - d["measured_position"]), lw=0.6, color="0.3")
    axes[1].set(ylabel="simulated - measured\nposition [um]")
    axes[2].plot(t, d["measured_force"], lw=0.6, label="measured")
    axes[2].plot(t, d["force"], lw=0.6, label="simulated")
    axes[2].set(xlabel="time [s]", ylabel="force [N]")
    axes[2].legend(fontsize=8)
    return _png(fig)


def _print_summary(fit, replay, out) -> None:
    from rich.markup import escape
    from rich.table import Table

    from ..identify.motion import PARAMETER_UNITS

    table = Table(title="Inverse dynamic model (IDIM-LS)")
    for column in ("parameter", "value", "std. error", "unit"):
        table.add_column(column, justify="left" if column == "parameter" else "right")
    for name, value in fit.parameters.items():
        table.add_row(name, f"{value:.5g}", f"{fit.stderr[name]:.2g}", PARAMETER_UNITS[name])
    print_table(table)
    for flag in fit.flags:  # only with --accept-implausible
        console.print(f"[yellow]implausible:[/yellow] {escape(str(flag))}")
    console.print(
        f"relative force error {100 * fit.relative_error:.2f} % "
        f"(RMS {fit.rmse:.3g} N over {fit.settings['regression_samples']} decimated samples)"
    )
    ref = fit.refinement
    if ref is not None:
        if ref.model is not None:
            console.print("pressure-dependent refinement (datasheet.json):")
            for line in ref.model.law_lines():
                console.print(terminal(f"  {line}", markup=False), markup=False)
            console.print(f"  relative force error {100 * ref.relative_error:.2f} %")
        for note in ref.notes:
            console.print(terminal(f"  note: {note}", markup=False), markup=False)
    if replay is not None:
        e = replay.errors
        console.print(
            f"closed-loop validation: relative errors position {100 * e['position']:.3g} %, "
            f"velocity {100 * e['velocity']:.3g} %, force {100 * e['force']:.3g} %"
        )
    console.print(
        terminal(f"wrote {out / FIT_JSON}, {SIGNALS_CSV}, {FIGURE}", markup=False), markup=False
    )
