"""Reader of MATLAB .mat records (scipy.io), e.g. the EMPS benchmark data."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .text import BenchFileError

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import pandas as pd

    from cylfric._typing import StrPath

__all__ = ["read_mat"]


def read_mat(
    path: StrPath, *, variables: Sequence[str] | None = None, units: Mapping[str, Any] | None = None
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Read the vector variables of a MATLAB v4-v7.2 ``.mat`` file.

    Parameters
    ----------
    path : path-like
        The file.
    variables : list of str, optional
        Variables to return (default: every vector of the longest length).
    units : dict, optional
        Variable -> unit text, kept in the column names (``"qm [m]"``).

    Returns
    -------
    data : pandas.DataFrame
        One column per vector variable, named ``"name [unit]"``.
    metadata : dict
        ``file``, ``scalars`` (scalar variables such as gains), ``variables``.
    """
    from scipy.io import loadmat  # only for .mat files: importing cylfric.io stays quick
    from scipy.io.matlab import MatReadError

    path = Path(path)
    try:
        content = loadmat(path, squeeze_me=True)
    except (MatReadError, ValueError, TypeError, OSError, NotImplementedError) as exc:
        raise BenchFileError(path, f"not a readable MATLAB .mat file ({exc})") from None
    arrays = {k: np.asarray(v) for k, v in content.items() if not k.startswith("__")}
    vectors = {
        k: v.astype(float) for k, v in arrays.items() if v.ndim == 1 and v.dtype.kind in "fiu"
    }
    scalars = {k: float(v) for k, v in arrays.items() if v.ndim == 0 and v.dtype.kind in "fiu"}
    if variables is None:
        if not vectors:
            raise BenchFileError(path, "no numeric vectors in the file")
        longest = max(v.size for v in vectors.values())
        variables = [k for k, v in vectors.items() if v.size == longest]
    missing = [v for v in variables if v not in vectors]
    if missing:
        raise BenchFileError(path, f"variables {missing} are missing; found {sorted(vectors)}")
    units = units or {}
    import pandas as pd

    data = pd.DataFrame({f"{k} [{units.get(k, '-')}]": vectors[k] for k in variables})
    return data, {"file": str(path), "scalars": scalars, "variables": list(variables)}
