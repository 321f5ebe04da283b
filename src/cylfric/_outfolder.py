"""An output folder written as one transaction: lock, staging folder, marker, swap.

Plumbing only, no science: :meth:`cylfric.pipeline.FitResult.write` and
:func:`cylfric.pipeline.fit_seals` write through :func:`staged`.

- :func:`lock`: ``.OUT.lock`` beside ``out`` holds the writer's process id; a live holder is
  refused, a stale lock (its process gone) taken over.
- :func:`staged`: everything is written into a staging folder ``.OUT.staging-XXXX`` beside
  ``out`` (marked at once with :data:`STAGING_MARKER`), listed in the output marker
  :data:`MARKER`, and swapped in whole (two renames; the earlier ``out`` goes aside as
  ``.OUT.old-PID`` until the new one is in place).
- Nothing of the user's is ever deleted: an existing ``out`` is replaced only while its marker
  lists everything in it (:func:`check_reusable`), and a leftover of a killed writer
  (``.OUT.staging-*``, ``.OUT.old-*``) is removed only when it carries the marker cylfric
  wrote into it and nothing else; a folder of such a name that cylfric did not make stops
  the write, naming it (:func:`remove_leftovers`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._atomic import atomic_write_text
from ._paths import failed, make_folder, refuse_link

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

__all__ = ["MARKER", "STAGING_MARKER", "check_out", "check_reusable", "lock", "staged"]

MARKER = ".cylfric-output"
"""File that marks a folder written by cylfric and lists every file and folder cylfric wrote
into it (one path a line, relative, folders ending in ``/``). The next write replaces such a
folder whole only when it holds nothing else."""

STAGING_MARKER = ".cylfric-staging"
"""File written into a staging folder as soon as it is made (its writer's process id): only a
folder that holds it (and nothing cylfric's marker does not list) is removed as a leftover."""

_MARKER_HEADER = (
    "# Written by cylfric fit. The next cylfric fit into this folder replaces it whole, but\n"
    "# only while it holds nothing but the files listed here (anything else: it refuses).\n"
)


def write_marker(folder: Path) -> None:
    """List everything in ``folder`` (the finished staging folder) in its marker file."""
    entries = sorted(
        path.relative_to(folder).as_posix() + ("/" if path.is_dir() else "")
        for path in folder.rglob("*")
    )
    listed = [e for e in entries if e not in (MARKER, STAGING_MARKER)]
    atomic_write_text(folder / MARKER, _MARKER_HEADER + "".join(f"{e}\n" for e in listed))
    (folder / STAGING_MARKER).unlink(missing_ok=True)  # after: never a folder without either


def _listed(out: Path) -> set[str]:
    """Paths the marker of ``out`` lists (empty for a marker of an older cylfric)."""
    try:
        text = (out / MARKER).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return set()
    return {line.strip() for line in text.splitlines() if line.strip() and line[0] != "#"}


def foreign(out: Path, extra: frozenset[str] = frozenset()) -> list[str]:
    """Files and folders in ``out`` that its marker does not list (folders end in ``/``;
    a folder that is not listed is named once, without its contents); ``extra`` names more
    paths that belong."""
    listed = _listed(out) | {MARKER} | set(extra)
    found = []

    def walk(folder: Path):
        for path in sorted(folder.iterdir()):
            name = path.relative_to(out).as_posix()
            if path.is_dir() and not path.is_symlink():
                if name + "/" in listed:
                    walk(path)
                else:
                    found.append(name + "/")
            elif name not in listed:
                found.append(name)

    walk(out)
    return found


def named(paths: list[str], limit: int = 4) -> str:
    """At most ``limit`` of ``paths``, then how many more."""
    shown = ", ".join(paths[:limit])
    return shown + (f" and {len(paths) - limit} more" if len(paths) > limit else "")


def check_reusable(out: Path) -> None:
    """Refuse an existing ``out`` that holds anything cylfric did not write there."""
    if not out.exists() and not out.is_symlink():
        return
    if not out.is_dir():
        raise ValueError(f"--out {out} is a file; expected a folder")
    if not any(out.iterdir()):
        return
    if not (out / MARKER).is_file():
        held = sorted(p.name + ("/" if p.is_dir() else "") for p in out.iterdir())
        raise ValueError(
            f"--out {out} exists and is not a cylfric output folder (no {MARKER} marker); "
            f"it holds {named(held)}. "
            "The output folder is replaced whole: choose a new or empty --out, or move "
            "those files"
        )
    found = foreign(out)
    if found:
        raise ValueError(
            f"--out {out} holds files cylfric did not write ({named(found)}; not listed in "
            f"its {MARKER}). The output folder is replaced whole and they would be lost: "
            "choose another --out, or move them out of it"
        )


def check_out(folder: Path, out: Path) -> None:
    """Refuse an output folder that would read back as runs of the campaign ``folder``,
    whose files would be lost, or that is a symbolic link."""
    refuse_link(out)
    campaign, target = folder.resolve(), out.resolve()
    if target == campaign or campaign in target.parents or target in campaign.parents:
        sibling = campaign.parent / f"{campaign.name or 'campaign'}-fit"
        if not folder.is_absolute():  # as the user would type it: 'fit .' -> ../NAME-fit
            with contextlib.suppress(ValueError):  # (another drive on Windows)
                sibling = Path(os.path.relpath(sibling))
        unnamed = folder.name in ("", ".", "..")  # 'fit .': which folder that is
        where = f"{folder}" + (f" ({campaign})" if unnamed else "")
        if target in campaign.parents:
            problem = (
                f"--out {out} contains the campaign folder {where}; the output folder is "
                "replaced whole, so choose one that does not hold the raw files"
            )
        else:
            problem = (
                f"--out {out} is inside the campaign folder {where}: its files would be read "
                "back as runs; choose an output folder outside the campaign"
            )
        import shlex

        raise ValueError(f"{problem}, e.g. --out {shlex.quote(str(sibling))}")
    check_reusable(out)


@contextlib.contextmanager
def lock(out: Path) -> Iterator[None]:
    """Hold ``.OUT.lock`` beside ``out`` (with this process id); refuse a live holder."""
    path = out.parent / f".{out.name}.lock"
    for _ in range(2):
        try:
            handle = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            break
        except FileExistsError:
            try:
                holder = int(path.read_text().strip() or 0)
            except (OSError, ValueError):
                holder = 0
            if holder and _alive(holder):
                raise ValueError(
                    f"another cylfric fit (process {holder}) is writing {out}; wait for it or "
                    f"choose another --out (lock file {path})"
                ) from None
            path.unlink(missing_ok=True)  # a stale lock of a process that is gone
        except OSError as exc:  # a read-only folder, a full disk
            raise failed(exc, f"writing --out {out}: creating the lock file", path) from exc
    else:  # pragma: no cover - lost a race twice
        raise ValueError(f"cannot take the lock {path}")
    try:
        try:
            os.write(handle, str(os.getpid()).encode())
        except OSError as exc:  # a full disk: name the lock file
            raise failed(exc, f"writing --out {out}: writing the lock file", path) from exc
        finally:
            os.close(handle)
        yield
    finally:
        path.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def swap_in(staging: Path, out: Path) -> None:
    """Replace ``out`` by ``staging`` (two renames on one file system); on a failed second
    rename the previous ``out`` is put back."""
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        if old.exists() or old.is_symlink():
            _remove_if_ours(old, out)
        try:
            out.rename(old)
        except OSError as exc:
            raise failed(exc, "writing --out: moving the previous folder aside", out) from exc
    try:
        staging.rename(out)
    except OSError as exc:
        if old is not None:
            old.rename(out)
        raise failed(exc, "writing --out: renaming the finished folder to", out) from exc
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _ours(path: Path) -> bool:
    """Whether ``path`` is a folder cylfric made: a staging folder (its staging marker) or a
    finished output (its marker), holding nothing its marker does not list."""
    if path.is_symlink() or not path.is_dir():
        return False
    if not any(path.iterdir()):
        return True  # empty: nothing in it can be lost (a writer killed before its marker)
    if (path / STAGING_MARKER).is_file():
        return True  # a killed writer's staging folder: every file in it is cylfric's
    if not (path / MARKER).is_file():
        return False
    try:
        return not foreign(path)
    except OSError:
        return False


def _remove_if_ours(path: Path, out: Path) -> None:
    if not _ours(path):
        raise ValueError(
            f"{path} is named like a leftover of an interrupted cylfric write into --out "
            f"{out}, but cylfric did not make it (no {STAGING_MARKER} or {MARKER} marker "
            "listing its contents), so it is left as it is; move or rename it, or choose "
            "another --out"
        )
    shutil.rmtree(path, ignore_errors=True)


def remove_leftovers(out: Path) -> None:
    """Staging and old folders of writes into ``out`` that were killed (called under the
    lock); a folder of such a name that cylfric did not make is refused, never removed."""
    for pattern in (f".{out.name}.staging-*", f".{out.name}.old-*"):
        for path in sorted(out.parent.glob(pattern)):
            _remove_if_ours(path, out)


def staged(out: Path, write: Callable[[Path], Any], *, locked: bool = False) -> tuple[Path, Any]:
    """``write(staging)`` into a staging folder beside ``out``, swapped in whole (see the
    module); returns (the staging folder's path, what ``write`` returned): paths ``write``
    returned are still in the staging folder and name the same files under ``out``.
    ``locked``: the caller already holds :func:`lock`."""
    make_folder(out.parent, f"--out {out}: its folder")
    with contextlib.nullcontext() if locked else lock(out):
        remove_leftovers(out)
        try:
            staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
        except OSError as exc:
            action = f"writing --out {out}: creating a staging folder in"
            raise failed(exc, action, out.parent) from exc
        try:
            atomic_write_text(staging / STAGING_MARKER, f"{os.getpid()}\n")
            mask = os.umask(0)
            os.umask(mask)
            staging.chmod(0o777 & ~mask)  # mkdtemp makes it private; the output is not
            result = write(staging)
            write_marker(staging)
            check_reusable(out)  # again: a file may have been added during the write
            swap_in(staging, out)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
    return staging, result
