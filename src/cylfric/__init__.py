"""cylfric: pressure-dependent friction of hydraulic cylinders.

Friction laws (:mod:`cylfric.friction`), bench-file ingestion (:mod:`cylfric.io`),
steady-state extraction (:mod:`cylfric.steady_state`), identification
(:mod:`cylfric.identify`), the friction model shared by every part (:mod:`cylfric.model`:
its uncertainty, guards and serialisation as the friction datasheet, :mod:`cylfric.datasheet`),
simulation (:mod:`cylfric.simulate`), the report (:mod:`cylfric.report`), the main job as a
function (:mod:`cylfric.pipeline`) and the command line (:mod:`cylfric.cli`). SI units inside;
engineering units at the edges (:mod:`cylfric.units`).

The main job in Python is :func:`cylfric.fit` (a campaign folder fitted in memory, what
``cylfric fit`` fits) and :meth:`FitResult.write` (the output folder ``cylfric fit`` writes)::

    import cylfric
    result = cylfric.fit("my_campaign/")
    result.model.friction(0.02, 80e5)      # [N] at 20 mm/s, 80 bar
    result.write("my_campaign-fit/")       # datasheet.json, tables, figures, report.html
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ._version import __version__

if TYPE_CHECKING:
    from .pipeline import FitResult, fit

__all__ = ["fit", "FitResult", "friction", "units", "__version__"]


def __getattr__(name: str) -> Any:
    """Subpackages and the main job (:func:`fit`) on first use: ``import cylfric`` stays
    quick for ``cylfric --version``."""
    if name in ("friction", "units"):
        import importlib

        return importlib.import_module(f".{name}", __name__)
    if name in ("fit", "FitResult"):
        from . import pipeline

        return getattr(pipeline, name)
    raise AttributeError(f"module 'cylfric' has no attribute {name!r}")
