"""Causally filtered joint states interpolated to a wrench's stamp, and their rates (the recursive mode's input)."""

from __future__ import annotations

import numpy as np

__all__ = ["AngleTrack"]


class AngleTrack:
    """Keeps the newest joint states: angles and velocities at a wrench stamp, rates at the newest state.

    Parameters
    ----------
    n_joints : int
        Joints per state.
    jump_s : float
        A stamp this far before the newest one is a clock jump (restart); closer, it is refused.
    reach_s : float
        A wrench farther than this from the states gets no angles.
    rate_window_s : float
        The angles' velocity and acceleration come from a quadratic fit over the states of this last span: long
        enough to average the marker noise out of a second derivative, short against a planned trajectory's 1 s
        ramps.
    """

    def __init__(self, n_joints: int, jump_s: float = 1.0, reach_s: float = 0.1, rate_window_s: float = 0.5) -> None:
        self.n = n_joints
        self.jump_ns = int(jump_s * 1e9)
        self.reach_ns = int(reach_s * 1e9)
        self.rate_window_ns = int(rate_window_s * 1e9)
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
        self.states.append((t_ns, q_rad, velocity))
        while len(self.states) > 2 and t_ns - self.states[0][0] > self.rate_window_ns:
            self.states.pop(0)
        return True

    def at(self, t_ns: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Angles (rad) and velocities (rad/s) linearly interpolated at ``t_ns`` between the two newest states;
        None if no state is near."""
        if not self.states:
            return None
        (t0, q0, v0), (t1, q1, v1) = self.states[-2] if len(self.states) > 1 else self.states[-1], self.states[-1]
        if t_ns - t1 > self.reach_ns or t_ns < t0 - self.reach_ns:
            return None
        w = 0.0 if t1 == t0 else min(max((t_ns - t0) / (t1 - t0), 0.0), 1.0)
        return (1 - w) * q0 + w * q1, (1 - w) * v0 + w * v1

    def rates(self) -> tuple[int, np.ndarray, np.ndarray, np.ndarray] | None:
        """The newest state's stamp (ns), angles (rad), velocities (rad/s) and accelerations (rad/s^2) from a
        quadratic fit over the last ``rate_window_s``; None while that span holds fewer than 5 states or less
        than half the window."""
        if len(self.states) < 5 or self.states[-1][0] - self.states[0][0] < self.rate_window_ns // 2:
            return None
        t_newest = self.states[-1][0]
        t_s = np.array([(t - t_newest) / 1e9 for t, _, _ in self.states])
        q = np.array([state[1] for state in self.states])
        # Quadratic in time about the newest stamp: the constant, linear and quadratic coefficients per joint.
        coefficients = np.linalg.lstsq(np.vander(t_s, 3, increasing=True), q, rcond=None)[0]
        return t_newest, coefficients[0], coefficients[1], 2.0 * coefficients[2]
