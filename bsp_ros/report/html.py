"""The report as one self-contained HTML page: text, tables and plots embedded as base64 PNG."""

from __future__ import annotations

import base64
import datetime as dt
from collections.abc import Mapping
from html import escape

from bsp_ros import __version__
from bsp_ros.report.analysis import CHANGE_SIGMAS, Analysis, Change, Series
from bsp_ros.report.labels import GROUP_TITLES
from bsp_ros.store.records import ParamKey, format_time

_CSS = """
body { font-family: 'DejaVu Sans', Arial, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { border-bottom: 2px solid #1f5fa6; padding-bottom: 0.2em; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: left; vertical-align: top; }
th { background: #eef3f9; } .bad { color: #b71c1c; font-weight: bold; } .ok { color: #1b5e20; }
.flag { background: #fdecea; border-left: 5px solid #c62828; padding: 0.5em 0.8em; margin: 0.4em 0; }
.note { background: #f4f4f4; padding: 0.6em 0.9em; } figure { margin: 1em 0 1.8em; }
figcaption { font-size: 0.9em; color: #555; } img { max-width: 100%; }
"""


def _day(time_ns: int) -> str:
    return format_time(time_ns).replace("T", " ").replace("Z", " UTC")


def _number(value: float | None, unit: str = "") -> str:
    if value is None:
        return "–"
    return f"{value:.3g} {unit}".strip()


def change_sentence(change: Change, label: str, unit: str) -> str:
    """One plain-language sentence describing a flagged change."""
    direction = "rose" if change.delta > 0 else "fell"
    times = f"{_day(change.before.time_ns)} and {_day(change.after.time_ns)}"
    return (
        f"{label} {direction} from {_number(change.before.value, unit)} to {_number(change.after.value, unit)} "
        f"between {times}: a change of {_number(abs(change.delta), unit)}, "
        f"{change.sigmas:.1f} times the combined uncertainty (flagged above {CHANGE_SIGMAS:g})."
    )


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
        A complete HTML document with no external resources.
    """
    sessions = analysis.sessions
    n_invalid = sum(not r.quality.valid for r in sessions)
    changes = analysis.changes
    by_key = {s.key: s for s in analysis.series}
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>Arm parameters of subject {escape(analysis.subject)}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>Arm parameters of subject <span id='subject'>{escape(analysis.subject)}</span></h1>",
        f"<p>{len(sessions)} session(s) from {_day(sessions[0].session_time_ns)} to "
        f"{_day(sessions[-1].session_time_ns)}. "
        f"<span class='{'bad' if n_invalid else 'ok'}'>{n_invalid} session(s) not valid.</span> "
        f"<span class='{'bad' if changes else 'ok'}'>{len(changes)} change(s) larger than the measurement "
        "uncertainty.</span></p>",
        "<p class='note'>Each plot shows one parameter across sessions: dots are the estimates, the blue band "
        "and bars are ±2 standard deviations (the estimate's uncertainty, about 95 %). A red line marks a change "
        f"between consecutive sessions larger than {CHANGE_SIGMAS:g} times their combined uncertainty: more "
        "than measurement noise explains. A black cross marks a session whose estimate is not valid.</p>",
        f"<p class='note' id='prior-note'>{escape(analysis.prior_note)}</p>",
        "<h2>Changes larger than the uncertainty</h2>",
    ]
    if changes:
        for change in changes:
            series = by_key[change.key]
            parts.append(f"<div class='flag'>{escape(change_sentence(change, series.label, series.unit))}</div>")
    else:
        parts.append("<p class='ok'>None: every change between sessions is within what the uncertainties explain.</p>")
    parts.append(_quality_table(analysis))
    for group in ("joints", "segments"):
        group_series = [s for s in analysis.series if s.key[0] == group]
        if group_series:
            parts.append(f"<h2>{escape(GROUP_TITLES.get(group, group))}</h2>")
            parts.extend(_figure(s, pngs.get(s.key)) for s in group_series)
    generated = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    parts.append(f"<p class='note'>Generated {generated} by bsp_ros {escape(__version__)}.</p></body></html>")
    return "\n".join(parts)


def _quality_table(analysis: Analysis) -> str:
    rows = [
        "<h2>Session quality</h2>",
        "<table id='sessions'><tr><th>Session</th><th>Date</th><th>Recording</th><th>Method</th>"
        "<th>Valid</th><th>Samples</th><th>Condition number</th><th>Warnings</th></tr>",
    ]
    for record in analysis.sessions:
        quality = record.quality
        valid = "<span class='ok'>yes</span>" if quality.valid else "<span class='bad'>NOT VALID</span>"
        warnings = "<br>".join(escape(w) for w in quality.warnings) or "none"
        rows.append(
            f"<tr><td>{record.id}</td><td>{_day(record.session_time_ns)}</td><td>{escape(record.source)}</td>"
            f"<td>{escape(record.method or 'not recorded')}</td><td>{valid}</td>"
            f"<td>{'–' if quality.n_samples is None else quality.n_samples}</td>"
            f"<td>{_number(quality.condition_number)}</td><td>{warnings}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _figure(series: Series, png: bytes | None) -> str:
    latest = next((p for p in reversed(series.points) if p.value is not None), None)
    caption = escape(series.label)
    if latest is not None:
        caption += f": latest {escape(_number(latest.value, series.unit))} ± {escape(_number(latest.std, series.unit))}"
        caption += f" (from {escape(latest.source)})"
    if series.changes:
        caption += f" — <span class='bad'>{len(series.changes)} change(s) flagged</span>"
    if png is None:
        return f"<figure><figcaption>{caption}: no finite estimate in any session.</figcaption></figure>"
    data = base64.b64encode(png).decode("ascii")
    alt = escape(f"Trend of {series.label} across sessions", quote=True)
    return f"<figure><img alt='{alt}' src='data:image/png;base64,{data}'><figcaption>{caption}</figcaption></figure>"
