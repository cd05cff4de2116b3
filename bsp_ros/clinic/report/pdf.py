"""The report as a PDF for the patient file (matplotlib PdfPages): summary, arm weight, plots, quality."""

from __future__ import annotations

import datetime as dt
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure

from bsp_ros import __version__
from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.report.plots import trend_figure
from bsp_ros.clinic.report.summary import (
    day,
    headline,
    joint_summaries,
    segment_summaries,
    session_marks,
    session_notes,
    support_table,
)
from bsp_ros.errors import InputError

_A4_IN = (8.27, 11.69)
_WIDTH_CHARS = 95
_LINE = 0.0155  # line height, fraction of the page


class _TextPages:
    """Flow headed, wrapped paragraphs onto A4 pages."""

    def __init__(self, pdf: PdfPages) -> None:
        self._pdf = pdf
        self._figure: Figure | None = None
        self._y = 0.0

    def _page(self) -> Figure:
        if self._figure is None or self._y < 0.06:
            self.flush()
            self._figure = Figure(figsize=_A4_IN)
            self._y = 0.95
        return self._figure

    def line(self, text: str, *, size: float = 9.0, weight: str = "normal", colour: str = "#222222") -> None:
        figure = self._page()
        figure.text(0.07, self._y, text, fontsize=size, weight=weight, color=colour, va="top", family="DejaVu Sans")
        self._y -= _LINE * size / 9.0

    def paragraph(self, text: str, *, colour: str = "#222222", indent: str = "") -> None:
        for row in textwrap.wrap(text, _WIDTH_CHARS, initial_indent=indent, subsequent_indent=indent) or [""]:
            self.line(row, colour=colour)
        self._y -= _LINE * 0.4

    def heading(self, text: str, size: float = 12.0) -> None:
        if self._figure is not None and self._y < 0.15:
            self._y = 0.0  # a heading does not start at the bottom of a page
        self._y -= _LINE * 0.5
        self.line(text, size=size, weight="bold", colour="#1f5fa6")
        self._y -= _LINE * 0.3

    def flush(self) -> None:
        if self._figure is not None:
            self._pdf.savefig(self._figure)
            self._figure = None


def write_report_pdf(analysis: Analysis, path: Path) -> Path:
    """Write the PDF report of ``analysis`` to ``path``; return the path.

    Raises
    ------
    InputError
        If the file cannot be written.
    """
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with PdfPages(path) as pdf:
            text = _TextPages(pdf)
            text.heading(f"Arm parameters of subject {analysis.subject}", 15.0)
            text.heading("Summary")
            text.paragraph(headline(analysis))
            for joint in joint_summaries(analysis):
                text.line(joint.title, weight="bold")
                for sentence in joint.sentences:
                    text.paragraph(sentence, indent="  ")
                for change in joint.flagged:
                    text.paragraph(f"CHANGED: {'.'.join(change.key)}", colour="#c62828", indent="  ")
            notes = session_notes(analysis)
            if notes:
                text.line("Marked sessions (kept in every plot and table):", weight="bold")
                for note in notes:
                    text.paragraph(note, colour="#b71c1c", indent="  ")
            text.heading("Arm weight (static moments) and weight support")
            for segment in segment_summaries(analysis):
                text.paragraph(f"{segment.title}: {segment.sentences[0]}")
            rows, note = support_table(analysis)
            for row in rows:
                (fy, fz, mx), (sy, sz, sm) = row.wrench_yzx, row.std_yzx
                text.paragraph(
                    f"Support {row.fraction:.0%}: F_y {fy:.2f} ± {sy:.2f} N, F_z {fz:.2f} ± {sz:.2f} N, "
                    f"M_x {mx:.2f} ± {sm:.2f} N·m",
                    indent="  ",
                )
            text.paragraph(note, colour="#555555")
            text.flush()
            for series in analysis.series:
                if series.has_values:
                    pdf.savefig(trend_figure(series))
            text.heading("Session quality")
            for record in analysis.sessions:
                marks = ", ".join(session_marks(record)) or "valid, tare applied, no warnings"
                text.paragraph(
                    f"Session {record.id} ({day(record.session_time_ns)}, {record.source}): {marks}. "
                    + " ".join(f"Warning: {w}" for w in record.quality.warnings),
                    indent="  ",
                )
            text.heading("Minimal detectable change: method")
            for method in analysis.methods or ["No session carries a repeatability measurement: no change claimed."]:
                text.paragraph(method)
            text.paragraph(analysis.prior_note, colour="#555555")
            generated = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
            text.paragraph(f"Generated {generated} by bsp_ros {__version__}.", colour="#555555")
            text.flush()
            info = pdf.infodict()
            info["Title"] = f"Arm parameters of subject {analysis.subject}"
            info["Creator"] = f"bsp_ros {__version__}"
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return path
