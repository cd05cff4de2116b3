"""Therapist-facing reports of a subject's sessions: one self-contained HTML page, a PDF, PNG plots, CSV."""

from bsp_ros.clinic.report.analysis import Analysis, Change, Point, Series, analyse, is_judged
from bsp_ros.clinic.report.labels import label, plain_name, plain_number, unit
from bsp_ros.clinic.report.priors import Prior, session_prior
from bsp_ros.clinic.report.writers import render_report, write_csv, write_html, write_pdf, write_pngs

__all__ = [
    "Analysis",
    "Change",
    "Point",
    "Prior",
    "Series",
    "analyse",
    "is_judged",
    "label",
    "plain_name",
    "plain_number",
    "render_report",
    "session_prior",
    "unit",
    "write_csv",
    "write_html",
    "write_pdf",
    "write_pngs",
]
