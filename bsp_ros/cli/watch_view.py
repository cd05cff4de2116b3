"""What `bsp watch` shows of a running cell, from the messages it receives: a plain class, no ROS (tested alone).

The estimate (each parameter with its std and the largest term of its uncertainty budget), the verdict with its
cause, the precision signal, the weight support, and the nodes' input rates and lost samples (differences of the
counters they publish on /diagnostics).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from bsp_ros.cli.live_table import estimate_rows, quantity_cells, state_line, support_line
from bsp_ros.core.estimate_schema import Estimate, Quantity
from bsp_ros.core.findings import plain_cause
from bsp_ros.live.online.precision import PrecisionState

__all__ = ["ESTIMATE_LATE_S", "CounterRate", "InputRates", "WatchView"]

#: An estimate older than this (s) is called late: bsp_identifier publishes 5 a second by default.
ESTIMATE_LATE_S = 2.0
#: The nodes' names on /diagnostics and the counters the rates and losses come from.
IDENTIFIER = "bsp_identifier"
ANGLES = "joint_angle_estimator"
# Samples a node received and could not use: refused (non-finite, out of order, duplicate, absurd), waiting for the
# wrench frame's first transform, a tare of another frame; frames missing a marker, rejected by the rigid chain.
IDENTIFIER_LOST = ("refused", "waiting_for_tf", "tare_frame_mismatch")
ANGLES_LOST = ("incomplete_frames", "rejected_frames", "refused", "frames_without_contact_point")


class CounterRate:
    """The rate of a cumulative counter over the last ``window_s`` of its stamps (a restarted node: started over).

    Parameters
    ----------
    window_s : the span the rate is taken over, s.
    """

    def __init__(self, window_s: float = 5.0) -> None:
        self.window_s = window_s
        self.samples: deque[tuple[float, int]] = deque()

    def add(self, t_s: float, count: int) -> None:
        """The counter's value ``count`` stamped ``t_s`` (s)."""
        if self.samples:
            t_last, count_last = self.samples[-1]
            if t_s <= t_last:
                return  # a repeated or reordered stamp
            if count < count_last:
                self.samples.clear()  # the counter went back: the node restarted
        self.samples.append((t_s, count))
        while len(self.samples) > 2 and t_s - self.samples[0][0] > self.window_s:
            self.samples.popleft()

    @property
    def rate_hz(self) -> float | None:
        """Counts per second over the kept span, or None before two samples."""
        if len(self.samples) < 2:
            return None
        (t0, c0), (t1, c1) = self.samples[0], self.samples[-1]
        return (c1 - c0) / (t1 - t0)


@dataclass(frozen=True, kw_only=True)
class InputRates:
    """The inputs as the nodes took them.

    Attributes
    ----------
    wrench_hz, angles_hz : wrenches and joint angles bsp_identifier took per second (None: unknown yet).
    marker_frames_hz : complete marker frames joint_angle_estimator processed per second (None: unknown yet).
    lost : what a node received and could not use since it started, ``{"<node>.<counter>": count}``.
    """

    wrench_hz: float | None
    angles_hz: float | None
    marker_frames_hz: float | None
    lost: Mapping[str, int]


def _count(values: Mapping[str, str], key: str) -> int | None:
    try:
        return int(values[key])
    except (KeyError, ValueError):
        return None


class WatchView:
    """The latest of each thing `bsp watch` shows, and the table it draws (times in s on the caller's clock)."""

    def __init__(self) -> None:
        self.estimate: Estimate | None = None
        self.estimate_t_s: float | None = None
        self.estimates = 0
        self.unreadable = 0
        self.support_yzx: tuple[float, float, float] | None = None
        self.precision_signal: bool | None = None
        self.rates = {name: CounterRate() for name in ("wrench", "angles", "marker_frames")}
        self.lost: dict[str, int] = {}

    # -- messages ---------------------------------------------------------------------------------------
    def on_estimate(self, text: str, t_s: float) -> None:
        """A ``bsp/estimate_json`` message (one that is not an estimate document, or names a method or mode this
        version does not know, is counted and skipped)."""
        import json

        try:
            estimate = Estimate.from_json(json.loads(text))
            _ = estimate.mode  # an unknown mode raises here, not while the table is drawn
        except (ValueError, TypeError, KeyError, AttributeError):
            self.unreadable += 1
            return
        self.estimate, self.estimate_t_s = estimate, t_s
        self.estimates += 1

    def on_diagnostics(self, name: str, values: Mapping[str, str], stamp_ns: int) -> None:
        """One ``/diagnostics`` status: the identifier's and the angle estimator's counters."""
        t_s = stamp_ns / 1e9
        if name == IDENTIFIER:
            self._add("wrench", t_s, _count(values, "wrench"))
            angles = _count(values, "joint_states")
            self._add("angles", t_s, angles if angles is not None else _count(values, "raw_angles"))
            self._lost(name, values, IDENTIFIER_LOST)
        elif name == ANGLES:
            self._add("marker_frames", t_s, _count(values, "frames"))
            self._lost(name, values, ANGLES_LOST)

    def _add(self, what: str, t_s: float, count: int | None) -> None:
        if count is not None:
            self.rates[what].add(t_s, count)

    def _lost(self, node: str, values: Mapping[str, str], keys: Sequence[str]) -> None:
        for key in keys:
            count = _count(values, key)
            if count is not None:
                self.lost[f"{node}.{key}"] = count

    def on_support(self, wrench_yzx: tuple[float, float, float]) -> None:
        """A ``bsp/weight_support`` wrench ``[F_y (N), F_z (N), M_x (Nm)]``."""
        self.support_yzx = wrench_yzx

    def on_precision(self, reached: bool) -> None:
        """A ``bsp/precision_reached`` message."""
        self.precision_signal = reached

    # -- what is shown --------------------------------------------------------------------------------------
    def input_rates(self) -> InputRates:
        """The input rates and lost samples as the nodes last reported them."""
        return InputRates(
            wrench_hz=self.rates["wrench"].rate_hz,
            angles_hz=self.rates["angles"].rate_hz,
            marker_frames_hz=self.rates["marker_frames"].rate_hz,
            lost=dict(self.lost),
        )

    def exit_code(self) -> int:
        """0: the last estimate is valid; 1: it is invalid; 3: no estimate arrived."""
        if self.estimate is None:
            return 3
        return 0 if self.estimate.valid else 1

    def render(self, now_s: float, header: str) -> str:
        """The table: ``header``, the verdict and its cause, the precision, each parameter, support and inputs."""
        lines = [header]
        if self.estimate is None or self.estimate_t_s is None:
            lines.append("waiting for the first estimate on bsp/estimate_json (is bsp_identifier running?)")
        else:
            age_s = now_s - self.estimate_t_s
            if age_s > ESTIMATE_LATE_S:
                lines.append(f"no estimate for {age_s:.1f} s (bsp_identifier stopped?); the last one:")
            lines += self._verdict_lines()
            lines.append(self._precision_line())
            lines += self._parameter_lines()
        if self.support_yzx is None and self.estimate is not None and self.estimate.valid:
            lines.append("weight support: none received (bsp_identifier's support_fraction is 0, or no joint states)")
        else:
            lines.append(support_line(self.support_yzx))
        lines += self._input_lines()
        return "\n".join(lines)

    def _verdict_lines(self) -> list[str]:
        assert self.estimate is not None
        mode = self.estimate.mode
        lines = [state_line(self.estimate, warming_up=False) + (f" ({mode})" if mode else "")]
        cause = plain_cause(self.estimate.quality.findings)
        if cause is not None:
            lines.append(f"  cause: {cause[0]}; what to do: {cause[1]}")
        return lines

    def _precision_line(self) -> str:
        block = self.estimate.extra.get("precision") if self.estimate is not None else None
        state = None
        if isinstance(block, Mapping):
            try:
                state = PrecisionState.from_json(block)
            except (KeyError, TypeError, ValueError):
                state = None
        if state is None:
            if self.precision_signal is None:
                return "precision: no target (bsp_identifier's target_std_percent is 0)"
            return f"precision: {'REACHED' if self.precision_signal else 'not yet'} (bsp/precision_reached)"
        targets, limit = _targets(state), max((p.target for p in state.parameters), default=0.0)
        if state.reached or self.precision_signal:
            after = "" if state.reached_after_s is None else f" {state.reached_after_s:.1f} s into the session"
            return f"precision: REACHED{after}: {_within(state)}"
        worst = state.worst
        if state.within_s is not None:
            return f"precision: not yet: every target met for {state.within_s:.1f} of {state.hold_s:g} s"
        if worst is None or worst.relative_std is None:
            return f"precision: not yet: no std for {targets} yet (target {100 * limit:g} %)"
        return (
            f"precision: not yet: {worst.owner} {worst.quantity} std {100 * worst.relative_std:.2f} % "
            f"(target {100 * worst.target:g} %)"
        )

    def _parameter_lines(self) -> list[str]:
        assert self.estimate is not None
        lines = [f"{'parameter':28s} {'estimate':>10s} {'+- std':>9s} {'std %':>7s}  largest uncertainty"]
        for _, owner, key, quantity in estimate_rows(self.estimate):
            lines.append(
                f"{owner + ' ' + key:28s} {quantity_cells(quantity)} {_relative(quantity)}  {_largest(quantity)}"
            )
        return lines

    def _input_lines(self) -> list[str]:
        rates = self.input_rates()
        lost = ", ".join(f"{key} {count}" for key, count in rates.lost.items()) or "none reported yet"
        return [
            f"inputs: wrench {_hz(rates.wrench_hz)}, joint angles {_hz(rates.angles_hz)} (taken by {IDENTIFIER}); "
            f"marker frames {_hz(rates.marker_frames_hz)} ({ANGLES})",
            f"lost (received, not usable; since each node started): {lost}",
        ]


def _targets(state: PrecisionState) -> str:
    """The targeted parameters: ``the static moments of upper_arm, forearm``, else each ``owner quantity``."""
    if all(p.quantity == "static_moment_kgm" for p in state.parameters):
        return "the static moments of " + ", ".join(p.owner for p in state.parameters)
    return ", ".join(f"{p.owner} {p.quantity}" for p in state.parameters)


def _within(state: PrecisionState) -> str:
    """The targets met: ``... within 5 % std``, or each parameter's own target where they differ (a plan's)."""
    limits = {p.target for p in state.parameters}
    if len(limits) == 1:
        return f"{_targets(state)} within {100 * limits.pop():g} % std"
    return ", ".join(f"{p.owner} {p.quantity} within {100 * p.target:.3g} %" for p in state.parameters) + " std"


def _hz(rate: float | None) -> str:
    return "? Hz" if rate is None else f"{rate:.0f} Hz"


def _relative(quantity: Quantity | None) -> str:
    """The relative std in %, 7 characters (blank where unknown)."""
    if quantity is None or not quantity.finite or not quantity.value:
        return f"{'':>7s}"
    assert quantity.std is not None and quantity.value is not None
    relative = 100 * quantity.std / abs(quantity.value)
    return f"{relative:7.2f}" if math.isfinite(relative) else f"{'':>7s}"


def _largest(quantity: Quantity | None) -> str:
    """The budget's largest term and its share of the variance, e.g. ``sensor_zero 71 %``."""
    largest = quantity.largest_term() if quantity is not None else None
    if largest is None:
        return ""
    term, share = largest
    return f"{term} {100 * share:.0f} %"
