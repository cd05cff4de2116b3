"""Trend panels: one parameter per panel, every arm in it; invalid sessions as marked gaps, never as values."""

from __future__ import annotations

import io
from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")

import matplotlib.dates as mdates
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from bsp_ros.clinic.report.analysis import Series
from bsp_ros.clinic.report.labels import plain_number, short_label
from bsp_ros.clinic.store.records import ns_to_datetime

ARM_COLOURS = ("#1f5fa6", "#e07b00")
PRIOR_COLOUR = "#9a9a9a"
FLAG_COLOUR = "#c62828"
GAP_COLOUR = "#7a7a7a"

Panel = Sequence[Series]
"""One parameter: its series of every arm (first arm first)."""


def _day(time_ns: int) -> float:
    """Matplotlib's date number (days) of ``time_ns``."""
    return float(mdates.date2num(ns_to_datetime(time_ns)))


def _plain_axis(axes: Axes) -> None:
    axes.yaxis.set_major_formatter(FuncFormatter(lambda v, _: plain_number(v, 3)))
    axes.yaxis.set_major_locator(MaxNLocator(4))
    locator = mdates.AutoDateLocator(minticks=2, maxticks=5)
    axes.xaxis.set_major_locator(locator)
    axes.xaxis.set_major_formatter(mdates.DateFormatter("%d %b"))
    axes.tick_params(labelsize=7)
    axes.grid(True, alpha=0.3)


def draw_panel(axes: Axes, panel: Panel, arm_names: Sequence[str], *, compact: bool = False) -> None:
    """Draw one parameter's trend of every arm into ``axes``.

    Usable sessions are dots joined by a line with ±2 std bars; a band around the first usable value shows
    the MDC95 (measurement error); a flagged step is drawn in red. An invalid session is a dotted vertical
    line marked "not usable" (an untared session's left-out arm weight: "no tare"): it takes no value, so it
    neither joins the line nor scales the axis. A table prediction is a grey band (±2 SD).
    """
    for k, series in enumerate(panel):
        colour = ARM_COLOURS[k % len(ARM_COLOURS)]
        usable = [p for p in series.points if p.usable]
        xs = [_day(p.time_ns) for p in usable]
        ys = [p.value or 0.0 for p in usable]
        name = arm_names[k] if k < len(arm_names) else ""
        if series.has_prior:
            priors = [(_day(p.time_ns), p.prior) for p in series.points if p.prior is not None]
            axes.fill_between(
                [t for t, _ in priors],
                [q.mean - 2 * q.std for _, q in priors],
                [q.mean + 2 * q.std for _, q in priors],
                color=PRIOR_COLOUR,
                alpha=0.2,
                lw=0,
                label="table range" if k == 0 else None,
            )
        mdc = series.error.mdc95_at(ys[0]) if usable else None
        if usable and series.judged and mdc is not None and len(xs) > 1:
            axes.fill_between(
                [xs[0], xs[-1]],
                [ys[0] - mdc] * 2,
                [ys[0] + mdc] * 2,
                color=colour,
                alpha=0.08,
                lw=0,
                label="measurement error" if k == 0 else None,
            )
        if usable:
            axes.errorbar(
                xs,
                ys,
                yerr=[2 * (p.std or 0.0) for p in usable],
                color=colour,
                marker="o",
                ms=3.5,
                lw=1.3,
                capsize=2,
                elinewidth=0.8,
                label=name or None,
            )
        for change in series.changes:
            xx = [_day(change.before.time_ns), _day(change.after.time_ns)]
            yy = [change.before.value or 0.0, change.after.value or 0.0]
            axes.plot(xx, yy, color=FLAG_COLOUR, lw=2.2, zorder=4)
            axes.plot(xx[1:], yy[1:], "o", ms=8, mfc="none", mec=FLAG_COLOUR, mew=1.6, zorder=5)
        for p in series.points:
            if not p.valid or p.left_out:
                x = _day(p.time_ns)
                axes.axvline(x, color=GAP_COLOUR, ls=":", lw=1.2, zorder=1)
                axes.text(
                    x,
                    0.97,
                    "not usable" if not p.valid else "no tare",
                    transform=axes.get_xaxis_transform(),
                    rotation=90,
                    va="top",
                    ha="right",
                    fontsize=6,
                    color=GAP_COLOUR,
                )
    series = panel[0]
    title = short_label(series.key) + (f" [{series.unit}]" if series.unit else "")
    axes.set_title(title, loc="left", fontsize=7.5 if compact else 8.5)
    _plain_axis(axes)
    times = [_day(p.time_ns) for s in panel for p in s.points]
    if times:
        pad = max(1.0, 0.04 * (max(times) - min(times)))
        axes.set_xlim(min(times) - pad, max(times) + pad)


def panel_grid(figure: Figure, rect: tuple[float, float, float, float], count: int, ncols: int = 3) -> list[Axes]:
    """``count`` axes in a grid of ``ncols`` columns inside ``rect`` (left, bottom, width, height, figure
    fractions), 0.5 in left free under it for tick labels and a legend."""
    ncols = min(ncols, count)
    nrows = -(-count // ncols)
    left, bottom, width, height = rect
    below = 0.5 / figure.get_figheight()
    grid = figure.add_gridspec(
        nrows,
        ncols,
        left=left,
        right=left + width,
        bottom=bottom + below,
        top=bottom + height,
        wspace=0.32,
        hspace=0.5,
    )
    return [figure.add_subplot(grid[i // ncols, i % ncols]) for i in range(count)]


def draw_panels(
    figure: Figure,
    rect: tuple[float, float, float, float],
    panels: Sequence[Panel],
    arm_names: Sequence[str],
    ncols: int = 3,
) -> None:
    """Lay ``panels`` out in a grid inside ``rect`` (left, bottom, width, height, figure fractions)."""
    if not panels:
        return
    legend: dict[str, Artist] = {}
    for axes, panel in zip(panel_grid(figure, rect, len(panels), ncols), panels, strict=True):
        draw_panel(axes, panel, arm_names, compact=True)
        handles, labels = axes.get_legend_handles_labels()
        for handle, text in zip(handles, labels, strict=True):
            legend.setdefault(text, handle)
    left, bottom, width, _ = rect
    if legend:
        figure.legend(
            list(legend.values()),
            list(legend),
            loc="upper right",
            bbox_to_anchor=(left + width, bottom - 0.01),
            ncol=4,
            fontsize=7,
            frameon=False,
        )


def panels_figure(panels: Sequence[Panel], arm_names: Sequence[str], ncols: int = 3, width_in: float = 7.2) -> Figure:
    """A figure of ``panels`` alone (for the HTML page and PNG export)."""
    nrows = max(1, -(-len(panels) // ncols))
    height_in = 0.6 + 1.75 * nrows
    figure = Figure(figsize=(width_in, height_in), dpi=110)
    bottom = 0.05 / height_in
    draw_panels(figure, (0.07, bottom, 0.9, 1.0 - bottom - 0.25 / height_in), panels, arm_names, ncols)
    return figure


def figure_png(figure: Figure) -> bytes:
    """``figure`` as PNG bytes."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()
