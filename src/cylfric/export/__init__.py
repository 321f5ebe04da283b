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
import os
import re
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .result import ExportResult

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from cylfric._typing import StrPath

    from ..model import FrictionModel

__all__ = [
    "export",
    "ExportResult",
    "TARGETS",
    "LOSSLESS",
    "SINGLE_FILE",
    "resolve",
    "parse_targets",
]

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

SINGLE_FILE = {"fmu": ".fmu", "modelica": ".mo"}
"""Targets that write one file -> its suffix: an ``out`` ending in it (and not an existing
folder) is that file (:func:`export`). The others write several files into a folder."""

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,62}")  # a model name valid in C and Modelica


def resolve(target: str) -> Callable[..., Any]:
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


def parse_targets(text: str | Iterable[str]) -> list[str]:
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


def export(
    model_or_datasheet: FrictionModel | Mapping[str, Any] | StrPath,
    to: str,
    out: StrPath,
    **options: Any,
) -> ExportResult:
    """Export a friction model to a simulator.

    Parameters
    ----------
    model_or_datasheet : FrictionModel, dict or path-like
        The model, a datasheet dict, or a datasheet.json path.
    to : {"fmu", "matlab", "modelica", "simscape", "hopsan"}
        Target (:data:`TARGETS`).
    out : path-like
        Output folder (created). For a single-file target (:data:`SINGLE_FILE`: ``fmu``,
        ``modelica``), a path ending in its suffix (``Friction.fmu``, ``Seal.mo``) that is
        not an existing folder is the file itself; its stem becomes the model name when it
        is an identifier (``[A-Za-z_][A-Za-z0-9_]*``) and no ``name`` is given; otherwise
        the model keeps its name and the file is written under the name given. A symbolic
        link (folder or file) is refused (:func:`cylfric._paths.refuse_link`).
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
    from .._paths import refuse_link

    out = refuse_link(out)
    model = _model(model_or_datasheet)
    suffix = SINGLE_FILE.get(to)
    if suffix is not None and out.suffix.lower() == suffix and not out.is_dir():
        return _export_file(function, to, model, out, options)
    return _result(to, function(model, out, **options))


def _result(to, result) -> ExportResult:
    if isinstance(result, ExportResult):
        return result
    return ExportResult(to, tuple(Path(p) for p in result), None)


def _export_file(function, to, model, path: Path, options) -> ExportResult:
    """Export into a staging folder beside ``path``, then rename the one file to ``path``."""
    from .._paths import failed, make_folder

    if path.exists() and not path.is_file():
        raise ValueError(f"--out {path} exists and is not a file; expected a {to} file path")
    if "name" not in options and _NAME.fullmatch(path.stem):
        options = {**options, "name": path.stem}
    make_folder(path.parent, f"--out {path}: its folder")
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{path.name}.staging-", dir=path.parent))
    except OSError as exc:
        raise failed(exc, f"writing {path}: creating a staging folder in", path.parent) from exc
    try:
        result = _result(to, function(model, staging, **options))
        (written,) = result.files  # a single-file target
        try:
            os.replace(written, path)
        except OSError as exc:
            raise failed(exc, "writing", path) from exc
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return ExportResult(to, (path,), result.loss)
