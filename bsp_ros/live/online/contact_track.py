"""The robot's contact point at live motion-capture frames: the last seconds of `/robot/handle_pose`, interpolated."""

from __future__ import annotations

import bisect
import collections

import numpy as np

from bsp_ros.core.contact_point import contact_at


class RobotContactTrack:
    """Robot handle poses of the last ``keep_s`` seconds, interpolated at frame stamps as offline (:func:`contact_at`).

    A frame can take its contact point once a pose stamped at or after it has arrived (:meth:`covers`); the robot
    streams on its own clock rate, so a frame waits at most one robot period. A pose stamped before the newest
    is refused (counted), unless the clock jumped back by more than a second, which starts the track afresh.
    """

    def __init__(self, keep_s: float = 2.0) -> None:
        self.keep_ns = int(keep_s * 1e9)
        self.t_ns: collections.deque[int] = collections.deque()
        self.position_m: collections.deque[np.ndarray] = collections.deque()
        self.n_refused = 0

    @property
    def newest_ns(self) -> int | None:
        """Stamp of the newest pose, ns (None before the first)."""
        return self.t_ns[-1] if self.t_ns else None

    def add(self, t_ns: int, position_m: np.ndarray) -> bool:
        """Add one pose (contact point in ``world``, (3,) m) stamped ``t_ns``; False if refused."""
        if t_ns <= 0 or not np.isfinite(position_m).all():
            self.n_refused += 1
            return False
        if self.t_ns and t_ns <= self.t_ns[-1]:
            if self.t_ns[-1] - t_ns <= 1_000_000_000:
                self.n_refused += 1
                return False
            self.t_ns.clear()
            self.position_m.clear()
        self.t_ns.append(int(t_ns))
        self.position_m.append(np.asarray(position_m, dtype=np.float64))
        while self.t_ns[-1] - self.t_ns[0] > self.keep_ns:
            self.t_ns.popleft()
            self.position_m.popleft()
        return True

    def covers(self, t_ns: int) -> bool:
        """Whether a pose at or after ``t_ns`` has arrived (the contact point at ``t_ns`` is then known or never)."""
        return bool(self.t_ns) and self.t_ns[-1] >= t_ns

    def at(self, t_ns: int) -> np.ndarray | None:
        """The contact point at ``t_ns``, (3,) m; None outside the track or across a robot gap (``MAX_POSE_GAP_S``)."""
        after = bisect.bisect_right(self.t_ns, t_ns)
        if after == len(self.t_ns) and self.t_ns and self.t_ns[-1] == t_ns:
            after -= 1  # exactly at the newest pose
        if after == 0 or after == len(self.t_ns):
            return None
        stamps = np.array([self.t_ns[after - 1], self.t_ns[after]], dtype=np.int64)
        positions = np.array([self.position_m[after - 1], self.position_m[after]])
        keep, contact_m = contact_at(stamps, positions, np.array([t_ns], dtype=np.int64))
        return contact_m[0] if keep[0] else None
