"""Every compensator on one axis and reference, with robustness cases; the outputs.

:func:`compare_compensators` returns a :class:`ControlResult` (the Python API); its
:meth:`~ControlResult.write` makes ``OUT/metrics.json``, ``OUT/timeseries.csv`` and
``OUT/control.html`` (PNG figures embedded), every file written atomically.
"""

from __future__ import annotations

import base64
import io
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._atomic import atomic_write_bytes, atomic_write_text
from ..escape import html_text
from ..model.names import IDENTIFY_ADVICE
from .axis import DEFAULT_AXIS, Axis
from .loop import (
    COMPENSATORS,
    FORCE_FILTER,
    OBSERVER_GAIN,
    SMOOTHING_VELOCITY,
    LoopRun,
    PlantFriction,
    Reference,
    _rest_viscous,
    make_reference,
    simulate_loop,
)
from .metrics import tracking_metrics
from .tuning import Tuning, feedforward_lead, tune

if TYPE_CHECKING:
    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "ControlResult",
    "compare_compensators",
    "ROBUSTNESS_CASES",
    "robustness_cases",
    "SIGMA_0_FACTORS",
    "LEVEL_FACTORS",
    "dynamic_parameters",
    "IDENTIFY_ADVICE",
]

SIGMA_0_FACTORS = (0.1, 0.3, 1.0, 3.0, 10.0)
"""Factors on the datasheet's sigma_0 of the plants of the sensitivity study [-]."""
LEVEL_FACTORS = (0.8, 1.0, 1.2)
"""Factors on the friction level (F_c, F_s, sigma_2) of the sensitivity study [-]."""


def dynamic_parameters(model: FrictionModel) -> dict[str, dict[str, Any]]:
    """sigma_0 and sigma_1 of the datasheet: value at the rest pressure (SI), ``status``
    (``identified`` or ``assumed``) and its reason."""
    out: dict[str, dict[str, Any]] = {}
    coefficients = model.coefficients()
    for name, unit in (("sigma_0", "N/m"), ("sigma_1", "N*s/m")):
        state, reason = model.dynamic_status.get(name, ("assumed", "not stated"))
        spec = coefficients.get(name)
        value = spec.get("intercept") if isinstance(spec, dict) else spec
        out[name] = {"value": value, "unit": unit, "status": state, "reason": reason}
    return out


def robustness_cases(
    model: FrictionModel,
    *,
    scatter: FrictionModel | None = None,
) -> list[PlantFriction]:
    """The plants the datasheet is wrong about: +-20 % friction level, half and double the
    pressure slope, two sessions at the edges of the datasheet's between-session band
    (friction level x (1 +- 2 s_R), s_R the relative reproducibility standard deviation of
    its ``fit.scatter`` record: a remounted seal on another day, ISO 5725-2), and (when
    given) another session's datasheet as the plant. A datasheet without a scatter record
    gets the points' band instead (F_c and F_s raised by twice the residual standard
    deviation), labelled as such."""
    cases = [
        PlantFriction("level +20 %", level=1.2),
        PlantFriction("level -20 %", level=0.8),
        PlantFriction("pressure slope x2", slope=2.0),
        PlantFriction("pressure slope x0.5", slope=0.5),
    ]
    record = model.scatter or {}
    relative = (record.get("reproducibility") or {}).get("std_percent")
    if relative and record.get("relative", True):
        s_r = float(relative) / 100.0
        cases.append(PlantFriction("session scatter +2 s_R", level=1.0 + 2.0 * s_r))
        cases.append(PlantFriction("session scatter -2 s_R", level=max(1.0 - 2.0 * s_r, 0.05)))
    else:
        residual = dict(model.statistics or {}).get("residual_std")
        if residual:
            cases.append(PlantFriction("point scatter +2 s", offset=2.0 * float(residual)))
    if scatter is not None:
        cases.append(PlantFriction("other session", model=scatter))
    return cases


ROBUSTNESS_CASES = (
    "level +20 %",
    "level -20 %",
    "pressure slope x2",
    "pressure slope x0.5",
    "session scatter +2 s_R",
    "session scatter -2 s_R",
    "point scatter +2 s",
    "other session",
)


@dataclass
class ControlResult:
    """Runs by compensator (the datasheet plant), metrics, tuning, robustness metrics."""

    axis: Axis
    reference: Reference
    tuning: Tuning
    runs: dict[str, LoopRun]
    metrics: dict[str, dict]
    robustness: dict[str, dict[str, dict]] = field(default_factory=dict)
    datasheet: str | None = None
    sensitivity: dict[str, Any] = field(default_factory=dict)
    dynamic: dict[str, dict[str, Any]] = field(default_factory=dict)
    force_filter: float = FORCE_FILTER

    def ratios(self, metrics: dict[str, dict] | None = None) -> dict[str, float | None]:
        """The acceptance ratios (RMS and reversal error of lugre against the others)."""
        m = self.metrics if metrics is None else metrics

        def ratio(a, b, key):
            x, y = m[a][key], m[b][key]
            return None if x is None or not y else x / y

        return {
            "lugre_rms_over_none": ratio("lugre", "none", "rms_error_m"),
            "lugre_reversal_over_none": ratio("lugre", "none", "reversal_error_m"),
            "lugre_reversal_over_coulomb": ratio("lugre", "coulomb", "reversal_error_m"),
            "lugre_rms_over_oracle": ratio("lugre", "oracle", "rms_error_m"),
        }

    def to_dict(self) -> dict[str, Any]:
        """The metrics.json document."""
        return {
            "datasheet": self.datasheet,
            "reference": self.reference.name,
            "axis": self.axis.to_dict(),
            "omega_h_rad_s": self.axis.natural_frequency(),
            "controller": {
                **self.tuning.to_dict(),
                "feedforward_lead_s": feedforward_lead(self.axis),
                "sign_smoothing_m_s": SMOOTHING_VELOCITY,
                "observer_gain_1_s": OBSERVER_GAIN,
                "force_filter_s": self.force_filter,
            },
            "compensators": self.metrics,
            "ratios": self.ratios(),
            "robustness": {
                case: {"compensators": metrics, "ratios": self.ratios(metrics)}
                for case, metrics in self.robustness.items()
            },
            "dynamic_parameters": self.dynamic,
            "sensitivity": self.sensitivity,
        }

    def to_pandas(self):
        """Time series of every compensator, side by side (units in the names)."""
        import pandas as pd

        frames: list[pd.DataFrame] = []
        for name, run in self.runs.items():
            frame = run.to_pandas()
            if frames:
                frame = frame.drop(
                    columns=["time [s]", "reference [m]", "reference velocity [m/s]"]
                )
            names = {
                c: c if c.startswith(("time", "reference")) else f"{name} {c}"
                for c in frame.columns
            }
            frames.append(frame.rename(columns=names))
        return pd.concat(frames, axis=1)

    def figure(self):
        """Tracking error against time for every compensator (a pyplot-free Figure)."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=(9, 6.5), layout="constrained")
        top, bottom = fig.subplots(2, 1, sharex=True)
        run = next(iter(self.runs.values()))
        top.plot(run.time, run.reference.position * 1e3, "k", lw=1, label="reference")
        top.set_ylabel("position [mm]")
        for name, r in self.runs.items():
            bottom.plot(r.time, r.error * 1e6, lw=1, label=name)
        bottom.set_ylabel("tracking error [µm]")
        bottom.set_xlabel("time [s]")
        bottom.legend(ncols=5, fontsize=8)
        top.legend(fontsize=8)
        return fig

    def write(self, out: StrPath) -> list[Path]:
        """metrics.json, timeseries.csv and control.html (with error.png) into ``out``."""
        from .._paths import make_folder

        out = Path(out)
        make_folder(out)
        written = [
            atomic_write_text(out / "metrics.json", json.dumps(self.to_dict(), indent=2) + "\n"),
            atomic_write_text(out / "timeseries.csv", self.to_pandas().to_csv(index=False)),
        ]
        buffer = io.BytesIO()
        self.figure().savefig(buffer, format="png", dpi=100)
        png = buffer.getvalue()
        written.append(atomic_write_bytes(out / "error.png", png))
        written.append(atomic_write_text(out / "control.html", self._html(png)))
        return written

    def _html(self, png: bytes) -> str:
        rows = []
        for name, m in self.metrics.items():
            cells = [m["rms_error_m"], m["max_error_m"], m["reversal_error_m"]]
            text = "".join(f"<td>{'-' if c is None else f'{c * 1e6:.2f}'}</td>" for c in cells)
            rows.append(
                f"<tr><td>{html_text(name)}</td>{text}<td>{m['control_effort_rms']:.4f}</td></tr>"
            )
        image = base64.b64encode(png).decode()
        dynamic = "".join(
            f"<tr><td>{html_text(n)}</td><td>{d['value']:.4g} "
            f"{html_text(d['unit'])}</td><td><b>{html_text(d['status'])}</b></td>"
            f"<td>{html_text(d['reason'])}</td></tr>"
            for n, d in self.dynamic.items()
        )
        assumed = [n for n, d in self.dynamic.items() if d["status"] != "identified"]
        warning = (
            f"<p><b>{html_text(', '.join(assumed))} assumed, not identified</b>: the LuGre "
            f"compensator depends on them (table below); {html_text(IDENTIFY_ADVICE)}.</p>"
            if assumed
            else ""
        )
        sens_rows = "".join(
            f"<tr><td>{html_text(kind)}</td><td>{row['factor']:g}</td>"
            f"<td>{row['none_rms_m'] * 1e6:.3f}</td><td>{row['lugre_rms_m'] * 1e6:.3f}</td>"
            f"<td>{_fmt(row['lugre_over_none'])}</td></tr>"
            for kind, rows in self.sensitivity.get("cases", {}).items()
            for row in rows
        )
        sensitivity = (
            "<h2>Sensitivity of the LuGre gain</h2><p>"
            + html_text(self.sensitivity.get("note", ""))
            + "</p><table border='1'><tr><th>plant differs in</th><th>factor</th>"
            "<th>PI alone RMS [µm]</th><th>LuGre RMS [µm]</th><th>LuGre / PI alone</th></tr>"
            + sens_rows
            + "</table>"
            if sens_rows
            else ""
        )
        title = html_text(self.datasheet or "datasheet")
        return (
            "<!DOCTYPE html><html><head><meta charset='utf-8'><title>cylfric control</title>"
            "</head><body>"
            f"<h1>Friction compensation: {title}</h1>"
            f"<p>Reference {html_text(self.reference.name)}; PI gain K_v = "
            f"{self.tuning.loop_gain_1_s:.2f} 1/s ({html_text(self.tuning.method)}); "
            f"omega_h = {self.axis.natural_frequency():.1f} rad/s.</p>"
            "<table border='1'><tr><th>compensator</th><th>RMS error [µm]</th>"
            "<th>max error [µm]</th><th>reversal error [µm]</th><th>command RMS [-]</th></tr>"
            + "".join(rows)
            + "</table>"
            + "<h2>Dynamic parameters of the datasheet</h2>"
            + warning
            + "<table border='1'><tr><th>parameter</th><th>value</th><th>status</th>"
            "<th>reason</th></tr>"
            + dynamic
            + "</table>"
            + sensitivity
            + f"<img alt='tracking error' src='data:image/png;base64,{image}'>"
            "</body></html>\n"
        )


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def _metrics(run: LoopRun) -> dict:
    return tracking_metrics(
        run.time,
        run.reference.position,
        run.reference.velocity,
        run.outputs[:, 0],
        run.outputs[:, 4],
    )


def compare_compensators(
    model: FrictionModel,
    *,
    axis: Axis = DEFAULT_AXIS,
    reference: Reference | str = "sine",
    robustness: bool = True,
    scatter: FrictionModel | None = None,
    tuning: Tuning | None = None,
    sensitivity: bool = True,
    progress: Callable[[str], None] | None = None,
    force_filter: float = FORCE_FILTER,
) -> ControlResult:
    """Run every compensator (:data:`~.loop.COMPENSATORS`) on ``axis`` with ``reference``;
    with ``robustness``, again on the plants of :func:`robustness_cases`; with
    ``sensitivity``, PI alone and LuGre on plants whose sigma_0 is :data:`SIGMA_0_FACTORS`
    times the datasheet's (sigma_1 by the square root) and whose friction level is
    :data:`LEVEL_FACTORS` times it, the compensator keeping the datasheet. ``progress`` is
    called with a line before each group of runs (the first run compiles the kernels);
    ``force_filter`` [s] the compensators' force filter (:data:`~.loop.FORCE_FILTER`)."""
    loop = partial(simulate_loop, force_filter=force_filter)
    say = progress or (lambda text: None)
    if isinstance(reference, str):
        reference = make_reference(reference, axis)
    tuning = tuning or tune(axis, viscous=_rest_viscous(model, axis))
    runs = {}
    for c in COMPENSATORS:
        say(f"running the loop: {c}")
        runs[c] = loop(model, c, axis=axis, reference=reference, tuning=tuning)
    result = ControlResult(
        axis,
        reference,
        tuning,
        runs,
        {c: _metrics(r) for c, r in runs.items()},
        datasheet=getattr(model, "source", None),
        dynamic=dynamic_parameters(model),
        force_filter=force_filter,
    )
    if sensitivity:
        say("sensitivity: plants with sigma_0 x0.1..x10 and friction x0.8..x1.2")
        result.sensitivity = _sensitivity(model, axis, reference, tuning, result.dynamic, loop)
    if robustness:
        say("robustness cases")
        for case in robustness_cases(model, scatter=scatter):
            result.robustness[case.name] = {
                c: _metrics(
                    loop(model, c, axis=axis, reference=reference, tuning=tuning, plant=case)
                )
                for c in COMPENSATORS
            }
    return result


def _sensitivity(model, axis, reference, tuning, dynamic, loop) -> dict[str, Any]:
    """PI alone and LuGre RMS errors on plants that differ from the datasheet (see
    :func:`compare_compensators`)."""
    cases: dict[str, list[dict[str, float | None]]] = {"sigma_0": [], "friction_level": []}
    plants = [("sigma_0", f, PlantFriction(f"x{f:g}", stiffness=f)) for f in SIGMA_0_FACTORS]
    plants += [("friction_level", f, PlantFriction(f"x{f:g}", level=f)) for f in LEVEL_FACTORS]
    for kind, factor, plant in plants:
        rms = {
            c: _metrics(loop(model, c, axis=axis, reference=reference, tuning=tuning, plant=plant))[
                "rms_error_m"
            ]
            for c in ("none", "lugre")
        }
        cases[kind].append(
            {
                "factor": factor,
                "none_rms_m": rms["none"],
                "lugre_rms_m": rms["lugre"],
                "lugre_over_none": rms["lugre"] / rms["none"] if rms["none"] else None,
            }
        )
    s0 = dynamic["sigma_0"]
    note = (
        f"The compensator keeps the datasheet (sigma_0 = {s0['value']:.4g} N/m, "
        f"{s0['status']}); the plant's sigma_0 is the factor times it (sigma_1 times its "
        "square root), or its friction level (F_c, F_s, sigma_2) the factor times the "
        "datasheet's."
    )
    return {"note": note, "cases": cases}
