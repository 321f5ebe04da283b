"""Figures and the HTML report of an identification. It draws only: it imports the model,
friction laws and writers, never :mod:`cylfric.identify`, and fits nothing. Imported by
:mod:`cylfric.pipeline` and :mod:`cylfric.cli` only."""

from .figures import all_figures, render_all, save_figure, save_rendered
from .html import render_report, write_report, write_report_folder

__all__ = [
    "all_figures",
    "render_all",
    "save_rendered",
    "save_figure",
    "render_report",
    "write_report",
    "write_report_folder",
]
