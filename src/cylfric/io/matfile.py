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

__all__ = ["read_mat", "MAT_BYTES"]

MAT_BYTES = 1 << 30
"""Most bytes the numbers of a .mat file may take once read [B] (1 GiB: 134 million
samples of 8 bytes; a record of 8 channels at 100 kHz for 10 minutes is 384 MB). The
variables' declared sizes are checked before anything is decompressed: a 3.5 MB file that
inflated to 3.6 GB had ended in MemoryError."""


def _inflated_bytes(path: Path, limit: int) -> int:
    """Bytes the data elements of a MATLAB v5-v7.2 file take decompressed, counted up to
    just past ``limit`` (compressed elements are inflated in 1 MiB pieces and dropped, so
    the count costs no memory); 0 for another format (v4 files are not compressed, v7.3 is
    HDF5, which :func:`scipy.io.loadmat` refuses) or a malformed file (left to loadmat)."""
    import struct
    import zlib

    piece = 1 << 20
    with open(path, "rb") as handle:
        header = handle.read(128)
        if len(header) < 128 or header[126:128] not in (b"IM", b"MI"):
            return 0
        order = "<" if header[126:128] == b"IM" else ">"
        total = 0
        while total <= limit:
            tag = handle.read(8)
            if len(tag) < 8:
                break
            kind, nbytes = struct.unpack(order + "II", tag)
            if kind >> 16:  # a small data element: its bytes are in the tag
                continue
            if kind != 15:  # miCOMPRESSED
                total += nbytes
                handle.seek(nbytes + (-nbytes % 8), 1)
                continue
            inflate, remaining = zlib.decompressobj(), nbytes
            try:
                while remaining > 0 and total <= limit:
                    chunk = handle.read(min(remaining, piece))
                    if not chunk:
                        break
                    remaining -= len(chunk)
                    total += len(inflate.decompress(chunk, piece))
                    while inflate.unconsumed_tail and total <= limit:
                        total += len(inflate.decompress(inflate.unconsumed_tail, piece))
            except zlib.error:
                return 0
            handle.seek(remaining, 1)
    return total


def _check_size(path: Path) -> None:
    """Refuse a file whose numbers take more than :data:`MAT_BYTES` once decompressed,
    before :func:`scipy.io.loadmat` inflates them."""
    try:
        total = _inflated_bytes(path, MAT_BYTES)
    except OSError:
        return  # loadmat names the file and the system's reason
    if total > MAT_BYTES:
        raise BenchFileError(
            path,
            f"its variables take more than {MAT_BYTES / 2**20:,.0f} MiB once decompressed "
            "(the most a .mat run may take): save the test's vectors only, or split the "
            "record",
        )


def _why_not_a_vector(name: str, value: np.ndarray) -> str:
    """Why the variable ``name`` is not a numeric vector, in words."""
    if value.dtype.kind == "c":
        return f"{name} is complex; expected real numbers"
    if value.dtype.kind not in "fiub":
        return f"{name} is not numeric ({value.dtype.kind!r} data: text, a cell or a struct)"
    if value.ndim == 0:
        return f"{name} is a single number; expected a vector of samples"
    return f"{name} is {'x'.join(map(str, value.shape))}; expected a vector (1-D) of samples"


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
    errors = (MatReadError, ValueError, TypeError, OSError, NotImplementedError, EOFError)
    _check_size(path)
    try:
        content = loadmat(path, squeeze_me=True)
    except errors as exc:
        raise BenchFileError(path, f"not a readable MATLAB .mat file ({exc})") from None
    except MemoryError:
        raise BenchFileError(path, "does not fit in memory once decompressed") from None
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
    unusable = [
        _why_not_a_vector(v, arrays[v]) for v in variables if v in arrays and v not in vectors
    ]
    if unusable:
        raise BenchFileError(path, "; ".join(unusable) + f" (the vectors: {sorted(vectors)})")
    missing = [v for v in variables if v not in vectors]
    if missing:
        raise BenchFileError(path, f"variables {missing} are missing; found {sorted(vectors)}")
    lengths = {v: vectors[v].size for v in variables}
    if len(set(lengths.values())) > 1:
        shown = ", ".join(f"{v}: {n}" for v, n in lengths.items())
        raise BenchFileError(
            path,
            f"the vectors are of unequal length ({shown}); expected one sample of each per "
            "time step",
        )
    if min(lengths.values(), default=0) < 2:
        raise BenchFileError(path, f"the vectors hold fewer than 2 samples ({lengths})")
    units = units or {}
    import pandas as pd

    data = pd.DataFrame({f"{k} [{units.get(k, '-')}]": vectors[k] for k in variables})
    return data, {"file": str(path), "scalars": scalars, "variables": list(variables)}
