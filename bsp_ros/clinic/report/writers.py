"""Write a subject's report: the HTML page, the PDF, the trend plots as PNG, and the CSV of every number."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.report.export import write_analysis_csv
from bsp_ros.clinic.report.html import render_html
from bsp_ros.errors import InputError


def _now() -> dt.datetime:
    return dt.datetime.now(dt.timezone.utc)


Figures = tuple[bytes | None, list[tuple[str, bytes]], bytes | None, list[tuple[str, bytes]]]


def _figures(analysis: Analysis) -> Figures:
    """PNGs of the first page's trends, of each detail group, of the torque-angle curves (None: none) and of each
    group of the engineer's appendix."""
    from bsp_ros.clinic.report.curve_plots import curve_panels, curves_figure
    from bsp_ros.clinic.report.panels import appendix_groups, arm_names, detail_groups, first_page_panels
    from bsp_ros.clinic.report.plots import figure_png, panels_figure  # matplotlib only when plotting

    names = arm_names(analysis)
    first = first_page_panels(analysis)
    first_png = figure_png(panels_figure(first, names)) if first else None
    detail = [(title, figure_png(panels_figure(panels, names))) for title, panels in detail_groups(analysis)]
    views, colours, titles = curve_panels(analysis)
    curves_png = figure_png(curves_figure(views, colours, titles)) if views else None
    appendix = [(title, figure_png(panels_figure(panels, names))) for title, panels in appendix_groups(analysis)]
    return first_png, detail, curves_png, appendix


def render_report(analysis: Analysis, generated: dt.datetime | None = None) -> str:
    """The HTML page of ``analysis``, plots included."""
    first_png, detail, curves_png, appendix = _figures(analysis)
    return render_html(analysis, first_png, detail, generated or _now(), curves_png, appendix)


def write_html(analysis: Analysis, path: str | Path) -> Path:
    """Write the self-contained HTML report to ``path``; return the path."""
    return _write(Path(path), render_report(analysis))


def write_pngs(analysis: Analysis, directory: str | Path) -> list[Path]:
    """Write the figures (``passive_moments.png``, ``passive_curves.png`` and one per detail group) into
    ``directory``."""
    target = Path(directory)
    first_png, detail, curves_png, appendix = _figures(analysis)
    named = (
        ([("passive_moments", first_png)] if first_png is not None else [])
        + ([("passive_curves", curves_png)] if curves_png is not None else [])
        + [(title.split(" (")[0].lower().replace(" ", "_"), png) for title, png in [*detail, *appendix]]
    )
    try:
        target.mkdir(parents=True, exist_ok=True)
        written = []
        for name, png in named:
            path = target / f"{name}.png"
            path.write_bytes(png)
            written.append(path)
    except OSError as error:
        raise InputError(f"cannot write plots to {target}: {error}") from None
    return written


def write_pdf(analysis: Analysis, path: str | Path) -> Path:
    """Write the A4 PDF report (first page alone, detail after, every page numbered and dated)."""
    from bsp_ros.clinic.report.pdf import write_report_pdf  # matplotlib is imported only when plotting

    return write_report_pdf(analysis, Path(path), _now())


def write_csv(analysis: Analysis, path: str | Path) -> Path:
    """Write every session and parameter with its changes and the MDC95 used (:mod:`.export`)."""
    try:
        with open(path, "w", newline="", encoding="utf-8") as stream:
            write_analysis_csv([analysis], stream)
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return Path(path)


def _write(path: Path, text: str) -> Path:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return path
