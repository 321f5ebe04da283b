"""A catalogue of seal friction datasheets: store, compare, select, predict other sizes.

:class:`Catalog` keeps datasheets with their seal metadata in an SQLite file
(:mod:`.store`); :mod:`.compare` draws and tabulates entries side by side with their bands;
:mod:`.scaling` predicts a seal's friction on another cylinder size by seal contact length
(the thesis' proposal of scale factors by sliding surface, ch. 5).
"""

from .scaling import RULE_RELATIVE_STDERR, contact_ratio, predict_datasheet, scale_model
from .store import SCHEMA_VERSION, Catalog, CatalogError, default_path

__all__ = [
    "Catalog",
    "CatalogError",
    "default_path",
    "SCHEMA_VERSION",
    "predict_datasheet",
    "contact_ratio",
    "scale_model",
    "RULE_RELATIVE_STDERR",
]
