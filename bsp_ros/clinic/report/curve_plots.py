"""Torque-angle panels: per joint, the first and the latest usable session's passive moment over its angle."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")

from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, MaxNLocator

from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.report.curve_views import CurveSession, CurveView, curve_views
from bsp_ros.clinic.report.labels import plain_number
from bsp_ros.clinic.report.plots import ARM_COLOURS, FLAG_COLOUR, GAP_COLOUR, panel_grid
from bsp_ros.clinic.report.summary import arm_title, day
from bsp_ros.clinic.store.curves import sample_curve


def _draw_session(axes: Axes, session: CurveSession, colour: str, style: str, label: str) -> None:
    low = [m - 2.0 * s for m, s in zip(session.moment_nm, session.std_nm, strict=True)]
    high = [m + 2.0 * s for m, s in zip(session.moment_nm, session.std_nm, strict=True)]
    axes.fill_between(session.angle_deg, low, high, color=colour, alpha=0.15, lw=0)
    axes.plot(session.angle_deg, session.moment_nm, style, color=colour, lw=1.5, label=label)


def draw_curve(axes: Axes, view: CurveView, colour: str, title: str) -> None:
    """Draw one joint's first (dashed grey) and latest (solid ``colour``) passive curve with ±2 SD bands."""
    first, latest = view.first, view.latest
    _draw_session(axes, first, GAP_COLOUR, "--", f"first usable (no. {first.number}, {day(first.time_ns)})")
    if latest is not None:
        _draw_session(axes, latest, colour, "-", f"latest usable (no. {latest.number}, {day(latest.time_ns)})")
        # The changed angles are the store's sampled ones (multiples of 5 deg): the same interpolation gives them.
        sampled = sample_curve(
            {"angle_deg": list(latest.angle_deg), "moment_nm": list(latest.moment_nm), "std_nm": list(latest.std_nm)}
        )
        for angle in view.changed_deg:
            axes.plot([angle], [sampled[angle][0]], "o", ms=7, mfc="none", mec=FLAG_COLOUR, mew=1.6)
    axes.axhline(0.0, color="#bbbbbb", lw=0.6, zorder=0)
    axes.set_title(title, loc="left", fontsize=8)
    axes.set_xlabel("angle [°]", fontsize=7)
    axes.set_ylabel("moment [N·m]", fontsize=7)
    axes.yaxis.set_major_formatter(FuncFormatter(lambda v, _: plain_number(v, 3)))
    axes.yaxis.set_major_locator(MaxNLocator(4))
    axes.xaxis.set_major_locator(MaxNLocator(5, integer=True))
    axes.tick_params(labelsize=7)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=6, frameon=False, loc="best")


def draw_curves(
    figure: Figure,
    rect: tuple[float, float, float, float],
    views: Sequence[CurveView],
    colours: Sequence[str],
    titles: Sequence[str],
) -> None:
    """Lay the torque-angle panels of ``views`` out in ``rect`` (figure fractions), three to a row."""
    if not views:
        return
    left, bottom, width, height = rect
    rect = (left, bottom, width * max(min(len(views), 3), 2) / 3, height)  # one panel takes two thirds, not all
    for axes, view, colour, title in zip(panel_grid(figure, rect, len(views)), views, colours, titles, strict=True):
        draw_curve(axes, view, colour, title)


def curves_figure(
    views: Sequence[CurveView], colours: Sequence[str], titles: Sequence[str], width_in: float = 7.2
) -> Figure:
    """A figure of the torque-angle panels alone (for the HTML page and PNG export)."""
    nrows = max(1, -(-len(views) // 3))
    height_in = 0.7 + 2.1 * nrows
    figure = Figure(figsize=(width_in, height_in), dpi=110)
    bottom = 0.05 / height_in
    draw_curves(figure, (0.08, bottom, 0.89, 1.0 - bottom - 0.25 / height_in), views, colours, titles)
    return figure


def curve_panels(analysis: Analysis) -> tuple[list[CurveView], list[str], list[str]]:
    """The views to draw, with each one's colour (its arm's, as in the trends) and panel title."""
    views = curve_views(analysis)
    colours = [ARM_COLOURS[analysis.arms.index(v.arm) % len(ARM_COLOURS)] for v in views]
    several = len(analysis.arms) > 1
    titles = [v.joint.capitalize() + (f" · {arm_title(analysis, v.arm).lower()}" if several else "") for v in views]
    return views, colours, titles
