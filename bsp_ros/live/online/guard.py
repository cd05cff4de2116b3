"""Input guard for live streams: finite values, increasing stamps, clock jumps; counts what it refuses."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


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

    def check(self, t_ns: int, values: np.ndarray) -> str:
        """``"ok"``, ``"refused"``, or ``"jump"`` / ``"gap"`` (the sample is accepted as the first of a new epoch)."""
        if t_ns <= 0:
            self.refused["bad_stamp"] += 1
            return "refused"
        if not np.isfinite(values).all():
            self.refused["non_finite"] += 1
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
