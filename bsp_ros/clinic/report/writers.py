"""Write a subject's report: the HTML page, a PDF, one PNG per parameter, and a CSV of the plotted numbers."""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

from bsp_ros.clinic.report.analysis import Analysis, compare
from bsp_ros.clinic.report.html import render_html
from bsp_ros.clinic.store.records import ParamKey, format_time
from bsp_ros.errors import InputError

REPORT_CSV_COLUMNS = (
    "subject",
    "session_id",
    "session_time_utc",
    "session_valid",
    "parameter",
    "group",
    "part",
    "quantity",
    "unit",
    "value",
    "std",
    "lower_2std",
    "upper_2std",
    "value_source",
    "prior_mean",
    "prior_std",
    "sem",
    "mdc95_from_previous",
    "change_from_previous_flagged",
    "change_over_mdc95",
)


def _pngs(analysis: Analysis) -> dict[ParamKey, bytes]:
    from bsp_ros.clinic.report.plots import trend_png  # matplotlib is imported only when plotting

    return {s.key: trend_png(s) for s in analysis.series if s.has_values}


def render_report(analysis: Analysis) -> str:
    """The HTML page of ``analysis``, plots included."""
    return render_html(analysis, _pngs(analysis))


def write_html(analysis: Analysis, path: str | Path) -> Path:
    """Write the self-contained HTML report to ``path``; return the path."""
    return _write(Path(path), render_report(analysis))


def write_pngs(analysis: Analysis, directory: str | Path) -> list[Path]:
    """Write one PNG per parameter (``<group>_<part>_<quantity>.png``) into ``directory``."""
    target = Path(directory)
    try:
        target.mkdir(parents=True, exist_ok=True)
        written = []
        for (group, part, quantity), png in _pngs(analysis).items():
            path = target / f"{group}_{part}_{quantity}.png"
            path.write_bytes(png)
            written.append(path)
    except OSError as error:
        raise InputError(f"cannot write plots to {target}: {error}") from None
    return written


def write_pdf(analysis: Analysis, path: str | Path) -> Path:
    """Write the report as a PDF for the patient file (summary first, as in the HTML); return the path."""
    from bsp_ros.clinic.report.pdf import write_report_pdf  # matplotlib is imported only when plotting

    return write_report_pdf(analysis, Path(path))


def write_csv(analysis: Analysis, path: str | Path) -> Path:
    """Write every plotted number (values, ±2 std bounds, priors, change flags) as CSV."""
    flagged = {(c.key, c.after.session_id): c for c in analysis.changes}
    previous = {}
    for series in analysis.series:
        usable = [p for p in series.points if p.valid and p.value is not None]
        for before, after in itertools.pairwise(usable):
            previous[(series.key, after.session_id)] = compare(series.key, before, after)
    try:
        with open(path, "w", newline="", encoding="utf-8") as stream:
            writer = csv.writer(stream, lineterminator="\n")
            writer.writerow(REPORT_CSV_COLUMNS)
            for series in analysis.series:
                group, part, quantity = series.key
                for p in series.points:
                    change = flagged.get((series.key, p.session_id))
                    step = previous.get((series.key, p.session_id))
                    bounds = (
                        ("", "") if p.value is None or p.std is None else (p.value - 2 * p.std, p.value + 2 * p.std)
                    )
                    writer.writerow(
                        [
                            analysis.subject,
                            p.session_id,
                            format_time(p.time_ns),
                            int(p.valid),
                            series.label,
                            group,
                            part,
                            quantity,
                            series.unit,
                            _cell(p.value),
                            _cell(p.std),
                            *bounds,
                            p.source,
                            "" if p.prior is None else p.prior.mean,
                            "" if p.prior is None else p.prior.std,
                            _cell(p.sem),
                            "" if step is None or step.mdc95 is None else step.mdc95,
                            int(change is not None),
                            "" if step is None or step.mdc_ratio is None else f"{step.mdc_ratio:.2f}",
                        ]
                    )
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return Path(path)


def _cell(value: float | None) -> str | float:
    return "" if value is None else value


def _write(path: Path, text: str) -> Path:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as error:
        raise InputError(f"cannot write {path}: {error}") from None
    return path
