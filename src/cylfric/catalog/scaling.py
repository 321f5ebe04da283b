"""Predict a seal's friction on another cylinder size: scaling by seal contact length.

The thesis' proposal (Pérez Dorado 2016, ch. 5): manufacturers publish ``F_c(p)``,
``F_s(p)``, ``sigma_2(p)``, ``alpha`` and ``v_s`` of each seal model from a standard test,
"and the size and other features of the cylinder may be easily considered by introducing
scale factors in order to compensate the increase of sliding surface".

The rule chosen here. A seal of a given profile (same cross-section, material, fit and
pressure) presses on its counter-surface with the same force per unit of contact length,
so its friction forces grow with the length of the contact line, the circumference
``pi D`` of the surface it slides on; the width of the contact band is a property of the
profile and does not change with the diameter. Hence the sliding surface grows as the
diameter and

    k = L_new / L_tested,   L = pi * D_bore               (piston seal, ``contact="piston"``)
                            L = pi * d_rod                (rod seal, ``contact="rod"``)
                            L = pi * (D_bore + n d_rod)   (``contact="total"``: one piston
                                                           seal and ``n`` rod seals with the
                                                           same friction per unit length)

Forces scale by ``k``: every coefficient of ``F_c(p)``, ``F_s(p)`` and of ``sigma_2(p)``
(a force per speed) except the rate of an exponential law, which is per pressure. The shape
parameters ``v_r`` and ``alpha`` are unchanged (the lubrication regime depends on speed,
not size), and so are ``sigma_0``, ``sigma_1`` (assumed values in most datasheets).

Its uncertainty. The rule is an engineering approximation: real seal families change
profile and squeeze with the diameter. Its error is modelled as one common factor
``(1 + e)``, ``e ~ N(0, r^2)`` on all scaled forces, with ``r`` the rule's relative
standard error (default :data:`RULE_RELATIVE_STDERR` = 10 %, an assumption, not a
measurement: set it from your own campaigns at two sizes). Then the covariance of the
scaled coefficients ``x' = k x`` is ``k^2 C + r^2 x' x'^T``: the fitted uncertainty
scaled, plus a rank-one term that moves every force together. The prediction's band
(``FrictionModel.band``) carries both.
"""

from __future__ import annotations

import json
import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

if TYPE_CHECKING:
    from ..model import FrictionModel

__all__ = ["predict_datasheet", "contact_ratio", "scale_model", "RULE_RELATIVE_STDERR"]

RULE_RELATIVE_STDERR = 0.10
"""Default relative standard error of the contact-length rule [-] (an assumption)."""

MAX_RATIO = 4.0
"""Largest contact-length ratio (or its inverse) the rule is used for [-]."""

CONTACTS = ("piston", "rod", "total")
_SCALED = ("F_c", "F_s", "sigma_2")


def contact_ratio(
    source_bore: float | None,
    bore: float | None,
    *,
    source_rod: float | None = None,
    rod: float | None = None,
    contact: Literal["piston", "rod", "total"] = "piston",
    rod_seals: int = 1,
) -> tuple[float, str]:
    """Contact-length ratio ``k`` [-] and the rule as text.

    Parameters
    ----------
    source_bore, bore : float or None
        Bore of the tested and of the target cylinder [m].
    source_rod, rod : float, optional
        Rod diameters of the tested and of the target cylinder [m].
    contact : {"piston", "rod", "total"}
        Which seals carry the catalogued friction (see the module docstring).
    rod_seals : int
        Number of rod seals for ``contact="total"`` (2 for a double-rod cylinder).
    """
    if contact not in CONTACTS:
        raise ValueError(f"contact = {contact!r}: unknown; valid: {list(CONTACTS)}")
    given = {"bore": (source_bore, bore), "rod": (source_rod, rod)}
    for what in _NEEDS[contact]:
        _check_diameters(what, *given[what], contact)
    if contact == "piston":
        assert bore is not None and source_bore is not None  # checked above
        ratio = bore / source_bore
        text = f"piston seal: L = pi D, k = {bore * 1e3:g} mm / {source_bore * 1e3:g} mm"
    elif contact == "rod":
        assert rod is not None and source_rod is not None  # checked above
        ratio = rod / source_rod
        text = f"rod seal: L = pi d, k = {rod * 1e3:g} mm / {source_rod * 1e3:g} mm"
    else:
        if not (isinstance(rod_seals, int) and rod_seals >= 1):
            raise ValueError(f"rod_seals = {rod_seals!r}: expected a whole number >= 1")
        assert bore is not None and source_bore is not None  # checked above
        assert rod is not None and source_rod is not None
        new = bore + rod_seals * rod
        old = source_bore + rod_seals * source_rod
        ratio = new / old
        text = (
            f"piston and {rod_seals} rod seal(s): L = pi (D + {rod_seals} d), "
            f"k = ({bore * 1e3:g} + {rod_seals} x {rod * 1e3:g}) mm / "
            f"({source_bore * 1e3:g} + {rod_seals} x {source_rod * 1e3:g}) mm"
        )
    if not 1 / MAX_RATIO <= ratio <= MAX_RATIO:
        raise ValueError(
            f"contact-length ratio {ratio:.3g}: beyond {1 / MAX_RATIO:g}-{MAX_RATIO:g}, "
            "further than the contact-length rule can be trusted; test the seal at a nearer size"
        )
    return ratio, f"{text} = {ratio:.4g}"


_NEEDS = {"piston": ("bore",), "rod": ("rod",), "total": ("bore", "rod")}
"""The diameters each contact's rule needs."""


def _check_diameters(what: str, tested: float | None, target: float | None, contact: str):
    """Refuse a missing tested or target ``what`` diameter, or one outside 0 < d <= 2 m."""
    if tested is None:
        raise ValueError(
            f"the catalogue entry does not record the tested {what} diameter; "
            f"add it (catalog add --{what}) to scale a {contact} seal"
        )
    if target is None:
        raise ValueError(f"a {contact} seal needs the target {what} diameter [m] (--{what})")
    for value in (tested, target):
        if not (math.isfinite(value) and 0 < value <= 2.0):
            raise ValueError(f"{what} = {value} m: expected a diameter in m, 0 < d <= 2 m")


def _scales(name) -> bool:
    """Whether a coefficient is a force (or force per speed) that the rule scales."""
    parameter, _, coefficient = name.partition(".")
    return parameter in _SCALED and coefficient != "rate"


def _factor(name, ratio):
    return ratio if _scales(name) else 1.0


def _scaled_covariance(
    model: FrictionModel, ratio: float, rule_stderr: float
) -> tuple[list[str], np.ndarray]:
    """(names, covariance) of the scaled coefficients: ``k^2 C`` over the fitted ones plus
    ``r^2 x' x'^T`` over every scaled one (no rule term for ``k = 1``) [SI units squared]."""
    values = {n: p.value for n, p in model.parameters.items() if p.value is not None}
    scaled = {n: v * _factor(n, ratio) for n, v in values.items()}
    names = list(model.covariance[0]) if model.covariance is not None else []
    names += [n for n in scaled if _scales(n) and n not in names]
    index = {n: i for i, n in enumerate(names)}
    cov = np.zeros((len(names), len(names)))
    if model.covariance is not None:
        old_names, old = model.covariance
        k = np.array([_factor(n, ratio) for n in old_names])
        idx = [index[n] for n in old_names]
        cov[np.ix_(idx, idx)] = old * np.outer(k, k)
    if ratio != 1.0:  # the tested size itself needs no rule
        x = np.array([scaled[n] if _scales(n) else 0.0 for n in names])
        cov += rule_stderr**2 * np.outer(x, x)
    return names, cov


def scale_model(
    model: FrictionModel, ratio: float, rule_stderr: float = RULE_RELATIVE_STDERR
) -> FrictionModel:
    """``model`` with its forces scaled by ``ratio`` and the rule's uncertainty added.

    Parameters
    ----------
    model : FrictionModel
    ratio : float
        Contact-length ratio ``k`` [-].
    rule_stderr : float
        Relative standard error ``r`` of the rule [-].

    Returns
    -------
    FrictionModel
        Coefficients ``k x`` (forces), covariance ``k^2 C + r^2 x' x'^T`` over the fitted
        coefficients and every scaled coefficient (no rule term for ``k = 1``, the tested
        size), standard errors from its diagonal, and
        the residual scatter and RMSE scaled by ``k`` (``fit.scatter.residual_function``'s
        absolute part too: the point band of the scaled model is k times the tested one's).
    """
    if not (math.isfinite(rule_stderr) and 0 <= rule_stderr < 1):
        raise ValueError(f"rule_stderr = {rule_stderr}: expected a fraction 0 <= r < 1")
    names, cov = _scaled_covariance(model, ratio, rule_stderr)
    index = {n: i for i, n in enumerate(names)}

    coefficients = model.coefficients(include_dynamic=False)
    stderr = model.stderr()
    for name in _SCALED:
        spec = coefficients.get(name)
        if spec is None:
            continue
        law = model.laws[name]
        coefficient_names = [c for c in spec if c != "law"]
        new_spec, new_err = dict(spec), {}
        for c in coefficient_names:
            key = name if law == "constant" else f"{name}.{c}"
            new_spec[c] = spec[c] * _factor(key, ratio)
            new_err[c] = math.sqrt(cov[index[key], index[key]]) if key in index else None
        coefficients[name] = new_spec
        stderr[name] = new_err
    for name in ("v_r", "alpha"):
        if name in index:
            stderr[name] = math.sqrt(cov[index[name], index[name]])
    statistics = dict(model.statistics)
    for key in ("rmse", "residual_std"):
        if statistics.get(key) is not None:
            statistics[key] = statistics[key] * ratio
    changes: dict[str, Any] = {}
    shape = (model.scatter or {}).get("residual_function")
    if shape and shape.get("absolute_std_N") is not None:  # [N]: scales; the relative part not
        fit = dict(model.record["fit"])
        fit["scatter"] = {
            **fit["scatter"],
            "residual_function": {**shape, "absolute_std_N": shape["absolute_std_N"] * ratio},
        }
        changes["record"] = {**model.record, "fit": fit}
    return model.replace(
        coefficients=coefficients,
        stderr={k: v for k, v in stderr.items() if v is not None},
        covariance=(names, cov),
        statistics=statistics,
        **changes,
    )


def predict_datasheet(
    sheet: dict,
    *,
    source_name: str,
    source_bore: float | None,
    bore: float | None,
    source_rod: float | None = None,
    rod: float | None = None,
    contact: Literal["piston", "rod", "total"] | None = None,
    rod_seals: int = 1,
    rule_stderr: float = RULE_RELATIVE_STDERR,
) -> dict:
    """A validated datasheet for the same seal on a cylinder of another size.

    Parameters
    ----------
    sheet : dict
        Datasheet of the tested cylinder.
    source_name : str
        Its catalogue name (recorded in the provenance).
    source_bore, source_rod : float or None
        Tested bore and rod diameters [m].
    bore, rod : float or None
        Target bore and rod diameters [m].
    contact : {"piston", "rod", "total"}, optional
        Which seals carry the friction; default ``"piston"`` without ``rod``, ``"total"``
        with it.
    rod_seals : int
        Rod seals counted by ``contact="total"``.
    rule_stderr : float
        Relative standard error of the rule [-], added to the covariance.

    Returns
    -------
    dict
        The predicted datasheet: scaled model, ``prediction`` (rule, ratio, uncertainty,
        source), ``fit.method`` naming the prediction, the tested cylinder's per-pressure
        table and offset left out (they are measurements of another cylinder).
    """
    from ..datasheet import validate
    from ..model import FrictionModel

    if contact is None:
        contact = "piston" if rod is None else "total"
    ratio, rule = contact_ratio(
        source_bore, bore, source_rod=source_rod, rod=rod, contact=contact, rod_seals=rod_seals
    )
    model = FrictionModel.from_datasheet(sheet)
    scaled = scale_model(model, ratio, rule_stderr)
    record = dict(scaled.record)
    record.pop("fit", None)  # law comparison and sensitivity belong to the tested cylinder
    record["per_pressure"] = []
    record["offset"] = None
    record.pop("offset_std", None)
    sizes = [(what, d) for what, d in (("bore", bore), ("rod", rod)) if d is not None]
    target = ", ".join(f"{what} {d * 1e3:g} mm" for what, d in sizes)
    record["name"] = f"{source_name} scaled to {target}"
    prediction = {
        "from": source_name,
        "rule": f"seal contact length ({rule})",
        "contact": contact,
        "ratio": ratio,
        "rule_relative_stderr": rule_stderr,
        "source_bore": source_bore,
        "source_rod": source_rod,
        "bore": bore,
        "rod": rod,
        "scaled": "F_c, F_s, sigma_2 coefficients (and rmse, residual_std) times the ratio; "
        "v_r, alpha, sigma_0, sigma_1 unchanged",
        "uncertainty": "covariance = ratio^2 x fitted covariance + rule_relative_stderr^2 "
        "x (scaled force coefficients) outer product (one common scale error)",
    }
    record["prediction"] = prediction
    record["notes"] = list(record.get("notes") or []) + [
        f"predicted from catalogue entry {source_name!r}: {prediction['rule']}; "
        f"the rule's own relative standard error {rule_stderr:.0%} (an assumption) is "
        "included in the covariance and bands; not measured on this cylinder"
    ]
    provenance = dict(scaled.provenance)
    provenance["method"] = (
        f"predicted by seal contact length from {source_name!r} ({rule}); "
        f"tested model: {model.provenance.get('method', 'given')}"
    )
    out = scaled.replace(record=record, provenance=provenance).to_datasheet()
    out = json.loads(json.dumps(out))
    return validate(out, source=f"prediction from {source_name!r}")
