"""The report as one self-contained HTML page; printed, its first page stands alone on A4, the detail follows."""

from __future__ import annotations

import base64
import datetime as dt
from collections.abc import Sequence
from html import escape

from bsp_ros import __version__
from bsp_ros.clinic.mdc import READING_GUIDE, RETEST_METHOD
from bsp_ros.clinic.report.analysis import Analysis
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
.changed, tr.changed td { color: #b71c1c; font-weight: bold; }
.unknown { color: #7a4f00; }
.possible { color: #b71c1c; }
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


_KIND_CLASS = {"change": "changed", "possible change": "possible", "cannot be judged yet": "unknown"}


def _headline(analysis: Analysis) -> list[str]:
    parts = ["<div class='headline' id='headline'>"]
    for arm in analysis.arms:
        if len(analysis.arms) > 1:
            parts.append(f"<p class='arm'>{escape(arm_title(analysis, arm))}</p>")
        for kind, sentence in headline_parts(analysis, arm):
            cls = _KIND_CLASS.get(kind)
            parts.append(f"<p{f' class={chr(39)}{cls}{chr(39)}' if cls else ''}>{escape(sentence)}</p>")
    parts.append("</div>")
    for sentence in tare_sentences(analysis):
        parts.append(f"<p class='changed tare'>{escape(sentence)}</p>")
    parts.append(f"<p class='source' id='error-source'>{escape(error_source(analysis))}</p>")
    rule = flag_rule(analysis)
    if rule:
        parts.append(f"<p class='source' id='flag-rule'>{escape(rule)}</p>")
    return parts


def _session_table(analysis: Analysis, rows_limit: int | None, table_id: str) -> str:
    first_page = rows_limit is not None
    shown, note = first_page_rows(session_rows(analysis, retests=not first_page), rows_limit)
    stored = "" if first_page else "<th>Stored as</th>"
    out = [f"<table id='{table_id}'><tr><th>No.</th><th>Date</th><th>Arm</th><th>Status</th>{stored}</tr>"]
    for row in shown:
        cls = " class='attention'" if row.attention else ""
        extra = "" if first_page else f"<td class='num'>{row.number}</td>"
        out.append(
            f"<tr{cls}><td class='num'>{escape(row.name)}</td><td class='num'>{row.date}</td>"
            f"<td>{escape(row.arm)}</td><td>{escape(row.status)}</td>{extra}</tr>"
        )
    out.append("</table>")
    if note:
        out.append(f"<p class='note'>{escape(note)}</p>")
    return "\n".join(out)


def _rows_table(rows: Sequence[DetailRow], table_id: str, *, error: bool = True) -> str:
    head = "<th>Measurement error</th>" if error else ""
    out = [
        f"<table id='{table_id}'><tr><th>Parameter</th><th>Arm</th><th>Latest</th><th>Since previous</th>"
        f"<th>Since first</th>{head}</tr>"
    ]
    for row in rows:
        cls = " class='changed'" if row.flagged else ""
        cell = f"<td>{escape(row.error)}</td>" if error else ""
        out.append(
            f"<tr{cls}><td>{escape(row.name)}</td><td>{escape(row.arm)}</td><td class='num'>{escape(row.latest)}</td>"
            f"<td class='num'>{escape(row.since_previous)}</td><td class='num'>{escape(row.since_first)}</td>"
            f"{cell}</tr>"
        )
    out.append("</table>")
    return "\n".join(out)


def _peers_table(analysis: Analysis) -> str:
    rows = peer_rows(analysis)
    if not rows:
        return f"<p class='note' id='prior-note'>{escape(analysis.prior_note)}</p>"
    two = len(analysis.arms) > 1
    out = [
        "<table id='peers'><tr><th>Segment</th>"
        + ("<th>Arm</th>" if two else "")
        + "<th>Measured (latest)</th><th>Tables predict (±2 SD)</th><th>Against peers</th></tr>"
    ]
    for arm, row in rows:
        measured, tables, words = peer_cells(row, unit(row.key[2]))
        out.append(
            f"<tr><td>{escape(row.label)}</td>"
            + (f"<td>{escape(arm)}</td>" if two else "")
            + f"<td class='num'>{escape(measured)}</td><td class='num'>{escape(tables)}</td>"
            + f"<td>{escape(words)}</td></tr>"
        )
    out.append("</table>")
    out.append(f"<p class='note' id='prior-note'>{escape(PEERS_NOTE)}</p>")
    return "\n".join(out)


def _norms_table(analysis: Analysis) -> str:
    """The passive moments with a published healthy range against it, the source named; the others listed."""
    rows, without = norm_rows(analysis)
    two = len(analysis.arms) > 1
    out = []
    if rows:
        out.append(
            "<table id='norms'><tr><th>Parameter</th>"
            + ("<th>Arm</th>" if two else "")
            + "<th>Measured (latest)</th><th>Healthy range</th><th>Against it</th><th>Source</th></tr>"
        )
        for row in rows:
            out.append(
                f"<tr><td>{escape(row.label)}</td>"
                + (f"<td>{escape(row.arm)}</td>" if two else "")
                + f"<td class='num'>{escape(row.measured)}</td><td class='num'>{escape(row.range_text)}</td>"
                + f"<td>{escape(row.words)}</td><td>{escape(row.healthy.citation)}</td></tr>"
            )
        out.append("</table>")
    note = " ".join(text for text in (NORMS_NOTE, sources_text(rows), without_text(without)) if text)
    out.append(f"<p class='note' id='norms-note'>{escape(note)}</p>")
    return f"<h3>{escape(NORMS_TITLE)}</h3>" + "\n".join(out)


def _precision(analysis: Analysis) -> list[str]:
    """The latest usable session's static and passive moments: their SD, its largest source, what would shrink it;
    nothing where the store holds no budget."""
    rows = precision_rows(analysis, clinician=True)
    if not rows:
        return []
    out = [
        f"<h3>{escape(PRECISION_TITLE)}</h3>",
        "<table id='precision'><tr><th>Parameter</th><th>Arm</th><th>Session</th><th>Latest ± SD</th>"
        "<th>Largest source of uncertainty (share)</th><th>What would make it more precise</th></tr>",
    ]
    for row in rows:
        out.append(
            f"<tr><td>{escape(row.name)}</td><td>{escape((row.arm or '–').capitalize())}</td>"
            f"<td class='num'>{escape(row.session)}, {day(row.time_ns)}</td><td class='num'>{escape(row.latest)}</td>"
            f"<td>{escape(row.words)}</td><td>{escape(row.remedy[:1].upper() + row.remedy[1:])}</td></tr>"
        )
    out.append("</table>")
    out.append(f"<p class='note'>{escape(PRECISION_NOTE)}</p>")
    return out


def _budget(analysis: Analysis) -> list[str]:
    """Every quantity's full uncertainty budget of the latest usable session, for the engineer."""
    rows = precision_rows(analysis, clinician=False)
    if not rows:
        return []
    out = [
        f"<h3>{escape(BUDGET_TITLE)}</h3>",
        "<table id='budget'><tr><th>Parameter</th><th>Arm</th><th>Session</th><th>SD</th><th>Terms</th>"
        "<th>Largest term's remedy</th></tr>",
    ]
    for row in rows:
        out.append(
            f"<tr><td>{escape(row.name)}</td><td>{escape((row.arm or '–').capitalize())}</td>"
            f"<td class='num'>{escape(row.session)}</td><td class='num'>{plain_number(row.std)} {unit(row.key[2])}</td>"
            f"<td>{escape(row.budget_text)}</td><td>{escape(row.engineer_remedy)}</td></tr>"
        )
    out.append("</table>")
    out.append(f"<p class='note'>{escape(BUDGET_NOTE)}</p>")
    return out


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


def _sessions(analysis: Analysis) -> list[str]:
    parts = ["<h2>All sessions</h2>", _session_table(analysis, None, "all-sessions")]
    notes = session_notes(analysis)
    if notes:
        parts.append("<h3>Session notes</h3><ul id='session-notes'>")
        parts += [f"<li>{escape(who)}: {escape(text)}.</li>" for who, text in notes]
        parts.append("</ul>")
    if tare_note(analysis):
        parts.append(f"<p class='note'>{escape(tare_note(analysis))}</p>")
    return parts


def _appendix(analysis: Analysis, pngs: Sequence[tuple[str, bytes]]) -> list[str]:
    parts = [
        "<section id='appendix'><h2>Appendix for the engineer</h2>",
        f"<p class='note'>{escape(APPENDIX_NOTE)}</p>",
        _rows_table(detail_rows(analysis, "appendix"), "appendix-table", error=False),
        *_budget(analysis),
    ]
    for title, png in pngs:
        parts.append(f"<h3>{escape(title)}</h3><figure>{_png(png, title)}</figure>")
    notes = technical_notes(analysis)
    if notes:
        parts.append("<h3>Technical notes of the estimator</h3>")
        parts += [f"<p class='tech'>{escape(who)}: {escape(text)}</p>" for who, text in notes]
    parts.append("</section>")
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
    appendix_pngs: Sequence[tuple[str, bytes]] = (),
) -> str:
    """The report page.

    Parameters
    ----------
    analysis : what to report.
    first_png : the passive-moment trend panels of the first page, None if there are none.
    detail_pngs : ``(title, png)`` of the detail trend groups.
    generated : when the report is made (printed on every page).
    curves_png : the torque-angle panels (first and latest usable session per joint), None if no curves.
    appendix_pngs : ``(title, png)`` of the engineer's appendix trend groups.
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
            "red: a flagged change; dotted line: a session that could not be used. "
            f"{escape(PROTOCOL)}</figcaption></figure>"
        )
    parts.append(_session_table(analysis, FIRST_PAGE_ROWS, "sessions"))
    parts.append("</section>")
    parts.append("<section id='detail'><h2>Detail: every parameter</h2>")
    if curves_png is not None:
        parts.append(
            f"<h3>{escape(CURVES_TITLE)}</h3><figure id='passive-curves'>{_png(curves_png, CURVES_TITLE)}"
            f"<figcaption>{escape(CURVES_CAPTION)}</figcaption></figure>"
        )
    parts.append("<h3>Passive joint moments</h3>" + _rows_table(detail_rows(analysis, "passive"), "changes"))
    parts.append("<h3>Arm weight against its peers</h3>" + _peers_table(analysis))
    parts.append(_norms_table(analysis))
    parts.append(
        "<h3>Arm weight, masses and centres of mass</h3>" + _rows_table(detail_rows(analysis, "weight"), "weight")
    )
    parts.extend(_precision(analysis))
    for title, png in detail_pngs:
        parts.append(f"<h3>{escape(title)}</h3><figure>{_png(png, title)}</figure>")
    parts.append("<h3>Segment lengths (from the markers)</h3>" + _lengths_table(analysis))
    parts.extend(_support(analysis))
    parts.extend(_sessions(analysis))
    parts.append(f"<h2>Method</h2><p class='note'>{escape(RETEST_METHOD)} {escape(flag_rule(analysis))}</p>")
    parts.append("</section>")
    parts.extend(_appendix(analysis, appendix_pngs))
    parts.append(f"<p class='note' id='reading-guide'>{escape(READING_GUIDE)}</p>")
    parts.append(f"<footer>{escape(footer)} by bsp_ros {escape(__version__)}.</footer></body></html>")
    return "\n".join(parts)
