"""Figures and the self-contained HTML report."""

from anklelab.report.html import Figure, Section, Table, figure_png, render_html, write_report

__all__ = ["Figure", "Section", "Table", "figure_png", "render_html", "write_report"]
