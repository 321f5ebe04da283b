"""``cylfric catalog``: a catalogue of seal datasheets (SQLite): add, list, show, compare,
select, predict another size, export and import.

The catalogue file: ``--db PATH``, else the ``CYLFRIC_CATALOG`` environment variable, else
the per-user data folder (``~/.local/share/cylfric/catalog.sqlite``).
"""

from __future__ import annotations

import re
from pathlib import Path

import typer

from ..escape import terminal
from .common import (
    JSON_HELP,
    BadInput,
    console,
    err_console,
    guarded,
    model_document,
    numbers,
    print_json,
    print_table,
)

catalog_app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="A catalogue of seal friction datasheets: add, list, show, compare, select, predict.",
)

DB_HELP = "Catalogue file (default: $CYLFRIC_CATALOG, else ~/.local/share/cylfric/catalog.sqlite)."
_TEMPERATURE = re.compile(r"^\s*([-+]?\d+(?:[.,]\d*)?(?:[eE][-+]?\d+)?)\s*(K|degC|°C|C)?\s*$")


def _db(path):
    from ..catalog import Catalog

    return Catalog(path)


def _one(text, dimension, unit, option):
    if text is None:
        return None
    values = numbers(text, dimension, unit)
    if len(values) != 1:
        raise BadInput(f"{option} {text!r}: expected one value (e.g. {option} 40{unit})")
    return values[0]


def _temperature(text):
    """``"40degC"``, ``"40"`` (degC) or ``"313K"`` -> kelvin."""
    if text is None:
        return None
    match = _TEMPERATURE.match(text)
    if not match:
        raise BadInput(
            f"--temperature {text!r}: expected a temperature such as 40degC or 313K "
            "(a bare number is in degC)"
        )
    value = float(match.group(1).replace(",", "."))
    return value if match.group(2) == "K" else value + 273.15


def _text(value):
    """Text of a metadata cell: "-" for None or NaN."""
    return terminal(value) if isinstance(value, str) and value else "-"


def _fmt(value, scale=1.0, digits=4):
    import math

    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return f"{value * scale:.{digits}g}"


@catalog_app.command("add")
@guarded
def add(
    datasheet: Path = typer.Argument(..., help="datasheet.json or a fit output folder."),
    name: str = typer.Option(..., "--name", help="Catalogue name (unique)."),
    seal: str = typer.Option(None, "--seal", help="Seal type or designation."),
    manufacturer: str = typer.Option(None, "--manufacturer", help="Seal or cylinder maker."),
    bore: str = typer.Option(None, "--bore", help="Tested bore, mm or with units (40mm)."),
    rod: str = typer.Option(None, "--rod", help="Tested rod diameter, mm or with units."),
    fluid: str = typer.Option(None, "--fluid", help="Working fluid (HLP 46, air, ...)."),
    temperature: str = typer.Option(None, "--temperature", help="Test temperature: 40degC, 313K."),
    replace: bool = typer.Option(False, "--replace", help="Replace an entry of the same name."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Add a datasheet (validated) with its seal metadata."""
    catalog = _db(db)
    catalog.add(
        datasheet,
        name,
        seal=seal,
        manufacturer=manufacturer,
        bore=_one(bore, "length", "mm", "--bore"),
        rod=_one(rod, "length", "mm", "--rod"),
        fluid=fluid,
        temperature=_temperature(temperature),
        replace=replace,
    )
    console.print(
        terminal(f"added {name!r} to {catalog.path} ({len(catalog)} entries)"), highlight=False
    )


@catalog_app.command("list")
@guarded
def list_entries(
    db: Path = typer.Option(None, "--db", help=DB_HELP),
    json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """List the catalogue (metadata in engineering units, validity ranges)."""
    from rich.markup import escape
    from rich.table import Table

    catalog = _db(db)
    frame = catalog.list()
    if json_output:
        print_json({"catalog": catalog.path, "entries": frame.to_dict("records")})
        return
    cells = {
        "name": lambda r: terminal(r["name"]),
        "seal": lambda r: _text(r["seal"]),
        "manufacturer": lambda r: _text(r["manufacturer"]),
        "bore [mm]": lambda r: _fmt(r["bore [m]"], 1e3),
        "rod [mm]": lambda r: _fmt(r["rod [m]"], 1e3),
        "fluid": lambda r: _text(r["fluid"]),
        "T [degC]": lambda r: _fmt(
            None if r["temperature [K]"] is None else r["temperature [K]"] - 273.15
        ),
        "law": lambda r: terminal(r["friction law"]),
        "p [bar]": lambda r: (
            f"{_fmt(r['pressure min [Pa]'], 1e-5, 3)}-{_fmt(r['pressure max [Pa]'], 1e-5, 3)}"
        ),
        "v [mm/s]": lambda r: (
            f"{_fmt(r['velocity min [m/s]'], 1e3, 3)}-{_fmt(r['velocity max [m/s]'], 1e3, 3)}"
        ),
        "RMSE [N]": lambda r: _fmt(r["rmse [N]"], 1, 3),
    }
    rows = [{k: f(r) for k, f in cells.items()} for r in frame.to_dict("records")]
    shown = [k for k in cells if k in ("name", "law") or any(r[k] != "-" for r in rows)]
    table = Table(title=terminal(f"Catalogue {catalog.path} ({len(frame)} entries)"))
    for column in shown:
        table.add_column(escape(column), overflow="fold")
    for row in rows:
        table.add_row(*(row[k] for k in shown))
    print_table(table)


@catalog_app.command("show")
@guarded
def show(
    name: str = typer.Argument(..., help="Catalogue name."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
    json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Show an entry: metadata and its pressure laws with standard errors."""
    from rich.table import Table

    catalog = _db(db)
    meta = catalog.metadata(name)
    model = catalog.model(name)
    if json_output:
        units = {"bore": "bore [m]", "rod": "rod [m]", "temperature": "temperature [K]"}
        metadata = {units.get(k, k): v for k, v in meta.items()}
        print_json({**model_document(model), "name": name, "metadata": metadata})
        return
    table = Table(title=terminal(name), show_header=False)
    table.add_column("", style="bold")
    table.add_column("")
    for key in ("seal", "manufacturer", "fluid"):
        table.add_row(key, _text(meta[key]))
    table.add_row("bore", "-" if meta["bore"] is None else f"{meta['bore'] * 1e3:.4g} mm")
    table.add_row("rod", "-" if meta["rod"] is None else f"{meta['rod'] * 1e3:.4g} mm")
    temperature = meta["temperature"]
    table.add_row("temperature", "-" if temperature is None else f"{temperature - 273.15:.4g} degC")
    for line in model.law_lines():
        key, sep, rest = line.partition(" = ")
        if not sep:
            key, _, rest = line.partition(": ")
        table.add_row(terminal(key), terminal(rest))
    if model.validity is not None:
        val = model.validity
        table.add_row(
            "valid for",
            f"{val['pressure_min'] / 1e5:.3g}-{val['pressure_max'] / 1e5:.3g} bar, "
            f"{val['velocity_min'] * 1e3:.3g}-{val['velocity_max'] * 1e3:.3g} mm/s",
        )
    table.add_row("method", terminal(model.provenance.get("method", "-")))
    table.add_row("added", terminal(meta["added"]))
    print_table(table)


def _default_points(models):
    """Three pressures and three speeds spanning the union of the validity ranges."""
    import numpy as np

    ranges = [m.validity for m in models if m.validity is not None]
    if not ranges:
        raise BadInput("no entry has validity ranges: give --pressures and --speeds")
    p_lo = min(r["pressure_min"] for r in ranges)
    p_hi = max(r["pressure_max"] for r in ranges)
    v_lo = max(min(r["velocity_min"] for r in ranges), 1e-5)
    v_hi = max(r["velocity_max"] for r in ranges)
    return list(np.linspace(p_lo, p_hi, 3)), list(np.geomspace(v_lo, v_hi, 3))


@catalog_app.command("compare")
@guarded
def compare(
    names: list[str] = typer.Argument(..., help="Catalogue names to compare."),
    out: Path = typer.Option(..., "--out", "-o", help="Folder for compare.csv/png/svg."),
    pressures: str = typer.Option(
        None, "--pressures", help="Pressures, bar or with units (default: 3 over the ranges)."
    ),
    speeds: str = typer.Option(
        None, "--speeds", help="Speeds, mm/s or with units (default: 3 over the ranges)."
    ),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Friction against velocity and pressure side by side with 95 % bands; a table."""
    from rich.markup import escape
    from rich.table import Table

    catalog = _db(db)
    models = [catalog.model(n) for n in names]
    p_default, v_default = _default_points(models) if not (pressures and speeds) else (0, 0)
    p = numbers(pressures, "pressure", "bar") if pressures else p_default
    v = numbers(speeds, "velocity", "mm/s") if speeds else v_default
    if not p or not v:
        raise BadInput("--pressures and --speeds need at least one value each")
    result = catalog.compare(names, out, p, v)
    table = Table(title="Friction at the operating points (95 % band of the mean)")
    for column in ("name", "p [bar]", "v [mm/s]", "friction [N]", "band [N]", "inside"):
        table.add_column(escape(column), justify="right")
    for row in result["table"].to_dict("records"):
        table.add_row(
            terminal(row["name"]),
            f"{row['pressure [Pa]'] / 1e5:.3g}",
            f"{row['velocity [m/s]'] * 1e3:.3g}",
            f"{row['friction [N]']:.2f}",
            f"{_fmt(row['lower [N]'], 1, 4)}-{_fmt(row['upper [N]'], 1, 4)}",
            "yes" if row["inside validity"] else "extrapolated",
        )
    print_table(table)
    console.print(
        terminal(f"outputs in {out}: compare.csv, compare.png, compare.svg"), highlight=False
    )


@catalog_app.command("select")
@guarded
def select(
    pressure: str = typer.Option(..., "--pressure", help="Operating pressure, bar or 100bar."),
    velocity: str = typer.Option(..., "--velocity", help="Speed, mm/s or 20mm/s."),
    max_friction: str = typer.Option(
        None, "--max-friction", help="Keep entries whose upper 95 % limit is below, N or 150N."
    ),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
    json_output: bool = typer.Option(False, "--json", help=JSON_HELP),
):
    """Rank the catalogue by friction at an operating point (lowest first), with bands."""
    from rich.markup import escape
    from rich.table import Table

    p = _one(pressure, "pressure", "bar", "--pressure")
    v = _one(velocity, "velocity", "mm/s", "--velocity")
    limit = _one(max_friction, "force", "N", "--max-friction")
    catalog = _db(db)
    ranked = catalog.select(p, v, max_friction=limit)
    unreadable = ranked.attrs.get("unreadable", {})
    for reason in unreadable.values():
        err_console.print(terminal(f"warning: left out: {reason}"), highlight=False)
    if json_output:
        print_json(
            {
                "pressure [Pa]": p,
                "velocity [m/s]": v,
                "max friction [N]": limit,
                "ranked": ranked.to_dict("records"),
                "unreadable": unreadable,
            }
        )
        return
    title = f"Friction at {p / 1e5:.4g} bar, {abs(v) * 1e3:.4g} mm/s"
    if limit is not None:
        title += f", upper limit <= {limit:.4g} N"
    table = Table(title=title)
    for column in ("rank", "name", "seal", "friction [N]", "95 % band [N]", "inside", "law"):
        table.add_column(escape(column), justify="right")
    for row in ranked.to_dict("records"):
        table.add_row(
            str(row["rank"]),
            terminal(row["name"]),
            _text(row["seal"]),
            f"{row['friction [N]']:.2f}",
            f"{_fmt(row['lower [N]'], 1, 4)}-{_fmt(row['upper [N]'], 1, 4)}",
            "yes" if row["inside validity"] else "extrapolated",
            terminal(row["friction law"]),
        )
    print_table(table)
    if ranked.empty:
        console.print("no entry meets the limit", highlight=False)


@catalog_app.command("predict")
@guarded
def predict(
    name: str = typer.Argument(..., help="Catalogue name of the tested seal."),
    bore: str = typer.Option(..., "--bore", help="Target bore, mm or with units (63mm)."),
    rod: str = typer.Option(None, "--rod", help="Target rod diameter, mm or with units."),
    out: Path = typer.Option(..., "--out", "-o", help="Predicted datasheet (JSON) to write."),
    contact: str = typer.Option(
        None, "--contact", help="piston, rod or total (default: piston; total with --rod)."
    ),
    rod_seals: int = typer.Option(1, "--rod-seals", help="Rod seals counted by --contact total."),
    rule_stderr: float = typer.Option(
        0.10, "--rule-stderr", help="Relative standard error of the scaling rule [-] (0.10)."
    ),
    add_as: str = typer.Option(None, "--add-as", help="Also add the prediction under this name."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Scale a seal's friction to another cylinder size by seal contact length."""
    import json

    from .._paths import refuse_link
    from ..io.writers import atomic_write_text
    from ..model import FrictionModel

    refuse_link(out)  # before the prediction: a symbolic link is refused, not replaced
    catalog = _db(db)
    target_bore = _one(bore, "length", "mm", "--bore")
    target_rod = _one(rod, "length", "mm", "--rod")
    sheet = catalog.predict(
        name,
        target_bore,
        target_rod,
        contact=contact,
        rod_seals=rod_seals,
        rule_stderr=rule_stderr,
    )
    atomic_write_text(out, json.dumps(sheet, indent=1) + "\n")
    prediction = sheet["prediction"]
    console.print(terminal(f"rule: {prediction['rule']}"), highlight=False)
    console.print(
        f"added uncertainty: {rule_stderr:.0%} relative standard error of the rule "
        "(an assumption), in the covariance and the bands",
        highlight=False,
    )
    for line in FrictionModel.from_datasheet(sheet).law_lines():
        console.print(terminal(line, markup=False), highlight=False, markup=False)
    if add_as:
        catalog.add(
            sheet,
            add_as,
            bore=target_bore,
            rod=target_rod,
            **{
                k: catalog.metadata(name)[k]
                for k in ("seal", "manufacturer", "fluid", "temperature")
            },
        )
        console.print(terminal(f"added {add_as!r} to {catalog.path}"), highlight=False)
    console.print(terminal(f"predicted datasheet in {out}"), highlight=False)


@catalog_app.command("remove")
@guarded
def remove(
    name: str = typer.Argument(..., help="Catalogue name."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Remove an entry."""
    catalog = _db(db)
    catalog.remove(name)
    console.print(terminal(f"removed {name!r} from {catalog.path}"), highlight=False)


@catalog_app.command("export")
@guarded
def export(
    path: Path = typer.Argument(..., help="JSON file to write."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Export the whole catalogue as one JSON file (a symbolic link PATH is refused)."""
    from .._paths import refuse_link

    refuse_link(path, "PATH")
    catalog = _db(db)
    catalog.export_json(path)
    console.print(terminal(f"exported {len(catalog)} entries to {path}"), highlight=False)


@catalog_app.command("import")
@guarded
def import_(
    path: Path = typer.Argument(..., help="JSON file written by catalog export."),
    replace: bool = typer.Option(False, "--replace", help="Replace entries of the same name."),
    db: Path = typer.Option(None, "--db", help=DB_HELP),
):
    """Import a catalogue export (all entries or none)."""
    catalog = _db(db)
    count = catalog.import_json(path, replace=replace)
    console.print(terminal(f"imported {count} entries into {catalog.path}"), highlight=False)


def register(app) -> None:
    """Add ``cylfric catalog ...`` to the app."""
    app.add_typer(catalog_app, name="catalog")
