"""Importing this module loads the compiled code of the reader and the extraction.

A process's first call of compiled (numba) code loads numba's CPU target, about 0.4-0.5 s.
``cylfric fit-many``'s worker server imports this module once, so that every worker forked
from it starts reading files at once instead of paying that load per worker.
"""

from __future__ import annotations

import numpy as np

from ._filters import rolling_median
from .io._scan import scan_lines

scan_lines(np.frombuffer(b"0.1\t2.5\n", dtype=np.uint8))
rolling_median(np.zeros(3), 3)
