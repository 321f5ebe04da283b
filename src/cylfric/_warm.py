"""Importing this module loads everything a fit needs, once, in the process that imports it.

- the compiled code of the reader and the extraction: a process's first call of compiled
  (numba) code loads numba's CPU target, about 0.4-0.5 s;
- the identification and the datasheet (scipy.optimize, jsonschema), which
  :mod:`cylfric.pipeline` imports lazily: about 0.4 s of processor time.

``cylfric fit-many``'s worker server imports this module once, so that every worker forked
from it starts fitting at once instead of paying these per worker (measured for issue 15:
without the second item each worker's first fit took 0.8 s of processor time, the next
ones 0.4 s).
"""

from __future__ import annotations

import numpy as np

from ._filters import rolling_median
from .io._scan import scan_lines
from .pipeline import _import_next_stages

scan_lines(np.frombuffer(b"0.1\t2.5\n", dtype=np.uint8))
rolling_median(np.zeros(3), 3)
_import_next_stages()
