"""The friction model: one object that identification, datasheet, simulation and report share.

A :class:`FrictionModel` holds the steady-state friction law (thesis eq. 2.7) with a pressure
law per parameter (eq. 2.10, 4.1-4.3), the LuGre bristle parameters ``sigma_0`` and ``sigma_1``
with their status, the operating-pressure rule, the validity ranges, the covariance of the
fitted coefficients and the provenance. It is built on :mod:`cylfric.friction` only: every
evaluation goes through :func:`~cylfric.friction.stribeck`,
:func:`~cylfric.friction.lugre_force` and :func:`~cylfric.friction.params_at_pressure`.

Each coefficient is a :class:`Parameter` (value, standard error, unit, bounds, vary),
named ``"<parameter>.<coefficient>"`` for pressure-dependent parameters (``"F_c.slope"``) and
``"<parameter>"`` for constants (``"v_r"``). All values are SI: N, Pa, m/s, N*s/m, N/m.

Examples
--------
>>> from cylfric.model import FrictionModel
>>> model = FrictionModel()                      # the thesis law, eq. 4.1-4.3
>>> round(model.friction(0.025, 55e5), 2)         # [N] at 25 mm/s and 55 bar
111.26
>>> model.parameters["F_c.slope"].unit
'N/Pa'
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING, cast, overload

import numpy as np

from ..friction import (
    get_law,
    lugre_force,
    operating_pressure,
    params_at_pressure,
    stribeck,
    stribeck_unchecked,
)
from ..friction._checks import check_parameters, clamp_roundoff
from ..friction.literature import THESIS_2016
from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS, PRESSURE_LAWS, PRESSURE_REFERENCES
from .names import (
    _DEFAULT_DYNAMIC,
    DYNAMIC_PARAMETERS,
    DYNAMIC_STATUS,
    FRICTION_LAWS,
    IDENTIFY_ADVICE,
    PARAMETER_BOUNDS,
    PARAMETER_UNITS,
    PRESSURE_DEPENDENT,
    STEADY_PARAMETERS,
    ValidityWarning,
    _si_unit,
    engineering_unit,
)

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence
    from typing import Any

    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from .._typing import StrPath


__all__ = [
    "FrictionModel",
    "Parameter",
    "ValidityWarning",
    "STEADY_PARAMETERS",
    "DYNAMIC_PARAMETERS",
    "PARAMETER_UNITS",
    "PARAMETER_BOUNDS",
    "FRICTION_LAWS",
    "DYNAMIC_STATUS",
    "engineering_unit",
]


@dataclass(frozen=True)
class Parameter:
    """One coefficient of a friction model, as lmfit's Parameter: value and all about it.

    Attributes
    ----------
    name : str
        ``"F_c.slope"`` for a pressure-law coefficient, ``"v_r"`` for a constant.
    value : float or None
        SI value; None when the parameter was not identified.
    unit : str
        SI unit (``"N/Pa"``).
    stderr : float or None
        Standard error [unit]; None when unknown, 0 for a parameter held fixed.
    vary : bool
        False when the parameter was held fixed (not fitted).
    bounds : tuple of float
        (lower, upper) bounds of the fit [unit].
    """

    name: str
    value: float | None
    unit: str
    stderr: float | None = None
    vary: bool = True
    bounds: tuple = (-math.inf, math.inf)

    @property
    def parameter(self) -> str:
        """The friction parameter this coefficient belongs to (``"F_c"``)."""
        return self.name.partition(".")[0]

    @property
    def coefficient(self) -> str | None:
        """The pressure-law coefficient (``"slope"``), or None for a constant."""
        return self.name.partition(".")[2] or None

    def engineering(self) -> tuple[float | None, float | None, str]:
        """(value, stderr, unit) in engineering units (bar, mm/s, N*s/mm)."""
        unit, k = engineering_unit(self.name)
        value = None if self.value is None else self.value * k
        stderr = None if self.stderr is None else self.stderr * k
        return value, stderr, unit

    def __repr__(self) -> str:
        """SI value and unit, and the engineering value the report prints beside them:
        ``Parameter('F_c.slope', value=5e-06 N/Pa [0.5 N/bar], stderr=...)``."""
        if self.value is None:
            return f"Parameter({self.name!r}, not identified, unit={self.unit!r})"
        value, stderr, unit = self.engineering()

        def both(si: float | None, eng: float | None) -> str:
            if si is None:
                return "None"
            shown = f"{si:.6g} {self.unit}"
            return shown if unit == self.unit else f"{shown} [{eng:.6g} {unit}]"

        fixed = "" if self.vary else ", fixed"
        return (
            f"Parameter({self.name!r}, value={both(self.value, value)}, "
            f"stderr={both(self.stderr, stderr)}{fixed})"
        )


def _spec_items(spec, default_law):
    """(law, {coefficient: value}) of one parameter's entry in a coefficient set."""
    if spec is None:
        return None, None
    if isinstance(spec, Mapping):
        spec = dict(spec)
        law = spec.pop("law", default_law)
        if law not in PRESSURE_LAW_COEFFICIENTS:
            raise ValueError(f"unknown pressure law {law!r}; valid: {sorted(PRESSURE_LAWS)}")
        names = PRESSURE_LAW_COEFFICIENTS[law]
        if set(spec) != set(names):
            raise ValueError(
                f"coefficients {sorted(spec)} do not fit the {law} pressure law; "
                f"expected {list(names)}"
            )
        return law, {n: float(spec[n]) for n in names}
    return "constant", {"intercept": float(spec)}


def _stderr_items(spec, law):
    """{coefficient: standard error or None} of one parameter's stderr entry."""
    if spec is None:
        return {}
    if isinstance(spec, Mapping):
        return {c: (None if v is None else float(v)) for c, v in spec.items() if c != "law"}
    return {"intercept": float(spec)} if law == "constant" else {}


def _reference_basis(basis, reference):
    """The pressure reference's basis as a read-only mapping (checked against ``reference``)."""
    if basis is None:
        return None
    basis = dict(basis)
    missing = {"kind", "rule", "stated_by"} - set(basis)
    if missing:
        raise ValueError(f"pressure_reference_basis lacks {sorted(missing)}")
    if basis["rule"] != reference:
        raise ValueError(
            f"pressure_reference_basis says rule {basis['rule']!r} but the model's reference is "
            f"{reference!r}; give both the same rule"
        )
    basis.setdefault("chamber", None)
    return MappingProxyType(basis)


SHARE_BLOCK = 1 << 20
"""Most entries of the (points x runs) matrix of the runs' shares that
:meth:`FrictionModel.effective_dof` holds at once (8 MB): a band of 200 speeds over 20,000
runs is 32 MB, and its squares as much again, in each process that draws the report."""


def _shares(jacobian: np.ndarray, influence: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sum a_g, sum a_g^2) over the runs g at each point, a_g = (J . influence_g)^2: each
    run's share of the variance [N^2], in blocks of points of at most :data:`SHARE_BLOCK`
    entries, squared in place (each point's sums the same to rounding whatever the block: BLAS
    may take another kernel for a block's last rows; in one block, as before, exactly)."""
    flat = jacobian.reshape(-1, jacobian.shape[-1])
    total, squares = np.empty(len(flat)), np.empty(len(flat))
    rows = max(1, SHARE_BLOCK // max(len(influence), 1))
    for start in range(0, len(flat), rows):
        share = flat[start : start + rows] @ influence.T  # (points, runs)
        np.square(share, out=share)
        total[start : start + rows] = share.sum(axis=-1)
        np.square(share, out=share)
        squares[start : start + rows] = share.sum(axis=-1)
    return total.reshape(jacobian.shape[:-1]), squares.reshape(jacobian.shape[:-1])


class FrictionModel:
    """Pressure-dependent friction of a cylinder: steady-state law, LuGre dynamics, uncertainty.

    A model read with :meth:`from_datasheet` from a file keeps its path in ``source`` (also
    through :meth:`replace`), and an evaluation error (a law extrapolated below its physical
    bound) names that file.

    Parameters
    ----------
    coefficients : mapping, optional
        Friction parameter -> constant (SI) or dict of pressure-law coefficients
        (``{"intercept": 70.2, "slope": 5e-6}``; a dict may carry its own ``"law"``), or None
        for a parameter that was not identified. Default: the thesis law (eq. 4.1-4.3).
        ``sigma_0`` [N/m] and ``sigma_1`` [N*s/m] may be included (e.g. a LuGre literature set).
    pressure_law : {"constant", "linear", "quadratic", "exponential"}
        Pressure law of the dict entries that name none.
    friction_law : {"stribeck", "coulomb_viscous", "coulomb"}
        Steady-state law; the reduced ones identify fewer parameters.
    sigma_0, sigma_1 : float or mapping, optional
        Bristle stiffness [N/m] and damping [N*s/m] (constants or pressure laws). They
        override entries of ``coefficients``; defaults 1e6 N/m and 1.58e3 N*s/m, ``assumed``.
    dynamic_status : mapping, optional
        ``{"sigma_0": ("identified", "from presliding tests"), ...}``: status and reason.
        Default: ``identified`` when the value came from ``coefficients``, ``assumed``
        (with the reason for the default) otherwise, and ``assumed`` for explicit keywords.
    reference : {"a", "b", "sum", "mean", "max"}
        Which chamber pressure the pressure laws see (:func:`cylfric.friction.operating_pressure`).
    pressure_reference_basis : mapping, optional
        Why the laws see that pressure: ``kind`` (``"single-acting"``, ``"double-acting"``),
        ``rule`` (= ``reference``), ``chamber`` (``"a"``, ``"b"`` or None) and ``stated_by``
        (:func:`cylfric.friction.pressure.pressure_reference_basis`); None when unknown.
        Replacing ``reference`` alone drops it.
    simulation_law : str
        Registered friction law that :func:`cylfric.simulate.simulate` integrates
        (``"lugre"`` for the compiled integrators; others with ``method="scipy"``).
    stderr : mapping, optional
        Standard errors mirroring ``coefficients`` (SI).
    fixed : iterable of str, optional
        Names held fixed in the fit (``"alpha"``, ``"F_c.slope"``, or ``"F_c"`` for all of
        its coefficients); their ``vary`` is False.
    bounds : mapping, optional
        Parameter name -> (lower, upper) used by the fit.
    covariance : (names, matrix), optional
        Covariance [SI] of the fitted (varying) coefficients, in the order of ``names``.
    influence : (names, matrix), optional
        Influence of each run of the fit on the coefficients (runs x coefficients, SI, the
        covariance's names): the cluster-robust (CR2) contributions with
        ``covariance = matrix.T @ matrix``. With it, :meth:`band` uses each point's effective
        degrees of freedom (few runs carrying a coefficient give few).
    covariance_nonrobust : (names, matrix), optional
        The model-based covariance ``s^2 (J^T W J)^-1`` [SI] of the same coefficients (the
        covariance's names), where ``covariance`` is cluster-robust: the mean's share of a
        band for new data of the same mount (:meth:`prediction_band` scopes "point" and
        "run", docs/uncertainty.md). None: ``covariance`` serves both.
    statistics : mapping, optional
        ``n_points``, ``n_variables``, ``rmse`` [N], ``residual_std`` [N], ``dof``, ``aic``,
        ``bic`` of the fit that made the model.
    validity : mapping, optional
        ``pressure_min``, ``pressure_max`` [Pa], ``velocity_min``, ``velocity_max`` [m/s]:
        the range the data covered.
    provenance : mapping, optional
        ``method`` (str) and ``source`` (``campaign``, ``files`` with ``name`` and ``sha256``).
    not_identified : mapping, optional
        Parameter -> reason, for the parameters the data could not identify.
    record : mapping, optional
        Everything else a datasheet says (per-pressure table, offset, notes, ...), kept
        verbatim so that datasheet -> model -> datasheet is the identity.
    """

    def __init__(
        self,
        coefficients: Mapping[str, Any] | None = None,
        *,
        pressure_law: str = "linear",
        friction_law: str = "stribeck",
        sigma_0: float | Mapping[str, Any] | None = None,
        sigma_1: float | Mapping[str, Any] | None = None,
        dynamic_status: Mapping[str, Any] | None = None,
        reference: str = "mean",
        simulation_law: str = "lugre",
        stderr: Mapping[str, Any] | None = None,
        fixed: Iterable[str] = (),
        bounds: Mapping[str, Any] | None = None,
        covariance: tuple[Sequence[str], np.ndarray] | None = None,
        statistics: Mapping[str, Any] | None = None,
        validity: Mapping[str, Any] | None = None,
        provenance: Mapping[str, Any] | None = None,
        not_identified: Mapping[str, Any] | None = None,
        record: Mapping[str, Any] | None = None,
        influence: tuple[Sequence[str], np.ndarray] | None = None,
        pressure_reference_basis: Mapping[str, Any] | None = None,
        covariance_nonrobust: tuple[Sequence[str], np.ndarray] | None = None,
    ) -> None:
        if coefficients is None:
            coefficients = THESIS_2016.coefficients
        if pressure_law not in PRESSURE_LAWS:
            raise ValueError(
                f"unknown pressure law {pressure_law!r}; valid: {sorted(PRESSURE_LAWS)}"
            )
        if friction_law not in FRICTION_LAWS:
            raise ValueError(
                f"unknown friction law {friction_law!r} for a model; valid: {sorted(FRICTION_LAWS)}"
            )
        if reference not in PRESSURE_REFERENCES:
            raise ValueError(
                f"unknown pressure reference {reference!r}; valid: {sorted(PRESSURE_REFERENCES)}"
            )
        get_law(simulation_law)
        unknown = set(coefficients) - set(PARAMETER_UNITS)
        if unknown:
            raise ValueError(
                f"unknown friction parameters {sorted(unknown)}; valid: {list(PARAMETER_UNITS)}"
            )
        self.pressure_law = pressure_law
        self.friction_law = friction_law
        self.reference = reference
        self.pressure_reference_basis = _reference_basis(pressure_reference_basis, reference)
        self.simulation_law = simulation_law
        not_identified = dict(not_identified or {})
        needed = FRICTION_LAWS[friction_law][0]
        for name in STEADY_PARAMETERS:
            if name in needed and coefficients.get(name) is None:
                raise ValueError(f"the {friction_law} law needs {name}; got {sorted(coefficients)}")
            if name not in needed:
                if coefficients.get(name) is not None:
                    raise ValueError(
                        f"{name} is given but the {friction_law} law has no {name}; "
                        f"give it as None (not identified) or use another friction_law"
                    )
                not_identified.setdefault(
                    name, f"not part of the {friction_law} law the data support"
                )
        status = dict(dynamic_status or {})
        dynamic = {}
        for name, keyword in (("sigma_0", sigma_0), ("sigma_1", sigma_1)):
            if keyword is not None:
                dynamic[name] = keyword
                status.setdefault(name, ("assumed", "given by the user"))
            elif coefficients.get(name) is not None:
                dynamic[name] = coefficients[name]
                status.setdefault(name, ("identified", "given with the coefficient set"))
            else:
                dynamic[name] = _DEFAULT_DYNAMIC[name][0]
                status.setdefault(name, ("assumed", _DEFAULT_DYNAMIC[name][1]))
        for name, value in dynamic.items():
            if not isinstance(value, Mapping):
                check_parameters(**{name: value})
        for name, (state, _) in status.items():
            if state not in DYNAMIC_STATUS:
                raise ValueError(
                    f"status of {name} {state!r} is unknown; valid: {list(DYNAMIC_STATUS)}"
                )
        self.dynamic_status = MappingProxyType({k: tuple(v) for k, v in status.items()})
        stderr = stderr or {}
        fixed = set(fixed)
        bounds = dict(bounds or {})
        laws, parameters = {}, {}
        for name in STEADY_PARAMETERS + DYNAMIC_PARAMETERS:
            spec = dynamic[name] if name in DYNAMIC_PARAMETERS else coefficients.get(name)
            if name not in needed and name in STEADY_PARAMETERS:
                spec = None
            law, values = _spec_items(spec, pressure_law)
            laws[name] = law
            if values is None:
                parameters[name] = Parameter(name, None, PARAMETER_UNITS[name], None, False)
                continue
            errors = _stderr_items(stderr.get(name), law)
            for coefficient, value in values.items():
                key = name if law == "constant" else f"{name}.{coefficient}"
                if not math.isfinite(value):
                    raise ValueError(f"parameter {key} = {value} is not finite")
                default_bounds = (
                    PARAMETER_BOUNDS[name]
                    if law == "constant" or coefficient == "intercept"
                    else (-math.inf, math.inf)
                )
                parameters[key] = Parameter(
                    key,
                    value,
                    _si_unit(name, None if law == "constant" else coefficient),
                    errors.get(coefficient),
                    key not in fixed and name not in fixed,
                    tuple(bounds.get(key, default_bounds)),
                )
        self.laws = MappingProxyType(laws)
        self.parameters = MappingProxyType(parameters)
        self.not_identified = MappingProxyType(not_identified)
        if covariance is not None:
            names, matrix = covariance
            matrix = np.array(matrix, dtype=float)
            names = tuple(names)
            if matrix.shape != (len(names), len(names)):
                raise ValueError(
                    f"covariance is {matrix.shape}; expected {len(names)} x {len(names)} "
                    "for its names"
                )
            missing = set(names) - set(parameters)
            if missing:
                raise ValueError(f"covariance names {sorted(missing)} are not model parameters")
            matrix.setflags(write=False)
            covariance = (names, matrix)
        self.covariance = covariance
        if influence is not None:
            names, matrix = tuple(influence[0]), influence[1]
            if not _frozen(matrix):  # one (runs x coefficients) array shared by replace()
                matrix = np.array(matrix, dtype=float)
            if covariance is None or names != covariance[0] or matrix.ndim != 2:
                raise ValueError(
                    "influence needs a covariance with the same names and a (runs x "
                    "coefficients) matrix"
                )
            if matrix.shape[1] != len(names) or not np.all(np.isfinite(matrix)):
                raise ValueError(
                    f"influence is {matrix.shape}; expected finite (runs x {len(names)})"
                )
            matrix.setflags(write=False)
            influence = (names, matrix)
        self.influence = influence
        if covariance_nonrobust is not None:
            names, matrix = (
                tuple(covariance_nonrobust[0]),
                np.array(covariance_nonrobust[1], dtype=float),
            )
            if covariance is None or names != covariance[0] or matrix.shape != covariance[1].shape:
                raise ValueError(
                    "covariance_nonrobust needs a covariance with the same names and shape"
                )
            if not np.all(np.isfinite(matrix)):
                raise ValueError("covariance_nonrobust has non-finite values")
            matrix.setflags(write=False)
            covariance_nonrobust = (names, matrix)
        self.covariance_nonrobust = covariance_nonrobust
        self.statistics = MappingProxyType(dict(statistics or {}))
        self.validity = None if validity is None else MappingProxyType(dict(validity))
        self.provenance = MappingProxyType(dict(provenance or {}))
        self.record = MappingProxyType(dict(record or {}))

    # ------------------------------------------------------------------ construction helpers
    def _init_kwargs(self) -> dict:
        fixed = [p.name for p in self.parameters.values() if not p.vary and p.value is not None]
        bounds = {p.name: p.bounds for p in self.parameters.values() if p.value is not None}
        return {
            "coefficients": self.coefficients(include_dynamic=False),
            "pressure_law": self.pressure_law,
            "friction_law": self.friction_law,
            "sigma_0": self.coefficients()["sigma_0"],
            "sigma_1": self.coefficients()["sigma_1"],
            "dynamic_status": dict(self.dynamic_status),
            "reference": self.reference,
            "pressure_reference_basis": self.pressure_reference_basis,
            "simulation_law": self.simulation_law,
            "stderr": self.stderr(),
            "fixed": fixed,
            "bounds": bounds,
            "covariance": self.covariance,
            "influence": self.influence,
            "covariance_nonrobust": self.covariance_nonrobust,
            "statistics": dict(self.statistics),
            "validity": None if self.validity is None else dict(self.validity),
            "provenance": dict(self.provenance),
            "not_identified": dict(self.not_identified),
            "record": dict(self.record),
        }

    def replace(self, **changes: Any) -> FrictionModel:
        """A copy with some constructor arguments changed (``model.replace(sigma_0=2e6)``).

        Changing a coefficient drops the covariance unless a new one is given. A model read
        from a file keeps its :attr:`source`, and :attr:`replaced` lists the arguments changed
        since, so that its errors still say where it came from (``rig.json, with sigma_0
        replaced: ...``); ``source="other.json"`` (or None) sets it instead and clears
        :attr:`replaced`.
        """
        source = changes.pop("source", self.source)
        replaced = () if source != self.source else tuple(sorted({*self.replaced, *changes}))
        kwargs = self._init_kwargs()
        if "coefficients" in changes and "covariance" not in changes:
            kwargs["covariance"] = None
        for name in ("sigma_0", "sigma_1"):
            if name in changes and "dynamic_status" not in changes:
                kwargs["dynamic_status"].pop(name, None)
        if "friction_law" in changes:
            kwargs["not_identified"] = {}
        if "reference" in changes and "pressure_reference_basis" not in changes:
            kwargs["pressure_reference_basis"] = None  # the basis said why the old rule
        kwargs.update(changes)
        if kwargs["covariance"] is None or ("covariance" in changes and "influence" not in changes):
            kwargs["influence"] = None  # the runs' influence belongs to its covariance
        if kwargs["covariance"] is None or (
            "covariance" in changes and "covariance_nonrobust" not in changes
        ):
            kwargs["covariance_nonrobust"] = None  # so does the model-based covariance
        model = FrictionModel(**kwargs)
        if source is not None:
            model.source, model.replaced = str(source), replaced
        return model

    # ------------------------------------------------------------------ views
    def coefficients(self, *, include_dynamic: bool = True) -> dict:
        """The coefficient set (SI) for :func:`cylfric.friction.params_at_pressure`.

        Constants are floats, pressure laws dicts (with ``"law"`` when it differs from
        :attr:`pressure_law`), parameters not identified None.
        """
        names = STEADY_PARAMETERS + (DYNAMIC_PARAMETERS if include_dynamic else ())
        return {name: self._spec(name, "value") for name in names}

    def stderr(self) -> dict:
        """Standard errors mirroring :meth:`coefficients` (None where unknown)."""
        return {name: self._spec(name, "stderr") for name in STEADY_PARAMETERS}

    def _spec(self, name, attribute):
        law = self.laws[name]
        if law is None:
            return None
        if law == "constant":
            value = getattr(self.parameters[name], attribute)
            if name not in PRESSURE_DEPENDENT:
                return value
            return {"intercept": value, **({} if self.pressure_law == "constant" else {"law": law})}
        spec = {
            c: getattr(self.parameters[f"{name}.{c}"], attribute)
            for c in PRESSURE_LAW_COEFFICIENTS[law]
        }
        if law != self.pressure_law:
            spec["law"] = law
        return spec

    @property
    def identified(self) -> tuple[str, ...]:
        """Steady-state parameters the model identifies (those of its friction law)."""
        return FRICTION_LAWS[self.friction_law][0]

    @property
    def varying(self) -> tuple[str, ...]:
        """Names of the fitted (varying) coefficients."""
        return tuple(p.name for p in self.parameters.values() if p.vary and p.value is not None)

    def __repr__(self) -> str:
        laws = ", ".join(f"{n}: {self.laws[n]}" for n in self.identified)
        return (
            f"FrictionModel({self.friction_law}, pressure laws {{{laws}}}, "
            f"reference={self.reference!r})"
        )

    def assumptions(self) -> list[str]:
        """What this model holds that was assumed rather than identified, one line each with
        how to identify it: ``sigma_0``/``sigma_1`` while their status is ``"assumed"`` (a
        steady-state campaign cannot give them). Empty when everything it holds was
        identified. Every command that uses them (``control``, ``simulate``, ``export``)
        says these lines on stderr and writes them into its outputs."""
        assumed = []
        for key in ("sigma_0", "sigma_1"):
            status, why = self.dynamic_status.get(key, ("assumed", ""))
            shown = self._dynamic_text(key)
            if status == "assumed" and shown is not None:
                assumed.append(f"{shown} ({why})" if why else shown)
        if not assumed:
            return []
        return [
            f"assumed, not identified: {'; '.join(assumed)}. They set the presliding "
            "stiffness and damping: what a LuGre compensator, a friction observer or a "
            "simulation does at reversals, in stick-slip and at breakaway depends on them. "
            f"To make them right: {IDENTIFY_ADVICE}"
        ]

    def __str__(self) -> str:
        """The laws in engineering units with their standard errors (``print(model)``)."""
        from .text import law_lines

        name = self.record.get("name") if isinstance(self.record, Mapping) else None
        head = f"FrictionModel {name!r}" if name else "FrictionModel"
        lines = [
            f"{head}: {self.friction_law} law; pressure laws on the {self.reference!r} "
            "chamber pressure (p in bar)"
        ]
        lines += [f"  {line}" for line in law_lines(self)]
        for key in ("sigma_0", "sigma_1"):
            status, why = self.dynamic_status.get(key, ("assumed", ""))
            shown = self._dynamic_text(key) or f"{key}: not set"
            lines.append(f"  {shown} ({status}{': ' + why if why else ''})")
        return "\n".join(lines)

    def _dynamic_text(self, key: str) -> str | None:
        """``sigma_0 = 1000 N/mm`` (a constant) or ``sigma_0: linear pressure law``; None
        when the model does not hold it."""
        law = self.laws.get(key)
        if law is None:
            return None
        if law != "constant":
            return f"{key}: {law} pressure law"
        value, _, unit = self.parameters[key].engineering()
        return None if value is None else f"{key} = {value:.4g} {unit}"

    def __getstate__(self) -> dict[str, Any]:
        """The model's attributes for pickle (a forked or Dask worker sends models back):
        its read-only mappings as plain dicts, named so :meth:`__setstate__` restores them."""
        state = dict(self.__dict__)
        proxies = [k for k, v in state.items() if isinstance(v, MappingProxyType)]
        state.update({k: dict(state[k]) for k in proxies})
        state["__read_only__"] = proxies
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        state = dict(state)
        proxies = state.pop("__read_only__", [])
        state.update({k: MappingProxyType(state[k]) for k in proxies})
        self.__dict__.update(state)

    # ------------------------------------------------------------------ evaluation
    def operating_pressure(
        self, pressure_a: ArrayLike, pressure_b: ArrayLike | None = None
    ) -> np.ndarray:
        """The pressure the laws see [Pa] from chamber pressures [Pa] (the model's rule)."""
        return operating_pressure(pressure_a, pressure_b, reference=self.reference)

    def params_at(self, pressure: ArrayLike) -> dict[str, float | np.ndarray]:
        """Friction-law parameters (SI) at an operating pressure [Pa], dynamic ones included.

        A reduced law is returned as eq. 2.7 with ``F_s = F_c`` (and ``sigma_2 = 0`` for
        ``coulomb``; ``v_r`` and ``alpha`` then do not act), so every model plugs into
        :func:`~cylfric.friction.stribeck` and :func:`~cylfric.friction.lugre_force`.
        """
        return self._params(pressure, self.coefficients())

    def _params(self, pressure, coefficients):
        given = {k: v for k, v in coefficients.items() if v is not None}
        params = params_at_pressure(pressure, given, law=self.pressure_law)
        if "F_s" not in given:
            params["F_s"] = params["F_c"]
        if "sigma_2" not in given:
            params["sigma_2"] = 0.0 * params["F_c"]
        params.setdefault("v_r", 1.0)
        params.setdefault("alpha", 1.0)
        return clamp_roundoff(params)  # a value fitted onto a bound, off by rounding only

    @overload
    def friction(self, velocity: float, pressure: float, *, strict: bool = False) -> float: ...
    @overload
    def friction(
        self, velocity: np.ndarray, pressure: ArrayLike, *, strict: bool = False
    ) -> np.ndarray: ...
    @overload
    def friction(
        self, velocity: ArrayLike, pressure: np.ndarray, *, strict: bool = False
    ) -> np.ndarray: ...
    @overload
    def friction(
        self, velocity: ArrayLike, pressure: ArrayLike, *, strict: bool = False
    ) -> np.ndarray | float: ...
    def friction(
        self, velocity: ArrayLike, pressure: ArrayLike, *, strict: bool = False
    ) -> np.ndarray | float:
        """Steady-state friction force [N] at ``velocity`` [m/s] and operating ``pressure`` [Pa].

        Vectorised (velocity and pressure broadcast). Warns with :class:`ValidityWarning`
        outside the validity ranges (raises with ``strict=True``); see :meth:`check`.
        """
        self.check(velocity, pressure, strict=strict)
        return self._friction(velocity, pressure, self.coefficients())

    source: str | None = None
    """The datasheet file this model was read from (None when built otherwise); kept by
    :meth:`replace`."""

    replaced: tuple = ()
    """Constructor arguments :meth:`replace` changed since the model was read from
    :attr:`source` (sorted names; empty for the file's own model)."""

    def _friction(self, velocity, pressure, coefficients, *, checked: bool = True):
        params = self._params(pressure, coefficients)
        if not checked:
            return stribeck_unchecked(velocity, **{k: params[k] for k in STEADY_PARAMETERS})
        try:
            return stribeck(velocity, **{k: params[k] for k in STEADY_PARAMETERS})
        except ValueError as exc:
            raise self._named(exc) from None

    def _named(self, exc: ValueError) -> ValueError:
        """``exc`` with the datasheet file in front of its message (when there is one)."""
        if self.source is None or str(exc).startswith(self.source):
            return exc
        changed = f", with {', '.join(self.replaced)} replaced" if self.replaced else ""
        return type(exc)(f"{self.source}{changed}: {exc}")

    def dynamic_force(
        self, velocity: ArrayLike, z: ArrayLike, pressure: ArrayLike
    ) -> np.ndarray | float:
        """LuGre friction force [N] (eq. 2.5) at velocity [m/s], bristle deflection z [m]."""
        params = self.params_at(pressure)
        try:
            return lugre_force(velocity, z, **{k: params[k] for k in PARAMETER_UNITS})
        except ValueError as exc:
            raise self._named(exc) from None

    def check(
        self, velocity: ArrayLike, pressure: ArrayLike, *, strict: bool = False
    ) -> np.ndarray:
        """Where (velocity [m/s], pressure [Pa]) lie inside the validity ranges.

        ``velocity=None`` checks the pressures only (a simulation passes through every
        speed, zero included). Returns a boolean array (broadcast shape). Points outside,
        or pressures below 1e3 Pa (pressures given in bar?), give a
        :class:`ValidityWarning`, or a ValueError with ``strict=True``. A model without
        validity ranges accepts everything.
        """
        p = np.asarray(pressure, dtype=float)
        speed = None
        if velocity is not None:
            speed, p = np.broadcast_arrays(np.abs(np.asarray(velocity, dtype=float)), p)
        problems = []
        positive = p[p > 0]
        if positive.size and positive.max() < 1e3:
            problems.append(
                f"pressures of at most {positive.max():.4g} Pa: pressures are in Pa "
                "(1 bar = 1e5 Pa)"
            )
        inside = np.ones(p.shape, dtype=bool)
        if self.validity is not None:
            val = self.validity
            tol_p = 1e-6 * max(abs(val["pressure_max"]), 1.0)
            tol_v = 1e-6 * max(val["velocity_max"], 1e-9)
            inside = (p >= val["pressure_min"] - tol_p) & (p <= val["pressure_max"] + tol_p)
            if speed is not None:
                inside &= (speed >= val["velocity_min"] - tol_v) & (
                    speed <= val["velocity_max"] + tol_v
                )
            if not inside.all():
                if speed is not None:
                    speeds = (
                        f", {val['velocity_min'] * 1e3:.4g}-{val['velocity_max'] * 1e3:.4g} mm/s"
                    )
                else:  # a pressure check only (a simulation): say which pressures
                    low, high = np.min(p[~inside]) / 1e5, np.max(p[~inside]) / 1e5
                    given = f"{low:.4g}" if low == high else f"{low:.4g} to {high:.4g}"
                    speeds = f" (pressures only; given {given} bar)"
                problems.append(
                    f"{int((~inside).sum())} of {inside.size} point(s) outside the validity "
                    f"ranges {val['pressure_min'] / 1e5:.4g}-{val['pressure_max'] / 1e5:.4g} bar"
                    f"{speeds}: the model is extrapolated there"
                )
        if problems:
            message = "; ".join(problems)
            if strict:
                raise ValueError(message)
            warnings.warn(message, ValidityWarning, stacklevel=3)
        return inside

    # ------------------------------------------------------------------ uncertainty
    def _jacobian(self, velocity, pressure):
        """d friction / d coefficient [N/unit] for the covariance names, by central differences."""
        names, matrix = cast("tuple[Sequence[str], np.ndarray]", self.covariance)  # callers check
        base: dict[str, Any] = {n: p.value for n, p in self.parameters.items()}
        columns = []
        for i, name in enumerate(names):
            scale = math.sqrt(matrix[i, i]) if matrix[i, i] > 0 else 0.0
            h = max(1e-4 * scale, 1e-9 * abs(base[name]), 1e-300)
            values = []
            for sign in (1.0, -1.0):
                shifted = dict(base, **{name: base[name] + sign * h})
                # a coefficient on its physical bound (sigma_2 = 0 at one end) is shifted
                # across it here: a difference quotient of the formula, not a model to check
                shifted = self._coefficients_from(shifted)
                values.append(self._friction(velocity, pressure, shifted, checked=False))
            columns.append((values[0] - values[1]) / (2 * h))
        return np.stack(columns, axis=-1)

    def jacobian(
        self, velocity: ArrayLike, pressure: ArrayLike, names: Sequence[str] | None = None
    ) -> np.ndarray:
        """Sensitivity of the steady-state friction to each coefficient, d F / d theta.

        Central differences of :meth:`friction` (no validity check) at (velocity [m/s],
        pressure [Pa]), broadcast; the last axis runs over ``names`` (default: the fitted
        steady-state coefficients, :attr:`varying` without ``sigma_0``, ``sigma_1``).
        Units: N per SI unit of each coefficient (N/N, N/(N/Pa), ...). Test design
        (:mod:`cylfric.plan`) builds its information matrix from it.
        """
        if names is None:
            names = [n for n in self.varying if n.partition(".")[0] in STEADY_PARAMETERS]
        base: dict[str, Any] = {n: p.value for n, p in self.parameters.items()}  # None: refused
        missing = [n for n in names if base.get(n) is None]
        if missing:
            raise ValueError(f"no value for {missing}; coefficients of this model: {self.varying}")
        columns = []
        for name in names:
            # friction is linear in these coefficients: a large step is exact and rounds
            # least; v_r, alpha and an exponential rate take a small relative step
            coefficient = name.partition(".")[2]
            if coefficient in ("intercept", "slope", "curvature", "amplitude"):
                floor = 1e-7 ** {"slope": 1, "curvature": 2}.get(coefficient, 0)  # per Pa
                h = 1e-2 * max(abs(base[name]), floor)
            else:
                h = 1e-6 * max(abs(base[name]), 1e-12)
            values = []
            for sign in (1.0, -1.0):
                shifted = dict(base, **{name: base[name] + sign * h})
                # a coefficient on its physical bound (sigma_2 = 0 at one end) is shifted
                # across it here: a difference quotient of the formula, not a model to check
                shifted = self._coefficients_from(shifted)
                values.append(self._friction(velocity, pressure, shifted, checked=False))
            columns.append((values[0] - values[1]) / (2 * h))
        return np.stack(columns, axis=-1)

    def _coefficients_from(self, values):
        out: dict[str, Any] = {}
        for name in STEADY_PARAMETERS:
            law = self.laws[name]
            if law is None:
                out[name] = None
            elif law == "constant":
                out[name] = values[name]
            else:
                out[name] = {
                    "law": law,
                    **{c: values[f"{name}.{c}"] for c in PRESSURE_LAW_COEFFICIENTS[law]},
                }
        return out

    def _quantile(self, level, dof=None, *, in_sample=False):
        """Student-t quantile of a two-sided ``level`` band (normal without a dof) [-].

        ``in_sample``: the quantile of an internally studentised residual instead,
        ``sqrt(nu B^-1(level; 1/2, (nu - 1)/2))`` (Cook & Weisberg 1982, *Residuals and
        Influence in Regression*, sec. 2.2.1): for data that repeat the fitted data's own
        effects, whose deviations are the residuals the scale was estimated from, not data
        independent of it. Below the Student-t quantile, and the normal one for many dof.
        """
        if not 0 < level < 1:
            raise ValueError(f"level = {level} is out of range; expected 0 < level < 1")
        from scipy.special import betaincinv, stdtrit

        dof = self.statistics.get("dof") if dof is None else dof
        q = 0.5 + level / 2
        if dof is None or np.all(np.asarray(dof) == 0):
            return float(_normal_quantile(q))
        if not in_sample:
            return stdtrit(dof, q)
        nu = np.asarray(dof, dtype=float)
        with np.errstate(invalid="ignore"):
            inside = np.sqrt(nu * betaincinv(0.5, np.maximum(nu - 1.0, 1e-9) / 2.0, level))
        # a million dof or more: the normal quantile (betaincinv loses digits there); one or
        # fewer: no residual scatter to repeat, the Student-t quantile
        inside = np.where(nu >= 1e6, _normal_quantile(q), inside)
        return np.where(nu > 1.0, inside, stdtrit(nu, q))

    def effective_dof(self, velocity: ArrayLike, pressure: ArrayLike) -> np.ndarray:
        """Degrees of freedom [-] of :meth:`standard_error` at (velocity [m/s], pressure [Pa]).

        With the runs' :attr:`influence` (a fitted model), Satterthwaite's effective number
        of runs ``(sum a_g)^2 / sum a_g^2`` with ``a_g`` each run's share of the variance at
        that point, at most the fit's ``dof``: near 1 where one run decides the friction, the
        fit's dof where all runs share it. Without it, the fit's ``dof`` everywhere.
        """
        v, p = np.broadcast_arrays(
            np.asarray(velocity, dtype=float), np.asarray(pressure, dtype=float)
        )
        dof = self.statistics.get("dof")
        if self.influence is None:
            return np.full(v.shape, np.nan if dof is None else float(dof))
        total, squares = _shares(self._jacobian(v, p), self.influence[1])
        with np.errstate(invalid="ignore", divide="ignore"):
            effective = np.where(total > 0, total**2 / squares, np.inf)
        return np.clip(effective, 1.0, np.inf if dof is None else float(dof))

    def standard_error(
        self, velocity: ArrayLike, pressure: ArrayLike, *, robust: bool = True
    ) -> np.ndarray:
        """Standard error [N] of the mean friction at (velocity [m/s], pressure [Pa]).

        First-order propagation of the coefficient covariance: ``sqrt(J C J^T)``, with the
        cluster-robust :attr:`covariance` (default), or with ``robust=False`` the
        model-based :attr:`covariance_nonrobust` where the model carries one (else the
        covariance).
        """
        if self.covariance is None:
            raise ValueError(
                "this model carries no covariance (a literature set or a hand-made model); "
                "uncertainty bands need a fitted model"
            )
        v, p = np.broadcast_arrays(
            np.asarray(velocity, dtype=float), np.asarray(pressure, dtype=float)
        )
        jac = self._jacobian(v, p)
        matrix = self.covariance[1]
        if not robust and self.covariance_nonrobust is not None:
            matrix = self.covariance_nonrobust[1]
        var = np.einsum("...i,ij,...j->...", jac, matrix, jac)
        return np.sqrt(np.clip(var, 0.0, None))

    def band(
        self, velocity: ArrayLike, pressure: ArrayLike, level: float = 0.95, *, strict: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """Confidence band (lower, upper) [N] of the mean friction at ``level``.

        The model's friction plus and minus the Student-t quantile (each point's
        :meth:`effective_dof`) times :meth:`standard_error`. It covers the *true
        steady-state curve*, not individual measurements (see :meth:`prediction_band`).
        Warns with :class:`ValidityWarning` outside the validity ranges, as
        :meth:`friction` does (raises with ``strict=True``).
        """
        self.check(velocity, pressure, strict=strict)
        f = self._friction(velocity, pressure, self.coefficients())
        dof = self.effective_dof(velocity, pressure) if self.influence is not None else None
        half = self._quantile(level, dof) * self.standard_error(velocity, pressure)
        return f - half, f + half

    @property
    def scatter(self) -> dict | None:
        """The ``fit.scatter`` record (repeatability, run, session components; relative), or
        None when the fit made none (docs/uncertainty.md)."""
        value = self.record.get("fit", {}).get("scatter")
        return None if value is None else dict(value)

    @property
    def lack_of_fit(self) -> dict | None:
        """The ``quality.lack_of_fit`` record (test, statistic, p-value, action), or None."""
        value = (self.record.get("quality") or {}).get("lack_of_fit")
        return None if value is None else dict(value)

    def prediction_band(
        self,
        velocity: ArrayLike,
        pressure: ArrayLike,
        level: float = 0.95,
        *,
        scope: str = "point",
        strict: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Band (lower, upper) [N] for a new measurement at ``level``, of the given ``scope``.

        ``scope="point"``: a new point of the fitted runs: the mean's band plus the fit's
        residual standard deviation (``statistics["residual_std"]``). ``"run"``: a new run on
        the same mount: the mean's band plus the repeatability and the run-to-run scatter of
        :attr:`scatter`. ``"session"``: a new session (seal remounted, another day): the
        between-session scatter of a level ``s_L`` (run and session components, the stated
        prior pooled with the estimate) instead of the run part. With F the model friction::

            u_point^2   = se^2 + s(F)^2
            u_run^2     = se^2 + max(s(F)^2, F^2 (s_r^2 + s_run^2))
            u_session^2 = se^2 + max(s(F)^2, F^2 (s_r^2 + s_L^2 + (s_L^2 - s_run^2) / n))

        with ``s_L >= s_run`` and ``n`` the sessions fitted (the fitted curve carries what
        every run of its sessions shared, ``s_L^2 - s_run^2``, over n). The point and run
        bands' quantile is on the residual variance's degrees of freedom (both scales come
        from the same residuals); the session band's, Welch-Satterthwaite's over its terms.
        ``s(F)`` [N] is the residual scatter at the level F (:meth:`residual_scale`:
        ``s_a^2 + (s_b F)^2`` from ``fit.scatter.residual_function``, whose mean over the
        fitted points is ``s_res^2``; ``s_res`` for a datasheet without it). Half-width = a
        quantile x u; the run band is never narrower than the point band, nor the session
        band than the run band. ``se`` is the
        standard error of the mean curve. For "point" and "run", new data of the same
        mount: the model-based ``se`` (``standard_error(robust=False)``, the residuals'
        dof) and the quantile of an internally studentised residual: such data repeat the
        mount's effects, so their deviations from the curve are distributed as the fitted
        residuals the scatter was estimated from (the curve adds its leverage on the
        scatter that is new). For "session": the cluster-robust ``se`` (each point's
        effective dof) and the Student-t quantile: a new mount shares nothing with the fit.
        A fit whose covariance is not clustered by run (no ``influence``: the friction level
        against pressure) has ``se`` at least the runs' share of its curve,
        :func:`level_offset_covariance` with the run component (on its dof).
        A model without ``covariance_nonrobust`` (an older datasheet) keeps the
        cluster-robust ``se`` and the Student-t quantile for every scope. The lack of fit
        is not added: it is already in s_res and s_run (docs/uncertainty.md). A model
        without a scatter record (an older datasheet) raises ValueError for "run" and
        "session" rather than give the point band under their name. Warns outside the
        validity ranges (raises with ``strict=True``).
        """
        if scope not in BAND_SCOPES:
            raise ValueError(f"unknown band scope {scope!r}; valid: {list(BAND_SCOPES)}")
        residual_std = self.statistics.get("residual_std")
        if residual_std is None:
            raise ValueError("this model carries no residual scatter (statistics.residual_std)")
        scatter = self.scatter
        if scope != "point" and scatter is None:
            raise ValueError(
                f"scope {scope!r} needs the scatter components (fit.scatter), which this model "
                "does not carry (a datasheet of an older cylfric, or a hand-made model): refit "
                "the campaign, or use scope='point' (a new point of the same runs only)"
            )
        self.check(velocity, pressure, strict=strict)
        f = self._friction(velocity, pressure, self.coefficients())
        same_mount = scope != "session" and self.covariance_nonrobust is not None
        n_dof = self._residual_dof(nested=same_mount)
        se = self.standard_error(velocity, pressure, robust=not same_mount)
        scatter_sd = self._residual_scale(f, residual_std)
        if scope == "point":
            dof = None
            if same_mount:  # s^2 (1 + h): one variance estimate, the residuals' dof
                dof = np.full(np.shape(se), float(n_dof))
            elif self.influence is not None:  # Welch-Satterthwaite: the mean's and the scatter's
                mean_dof = self.effective_dof(velocity, pressure)
                with np.errstate(invalid="ignore", divide="ignore"):
                    dof = (se**2 + scatter_sd**2) ** 2 / (se**4 / mean_dof + scatter_sd**4 / n_dof)
            quantile = self._quantile(level, dof, in_sample=same_mount)
            half = quantile * np.sqrt(se**2 + scatter_sd**2)
            return f - half, f + half
        assert scatter is not None  # refused above for these scopes
        part = _band_parts(scatter, scope)
        force2 = np.asarray(f, dtype=float) ** 2
        use = force2 * (part["repeat"] ** 2 + part["between"] ** 2) >= scatter_sd**2
        terms = [
            (
                np.where(use, force2 * part["repeat"] ** 2, scatter_sd**2),
                np.where(use, part["repeat_dof"], n_dof),
            ),
            (
                np.where(use, force2 * part["between"] ** 2, 0.0),
                np.where(use, part["between_dof"], np.inf),
            ),
        ]
        runs_dof: np.ndarray | None = None
        if scope == "session" and self.influence is None:
            # a covariance without the runs as clusters treats the points as independent:
            # the fitted curve's share of the runs' offsets is then not in se (each level's
            # runs average them, s_run^2 / runs, spread over the law)
            runs_se = _level_offset_se(self, velocity, pressure, run=part["run"])
            if runs_se is not None:
                runs_dof = np.where(runs_se > se, part["run_dof"], np.nan)
                se = np.maximum(se, runs_se)
        variance = se**2 + sum(t for t, _ in terms)
        if same_mount:  # one scale, the residuals': their dof (the point band's)
            dof = np.full(np.shape(variance), float(n_dof))
        else:
            fit_dof = self.statistics.get("dof")
            band_dof = np.asarray(
                self.effective_dof(velocity, pressure)
                if self.influence is not None
                else (np.inf if fit_dof is None else fit_dof),
                dtype=float,
            )
            if runs_dof is not None:
                band_dof = np.where(np.isfinite(runs_dof), runs_dof, band_dof)
            with np.errstate(invalid="ignore", divide="ignore"):  # Welch-Satterthwaite
                denominator = se**4 / band_dof + sum(t**2 / d for t, d in terms)
                dof = np.where(denominator > 0, variance**2 / denominator, 1e9)
        half = self._quantile(level, np.minimum(dof, 1e9), in_sample=same_mount)
        half = half * np.sqrt(variance)
        if same_mount:  # the point band's se, quantile and s(F)^2 under the max: never wider
            return f - half, f + half
        # a new run is never predicted better than a new point, a new session than a new run
        narrower = "run" if scope == "session" else "point"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # checked above
            low, high = self.prediction_band(velocity, pressure, level, scope=narrower)
        half = np.maximum(half, 0.5 * (high - low))
        return f - half, f + half

    def residual_scale(self, velocity: ArrayLike, pressure: ArrayLike) -> np.ndarray:
        """Residual scatter ``s(F)`` [N] of the fit at speed ``velocity`` [m/s] and chamber
        pressure ``pressure`` [Pa]: ``sqrt(s_a^2 + (s_b F)^2)``, F the model friction [N].

        ``s_a`` [N] and ``s_b`` [-] are ``fit.scatter.residual_function`` (the two-component
        variance function of the residuals, :func:`cylfric.identify.scatter.residual_function`;
        its mean over the fitted points is ``statistics["residual_std"]^2``): the scatter a
        new point of the fitted runs has at that level, which the point band uses. A model
        without the record (an older datasheet) gives ``statistics["residual_std"]`` at every
        level. Raises ValueError for a model without a residual scatter.
        """
        residual_std = self.statistics.get("residual_std")
        if residual_std is None:
            raise ValueError("this model carries no residual scatter (statistics.residual_std)")
        f = self._friction(velocity, pressure, self.coefficients())
        return self._residual_scale(f, residual_std)

    def _residual_scale(self, force: np.ndarray, residual_std: float) -> np.ndarray:
        """:meth:`residual_scale` [N] at the model friction ``force`` [N]."""
        shape = (self.scatter or {}).get("residual_function") or {}
        a, b = shape.get("absolute_std_N"), shape.get("relative_std_percent")
        if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
            return np.full(np.shape(force), float(residual_std))
        return np.sqrt(a**2 + (b / 100.0 * np.asarray(force, dtype=float)) ** 2)

    def _residual_dof(self, *, nested: bool = True) -> float:
        """Degrees of freedom [-] of the residual variance ``statistics["residual_std"]^2``.

        ``nested`` (the bands of new data of the same mount, whose deviations repeat the
        fitted residuals): the Satterthwaite degrees of freedom of the campaign's nested
        strata where the fit recorded them (``fit.scatter.residual_variance.dof``:
        :func:`cylfric.identify.scatter.residual_strata`; runs that share a pressure block
        share its offset, so their residuals are fewer independent values than points), the
        shape of the internally studentised residual's distribution. Else, and without the
        record, ``n_points - n_variables``; at least 1.
        """
        plain = self.statistics.get("n_points", 0) - self.statistics.get("n_variables", 0)
        strata = (self.scatter or {}).get("residual_variance") or {}
        nu = strata.get("dof") if nested else None
        if nu is not None and math.isfinite(nu) and nu > 0:
            return float(max(min(nu, plain), 1.0))
        return float(max(plain, 1))

    def correlations(self) -> tuple[tuple[str, ...], np.ndarray] | None:
        """(names, matrix) of the correlation coefficients of the fitted coefficients."""
        if self.covariance is None:
            return None
        names, cov = self.covariance
        sd = np.sqrt(np.clip(np.diag(cov), 0, None))
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov / np.outer(sd, sd)
        corr[~np.isfinite(corr)] = 0.0
        np.fill_diagonal(corr, 1.0)
        return names, corr

    # ------------------------------------------------------------------ reports
    def fit_report(self, *, min_correlation: float = 0.1) -> str:
        """A text report like lmfit's ``fit_report``, in engineering units (N, bar, mm/s)."""
        from .text import fit_report

        return fit_report(self, min_correlation=min_correlation)

    def law_lines(self) -> list[str]:
        """The pressure laws as text with standard errors, e.g. ``F_c(p) = 70.2 ± 0.1 N + ...``."""
        from .text import law_lines

        return law_lines(self)

    def to_pandas(self) -> pd.DataFrame:
        """The coefficients as a DataFrame: SI and engineering values, units, standard errors,
        pressure law, held or fitted (:func:`cylfric.model.text.parameter_table`)."""
        from .text import parameter_table

        return parameter_table(self)

    def _repr_html_(self) -> str:
        """The parameter table with units and standard errors, for Jupyter."""
        from .text import html_summary

        return html_summary(self)

    def plot(
        self,
        pressures: Sequence[float] | None = None,
        *,
        velocities: Sequence[float] | None = None,
        level: float = 0.95,
        ax: Axes | None = None,
    ) -> Figure:
        """Friction against speed at a few pressures with the band of the mean (if any).

        Delegates to :func:`cylfric.report.figures.figure_model` (the report's style).

        Parameters
        ----------
        pressures : sequence of float, optional
            Operating pressures [Pa]; default three over the validity range (else 0-100 bar).
        velocities : sequence of float, optional
            Speeds [m/s] of the curve; default 120 on a log grid over the validity range.
        level : float
            Confidence level of the band of the mean [-].
        ax : matplotlib Axes, optional
            Draw into these axes instead of a new figure.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from ..report.figures import figure_model  # the plotting module; it imports no model

        return figure_model(self, pressures, velocities=velocities, level=level, ax=ax)

    # ------------------------------------------------------------------ datasheet
    def to_datasheet(self) -> dict:
        """The datasheet dict (SI, JSON-ready) of this model and its :attr:`record`."""
        from .serialize import to_datasheet

        return to_datasheet(self)

    @classmethod
    def from_datasheet(cls, source: StrPath | Mapping[str, Any]) -> FrictionModel:
        """The model of a datasheet (a path to a JSON file, or the dict); validated."""
        from .serialize import from_datasheet

        return from_datasheet(cls, source)


BAND_SCOPES = ("point", "run", "session")
"""Scopes of :meth:`FrictionModel.prediction_band` (docs/uncertainty.md)."""


def _band_parts(scatter: Mapping, scope: str) -> dict[str, float]:
    """Relative standard deviations [-] and their dof of a band's scatter terms."""
    c = scatter["components"]
    repeat = c["repeatability"]["std_percent"] / 100.0
    run = c["run"]["std_percent"] / 100.0
    session = c["session"]
    if scope == "run":  # the run component's own degrees of freedom
        between, between_dof = run, float(c["run"].get("dof") or np.inf)
    else:
        between_dof = float(session.get("dof") or np.inf)
        between = session.get("between_percent")
        between = (
            math.hypot(run, session["std_percent"] / 100.0) if between is None else between / 100
        )
        between = max(between, run)
        # the fitted curve is the mean of the fitted sessions, itself off the sessions'
        # population by what every run of a session shares, s_session^2 = s_L^2 - s_run^2,
        # over n sessions (the run-to-run part averages out over the runs and stays in the
        # residuals): a new session differs from it by s_L^2 + s_session^2 / n
        sessions = max(int(scatter.get("sessions") or 1), 1)
        between = math.sqrt(between**2 + max(between**2 - run**2, 0.0) / sessions)
    return {
        "repeat": repeat,
        "repeat_dof": float(c["repeatability"].get("dof") or np.inf),
        "between": between,
        "between_dof": between_dof,
        "run": run,
        "run_dof": float(c["run"].get("dof") or np.inf),
    }


def level_offset_covariance(
    model: FrictionModel, *, run: float, session: float, sessions: int = 1
) -> np.ndarray | None:
    """Covariance of the fitted coefficients [covariance names] from relative offsets of the
    fitted pressure levels: each run's ``run`` [-] (s.d.; a level's runs average theirs) and
    each session's ``session`` [-] (shared by every level; ``sessions`` of them averaged).

    The datasheet's levels (``fit.scatter.levels``: each level's pressure and number of
    runs) at speeds over the validity range are the design; an offset ``b_i`` of level i
    scales the friction there, ``F(v, p_i) (1 + b_i)``, and the law's least-squares map
    ``G = J^+`` (J the jacobian in the coefficients at the design) carries it to the
    coefficients: ``G D Sigma_b D^T G^T``, ``D`` the design's friction on its level,
    ``Sigma_b = diag(run^2 / runs_i) + session^2 / sessions``. None without the levels or a
    covariance (an older datasheet, a hand-made model).
    """
    levels = (model.scatter or {}).get("levels") or {}
    if model.covariance is None or not levels.get("pressure_Pa"):
        return None
    pressures = np.asarray(levels["pressure_Pa"], dtype=float)
    runs = np.maximum(np.asarray(levels.get("runs") or [1] * pressures.size, dtype=float), 1.0)
    validity = model.validity
    if validity and validity.get("velocity_max", 0) > 0:
        low = max(float(validity.get("velocity_min") or 0.0), 1e-6)
        high = max(float(validity["velocity_max"]), low)
        speeds = np.geomspace(low, high, 5) if high > low else np.array([high])
    else:
        speeds = np.array([0.01])
    v, p = (a.ravel() for a in np.meshgrid(speeds, pressures, indexing="xy"))
    level = np.repeat(np.arange(pressures.size), speeds.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        jac = model._jacobian(v, p)
        force = np.abs(model._friction(v, p, model.coefficients(), checked=False))
    spread = np.zeros((v.size, pressures.size))
    spread[np.arange(v.size), level] = force
    sigma = np.diag(run**2 / runs) + session**2 / max(int(sessions), 1)
    mapped = np.linalg.pinv(jac) @ spread
    return mapped @ sigma @ mapped.T


def _level_offset_se(model, velocity, pressure, *, run: float) -> np.ndarray | None:
    """Standard error [N] of the fitted curve from its runs' relative offsets (s.d. ``run``
    [-]), :func:`level_offset_covariance` propagated to (velocity [m/s], pressure [Pa])."""
    covariance = level_offset_covariance(model, run=run, session=0.0)
    if covariance is None:
        return None
    v, p = np.broadcast_arrays(np.asarray(velocity, dtype=float), np.asarray(pressure, dtype=float))
    jac = model._jacobian(np.abs(v), p)
    return np.sqrt(np.clip(np.einsum("...i,ij,...j->...", jac, covariance, jac), 0.0, None))


def _normal_quantile(q):
    from statistics import NormalDist

    return NormalDist().inv_cdf(q)


def _frozen(matrix) -> bool:
    """Whether ``matrix`` is a read-only float array owning its data (a model's own, which
    another model may share instead of copying)."""
    return (
        isinstance(matrix, np.ndarray)
        and matrix.dtype == np.float64
        and not matrix.flags.writeable
        and matrix.base is None
    )
