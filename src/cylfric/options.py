"""The options of one fit, checked once: :class:`FitOptions`.

:func:`cylfric.pipeline.fit_campaign`, :func:`cylfric.many.fit_many` and the command line
build one ``FitOptions`` and pass it down; the steps read it, none re-checks it. This
module imports nothing heavy (no numpy, no readers): the process that only dispatches
fits to workers (:mod:`cylfric.many`) builds one too.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

__all__ = ["FitOptions", "FITTED_PRESSURE_LAWS"]

FITTED_PRESSURE_LAWS = ("linear", "quadratic", "exponential")
"""Pressure laws a fit can report in its datasheet: those the identification fits and
compares (:data:`cylfric.identify.steady.LAWS_COMPARED`; a test keeps the two equal)."""


@dataclass(frozen=True)
class FitOptions:
    """How to fit a campaign (everything but the folders and the progress callbacks).

    Attributes
    ----------
    fixed : dict
        Parameters held fixed (SI), e.g. ``{"alpha": 1.0, "v_r": 0.010}`` [-], [m/s].
    pressure_law : str
        Pressure law of the datasheet (:data:`FITTED_PRESSURE_LAWS`).
    per_direction : bool
        Also identify extension and retraction separately (``per_direction.csv``).
    skip_bad : bool
        Skip unreadable files instead of stopping at the first.
    report : bool
        Draw the figures and write ``report.html``.
    name : str or None
        Name recorded in the datasheet (default: the campaign folder's name).
    glob : str or None
        Which files of the folder are runs (overrides ``campaign.toml [files] glob``).
    config : str or None
        Path of a campaign.toml to use instead of the folder's (``--config``: a recipe kept
        outside read-only data; the folder stays untouched). Recorded in the datasheet
        (``fit.source.recipe``).
    strict : bool
        Raise (ValueError) instead of leaving out the runs the data-quality gate flags
        (:func:`cylfric.quality.assess`); by default they are listed in ``excluded.csv``.
    export : tuple of str
        Export targets (``"fmu"``, ``"simscape"``, ...; :data:`cylfric.export.TARGETS`),
        checked and without repeats (a string ``"fmu,matlab"`` is split), written into
        ``out/export/<target>/`` after the datasheet.
    workers : int or None
        Processes for the extraction and the figures (default: the cores this process may
        use, :func:`cylfric._parallel.cores`, forked on Linux, else 1; see
        :func:`~cylfric.steady_state.extract_campaign`); 1 keeps the fit on one core, as
        the workers of :func:`cylfric.many.fit_many` do when several fits run at once.
    scheduler : str or None
        A Dask distributed scheduler address (``"tcp://10.0.0.5:8786"``): the run files
        are read by that cluster's workers, in tasks of consecutive files
        (:func:`cylfric.steady_state.start_extraction`), the rest of the fit runs here
        (``workers`` then counts only the figures' processes). None: this machine.
    viscosity_correction : bool or None
        Identify at the reference temperature of ``campaign.toml [oil]``, each point's speed
        mapped by the oil's viscosity at its run's temperature (equal Hersey number; see
        :func:`cylfric.drift.correct_campaign`). None: when both ``[oil]`` and temperatures
        are there (a note says which is missing otherwise); True: required (ValueError
        without them); False: never.
    accept_force_balance : bool
        Fit even when the gate's physical checks (:mod:`cylfric.quality.plausibility`) find the
        force balance contradicted (the offset or the friction following the pressure
        force: a ``load_cell_sign`` / ``position_sign`` of campaign.toml) or a friction
        above the pressure force the cylinder could make (a unit slip); the findings become
        notes. By default they stop the fit (exit 2).

    Every value is checked on construction; a wrong one raises ValueError naming the option
    and the valid values.

    >>> FitOptions(pressure_law="quadratic", export="fmu,matlab").export
    ('fmu', 'matlab')
    >>> FitOptions(pressure_law="cubic")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: unknown pressure law 'cubic' (pressure_law); valid: ['linear', 'quadratic', ...]
    """

    fixed: Mapping[str, float] = field(default_factory=dict)
    pressure_law: str = "linear"
    per_direction: bool = False
    skip_bad: bool = False
    report: bool = True
    name: str | None = None
    glob: str | None = None
    config: str | None = None
    strict: bool = False
    export: tuple[str, ...] = ()
    workers: int | None = None
    viscosity_correction: bool | None = None
    scheduler: str | None = None
    accept_force_balance: bool = False

    def __post_init__(self) -> None:
        fixed = {} if self.fixed is None else self.fixed
        if not isinstance(fixed, Mapping):
            raise ValueError(
                f"fixed = {fixed!r}: expected a dict of parameter -> value (SI), "
                'e.g. {"alpha": 1.0, "v_r": 0.010}'
            )
        object.__setattr__(self, "fixed", dict(fixed))
        if self.pressure_law not in FITTED_PRESSURE_LAWS:
            raise ValueError(
                f"unknown pressure law {self.pressure_law!r} (pressure_law); "
                f"valid: {list(FITTED_PRESSURE_LAWS)}"
            )
        for name in ("per_direction", "skip_bad", "report", "strict", "accept_force_balance"):
            _check_choice(name, getattr(self, name), (True, False))
            object.__setattr__(self, name, bool(getattr(self, name)))
        _check_choice("viscosity_correction", self.viscosity_correction, (None, True, False))
        if self.viscosity_correction is not None:
            object.__setattr__(self, "viscosity_correction", bool(self.viscosity_correction))
        if isinstance(self.config, os.PathLike):
            object.__setattr__(self, "config", os.fspath(self.config))
        for name in ("name", "glob", "config", "scheduler"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, str):
                raise ValueError(f"{name} = {value!r}: expected a string or None")
        object.__setattr__(self, "export", _targets(self.export))
        workers = self.workers
        if workers is not None and (
            isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
        ):
            raise ValueError(f"workers = {workers!r}: expected a whole number >= 1, or None")

    @classmethod
    def from_keywords(cls, options: FitOptions | None = None, **keywords: Any) -> FitOptions:
        """``options`` or, without it, the options the keywords name (not both).

        Unknown keywords raise ValueError listing the valid ones.
        """
        if options is not None:
            if keywords:
                raise ValueError(
                    f"pass either options (a FitOptions) or its keywords, not both "
                    f"(got options and {sorted(keywords)})"
                )
            if not isinstance(options, FitOptions):
                raise ValueError(
                    f"options = {options!r}: expected a FitOptions (or keywords such as "
                    "pressure_law='linear')"
                )
            return options
        valid = [f.name for f in fields(cls)]
        unknown = sorted(set(keywords) - set(valid))
        if unknown:
            raise ValueError(f"unknown fit option(s) {unknown}; valid: {valid}")
        return cls(**keywords)


def _check_choice(name: str, value: object, valid: tuple[object, ...]) -> None:
    if not any(value is choice or (choice is not None and value == choice) for choice in valid):
        raise ValueError(f"{name} = {value!r}: expected one of {list(valid)}")


def _targets(export: str | Iterable[str] | None) -> tuple[str, ...]:
    """Export targets checked by :func:`cylfric.export.parse_targets` (empty: none)."""
    if export is None:
        return ()
    if not isinstance(export, str):
        export = list(export)
    if not export:
        return ()
    from .export import parse_targets  # the registry only: no target module is imported

    return tuple(parse_targets(export))
