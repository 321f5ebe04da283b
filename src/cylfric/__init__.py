"""cylfric: pressure-dependent friction of hydraulic cylinders.

Friction laws (:mod:`cylfric.friction`), bench-file ingestion (:mod:`cylfric.io`),
steady-state extraction (:mod:`cylfric.steady_state`), identification
(:mod:`cylfric.identify`), the friction model shared by every part (:mod:`cylfric.model`:
its uncertainty, guards and serialisation as the friction datasheet, :mod:`cylfric.datasheet`),
simulation (:mod:`cylfric.simulate`), the report (:mod:`cylfric.report`), the main job as a
function (:mod:`cylfric.pipeline`) and the command line (:mod:`cylfric.cli`). SI units inside;
engineering units at the edges (:mod:`cylfric.units`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._version import __version__

if TYPE_CHECKING:
    from types import ModuleType

__all__ = ["friction", "units", "__version__"]


def __getattr__(name: str) -> ModuleType:
    """Subpackages on first use (``import cylfric`` stays quick for ``cylfric --version``)."""
    if name in ("friction", "units"):
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'cylfric' has no attribute {name!r}")
