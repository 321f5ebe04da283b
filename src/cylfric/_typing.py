"""Type aliases shared by the annotations of the public API (imported only for type checking)."""

from __future__ import annotations

import os
from typing import TypeAlias

StrPath: TypeAlias = "os.PathLike[str] | str"
"""A path given by the caller: a string or any path-like object (``pathlib.Path``)."""

OilPoints: TypeAlias = "tuple[tuple[float, float], tuple[float, float]]"
"""Two (temperature [K], kinematic viscosity [m^2/s]) points of an oil's data sheet."""
