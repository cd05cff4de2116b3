"""Causal joint states smoothed with zero phase half a window behind the newest (the recursive mode's input)."""

from __future__ import annotations

import bisect

import numpy as np

__all__ = ["AngleTrack", "Kinematics"]

#: (stamp ns, angles (n,) rad, velocities (n,) rad/s, accelerations (n,) rad/s^2) at one joint state.
Kinematics = tuple[int, np.ndarray, np.ndarray, np.ndarray]


class AngleTrack:
    """Joint angles, velocities and accelerations from a quadratic fit centred on each joint state.

    A causal direction velocity lags the motion (a 0.5 Hz low-pass by 0.3 s): after every reversal it keeps the
    old sign for a while, and a friction amplitude fitted on it comes out low (by a fifth to a third at 0.12
    rad/s). A fit centred on the state, over the states within ``half_window_s`` either side, has no lag: each
    state's kinematics are known once the states half a window after it have arrived, so the recursive filter
    runs that much behind the stream (a fraction of its memory).

    Parameters
    ----------
    n_joints : int
        Joints per state.
    jump_s : float
        A stamp this far before the newest one is a clock jump (restart); closer, it is refused.
    half_window_s : float
        Half the span of each fit: long enough to average the marker noise out of a slow wrist's velocity, short
        against a planned trajectory's 1 s ramps.
    """

    def __init__(self, n_joints: int, jump_s: float = 1.0, half_window_s: float = 0.5) -> None:
        self.n = n_joints
        self.jump_ns = int(jump_s * 1e9)
        self.half_ns = int(half_window_s * 1e9)
        self.t_ns: list[int] = []
        self.q_rad: list[np.ndarray] = []
        self._next = 0  # index of the next state to centre a fit on

    def add(self, t_ns: int, q_rad: np.ndarray) -> list[Kinematics] | None:
        """Add one state; the kinematics of the states it completes (oldest first), or None if it is refused
        (non-finite, of the wrong size, out of order or a duplicate). A backwards clock jump starts over."""
        if q_rad.size != self.n or not np.isfinite(q_rad).all():
            return None
        if self.t_ns and t_ns <= self.t_ns[-1]:
            if self.t_ns[-1] - t_ns <= self.jump_ns:
                return None
            self.reset()
        self.t_ns.append(int(t_ns))
        self.q_rad.append(np.asarray(q_rad, dtype=np.float64))
        done = []
        while self._next < len(self.t_ns) and self.t_ns[self._next] <= t_ns - self.half_ns:
            kinematics = self._centred(self._next)
            if kinematics is not None:
                done.append(kinematics)
            self._next += 1
        # States older than the next fit's window are no longer needed.
        if self._next < len(self.t_ns):
            keep_from = bisect.bisect_left(self.t_ns, self.t_ns[self._next] - self.half_ns)
            del self.t_ns[:keep_from], self.q_rad[:keep_from]
            self._next -= keep_from
        return done

    def _centred(self, k: int) -> Kinematics | None:
        """The fit centred on state ``k``; None where the states around it do not span most of the window (a
        gap, the start)."""
        t_center = self.t_ns[k]
        # bisect on the list itself: numpy's searchsorted would copy the list into an array at every call.
        lo = bisect.bisect_left(self.t_ns, t_center - self.half_ns)
        hi = bisect.bisect_right(self.t_ns, t_center + self.half_ns)
        if hi - lo < 7 or min(t_center - self.t_ns[lo], self.t_ns[hi - 1] - t_center) < 0.8 * self.half_ns:
            return None
        t_s = (np.array(self.t_ns[lo:hi]) - t_center) / 1e9
        coefficients = np.linalg.lstsq(np.vander(t_s, 3, increasing=True), np.array(self.q_rad[lo:hi]), rcond=None)[0]
        return t_center, coefficients[0], coefficients[1], 2.0 * coefficients[2]

    def reset(self) -> None:
        """Forget every state."""
        self.t_ns, self.q_rad, self._next = [], [], 0
