"""Trend plots of one parameter across sessions, rendered to PNG with matplotlib's Agg backend."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import matplotlib.dates as mdates
from matplotlib.figure import Figure

from bsp_ros.clinic.report.analysis import Series
from bsp_ros.clinic.store.records import ns_to_datetime

DATA_COLOUR = "#1f5fa6"
PRIOR_COLOUR = "#9a9a9a"
FLAG_COLOUR = "#c62828"


def trend_figure(series: Series) -> Figure:
    """A figure of ``series``: values with ±2 std bands, the prior band, flagged changes in red."""
    figure = Figure(figsize=(7.5, 2.9), dpi=100)
    # Fixed margins (legend on the right): a layout engine would cost a third of the rendering time.
    figure.subplots_adjust(left=0.1, right=0.75, bottom=0.16, top=0.89)
    axes = figure.add_subplot()
    points = [p for p in series.points if p.value is not None]
    times = [_day(p.time_ns) for p in points]
    values = [p.value or 0.0 for p in points]
    stds = [p.std or 0.0 for p in points]
    priors = [(_day(p.time_ns), p.prior) for p in series.points if p.prior is not None]
    if priors:
        prior_times = [t for t, _ in priors]
        lower = [prior.mean - 2 * prior.std for _, prior in priors]
        upper = [prior.mean + 2 * prior.std for _, prior in priors]
        if len(priors) == 1:
            axes.axhspan(lower[0], upper[0], color=PRIOR_COLOUR, alpha=0.25, lw=0, label="table range (±2 SD)")
        else:
            axes.fill_between(
                prior_times, lower, upper, color=PRIOR_COLOUR, alpha=0.25, lw=0, label="table range (±2 SD)"
            )
    if points:
        axes.fill_between(
            times,
            [v - 2 * s for v, s in zip(values, stds, strict=True)],
            [v + 2 * s for v, s in zip(values, stds, strict=True)],
            color=DATA_COLOUR,
            alpha=0.18,
            lw=0,
            label="uncertainty (±2 SD)",
        )
        axes.errorbar(
            times, values, yerr=[2 * s for s in stds], color=DATA_COLOUR, marker="o", ms=5, capsize=3, label="estimate"
        )
        invalid = [(t, v) for t, v, p in zip(times, values, points, strict=True) if not p.valid]
        if invalid:
            axes.plot(*zip(*invalid, strict=True), ls="none", marker="x", ms=9, mew=2, color="black", label="not valid")
    for change in series.changes:
        xs = [_day(change.before.time_ns), _day(change.after.time_ns)]
        ys = [change.before.value or 0.0, change.after.value or 0.0]
        axes.plot(xs, ys, color=FLAG_COLOUR, lw=2.5, zorder=4)
        axes.plot(xs[1:], ys[1:], "o", ms=12, mfc="none", mec=FLAG_COLOUR, mew=2, zorder=5)
    if series.changes:
        axes.plot([], [], color=FLAG_COLOUR, lw=2.5, label="unexplained change")
    axes.set_title(series.label, loc="left", fontsize=11)
    axes.set_ylabel(series.unit)
    axes.grid(True, alpha=0.3)
    axes.xaxis_date()
    locator = mdates.AutoDateLocator(minticks=3, maxticks=8)
    axes.xaxis.set_major_locator(locator)
    axes.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
    axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return figure


def _day(time_ns: int) -> float:
    """Matplotlib's date number (days) of ``time_ns``."""
    return float(mdates.date2num(ns_to_datetime(time_ns)))


def figure_png(figure: Figure) -> bytes:
    """``figure`` as PNG bytes."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()


def trend_png(series: Series) -> bytes:
    """PNG bytes of :func:`trend_figure` of ``series``."""
    return figure_png(trend_figure(series))
