"""Input guard for live streams: finite and physical values, increasing stamps, clock jumps; counts what it refuses."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bsp_ros.core.identification.data import MAX_FORCE_N, MAX_TORQUE_NM


def absurd_wrench_yzx(wrench_yzx: np.ndarray) -> bool:
    """Whether a finite ``[F_y (N), F_z (N), M_x (Nm)]`` is beyond any arm's (a sensor's glitch), by the limits
    `bsp identify` removes samples at (``MAX_FORCE_N``, ``MAX_TORQUE_NM``).

    One such sample in a block mean or a fit's noise estimate makes every estimate of the window invalid where the
    rest of its samples are sound.
    """
    return (
        math.hypot(float(wrench_yzx[0]), float(wrench_yzx[1])) > MAX_FORCE_N
        or abs(float(wrench_yzx[2])) > MAX_TORQUE_NM
    )


@dataclass
class StreamGuard:
    """Decides whether a live sample may enter an estimate.

    A stamp at or before the previous one is refused (out of order or duplicate); a stamp more than
    ``jump_back_s`` before it is a backwards clock jump (a bag replayed with ``--loop``, a reset clock):
    the caller must restart, since nothing before the jump belongs with what follows. A forward gap longer
    than ``session_gap_s`` starts a new session: the caller restarts too.
    """

    name: str
    jump_back_s: float = 1.0
    session_gap_s: float = 5.0
    last_t_ns: int | None = None
    refused: dict[str, int] = field(default_factory=lambda: {"non_finite": 0, "out_of_order": 0, "bad_stamp": 0})
    clock_jumps: int = 0
    # True for a finite sample no sensor of this stream could give (refused and counted as "absurd"), or None.
    absurd: Callable[[np.ndarray], bool] | None = None

    def check(self, t_ns: int, values: np.ndarray) -> str:
        """``"ok"``, ``"refused"``, or ``"jump"`` / ``"gap"`` (the sample is accepted as the first of a new epoch)."""
        if t_ns <= 0:
            self.refused["bad_stamp"] += 1
            return "refused"
        if not np.isfinite(values).all():
            self.refused["non_finite"] += 1
            return "refused"
        if self.absurd is not None and self.absurd(values):
            self.refused["absurd"] = self.refused.get("absurd", 0) + 1
            return "refused"
        if self.last_t_ns is not None and t_ns <= self.last_t_ns:
            if self.last_t_ns - t_ns > self.jump_back_s * 1e9:
                self.clock_jumps += 1
                self.last_t_ns = t_ns
                return "jump"
            self.refused["out_of_order"] += 1
            return "refused"
        gap = self.last_t_ns is not None and t_ns - self.last_t_ns > self.session_gap_s * 1e9
        self.last_t_ns = t_ns
        return "gap" if gap else "ok"
