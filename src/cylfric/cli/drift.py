"""``cylfric drift A [B]``: did the friction change between two fits, and along a campaign?"""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import plot_text, terminal
from .common import JSON_HELP, BadInput, console, guarded, print_json, print_table


def _trend(source, label, out, order, campaign, quiet=False):
    from ..drift import figure_run_order, load_fit, run_order_trend

    model, points, _ = load_fit(source)
    if points is None:
        return None
    trend = run_order_trend(points, model, order=order, campaign=campaign)
    if not quiet:
        console.print(
            f"[bold]{terminal(label)}[/bold]: friction against run order ({len(trend.runs)} runs)"
        )
        console.print(terminal(trend.summary(), markup=False, multiline=True), markup=False)
    if out is not None:
        import io

        from ..escape import csv_frame
        from ..io.writers import atomic_write_bytes, atomic_write_text

        fig = figure_run_order(trend, title=f"{plot_text(label)}: friction against run order")
        for fmt in ("png", "svg"):
            buffer = io.BytesIO()
            fig.savefig(buffer, format=fmt, dpi=110)
            atomic_write_bytes(Path(out) / f"run_order_{label}.{fmt}", buffer.getvalue())
        atomic_write_text(
            Path(out) / f"run_order_{label}.csv", csv_frame(trend.runs).to_csv(index=False)
        )
    return trend


def register(app) -> None:
    """Add ``cylfric drift`` to the app."""

    @app.command("drift")
    @guarded
    def drift(
        a: Path = typer.Argument(..., help="Earlier datasheet.json or fit output folder."),
        b: Path = typer.Argument(None, help="Later datasheet.json or fit output folder."),
        out: Path = typer.Option(None, "--out", "-o", help="Folder for CSV, JSON and figures."),
        level: float = typer.Option(0.95, "--level", help="Confidence level of the marks [-]."),
        order: str = typer.Option("run", "--order", help="Run order: run (manifest) or mtime."),
        campaign: Path = typer.Option(
            None, "--campaign", help="Raw-file folder of A (for --order mtime)."
        ),
        scope: str = typer.Option(
            "auto",
            "--scope",
            help="Judge the change against: session (different sessions: reproducibility), "
            "repeatability (the same session), auto (same session names: repeatability).",
        ),
        json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
    ):
        """Change of friction between two fits (z-scores), and friction against run order.

        Two fits of different sessions are judged against the between-session scatter
        their datasheets state (reproducibility), two fits of the same session against
        their standard errors (repeatability); the output says which. Coefficients are
        compared only when both fits have the same friction law and the coefficient's
        pressure law is the same; otherwise only the friction at operating points is (a
        note says why). Fits whose pressure laws see different pressures (reference a, b,
        sum, mean, max) are refused (exit 2).
        """
        from ..drift import DRIFT_SCOPES

        if scope not in DRIFT_SCOPES:
            raise BadInput(f"--scope {scope}: unknown; valid: {', '.join(DRIFT_SCOPES)}")
        for path in (a, b):
            if path is not None and not path.exists():
                raise BadInput(f"{path}: not found; expected a datasheet.json or a fit folder")
        if out is not None:
            from .._paths import make_folder

            make_folder(out)  # a symbolic link is refused (exit 2), not written through
        if b is None:
            if scope != "auto":
                raise BadInput("--scope applies to two fits (cylfric drift A B --scope ...)")
            _one_fit(a, out, order, campaign, json_output)
        else:
            _two_fits(a, b, out, level, order, campaign, json_output, scope)


def _one_fit(a: Path, out, order: str, campaign, json_output: bool) -> None:
    """``cylfric drift A``: the run-order trend of one fit."""
    from ..drift import fit_labels

    (label,) = fit_labels(a)
    trend = _trend(a, label, out, order, campaign, quiet=json_output)
    if trend is None:
        raise BadInput(
            f"{a}: no points.csv beside the datasheet; the run-order trend needs a fit "
            "output folder (or give a second datasheet B to compare)"
        )
    if json_output:
        print_json(
            {
                "fit": a,
                "order": trend.order,
                "between_slope [N/run]": trend.between_slope,
                "between_stderr [N/run]": trend.between_stderr,
                "within_slope [N/stroke]": trend.within_slope,
                "within_stderr [N/stroke]": trend.within_stderr,
                "runs": trend.runs.to_dict("records"),
            }
        )


def _two_fits(
    a: Path, b: Path, out, level: float, order: str, campaign, json_output: bool, scope: str
):
    """``cylfric drift A B``: the change between two fits, then each fit's run-order trend."""
    from ..drift import SCOPE_WORDS, fit_labels, write_drift
    from ..drift import drift as compute

    if order != "run" or campaign is not None:
        raise BadInput(
            "--order and --campaign apply to one campaign (cylfric drift A --order mtime "
            "--campaign RAW); with two fits the run-order trends use the run order"
        )
    table = compute(a, b, level=level, scope=scope)
    labels = fit_labels(a, b)
    if json_output:
        if out is not None:
            write_drift(table, out)
        print_json(
            {
                "a": a,
                "b": b,
                "labels": labels,
                "scope": table.attrs["scope"],
                "judged_against": SCOPE_WORDS[table.attrs["scope"]],
                "scope_reason": table.attrs["scope_reason"],
                "verdict": table.attrs["verdict"],
                "level": level,
                "z_critical": table.attrs.get("z_critical"),
                "dof": table.attrs.get("dof"),
                "notes": list(table.attrs.get("notes", [])),
                "rows": table.to_dict("records"),
            }
        )
        return
    _print_scope(table)
    _print_coefficients(table, labels)
    _print_friction(table, level, labels)
    if out is not None:
        write_drift(table, out)
    for source, label in zip((a, b), labels, strict=True):
        _trend(source, label, out, "run", None)
    if out is not None:
        console.print(terminal(f"outputs in {out}"), highlight=False)


def _print_scope(table) -> None:
    """What the change is judged against, and why."""
    from rich.markup import escape

    from ..drift import SCOPE_WORDS

    words = escape(SCOPE_WORDS[table.attrs["scope"]])
    reason = escape(terminal(table.attrs["scope_reason"]))
    console.print(f"[bold]judged against {words}[/bold] ({reason})", highlight=False)


def _print_coefficients(table, labels) -> None:
    """The table of the coefficients' changes (in engineering units), then the notes."""
    from rich.markup import escape
    from rich.table import Table

    from ..model.core import engineering_unit

    params = table[table["kind"] == "parameter"]
    first, second = labels
    view = Table(title=terminal(f"Change of the coefficients, {second} - {first}"))
    for column in ("coefficient", "unit", first, second, "change", "z", "sig."):
        view.add_column(escape(column), justify="right", no_wrap=True)
    for row in params.to_dict("records"):
        unit, k = engineering_unit(row["quantity"])
        view.add_row(
            row["quantity"],
            unit,
            f"{row['a'] * k:.4g}",
            f"{row['b'] * k:.4g}",
            f"{row['change'] * k:+.3g}",
            f"{row['z [-]']:+.2f}",
            "yes" if row["significant"] else "no",
        )
    if len(params):
        print_table(view)
    for note in table.attrs.get("notes", []):
        console.print(f"[yellow]note:[/yellow] {escape(note)}", highlight=False)


def _print_friction(table, level: float, labels) -> None:
    """The table of the friction's changes [N] at the operating points, their count and the
    verdict."""
    from rich.markup import escape
    from rich.table import Table

    friction = table[table["kind"] == "friction"]
    view = Table(title="Change of the friction over the common validity range")
    first, second = labels
    columns = ("p [bar]", "v [mm/s]", f"{first} [N]", f"{second} [N]", "change [N]", "z", "sig.")
    for column in columns:
        view.add_column(escape(column), justify="right")
    for row in friction.to_dict("records"):
        view.add_row(
            f"{row['pressure [Pa]'] / 1e5:.4g}",
            f"{row['velocity [m/s]'] * 1e3:.3g}",
            f"{row['a']:.2f}",
            f"{row['b']:.2f}",
            f"{row['change']:+.2f}",
            f"{row['z [-]']:+.2f}",
            "yes" if row["significant"] else "no",
        )
    print_table(view)
    dof = table.attrs.get("dof")
    quantile = "normal" if dof is None else f"Student-t, {dof:.3g} dof"
    console.print(
        f"{int(friction['significant'].sum())} of {len(friction)} operating points changed "
        f"more than their uncertainty (|z| > {table.attrs['z_critical']:.2f}, "
        f"{level:.0%} two-sided, {quantile}); largest |z| = {friction['z [-]'].abs().max():.2f}",
        highlight=False,
    )
    verdict = table.attrs["verdict"]
    word = "a significant change" if verdict["significant"] else "no significant change"
    p_value = "" if verdict["p_value"] is None else f", p = {verdict['p_value']:.3g}"
    console.print(
        f"[bold]{word}[/bold] at the {table.attrs['scope']} scope ({escape(verdict['test'])}: "
        f"{verdict['statistic']:.3g} against {verdict['critical']:.3g}{p_value})",
        highlight=False,
    )
