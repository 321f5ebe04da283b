"""Atomic writes with nothing but the standard library (re-exported by
:mod:`cylfric.io.writers`).

The text goes to a temporary file in the target folder, which is then renamed over the
target, so a reader never sees half a file. Kept apart from :mod:`cylfric.io`, whose package
imports the readers (numba, scipy), so that a process that only writes a summary, such as
the command of ``cylfric fit-many`` while its workers fit, does not load them (issue 15:
0.3 s of processor time at import and again at exit).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from ._paths import OutputPathError, failed, os_error_message, refuse_link

if TYPE_CHECKING:
    from collections.abc import Iterable

    from ._typing import StrPath

__all__ = [
    "atomic_write_bytes",
    "atomic_write_chunks",
    "atomic_write_text",
    "failed",
    "os_error_message",
]

_UMASK = os.umask(0o022)
os.umask(_UMASK)  # read once at import: mkstemp makes 0600 files, outputs get 0666 & ~umask


def atomic_write_bytes(path: StrPath, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    Raises OutputPathError (a ValueError) when ``path`` is a symbolic link, and OSError
    naming ``path`` and the action (see the module docstring) when the write fails.
    """
    return atomic_write_chunks(path, (data,))


def atomic_write_chunks(path: StrPath, chunks: Iterable[bytes]) -> Path:
    """Write the bytes of the iterable ``chunks`` one after the other to ``path``, through a
    temporary file and a rename (a large file never held whole in memory); errors as
    :func:`atomic_write_bytes`."""
    path = refuse_link(path, "output file")
    if path.exists() and not path.is_file() and not path.is_dir():
        raise OutputPathError(
            f"output file {path} is not a regular file (a device, pipe or socket); cylfric "
            "writes a new file and renames it over the old one, which would replace it: "
            "choose the path of a regular file"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        folder = exc.filename or path.parent
        raise failed(exc, f"writing {path}: creating the folder", folder) from exc
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise failed(exc, "writing", path) from exc
    try:
        with os.fdopen(fd, "wb") as handle:
            for chunk in chunks:
                handle.write(chunk)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise failed(exc, "writing", path) from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path: StrPath, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode(encoding))
