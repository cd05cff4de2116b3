"""The report as one self-contained HTML page: summary first, then arm weight, plots, quality and detail."""

from __future__ import annotations

import base64
import datetime as dt
from collections.abc import Mapping
from html import escape

from bsp_ros import __version__
from bsp_ros.clinic.report.analysis import Analysis, Change, Series
from bsp_ros.clinic.report.labels import GROUP_TITLES
from bsp_ros.clinic.report.summary import (
    day,
    headline,
    joint_summaries,
    number,
    segment_summaries,
    session_notes,
    support_table,
)
from bsp_ros.clinic.store.records import ParamKey

_CSS = """
body { font-family: 'DejaVu Sans', Arial, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { border-bottom: 2px solid #1f5fa6; padding-bottom: 0.2em; }
h3 { margin: 0.8em 0 0.2em; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: left; vertical-align: top; }
th { background: #eef3f9; } .bad { color: #b71c1c; font-weight: bold; } .ok { color: #1b5e20; }
.flag { background: #fdecea; border-left: 5px solid #c62828; padding: 0.5em 0.8em; margin: 0.4em 0; }
.note { background: #f4f4f4; padding: 0.6em 0.9em; } figure { margin: 1em 0 1.8em; }
figcaption { font-size: 0.9em; color: #555; } img { max-width: 100%; } ul.flags { list-style: none; padding: 0; }
"""


def change_sentence(change: Change, label: str, unit: str, since: str = "") -> str:
    """One plain-language sentence describing a change beyond the MDC95."""
    direction = "rose" if change.delta > 0 else "fell"
    ratio = change.mdc_ratio
    return (
        f"{label} {direction} from {number(change.before.value, unit)} ({day(change.before.time_ns)}) to "
        f"{number(change.after.value, unit)} ({day(change.after.time_ns)}){since}: a change of "
        f"{number(abs(change.delta), unit)}, {ratio:.1f} times the minimal detectable change "
        f"(MDC95 {number(change.mdc95, unit)})."
    )


def _since(series: Series, change: Change) -> str:
    return "previous" if change is series.since_previous else "first"


def render_html(analysis: Analysis, pngs: Mapping[ParamKey, bytes]) -> str:
    """The report page.

    Parameters
    ----------
    analysis : Analysis
        What to report.
    pngs : Mapping
        The trend plot of each parameter that has one, as PNG bytes.

    Returns
    -------
    str
        A complete HTML document with no external resources; the summary comes first.
    """
    by_key = {s.key: s for s in analysis.series}
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>Arm parameters of subject {escape(analysis.subject)}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Arm parameters of subject <span id='subject'>{escape(analysis.subject)}</span></h1>",
        "<section id='summary'><h2>Summary</h2>",
        f"<p id='headline'>{escape(headline(analysis))}</p>",
    ]
    for joint in joint_summaries(analysis):
        parts.append(f"<h3>{escape(joint.title)}</h3>")
        parts.extend(f"<p>{escape(sentence)}</p>" for sentence in joint.sentences)
        parts.append(_flags(joint.flagged, by_key))
    notes = session_notes(analysis)
    if notes:
        parts.append("<p><b>Marked sessions</b> (kept in every plot and table):</p><ul id='session-notes'>")
        parts.extend(f"<li class='bad'>{escape(n)}</li>" for n in notes)
        parts.append("</ul>")
    parts.append("</section>")
    parts.append(_arm_weight(analysis, by_key))
    parts.append("<section id='trends'><h2>Trends</h2>")
    parts.append(
        "<p class='note'>Each plot shows one parameter across sessions: dots are the estimates, the blue band "
        "and bars are ±2 standard deviations of the estimate. A red line marks a change between consecutive "
        "valid sessions larger than the minimal detectable change (MDC95, see Detail): more than repeated "
        "measurement explains. A black cross marks a session whose estimate is not valid.</p>"
    )
    parts.append(f"<p class='note' id='prior-note'>{escape(analysis.prior_note)}</p>")
    for group in ("joints", "segments"):
        group_series = [s for s in analysis.series if s.key[0] == group]
        if group_series:
            parts.append(f"<h3>{escape(GROUP_TITLES.get(group, group))}</h3>")
            parts.extend(_figure(s, pngs.get(s.key)) for s in group_series)
    parts.append("</section>")
    parts.append(_quality_table(analysis))
    parts.append(_detail(analysis))
    generated = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    parts.append(f"<p class='note'>Generated {generated} by bsp_ros {escape(__version__)}.</p></body></html>")
    return "\n".join(parts)


def _flags(changes: tuple[Change, ...], by_key: Mapping[ParamKey, Series]) -> str:
    if not changes:
        return ""
    items = []
    for change in changes:
        series = by_key[change.key]
        since = _since(series, change)
        text = change_sentence(change, series.label, series.unit, f", since the {since} valid session")
        items.append(
            f"<li class='flag' data-param='{escape('.'.join(change.key))}' data-since='{since}'>{escape(text)}</li>"
        )
    return "<ul class='flags'>" + "".join(items) + "</ul>"


def _arm_weight(analysis: Analysis, by_key: Mapping[ParamKey, Series]) -> str:
    parts = ["<section id='arm-weight'><h2>Arm weight (static moments) and weight support</h2>"]
    segments = segment_summaries(analysis)
    if not segments:
        parts.append("<p>No static moments in these sessions.</p>")
    for segment in segments:
        parts.append(f"<p><b>{escape(segment.title)}</b>: {escape(segment.sentences[0])}</p>")
        parts.append(_flags(segment.flagged, by_key))
    rows, note = support_table(analysis)
    if rows:
        parts.append(
            "<table id='support'><tr><th>Support fraction</th><th>F_y forward (N)</th><th>F_z up (N)</th>"
            "<th>M_x (N·m)</th></tr>"
        )
        for row in rows:
            cells = "".join(
                f"<td>{value:.2f} ± {std:.2f}</td>" for value, std in zip(row.wrench_yzx, row.std_yzx, strict=True)
            )
            parts.append(f"<tr><td>{row.fraction:.0%}</td>{cells}</tr>")
        parts.append("</table>")
    parts.append(f"<p class='note'>{escape(note)}</p></section>")
    return "\n".join(parts)


def _quality_table(analysis: Analysis) -> str:
    rows = [
        "<section id='quality'><h2>Session quality</h2>",
        "<table id='sessions'><tr><th>Session</th><th>Date</th><th>Recording</th><th>Method</th>"
        "<th>Valid</th><th>Tare</th><th>Samples</th><th>Condition number</th><th>Cycles for SEM</th>"
        "<th>Warnings</th></tr>",
    ]
    for record in analysis.sessions:
        quality = record.quality
        valid = "<span class='ok'>yes</span>" if quality.valid else "<span class='bad'>NOT VALID</span>"
        tare = (
            f"<span class='ok'>applied ({escape(quality.tare_file or 'file not named')})</span>"
            if quality.tare_applied
            else "<span class='bad'>no tare</span>"
        )
        warnings = "<br>".join(escape(w) for w in quality.warnings) or "none"
        cycles = record.repeatability.get("n_valid_cycles")
        rows.append(
            f"<tr><td>{record.id}</td><td>{day(record.session_time_ns)}</td><td>{escape(record.source)}</td>"
            f"<td>{escape(record.method or 'not recorded')}</td><td>{valid}</td><td>{tare}</td>"
            f"<td>{'–' if quality.n_samples is None else quality.n_samples}</td>"
            f"<td>{number(quality.condition_number)}</td><td>{'–' if cycles is None else cycles}</td>"
            f"<td>{warnings}</td></tr>"
        )
    rows.append("</table></section>")
    return "\n".join(rows)


def _detail(analysis: Analysis) -> str:
    parts = ["<section id='detail'><h2>Detail</h2>", "<h3>Minimal detectable change: method</h3>"]
    methods = analysis.methods
    if methods:
        parts.extend(f"<p class='note'>{escape(m)}</p>" for m in methods)
    else:
        parts.append("<p class='note'>No session carries a repeatability measurement: no MDC, no change claimed.</p>")
    parts.append(
        "<p>MDC95 = 1.96 × √2 × SEM; between two sessions of different SEM, 1.96 × √(SEM₁² + SEM₂²). A change is "
        "flagged only when it exceeds this. Changes are compared between valid sessions only.</p>"
    )
    parts.append(
        "<table id='mdc'><tr><th>Parameter</th><th>Latest valid</th><th>± std</th><th>SEM</th><th>MDC95</th>"
        "<th>Since previous</th><th>Since first</th></tr>"
    )
    for s in analysis.series:
        latest = s.latest
        if latest is None:
            continue
        mdc = None if latest.sem is None else 1.96 * 2**0.5 * latest.sem
        cells = [
            escape(s.label),
            number(latest.value, s.unit),
            number(latest.std, s.unit),
            number(latest.sem, s.unit),
            number(mdc, s.unit),
            _delta_cell(s.since_previous, s.unit),
            _delta_cell(s.since_first, s.unit),
        ]
        parts.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    parts.append("</table>")
    changes = analysis.changes
    parts.append("<h3>All changes between consecutive valid sessions beyond the MDC95</h3>")
    if changes:
        by_key = {s.key: s for s in analysis.series}
        parts.extend(f"<p>{escape(change_sentence(c, by_key[c.key].label, by_key[c.key].unit))}</p>" for c in changes)
    else:
        parts.append("<p>None.</p>")
    parts.append("</section>")
    return "\n".join(parts)


def _delta_cell(change: Change | None, unit: str) -> str:
    if change is None:
        return "–"
    text = escape(f"{change.delta:+.3g} {unit}".strip())
    return f"<span class='bad'>{text}</span>" if change.beyond_mdc else text


def _figure(series: Series, png: bytes | None) -> str:
    latest = next((p for p in reversed(series.points) if p.value is not None), None)
    caption = escape(series.label)
    if latest is not None:
        caption += f": latest {escape(number(latest.value, series.unit))} ± {escape(number(latest.std, series.unit))}"
        caption += f" (from {escape(latest.source)})"
    if series.changes:
        caption += f" — <span class='bad'>{len(series.changes)} change(s) beyond the MDC95</span>"
    if png is None:
        return f"<figure><figcaption>{caption}: no finite estimate in any session.</figcaption></figure>"
    data = base64.b64encode(png).decode("ascii")
    alt = escape(f"Trend of {series.label} across sessions", quote=True)
    return f"<figure><img alt='{alt}' src='data:image/png;base64,{data}'><figcaption>{caption}</figcaption></figure>"
