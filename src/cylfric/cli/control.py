"""``cylfric control DATASHEET``: the datasheet's friction compensation in a servo loop."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import JSON_HELP, BadInput, console, err_console, guarded, print_json


def default_axis_note() -> str:
    """What ``cylfric control --export-compensator`` prints on stderr without ``--axis``."""
    from ..control.axis import DEFAULT_AXIS as a

    kind = "double-rod" if a.rod_a > 0 else "single-rod"
    return (
        "note: no --axis given: the exported compensator's `command` output is computed for "
        f"cylfric's DEFAULT axis ({a.bore * 1e3:g}/{a.rod * 1e3:g} x {a.stroke * 1e3:g} mm "
        f"{kind} cylinder, {a.supply_pressure / 1e5:g} bar supply, "
        f"{a.valve_nominal_flow * 6e4:g} L/min valve; every value is listed in the generated "
        "files). On another axis that command is wrong: export again with --axis axis.toml, "
        "or use the `force` output [N], which does not depend on the axis's hydraulics, "
        "through your own force-to-valve path (docs/control.md)."
    )


def register(app) -> None:
    """Add ``cylfric control`` to the app."""

    @app.command("control")
    @guarded
    def control(
        datasheet: Path = typer.Argument(..., help="A datasheet.json file (never modified)."),
        out: Path = typer.Option(..., "--out", "-o", help="Output folder (a link is refused)."),
        axis: Path = typer.Option(
            None,
            "--axis",
            help="axis.toml (table [axis], values with units); default: the "
            "documented 40/28 x 200 mm double-rod servo axis.",
        ),
        reference: str = typer.Option(
            "sine",
            "--reference",
            help="sine, steps, ramp, or a CSV file with columns "
            "'time [s]' and 'position [m]' (or 'position [mm]').",
        ),
        robustness: bool = typer.Option(
            True,
            "--robustness/--no-robustness",
            help="Also run plants whose friction differs from the datasheet.",
        ),
        export: str = typer.Option(
            None,
            "--export-compensator",
            help="Also write the compensator step into OUT/compensator: any of c, fmu, "
            "matlab, comma-separated (C source, FMI 2.0 co-simulation FMU, MATLAB function). "
            "Its valve command is computed for --axis (the default axis without it).",
        ),
        fmu_kind: str = typer.Option(
            "lugre",
            "--fmu-compensator",
            help="The kind the FMU carries: none, coulomb, static or lugre.",
        ),
        export_only: bool = typer.Option(
            False, "--export-only", help="Write the exports only; do not run the loop."
        ),
        force_filter_ms: float = typer.Option(
            0.0,
            "--force-filter-ms",
            help="Time constant [ms] of the first-order filter on the compensators' force "
            "estimate, in the loop and the exports (0: none; a few samples smooth the "
            "velocity steps of a quantised position, docs/control.md).",
        ),
        velocity_input: bool = typer.Option(
            False,
            "--velocity-input",
            help="The exported step reads a measured velocity input instead of differencing "
            "the position.",
        ),
        json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
    ):
        """Run the position loop with every compensator (none, coulomb, static, lugre,
        oracle); write metrics.json, timeseries.csv and control.html into --out; with
        --export-compensator, the compensator as C, FMU and/or MATLAB code."""
        from .._paths import refuse_link
        from ..control.axis import DEFAULT_AXIS, load_axis
        from ..control.study import compare_compensators
        from ..model import FrictionModel

        if not datasheet.is_file():
            raise BadInput(f"{datasheet}: not found; expected a datasheet.json file")
        refuse_link(out)
        model = FrictionModel.from_datasheet(datasheet)
        the_axis = load_axis(axis) if axis is not None else DEFAULT_AXIS
        ref = _resolve_reference(reference, the_axis)
        targets = _export_targets(export, fmu_kind, export_only)
        if not (0.0 <= force_filter_ms < 1e4):
            raise BadInput(f"--force-filter-ms {force_filter_ms!r}: expected 0 <= ms < 10000")
        _note_assumed(model)
        tau = force_filter_ms * 1e-3
        if targets:
            _write_exports(
                model,
                out,
                targets,
                the_axis,
                fmu_kind,
                default_axis=axis is None,
                force_filter=tau,
                velocity_input=velocity_input,
            )
        if export_only:
            return
        result = compare_compensators(
            model,
            axis=the_axis,
            reference=ref,
            robustness=robustness,
            progress=_progress(),
            force_filter=tau,
        )
        result.write(out)
        document = result.to_dict()
        if json_output:
            print_json(document)
            return
        _print_metrics(result)
        console.print(terminal(f"written: {out}", markup=False), markup=False)


def _resolve_reference(reference: str, axis):
    """The ``--reference`` value: a built-in name, or the trajectory read from a CSV file."""
    from ..control.loop import RAMP_IN_SPEED, REFERENCES, ramp_in, read_reference

    if reference in REFERENCES:
        return reference
    if Path(reference).is_file():
        try:
            read = read_reference(reference, axis)
        except ValueError as exc:
            raise BadInput(str(exc)) from None
        ramped = ramp_in(read, axis)
        if ramped is not read:
            err_console.print(
                terminal(
                    f"note: {reference} starts at {read.position[0] * 1e3:.4g} mm, not at the "
                    f"axis's start position {axis.start_position * 1e3:.4g} mm: the loop first "
                    f"moves there (half-cosine ramp, peak {RAMP_IN_SPEED * 1e3:g} mm/s, "
                    f"{ramped.time[-1] - read.time[-1]:.3g} s with a 0.5 s hold); the "
                    "metrics include that ramp. Set start_position in axis.toml to avoid it.",
                    markup=False,
                ),
                markup=False,
                highlight=False,
            )
        return ramped
    raise BadInput(f"--reference {reference!r}: expected one of {list(REFERENCES)} or a CSV file")


def _note_assumed(model) -> None:
    """Name an assumed sigma_0 / sigma_1 on stderr, with how to identify them."""
    from ..control.study import IDENTIFY_ADVICE, dynamic_parameters

    dynamic = dynamic_parameters(model)
    assumed = {n: d for n, d in dynamic.items() if d["status"] != "identified"}
    if not assumed:
        return
    values = ", ".join(f"{n} = {d['value']:.4g} {d['unit']}" for n, d in assumed.items())
    err_console.print(
        terminal(
            f"note: the datasheet's {values} {'are' if len(assumed) > 1 else 'is'} ASSUMED, "
            "not identified; the LuGre compensator and its loop study use "
            f"{'them' if len(assumed) > 1 else 'it'} (metrics.json 'dynamic_parameters'; "
            f"'sensitivity' shows the LuGre gain for sigma_0 x0.1..x10): {IDENTIFY_ADVICE}.",
            markup=False,
        ),
        markup=False,
        highlight=False,
    )


def _progress():
    """A callback printing the loop study's progress on stderr (the first run compiles the
    numba kernels, tens of seconds)."""
    first = [True]

    def say(text: str) -> None:
        suffix = " (the first run compiles the loop kernels: up to a minute)" if first[0] else ""
        first[0] = False
        err_console.print(terminal(f"{text}{suffix}", markup=False), markup=False, highlight=False)

    return say


def _export_targets(export: str | None, fmu_kind: str, export_only: bool) -> list[str]:
    """The checked targets of ``--export-compensator`` (empty without it)."""
    if export is None:
        if export_only:
            raise BadInput("--export-only needs --export-compensator c,fmu,matlab")
        return []
    from ..control.export import EXPORT_TARGETS, EXPORTABLE_COMPENSATORS

    targets = [t.strip() for t in export.split(",") if t.strip()]
    bad = [t for t in targets if t not in EXPORT_TARGETS]
    if bad or not targets:
        raise BadInput(
            f"--export-compensator {export!r}: expected some of "
            f"{list(EXPORT_TARGETS)}, comma-separated"
        )
    if fmu_kind not in EXPORTABLE_COMPENSATORS:
        raise BadInput(
            f"--fmu-compensator {fmu_kind!r}: expected one of {list(EXPORTABLE_COMPENSATORS)}"
        )
    return targets


def _write_exports(
    model,
    out: Path,
    targets,
    axis,
    fmu_kind: str,
    *,
    default_axis: bool,
    force_filter: float = 0.0,
    velocity_input: bool = False,
) -> None:
    """Write the compensator into ``out/compensator``; note the default axis on stderr."""
    from ..control.export import export_compensator

    written = export_compensator(
        model,
        out / "compensator",
        targets=targets,
        axis=axis,
        compensator=fmu_kind,
        force_filter=force_filter,
        velocity_input=velocity_input,
    )
    for path in written:
        console.print(terminal(f"written: {path}", markup=False), markup=False)
    if default_axis:
        err_console.print(default_axis_note(), markup=False, highlight=False)


def _print_metrics(result) -> None:
    """The loop gain and one line of errors [um] per compensator."""
    console.print(
        terminal(
            f"PI loop gain K_v = {result.tuning.loop_gain_1_s:.2f} 1/s "
            f"(omega_h {result.axis.natural_frequency():.0f} rad/s, 6 dB gain margin)",
            markup=False,
        ),
        markup=False,
    )
    for name, m in result.metrics.items():
        reversal = m["reversal_error_m"]
        text = "-" if reversal is None else f"{reversal * 1e6:.2f}"
        console.print(
            terminal(
                f"{name:8s} RMS {m['rms_error_m'] * 1e6:8.2f} um   max "
                f"{m['max_error_m'] * 1e6:8.2f} um   reversal {text} um",
                markup=False,
            ),
            markup=False,
        )
