"""The friction model object shared by every part of cylfric (identify, datasheet, simulate,
report, exports).

:class:`FrictionModel` holds the steady-state law with a pressure law per parameter, the
LuGre bristle parameters with their status, the operating-pressure rule, validity ranges,
covariance and provenance; :class:`Parameter` is one of its coefficients. The datasheet
(JSON) is its serialised form: :meth:`FrictionModel.to_datasheet` and
:meth:`FrictionModel.from_datasheet`, validated against :data:`SCHEMA`.
Imports only :mod:`cylfric.friction` (and jsonschema for validation).
"""

from .core import (
    DYNAMIC_PARAMETERS,
    DYNAMIC_STATUS,
    FRICTION_LAWS,
    PARAMETER_BOUNDS,
    PARAMETER_UNITS,
    STEADY_PARAMETERS,
    FrictionModel,
    Parameter,
    ValidityWarning,
    engineering_unit,
)
from .serialize import SCHEMA, SCHEMA_ID, DatasheetError, read_datasheet, validate

__all__ = [
    "FrictionModel",
    "Parameter",
    "ValidityWarning",
    "DatasheetError",
    "SCHEMA",
    "SCHEMA_ID",
    "read_datasheet",
    "validate",
    "engineering_unit",
    "STEADY_PARAMETERS",
    "DYNAMIC_PARAMETERS",
    "DYNAMIC_STATUS",
    "FRICTION_LAWS",
    "PARAMETER_UNITS",
    "PARAMETER_BOUNDS",
]
