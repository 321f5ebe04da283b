"""``cylfric control DATASHEET``: the datasheet's friction compensation in a servo loop."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import JSON_HELP, BadInput, console, guarded, print_json


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
        json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
    ):
        """Run the position loop with every compensator (none, coulomb, static, lugre,
        oracle); write metrics.json, timeseries.csv and control.html into --out."""
        from .._paths import refuse_link
        from ..control.axis import DEFAULT_AXIS, load_axis
        from ..control.loop import REFERENCES, Reference, read_reference
        from ..control.study import compare_compensators
        from ..model import FrictionModel

        if not datasheet.is_file():
            raise BadInput(f"{datasheet}: not found; expected a datasheet.json file")
        refuse_link(out)
        model = FrictionModel.from_datasheet(datasheet)
        the_axis = load_axis(axis) if axis is not None else DEFAULT_AXIS
        ref: Reference | str
        if reference in REFERENCES:
            ref = reference
        elif Path(reference).is_file():
            ref = read_reference(reference, the_axis)
        else:
            raise BadInput(
                f"--reference {reference!r}: expected one of {list(REFERENCES)} or a CSV file"
            )
        result = compare_compensators(model, axis=the_axis, reference=ref, robustness=robustness)
        result.write(out)
        document = result.to_dict()
        if json_output:
            print_json(document)
            return
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
        console.print(terminal(f"written: {out}", markup=False), markup=False)
