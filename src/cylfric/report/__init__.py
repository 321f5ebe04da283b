"""Figures and the HTML report of an identification (a leaf: nothing of cylfric imports it)."""

from .figures import FigureRenderer, all_figures, render_all, save_figure, save_rendered
from .html import law_lines, render_report, write_report

__all__ = [
    "FigureRenderer",
    "all_figures",
    "render_all",
    "save_rendered",
    "save_figure",
    "render_report",
    "write_report",
    "law_lines",
]
