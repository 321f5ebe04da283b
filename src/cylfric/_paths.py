"""Where outputs may go (issue 23): an ``--out`` that is a symbolic link is refused, and a
name that becomes part of an output path stays inside the output folder.

A symbolic link given as ``--out`` (to a folder or a file, or dangling) is never written
through and never replaced: the user may not know where it points, and a fit replaces its
output folder whole. The message names the link and its target and says what to pass
instead (the target itself). Only the last part of the path is checked: folders above it
may be links (``/tmp`` on macOS, a home folder on another disk) as usual.

Standard library only, as :mod:`cylfric._atomic`: the ``cylfric fit-many`` command process
imports it without the readers (numba, scipy).
"""

from __future__ import annotations

import os
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ._typing import StrPath

__all__ = [
    "OutputPathError",
    "refuse_link",
    "make_folder",
    "inside",
    "failed",
    "os_error_message",
]


class OutputPathError(ValueError):
    """An output path cylfric will not write: a symbolic link, or a name that would leave
    the output folder (exit code 2 on the command line)."""


def refuse_link(path: StrPath, option: str = "--out") -> Path:
    """``path`` as a Path; OutputPathError when it is a symbolic link (even a dangling one).

    Parameters
    ----------
    path : path-like
        The output folder or file the user named.
    option : str
        How the user named it, for the message (``"--out"``, ``"OUT_DIR"``, ``"PATH"``).
    """
    path = Path(path)
    if not path.is_symlink():
        return path
    try:
        target = os.readlink(path)
    except OSError:  # pragma: no cover - removed between the two calls
        target = "?"
    resolved = path.resolve()
    if resolved.exists():
        advice = f"pass the target itself ({option} {resolved}) or remove the link"
    else:
        advice = f"{resolved} does not exist; remove the link or name another {option}"
    raise OutputPathError(
        f"{option} {path} is a symbolic link to {target}; cylfric neither writes through a "
        f"link nor replaces it: {advice}"
    )


def inside(out: Path, relative: StrPath, what: str = "name") -> Path:
    """``out / relative``, refused (OutputPathError) unless it stays inside ``out``.

    ``relative`` is a name or a relative path made of names that came from outside cylfric
    (a campaign folder's path under a root, a catalogue or datasheet name): it must not be
    empty or absolute, nor hold ``.``/``..`` parts, backslashes or control characters (NUL,
    newline), and ``out / relative`` must resolve inside ``out``. A leading ``-`` is kept:
    the path always starts with ``out``, so it cannot be read as a command-line option.
    """
    out = Path(out)
    text = str(relative)
    parts = PurePosixPath(text).parts
    bad = (
        not text
        or PurePosixPath(text).is_absolute()
        or PureWindowsPath(text).drive
        or "\\" in text
        or any(ord(c) < 32 or ord(c) == 127 for c in text)
        or any(part in (".", "..") for part in text.split("/"))
    )
    if not bad:
        path = out.joinpath(*parts)
        base = out.resolve()
        if path.resolve() == base or base not in path.resolve().parents:
            bad = True
    if bad:
        raise OutputPathError(
            f"{what} {text!r} cannot name a file or folder inside {out}: expected a relative "
            "name without '..', '.', '\\', control characters or a leading '/', staying "
            f"inside {out}"
        )
    return path


def failed(exc: OSError, action: str, path: StrPath) -> OSError:
    """``exc`` made again for the user: same class and errno, ``filename`` = ``path`` and an
    ``action`` attribute (``"writing"``, ``"creating the folder"``); chain it ``from exc``."""
    again = type(exc)(exc.errno, exc.strerror or str(exc), str(path))
    again.action = action  # type: ignore[attr-defined]  # read by os_error_message
    return again


def os_error_message(exc: OSError) -> str:
    """``"writing OUT/datasheet.json: No space left on device"``: the action (when known),
    the file and the system's reason."""
    reason = exc.strerror or str(exc)
    action = getattr(exc, "action", None)
    name = exc.filename if exc.filename not in (None, "") else None
    if name is None:
        return f"{action}: {reason}" if action else str(exc)
    where = f"{name} -> {exc.filename2}" if exc.filename2 else f"{name}"
    return f"{action} {where}: {reason}" if action else f"{where}: {reason}"


def make_folder(path: StrPath, option: str = "--out") -> Path:
    """Create the output folder ``path`` (and its parents) after :func:`refuse_link`; an
    OSError names the folder and the action (``creating the folder OUT: Not a directory``)."""
    path = refuse_link(path, option)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except FileExistsError as exc:  # a file where the folder should be
        raise OutputPathError(
            f"{option} {path} is a file; expected a folder (or a path that does not exist)"
        ) from exc
    except OSError as exc:
        raise failed(exc, "creating the folder", exc.filename or path) from exc
    return path
