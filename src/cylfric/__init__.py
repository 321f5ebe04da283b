"""cylfric: pressure-dependent friction of hydraulic cylinders.

Friction laws (:mod:`cylfric.friction`), bench-file ingestion (:mod:`cylfric.io`),
steady-state extraction (:mod:`cylfric.steady_state`), identification
(:mod:`cylfric.identify`), simulation (:mod:`cylfric.simulate`) and the friction datasheet
(:mod:`cylfric.datasheet`). SI units inside; engineering units at the edges
(:mod:`cylfric.units`).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("cylfric")
except PackageNotFoundError:  # pragma: no cover - source tree without install
    __version__ = "0.0.0"

from . import friction, units  # noqa: E402

__all__ = ["friction", "units", "__version__"]
