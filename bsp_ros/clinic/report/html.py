"""The report as one self-contained HTML page; printed, its first page stands alone on A4, the detail follows."""

from __future__ import annotations

import base64
import datetime as dt
from collections.abc import Sequence
from html import escape

from bsp_ros import __version__
from bsp_ros.clinic.mdc import READING_GUIDE, RETEST_METHOD
from bsp_ros.clinic.report.analysis import Analysis, Change, Series
from bsp_ros.clinic.report.labels import plain_name, plain_number, with_unit
from bsp_ros.clinic.report.summary import (
    arm_title,
    day,
    error_source,
    first_page_rows,
    headline,
    percent,
    period_line,
    quality_notes,
    session_rows,
    subject_line,
    support_table,
)

FIRST_PAGE_ROWS = 12
"""The first page lists the latest sessions; the full list is in the detail."""

_CSS = """
body { font-family: 'DejaVu Sans', Arial, sans-serif; margin: 1.5em auto; max-width: 900px; color: #222;
  font-size: 15px; line-height: 1.35; }
h1 { font-size: 1.5em; margin: 0 0 0.1em; } h2 { font-size: 1.15em; margin: 0.9em 0 0.3em; color: #1f5fa6; }
h3 { font-size: 1em; margin: 0.8em 0 0.2em; }
.who { margin: 0 0 0.6em; color: #444; }
.headline { border-left: 5px solid #1f5fa6; background: #f3f6fa; padding: 0.5em 0.8em; margin: 0.4em 0; }
.headline p { margin: 0.25em 0; } .headline .arm { font-weight: bold; }
.changed { color: #b71c1c; font-weight: bold; }
.source { font-size: 0.85em; color: #555; margin: 0.3em 0; }
figure { margin: 0.4em 0; } figure img { width: 100%; height: auto; display: block; }
figcaption { font-size: 0.8em; color: #555; }
table { border-collapse: collapse; margin: 0.3em 0 0.8em; font-size: 0.85em; width: 100%; }
th, td { border-bottom: 1px solid #ddd; padding: 0.2em 0.5em; text-align: left; vertical-align: top; }
th { background: #eef3f9; } td.num { white-space: nowrap; }
tr.attention td { color: #b71c1c; font-weight: bold; }
.note { font-size: 0.85em; color: #555; }
.tech { font-size: 0.75em; color: #666; }
footer { font-size: 0.75em; color: #777; margin-top: 1.5em; }
@media print {
  body { max-width: none; margin: 0; font-size: 9.5pt; }
  #first-page { break-after: page; }
  figure, table, tr, .headline { break-inside: avoid; }
  h2, h3 { break-after: avoid; }
  footer { display: none; }
}
"""


def _png(data: bytes, alt: str) -> str:
    encoded = base64.b64encode(data).decode("ascii")
    return f"<img alt='{escape(alt, quote=True)}' src='data:image/png;base64,{encoded}'>"


def _headline(analysis: Analysis) -> list[str]:
    parts = ["<div class='headline' id='headline'>"]
    for arm in analysis.arms:
        if len(analysis.arms) > 1:
            parts.append(f"<p class='arm'>{escape(arm_title(analysis, arm))}</p>")
        flagged = {id(s): s for s in analysis.arm_series(arm) if s.flagged_latest}
        for sentence in headline(analysis, arm):
            changed = any(plain_name(s.key).lower() in sentence.lower() for s in flagged.values())
            parts.append(f"<p{' class=' + chr(39) + 'changed' + chr(39) if changed else ''}>{escape(sentence)}</p>")
    parts.append("</div>")
    parts.append(f"<p class='source' id='error-source'>{escape(error_source(analysis))}</p>")
    return parts


def _session_table(analysis: Analysis, rows_limit: int | None, table_id: str) -> str:
    shown, note = first_page_rows(session_rows(analysis), rows_limit)
    out = [f"<table id='{table_id}'><tr><th>No.</th><th>Date</th><th>Arm</th><th>Status</th></tr>"]
    for row in shown:
        cls = " class='attention'" if row.attention else ""
        out.append(
            f"<tr{cls}><td class='num'>{row.number}</td><td class='num'>{row.date}</td><td>{escape(row.arm)}</td>"
            f"<td>{escape(row.status)}</td></tr>"
        )
    out.append("</table>")
    if note:
        out.append(f"<p class='note'>{escape(note)}</p>")
    return "\n".join(out)


def _change_cell(change: Change | None, unit: str) -> str:
    if change is None:
        return "–"
    sign = "+" if change.delta > 0 else "−"
    text = escape(f"{sign}{with_unit(abs(change.delta), unit)} ({sign}{percent(change.percent)})")
    return f"<span class='changed'>{text}</span>" if change.beyond_mdc else text


def _error_cell(series: Series) -> str:
    error = series.error
    if error.mdc95 is None:
        return "unknown (too few retests)" if series.judged else "not judged"
    whose = "this patient" if error.source == "subject" else "cell"
    text = f"{escape(with_unit(error.mdc95, series.unit))} ({error.n_pairs} retests, {whose})"
    return text if series.judged else text + ", for reference: not judged"


def _changes_table(analysis: Analysis) -> str:
    out = [
        "<table id='changes'><tr><th>Parameter</th><th>Arm</th><th>Latest</th><th>Since previous</th>"
        "<th>Since first</th><th>Measurement error (MDC95)</th></tr>"
    ]
    for series in analysis.series:
        latest = series.latest
        if latest is None or series.key[2] == "length_m":
            continue
        name = plain_name(series.key)
        out.append(
            f"<tr><td>{escape(name[0].upper() + name[1:])}</td><td>{escape((series.arm or '–').capitalize())}</td>"
            f"<td class='num'>{escape(with_unit(latest.value, series.unit))}</td>"
            f"<td class='num'>{_change_cell(series.since_previous, series.unit)}</td>"
            f"<td class='num'>{_change_cell(series.since_first, series.unit)}</td><td>{_error_cell(series)}</td></tr>"
        )
    out.append("</table>")
    return "\n".join(out)


def _lengths_table(analysis: Analysis) -> str:
    out = ["<table id='lengths'><tr><th>Segment length</th><th>Arm</th><th>Latest</th></tr>"]
    for series in analysis.series:
        if series.key[2] == "length_m" and series.latest is not None:
            name = plain_name(series.key)
            value = f"{plain_number((series.latest.value or 0.0) * 100, 3)} cm"
            out.append(
                f"<tr><td>{escape(name[0].upper() + name[1:])}</td><td>{escape((series.arm or '–').capitalize())}</td>"
                f"<td class='num'>{value}</td></tr>"
            )
    out.append("</table>")
    return "\n".join(out)


def _support(analysis: Analysis) -> list[str]:
    parts = ["<h2>Weight support</h2>"]
    for arm in analysis.arms:
        rows, note = support_table(analysis, arm)
        if len(analysis.arms) > 1:
            parts.append(f"<h3>{escape(arm_title(analysis, arm))}</h3>")
        if rows:
            parts.append(
                "<table class='support'><tr><th>Share of arm weight carried</th><th>Forward force</th>"
                "<th>Upward force</th><th>Moment at the handle</th></tr>"
            )
            for row in rows:
                (fy, fz, mx), (sy, sz, sm) = row.wrench_yzx, row.std_yzx
                parts.append(
                    f"<tr><td>{row.fraction:.0%}</td><td class='num'>{plain_number(fy)} ± {plain_number(sy)} N</td>"
                    f"<td class='num'>{plain_number(fz)} ± {plain_number(sz)} N</td>"
                    f"<td class='num'>{plain_number(mx)} ± {plain_number(sm)} N·m</td></tr>"
                )
            parts.append("</table>")
        parts.append(f"<p class='note'>{escape(note)}</p>")
    return parts


def _quality(analysis: Analysis) -> list[str]:
    parts = ["<h2>All sessions</h2>", _session_table(analysis, None, "all-sessions"), "<h3>Session notes</h3><ul>"]
    for record in analysis.sessions:
        notes = quality_notes(record)
        text = "; ".join(notes) if notes else "no notes"
        parts.append(f"<li>Session {record.number} ({day(record.session_time_ns)}): {escape(text)}</li>")
    parts.append("</ul><h3>Technical notes (for the engineer)</h3>")
    for record in analysis.sessions:
        lines = [record.quality.message] if not record.quality.valid and record.quality.message else []
        lines += list(record.quality.warnings)
        if lines:
            parts.append(
                f"<p class='tech'>Session {record.number}: " + " | ".join(escape(line) for line in lines) + "</p>"
            )
    return parts


def _page_css(footer: str) -> str:
    """A4 pages with the subject, date and page number in the bottom margin of every printed page."""
    text = footer.replace("\\", "").replace('"', "'")
    return (
        "@page { size: A4; margin: 13mm 13mm 16mm 13mm;\n"
        f'  @bottom-left {{ content: "{text}"; font-size: 8pt; color: #666; }}\n'
        '  @bottom-right { content: "Page " counter(page) " of " counter(pages); font-size: 8pt; color: #666; } }\n'
    )


def render_html(
    analysis: Analysis,
    first_png: bytes | None,
    detail_pngs: Sequence[tuple[str, bytes]],
    generated: dt.datetime,
    curves_png: bytes | None = None,
) -> str:
    """The report page.

    Parameters
    ----------
    analysis : what to report.
    first_png : the passive-moment trend panels of the first page, None if there are none.
    detail_pngs : ``(title, png)`` of the detail trend groups.
    generated : when the report is made (printed on every page).
    curves_png : the torque-angle panels (first and latest usable session per joint), None if no curves.
    """
    from bsp_ros.clinic.report.curve_views import CURVES_CAPTION, CURVES_TITLE

    stamp = generated.strftime("%Y-%m-%d %H:%M UTC")
    footer = f"Subject {analysis.subject} · arm assessment · made {stamp}"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>Arm assessment of subject {escape(analysis.subject)}</title>",
        f"<style>{_CSS}{_page_css(footer)}</style></head><body>",
        "<section id='first-page'>",
        f"<h1>Arm assessment · subject <span id='subject'>{escape(analysis.subject)}</span></h1>",
        f"<p class='who'>{escape(subject_line(analysis))} · {escape(period_line(analysis))}</p>",
        *_headline(analysis),
    ]
    if first_png is not None:
        parts.append(
            "<figure id='passive-trends'>"
            + _png(first_png, "Passive joint moments across sessions")
            + "<figcaption>Dots: usable sessions (bars ±2 SD); shaded: measurement error around the first session; "
            "red: a change beyond it; dotted line: a session that could not be used.</figcaption></figure>"
        )
    parts.append(_session_table(analysis, FIRST_PAGE_ROWS, "sessions"))
    parts.append("</section>")
    parts.append("<section id='detail'><h2>Detail: every parameter</h2>")
    if curves_png is not None:
        parts.append(
            f"<h3>{escape(CURVES_TITLE)}</h3><figure id='passive-curves'>{_png(curves_png, CURVES_TITLE)}"
            f"<figcaption>{escape(CURVES_CAPTION)}</figcaption></figure>"
        )
    parts.append(_changes_table(analysis))
    for title, png in detail_pngs:
        parts.append(f"<h3>{escape(title)}</h3><figure>{_png(png, title)}</figure>")
    parts.append(f"<p class='note' id='prior-note'>{escape(analysis.prior_note)}</p>")
    parts.append("<h3>Segment lengths (from the markers)</h3>" + _lengths_table(analysis))
    parts.extend(_support(analysis))
    parts.extend(_quality(analysis))
    parts.append(f"<h2>Method</h2><p class='note'>{escape(RETEST_METHOD)}</p>")
    parts.append(f"<p class='note' id='reading-guide'>{escape(READING_GUIDE)}</p>")
    parts.append("</section>")
    parts.append(f"<footer>{escape(footer)} by bsp_ros {escape(__version__)}.</footer></body></html>")
    return "\n".join(parts)
