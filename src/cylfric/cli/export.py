"""``cylfric export DATASHEET --to TARGET --out PATH``: the datasheet in a simulator's form."""

from __future__ import annotations

from pathlib import Path

import typer

from ..escape import terminal
from .common import JSON_HELP, BadInput, console, err_console, guarded, print_json

TARGET_NAMES = ("fmu", "modelica", "simscape", "hopsan", "matlab")


def register(app) -> None:
    """Add ``cylfric export`` to the app."""

    @app.command("export")
    @guarded
    def export_command(
        datasheet: Path = typer.Argument(..., help="A datasheet.json file (never modified)."),
        to: str = typer.Option(..., "--to", help=f"Target: {', '.join(TARGET_NAMES)}."),
        out: Path = typer.Option(
            Path("cylfric-export"),
            "--out",
            "-o",
            help="Output folder. For fmu and modelica, a path ending in .fmu or .mo (and not "
            "an existing folder) is the file itself; its stem names the model when it is an "
            "identifier and --name is not given. A symbolic link is refused.",
        ),
        name: str = typer.Option(
            None, "--name", help="Name of the exported files (default: the datasheet's name)."
        ),
        element: str = typer.Option(
            None,
            "--element",
            help="FMU only: 'friction' (the friction element, default) or 'cylinder' (with "
            "the moving mass, driven by a force or a position servo).",
        ),
        json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
    ):
        """Datasheet -> FMU, Modelica package, Simscape or Hopsan parameters, MATLAB function.

        Lossy targets (simscape, hopsan) fit the simulator's own friction block over the
        datasheet's validity range and write a loss report (CSV, text, figure) beside it.
        --out f.fmu (fmu) and --out Seal.mo (modelica) write that one file; the other
        targets write several files into the --out folder.
        """
        from .._paths import refuse_link
        from ..export import TARGETS, export

        target = to.strip().lower()
        if target not in TARGETS:
            raise BadInput(f"--to {to!r}: unknown export target; valid: {sorted(TARGETS)}")
        if not datasheet.is_file():
            raise BadInput(f"{datasheet}: no such datasheet file; expected a datasheet.json")
        refuse_link(out)  # a symbolic link (folder or file) is refused, not written through
        _check_out(out, target)
        import warnings

        from ..model import FrictionModel

        options = _export_options(target, name, element)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            model = FrictionModel.from_datasheet(datasheet)  # read once: export and notes
            result = export(model, target, out, **options)
        assumed = model.assumptions()
        for line in assumed:  # on stderr, whatever is printed on stdout
            err_console.print(f"[yellow]note:[/yellow] {terminal(line)}", highlight=False)
        notes = list(dict.fromkeys(str(w.message) for w in caught))
        if json_output:
            losses = [
                {"block": r.title, "rms [N]": r.rms, "max [N]": r.max_abs}
                for r in result.loss or ()
            ]
            print_json(
                {
                    "target": target,
                    "files": list(result.files),
                    "lossless": result.loss is None,
                    "loss": losses,
                    "notes": notes,
                    "assumptions": assumed,
                }
            )
            return
        for message in notes:  # each once, as a note
            console.print(f"[yellow]note:[/yellow] {terminal(message)}", highlight=False)
        for line in result.summary().splitlines():
            console.print(terminal(line, markup=False), markup=False, highlight=False)
        for path in result.files:
            console.print(terminal(f"  wrote {path}", markup=False), markup=False, highlight=False)


def _check_out(out: Path, target: str) -> None:
    """Refuse an ``--out`` that is an existing file, unless it is the target's single file."""
    from ..export import SINGLE_FILE

    suffix = SINGLE_FILE.get(target)
    as_file = suffix is not None and out.suffix.lower() == suffix and not out.is_dir()
    if out.exists() and not out.is_dir() and not as_file:
        files = ", ".join(f"{k}: {v}" for k, v in SINGLE_FILE.items())
        raise BadInput(
            f"--out {out} is a file; expected a folder (a file path only for the "
            f"single-file targets, with their suffix: {files})"
        )


def _export_options(target: str, name: str | None, element: str | None) -> dict[str, str]:
    """The keywords of ``export`` given by ``--name`` and ``--element`` (FMU only)."""
    options = {} if name is None else {"name": name}
    if element is not None:
        if target != "fmu":
            raise BadInput(f"--element is for --to fmu only; --to {target} has one form")
        options["element"] = element
    return options
