"""Exports of a friction model to simulators: FMU, Modelica, Simscape, Hopsan, MATLAB.

``export(model_or_datasheet, to, out, **options) -> ExportResult`` dispatches through the
registry :data:`TARGETS` (each target's module is imported only when it is used). Lossless
targets carry the full pressure-dependent LuGre model (FMU, MATLAB, Modelica); lossy ones fit
a simulator's own friction block to the model and write a loss report beside it (Simscape,
Hopsan; :mod:`cylfric.export.loss`).
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Mapping
from pathlib import Path

from .result import ExportResult

__all__ = ["export", "ExportResult", "TARGETS", "LOSSLESS", "resolve", "parse_targets"]

TARGETS = {
    "fmu": "cylfric.export.fmu:export_fmu",
    "matlab": "cylfric.export.matlab:export_matlab",
    "modelica": "cylfric.export.modelica:export_modelica",
    "simscape": "cylfric.export.simscape:export_simscape",
    "hopsan": "cylfric.export.hopsan:export_hopsan",
}
"""Export target -> ``"module:function"``; the function takes ``(model, out, **options)``."""

LOSSLESS = ("fmu", "matlab", "modelica")
"""Targets that carry the full model (no loss report)."""


def resolve(target: str):
    """The export function of ``target`` (imported on first use)."""
    if target not in TARGETS:
        raise ValueError(f"unknown export target {target!r}; valid: {sorted(TARGETS)}")
    module_name, _, function = TARGETS[target].partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name != module_name:
            raise
        raise ImportError(
            f"export target {target!r} is registered but its module {module_name} is not "
            "part of this installation"
        ) from None
    return getattr(module, function)


def parse_targets(text) -> list[str]:
    """``"fmu,simscape"`` (or a list) -> checked target names, in order, without repeats."""
    items = text.split(",") if isinstance(text, str) else list(text)
    names = []
    for item in items:
        name = str(item).strip().lower()
        if not name:
            continue
        if name not in TARGETS:
            raise ValueError(f"unknown export target {name!r}; valid: {sorted(TARGETS)}")
        if name not in names:
            names.append(name)
    if not names:
        raise ValueError(f"no export target in {text!r}; valid: {sorted(TARGETS)}")
    return names


def _model(source):
    from ..model import FrictionModel

    if isinstance(source, FrictionModel):
        return source
    if isinstance(source, Mapping | str | Path):
        return FrictionModel.from_datasheet(source)
    raise TypeError(
        f"expected a FrictionModel, a datasheet dict or a path to datasheet.json; "
        f"got {type(source).__name__}"
    )


def export(model_or_datasheet, to: str, out, **options) -> ExportResult:
    """Export a friction model to a simulator.

    Parameters
    ----------
    model_or_datasheet : FrictionModel, dict or path-like
        The model, a datasheet dict, or a datasheet.json path.
    to : {"fmu", "matlab", "modelica", "simscape", "hopsan"}
        Target (:data:`TARGETS`).
    out : path-like
        Output folder (created).
    **options
        Keywords of the target's function (e.g. ``name``, ``velocity_range`` [m/s],
        ``pressure_range`` [Pa]); unknown keywords raise ValueError listing the valid ones.

    Returns
    -------
    ExportResult
        The files written and, for lossy targets, the loss reports (None for lossless).
    """
    function = resolve(to)
    accepted = [
        p.name
        for p in list(inspect.signature(function).parameters.values())[2:]
        if p.kind is inspect.Parameter.KEYWORD_ONLY
    ]
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise ValueError(f"export to {to}: unknown option(s) {unknown}; valid: {accepted}")
    model = _model(model_or_datasheet)
    result = function(model, Path(out), **options)
    if isinstance(result, ExportResult):
        return result
    return ExportResult(to, tuple(Path(p) for p in result), None)
