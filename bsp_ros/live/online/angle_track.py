"""The last two causally filtered joint states, interpolated to a wrench's stamp (the recursive mode's input)."""

from __future__ import annotations

import numpy as np

__all__ = ["AngleTrack"]


class AngleTrack:
    """Keeps the two newest joint states and gives angles and velocities at a wrench stamp.

    Parameters
    ----------
    n_joints : int
        Joints per state.
    jump_s : float
        A stamp this far before the newest one is a clock jump (restart); closer, it is refused.
    reach_s : float
        A wrench farther than this from the states gets no angles.
    """

    def __init__(self, n_joints: int, jump_s: float = 1.0, reach_s: float = 0.1) -> None:
        self.n = n_joints
        self.jump_ns = int(jump_s * 1e9)
        self.reach_ns = int(reach_s * 1e9)
        self.states: list[tuple[int, np.ndarray, np.ndarray]] = []

    def add(self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray) -> bool:
        """Add one state; False (refused) if non-finite, of the wrong size, out of order or a duplicate."""
        if q_rad.size != self.n or not np.isfinite(q_rad).all():
            return False
        velocity = velocity_rad_s if velocity_rad_s.size == self.n else np.zeros(self.n)
        if self.states and t_ns <= self.states[-1][0]:
            if self.states[-1][0] - t_ns <= self.jump_ns:
                return False
            self.states = []  # the clock jumped back: start over
        self.states = [*self.states[-1:], (t_ns, q_rad, velocity)]
        return True

    def at(self, t_ns: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Angles (rad) and velocities (rad/s) linearly interpolated at ``t_ns``; None if no state is near."""
        if not self.states:
            return None
        (t0, q0, v0), (t1, q1, v1) = self.states[0], self.states[-1]
        if t_ns - t1 > self.reach_ns or t_ns < t0 - self.reach_ns:
            return None
        w = 0.0 if t1 == t0 else min(max((t_ns - t0) / (t1 - t0), 0.0), 1.0)
        return (1 - w) * q0 + w * q1, (1 - w) * v0 + w * v1
