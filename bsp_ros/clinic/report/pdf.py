"""The report as an A4 PDF for the patient file: a first page that stands alone, the detail after it."""

from __future__ import annotations

import datetime as dt
import textwrap
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from bsp_ros import __version__
from bsp_ros.clinic.mdc import READING_GUIDE, RETEST_METHOD
from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.report.curve_plots import curve_panels, draw_curves
from bsp_ros.clinic.report.curve_views import CURVES_CAPTION, CURVES_TITLE
from bsp_ros.clinic.report.detail import (
    APPENDIX_NOTE,
    PEERS_NOTE,
    PROTOCOL,
    DetailRow,
    detail_rows,
    peer_cells,
    peer_rows,
)
from bsp_ros.clinic.report.labels import plain_name, plain_number, unit
from bsp_ros.clinic.report.norm_rows import NORMS_NOTE, NORMS_TITLE, norm_rows, sources_text, without_text
from bsp_ros.clinic.report.panels import appendix_groups, arm_names, detail_groups, first_page_panels
from bsp_ros.clinic.report.plots import Panel, draw_panels
from bsp_ros.clinic.report.precision import BUDGET_NOTE, BUDGET_TITLE, PRECISION_NOTE, PRECISION_TITLE, precision_rows
from bsp_ros.clinic.report.summary import (
    arm_title,
    day,
    error_source,
    first_page_rows,
    flag_rule,
    headline_parts,
    period_line,
    session_notes,
    session_rows,
    subject_line,
    support_table,
    tare_note,
    tare_sentences,
    technical_notes,
)
from bsp_ros.errors import InputError

A4_IN = (8.27, 11.69)
LEFT, RIGHT, TOP, BOTTOM = 0.07, 0.93, 0.955, 0.06
LINE = 0.0145  # height of a 9 pt line, fraction of the page
BLUE, RED, GREY, INK, AMBER = "#1f5fa6", "#b71c1c", "#666666", "#222222", "#7a4f00"
FIRST_PAGE_ROWS = 12


class _Flow:
    """Text and panels flowed onto A4 pages, top to bottom."""

    def __init__(self) -> None:
        self.pages: list[Figure] = []
        self.y = 0.0
        self.page = self.new_page()

    def new_page(self) -> Figure:
        self.page = Figure(figsize=A4_IN)
        self.pages.append(self.page)
        self.y = TOP
        return self.page

    def room(self, height: float) -> None:
        if self.y - height < BOTTOM + 0.01:
            self.new_page()

    def line(self, text: str, size: float = 9.0, colour: str = INK, weight: str = "normal", x: float = LEFT) -> None:
        height = LINE * size / 9.0
        self.room(height)
        self.page.text(x, self.y, text, fontsize=size, color=colour, weight=weight, va="top", family="DejaVu Sans")
        self.y -= height

    def paragraph(
        self, text: str, size: float = 9.0, colour: str = INK, weight: str = "normal", indent: float = 0.0
    ) -> None:
        width = int(100 * 9.0 / size * (RIGHT - LEFT - indent) / (RIGHT - LEFT))
        for row in textwrap.wrap(text, width) or [""]:
            self.line(row, size, colour, weight, LEFT + indent)
        self.y -= LINE * 0.3

    def heading(self, text: str, size: float = 11.0) -> None:
        self.room(LINE * 4)
        self.y -= LINE * 0.5
        self.line(text, size, BLUE, "bold")
        self.y -= LINE * 0.2

    def panels(self, panels: Sequence[Panel], names: Sequence[str]) -> None:
        rows = -(-len(panels) // 3)
        height = 0.035 + 0.165 * rows
        self.room(height)
        draw_panels(
            self.page, (LEFT + 0.02, self.y - height + 0.03, RIGHT - LEFT - 0.02, height - 0.055), panels, names
        )
        self.y -= height


def _headline_box(flow: _Flow, analysis: Analysis) -> None:
    top = flow.y
    flow.y -= LINE * 0.4
    for arm in analysis.arms:
        if len(analysis.arms) > 1:
            flow.line(arm_title(analysis, arm), 9.5, INK, "bold", LEFT + 0.015)
        for kind, sentence in headline_parts(analysis, arm):
            colour, weight = {
                "change": (RED, "bold"),
                "possible change": (RED, "normal"),
                "cannot be judged yet": (AMBER, "normal"),
            }.get(kind, (INK, "normal"))
            flow.paragraph(sentence, 9.5, colour, weight, indent=0.015)
    for artist in (
        Rectangle((LEFT - 0.005, flow.y), RIGHT - LEFT + 0.01, top - flow.y, facecolor="#f3f6fa", zorder=-1),
        Rectangle((LEFT - 0.005, flow.y), 0.006, top - flow.y, facecolor=BLUE),
    ):
        artist.set(transform=flow.page.transFigure, edgecolor="none")
        flow.page.add_artist(artist)
    flow.y -= LINE * 0.5
    for sentence in tare_sentences(analysis):
        flow.paragraph(sentence, 8.5, RED, "bold")


def _session_list(flow: _Flow, analysis: Analysis, limit: int | None) -> None:
    shown, note = first_page_rows(session_rows(analysis, retests=limit is None), limit)
    flow.line("No.   Date          Arm     Status", 8.0, GREY, "bold")
    for row in shown:
        colour, weight = (RED, "bold") if row.attention else (INK, "normal")
        status = textwrap.wrap(row.status, 78) or [""]
        flow.room(LINE * len(status))
        flow.page.text(LEFT, flow.y, row.name, fontsize=8, color=colour, weight=weight, va="top")
        flow.page.text(LEFT + 0.05, flow.y, row.date, fontsize=8, color=colour, weight=weight, va="top")
        flow.page.text(LEFT + 0.165, flow.y, row.arm, fontsize=8, color=colour, weight=weight, va="top")
        for part in status:
            flow.page.text(LEFT + 0.24, flow.y, part, fontsize=8, color=colour, weight=weight, va="top")
            flow.y -= LINE * 0.9
    if note:
        flow.line(note, 7.5, GREY)


def _rows(flow: _Flow, rows: Sequence[DetailRow], *, error: bool = True) -> None:
    for row in rows:
        text = (
            f"{row.name} ({row.arm}): latest {row.latest}; since previous {row.since_previous}; "
            f"since first {row.since_first}"
        )
        flow.paragraph(text + (f"; {row.error}." if error and row.error else "."), 8.0, RED if row.flagged else INK)


def _peers(flow: _Flow, analysis: Analysis) -> None:
    rows = peer_rows(analysis)
    if not rows:
        flow.paragraph(analysis.prior_note, 8.0, GREY)
        return
    two = len(analysis.arms) > 1
    for arm, row in rows:
        measured, tables, words = peer_cells(row, unit(row.key[2]))
        flow.paragraph(
            f"{row.label}{f' ({arm})' if two else ''}: measured {measured}; tables predict {tables}; {words}.", 8.0
        )
    flow.paragraph(PEERS_NOTE, 7.5, GREY)


def _norms(flow: _Flow, analysis: Analysis) -> None:
    """The passive moments with a published healthy range against it, the source named; the others listed."""
    rows, without = norm_rows(analysis)
    flow.heading(NORMS_TITLE)
    two = len(analysis.arms) > 1
    for row in rows:
        flow.paragraph(
            f"{row.label}{f' ({row.arm})' if two else ''}: measured {row.measured}; healthy {row.range_text}, "
            f"{row.healthy.citation}; {row.words}.",
            8.0,
        )
    flow.paragraph(" ".join(t for t in (NORMS_NOTE, sources_text(rows), without_text(without)) if t), 7.5, GREY)


def _precision(flow: _Flow, analysis: Analysis) -> None:
    """The latest usable session's static and passive moments: their SD, its largest source, what would shrink it;
    nothing where the store holds no budget."""
    rows = precision_rows(analysis, clinician=True)
    if not rows:
        return
    flow.heading(PRECISION_TITLE)
    for row in rows:
        text = (
            f"{row.name} ({(row.arm or '–').capitalize()}, session {row.session}, {day(row.time_ns)}): "
            f"{row.latest}. Largest source: {row.words}."
        )
        flow.paragraph(text + (f" More precise with: {row.remedy}." if row.remedy else ""), 8.0)
    flow.paragraph(PRECISION_NOTE, 7.5, GREY)


def _budget(flow: _Flow, analysis: Analysis) -> None:
    """Every quantity's full uncertainty budget of the latest usable session, for the engineer."""
    rows = precision_rows(analysis, clinician=False)
    if not rows:
        return
    flow.heading(BUDGET_TITLE, 10.0)
    for row in rows:
        text = (
            f"{row.name} ({(row.arm or '–').capitalize()}, session {row.session}): SD {plain_number(row.std)} "
            f"{unit(row.key[2])}: {row.budget_text}"
        )
        flow.paragraph(text + (f"; {row.engineer_remedy}." if row.engineer_remedy else "."), 7.5)
    flow.paragraph(BUDGET_NOTE, 7.0, GREY)


def _curves(flow: _Flow, analysis: Analysis) -> None:
    """The torque-angle panels, three to a row, with their caption."""
    views, colours, titles = curve_panels(analysis)
    if not views:
        return
    flow.heading(CURVES_TITLE)
    for start in range(0, len(views), 3):
        height = 0.235
        flow.room(height)
        rect = (LEFT + 0.03, flow.y - height + 0.03, RIGHT - LEFT - 0.03, height - 0.05)
        part = slice(start, start + 3)
        draw_curves(flow.page, rect, views[part], colours[part], titles[part])
        flow.y -= height
    flow.paragraph(CURVES_CAPTION, 7.5, GREY)


def _support(flow: _Flow, analysis: Analysis) -> None:
    flow.heading("Weight support")
    for side in analysis.arms:
        rows, note = support_table(analysis, side)
        if len(analysis.arms) > 1:
            flow.line(arm_title(analysis, side), 9.0, INK, "bold")
        for row in rows:
            (fy, fz, mx), (sy, sz, sm) = row.wrench_yzx, row.std_yzx
            flow.line(
                f"{row.fraction:.0%} of the arm weight: forward {plain_number(fy)} ± {plain_number(sy)} N, upward "
                f"{plain_number(fz)} ± {plain_number(sz)} N, moment {plain_number(mx)} ± {plain_number(sm)} N·m",
                8.0,
            )
        flow.paragraph(note, 8.0, GREY)


def _lengths(flow: _Flow, analysis: Analysis) -> None:
    flow.heading("Segment lengths (from the markers)")
    for series in analysis.series:
        if series.key[2] == "length_m" and series.latest is not None:
            name = plain_name(series.key)
            arm = f" ({series.arm} arm)" if series.arm and len(analysis.arms) > 1 else ""
            flow.line(
                f"{name[0].upper()}{name[1:]}{arm}: {plain_number((series.latest.value or 0.0) * 100, 3)} cm", 8.0
            )


def _detail(flow: _Flow, analysis: Analysis) -> None:
    flow.new_page()
    flow.heading("Detail: every parameter", 13.0)
    _curves(flow, analysis)
    flow.heading("Passive joint moments")
    _rows(flow, detail_rows(analysis, "passive"))
    flow.heading("Arm weight against its peers")
    _peers(flow, analysis)
    _norms(flow, analysis)
    flow.heading("Arm weight, masses and centres of mass")
    _rows(flow, detail_rows(analysis, "weight"))
    _precision(flow, analysis)
    names = arm_names(analysis)
    for title, panels in detail_groups(analysis):
        flow.heading(title)
        for start in range(0, len(panels), 6):
            flow.panels(panels[start : start + 6], names)
    _lengths(flow, analysis)
    _support(flow, analysis)
    flow.heading("All sessions")
    _session_list(flow, analysis, None)
    notes = session_notes(analysis)
    if notes:
        flow.heading("Session notes", 10.0)
        for who, text in notes:
            flow.paragraph(f"{who}: {text}.", 8.0)
    if tare_note(analysis):
        flow.paragraph(tare_note(analysis), 8.0, GREY)
    flow.heading("Method")
    flow.paragraph(f"{RETEST_METHOD} {flag_rule(analysis)}", 8.0, GREY)
    _appendix(flow, analysis)
    flow.paragraph(READING_GUIDE, 8.0, GREY)


def _appendix(flow: _Flow, analysis: Analysis) -> None:
    flow.new_page()
    flow.heading("Appendix for the engineer", 13.0)
    flow.paragraph(APPENDIX_NOTE, 8.0, GREY)
    _rows(flow, detail_rows(analysis, "appendix"), error=False)
    _budget(flow, analysis)
    names = arm_names(analysis)
    for title, panels in appendix_groups(analysis):
        flow.heading(title)
        for start in range(0, len(panels), 6):
            flow.panels(panels[start : start + 6], names)
    notes = technical_notes(analysis)
    if notes:
        flow.heading("Technical notes of the estimator", 10.0)
        for who, text in notes:
            flow.paragraph(f"{who}: {text}", 7.0, GREY)


def report_pages(analysis: Analysis, generated: dt.datetime) -> list[Figure]:
    """The report's A4 pages: the first page alone, then the detail; each numbered and dated."""
    flow = _Flow()
    page = flow.page
    page.text(LEFT, flow.y, f"Arm assessment · subject {analysis.subject}", fontsize=15, weight="bold", va="top")
    flow.y -= LINE * 1.9
    flow.line(f"{subject_line(analysis)} · {period_line(analysis)}", 9.0, GREY)
    flow.y -= LINE * 0.4
    _headline_box(flow, analysis)
    flow.paragraph(error_source(analysis), 7.5, GREY)
    if flag_rule(analysis):
        flow.paragraph(flag_rule(analysis), 7.5, GREY)
    panels = first_page_panels(analysis)
    if panels:
        flow.panels(panels, arm_names(analysis))
        flow.paragraph(PROTOCOL, 7.5, GREY)
    _session_list(flow, analysis, FIRST_PAGE_ROWS)
    _detail(flow, analysis)
    stamp = generated.strftime("%Y-%m-%d %H:%M UTC")
    for number, figure in enumerate(flow.pages, start=1):
        figure.text(
            LEFT,
            0.025,
            f"Subject {analysis.subject} · arm assessment · made {stamp} · bsp_ros {__version__}",
            fontsize=7,
            color=GREY,
        )
        figure.text(RIGHT, 0.025, f"Page {number} of {len(flow.pages)}", fontsize=7, color=GREY, ha="right")
    return flow.pages


def write_report_pdf(analysis: Analysis, path: Path, generated: dt.datetime) -> Path:
    """Write the PDF report of ``analysis`` to ``path``; return the path.

    Raises
    ------
    InputError
        If the file cannot be written.
    """
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with PdfPages(path) as pdf:
            for figure in report_pages(analysis, generated):
                pdf.savefig(figure)
            info = pdf.infodict()
            info["Title"] = f"Arm assessment of subject {analysis.subject}"
            info["Creator"] = f"bsp_ros {__version__}"
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return path
