"""Command-line commands that live in their own modules.

Each module here defines ``register(app)``, which adds its typer commands to the ``cylfric``
app; :mod:`cylfric.cli` calls every module's ``register`` in name order when it is imported.
A module imports only typer and :mod:`cylfric.cli`'s helpers at the top (``guarded``,
``BadInput``, ``console``, ``err_console``, ``progress_bar``, ``numbers``) and everything
numerical inside its command bodies, so ``cylfric --version`` stays fast.
"""

from __future__ import annotations

import importlib
import pkgutil


def register_all(app) -> None:
    """Add every command module's commands to ``app`` (modules in name order)."""
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        importlib.import_module(f"{__name__}.{info.name}").register(app)
