"""A small load-cell rig written apart from cylfric's simulators (tests of the gate's physics).

Each run: a triangle motion of ``travel`` at ``speed`` (``strokes`` strokes), both chambers
measured, and a load cell whose reading follows the true force balance
``F_f sign(v) = A_a p_a - A_b p_b + s F_lc - W`` (thesis eq. 3.1) with the rig's true signs:
``F_lc = s (F_f sign(v) - A_a p_a + A_b p_b + W)``, the position written as ``s_x x``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cylfric.io.writers import write_mts_text


def friction_law(pressure_bar: float) -> float:
    """The rig's true friction level [N] at a chamber pressure [bar]: 3 N + 0.7 N/bar."""
    return 3.0 + 0.7 * pressure_bar


def write_run(
    path: Path,
    pressure_bar: float,
    *,
    area_a: float,
    area_b: float,
    pressure_b_bar: float | None = None,
    load_cell_sign: int = -1,
    position_sign: int = -1,
    weight: float = 12.0,
    speed: float = 0.010,
    travel: float = 0.040,
    strokes: int = 4,
    direction_drop_bar: float = 0.06,
    force_unit: str = "N",
    force_values_in: str | None = None,
    seed: int = 0,
) -> None:
    """One run file (Time [s], Position [mm], Force [force_unit], Pressure A/B [bar]);
    ``force_values_in`` writes the force in another unit than its label says (a slip)."""
    rng = np.random.default_rng(seed)
    dt = 0.01
    period = travel / speed
    t = np.arange(0.0, strokes * period, dt)
    phase = (t / period) % 2.0
    x = np.where(phase < 1.0, phase, 2.0 - phase) * travel  # triangle: up, down, ...
    v = np.where(phase < 1.0, speed, -speed)
    pb_bar = pressure_bar if pressure_b_bar is None else pressure_b_bar
    # the chamber pressure sags by a little in one direction (a regulator's droop)
    pa = (pressure_bar - direction_drop_bar * (v < 0)) * 1e5
    pb = np.full(t.size, pb_bar * 1e5)
    friction = friction_law(pressure_bar) * np.sign(v)
    force = load_cell_sign * (friction - area_a * pa + area_b * pb + weight)
    force = force + 0.05 * rng.standard_normal(t.size)
    scale = {"N": 1.0, "kN": 1e3, "MN": 1e6}[force_values_in or force_unit]
    write_mts_text(
        path,
        [
            {
                "Time": t,
                "Position": position_sign * x * 1e3,
                "Force": force / scale,
                "Pressure A": (pa + 0.01e5 * rng.standard_normal(t.size)) / 1e5,
                "Pressure B": (pb + 0.01e5 * rng.standard_normal(t.size)) / 1e5,
            }
        ],
        header={"Station Name": "synthetic rig", "Pressure": f"{pressure_bar:g} bar"},
        units={
            "Time": "s",
            "Position": "mm",
            "Force": force_unit,
            "Pressure A": "bar",
            "Pressure B": "bar",
        },
        decimals={"Time": 3, "Position": 4, "Force": 9, "Pressure A": 4, "Pressure B": 4},
    )


def write_campaign(
    folder: Path,
    *,
    pressures_bar=(1.0, 3.0, 5.0, 7.0),
    repeats: int = 2,
    bore_mm: float = 25.0,
    rod_mm: float = 0.0,
    kind: str = "single-acting",
    recipe_signs: tuple[int | None, int | None] = (-1, -1),
    reference: str | None = None,
    both_chambers: bool = False,
    manifest: dict | None = None,
    **run,
) -> Path:
    """A campaign folder: ``run_NN_p<p>bar.txt`` files, manifest.csv and campaign.toml.

    ``recipe_signs`` are the (load_cell_sign, position_sign) campaign.toml states (None:
    not stated); the files follow the rig's true signs (``run`` keywords of
    :func:`write_run`). ``both_chambers``: chamber B holds the same pressure as A.
    ``manifest`` maps a file index to the pressure [bar] its manifest row says instead.
    """
    folder.mkdir(parents=True, exist_ok=True)
    piston = math.pi / 4 * (bore_mm / 1e3) ** 2
    annulus = piston - math.pi / 4 * (rod_mm / 1e3) ** 2
    area_a, area_b = {
        "single-acting": (piston, 0.0),
        "single-rod": (piston, annulus),
        "double-rod": (annulus, annulus),
    }[kind]
    rows = ["file,pressure_bar"]
    index = 0
    for _ in range(repeats):
        for p in pressures_bar:
            name = f"run_{index:02d}_p{p:g}bar.txt"
            write_run(
                folder / name,
                p,
                area_a=area_a,
                area_b=area_b,
                pressure_b_bar=p if both_chambers else 0.0,
                seed=index,
                **run,
            )
            said = (manifest or {}).get(index, p)
            rows.append(f"{name},{said:g}")
            index += 1
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    lines = ['[files]\nglob = "*.txt"\n', "[cylinder]", f'bore = "{bore_mm:g} mm"']
    if rod_mm:
        lines.append(f'rod = "{rod_mm:g} mm"')
    lines.append(f'kind = "{kind}"')
    if reference is not None:
        lines.append(f'pressure_reference = "{reference}"')
    lines.append("\n[force_balance]")
    for key, value in zip(("load_cell_sign", "position_sign"), recipe_signs, strict=True):
        if value is not None:
            lines.append(f"{key} = {value}")
    (folder / "campaign.toml").write_text("\n".join(lines) + "\n")
    return folder
