"""Causal joint angles from streaming marker frames: what a live node can know at each instant."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy import signal

from bsp_ros.joint_angles import joint_angles_from_positions, sagittal_from_world
from bsp_ros.streams import markers_for
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class CausalAnglesConfig:
    """Settings of :class:`CausalJointAngles`.

    Attributes
    ----------
    rate_hz : nominal marker frame rate.
    cutoff_hz : causal low-pass for the angles.
    direction_cutoff_hz : causal low-pass for the direction velocity (lags ~1/(2 pi f)).
    max_gap_s : a frame gap longer than this restarts the filters (no angle until they settle).
    settle_s : time after a (re)start before angles are published.
    length_frames : frames kept for the running-median segment lengths.
    """

    rate_hz: float = 50.0
    cutoff_hz: float = 5.0
    direction_cutoff_hz: float = 0.5
    max_gap_s: float = 0.1
    settle_s: float = 2.0
    length_frames: int = 3000

    def __post_init__(self) -> None:
        check_positive("rate_hz", self.rate_hz, 10_000.0)
        check_positive("cutoff_hz", self.cutoff_hz, self.rate_hz / 2)
        check_positive("direction_cutoff_hz", self.direction_cutoff_hz, self.cutoff_hz)
        check_finite_scalar("max_gap_s", self.max_gap_s, 0.0, 10.0)
        check_finite_scalar("settle_s", self.settle_s, 0.0, 60.0)
        check_positive("length_frames", self.length_frames)


@dataclass(frozen=True)
class AngleSample:
    """One causal estimate: stamp (ns), angles (n,) rad, direction velocity (n,) rad/s, lengths (n,) m."""

    t_ns: int
    q_rad: np.ndarray
    velocity_rad_s: np.ndarray
    lengths_m: np.ndarray


class CausalJointAngles:
    """Joint angles frame by frame with causal filters and occlusion handling.

    A frame needs every marker of the chain; a frame with a marker missing is skipped, and a gap longer
    than ``max_gap_s`` restarts the filters so that no angle is interpolated across it.
    """

    def __init__(self, n_segments: int, config: CausalAnglesConfig | None = None) -> None:
        self.config = config or CausalAnglesConfig()
        self.names = markers_for(n_segments)
        self.n = n_segments
        c = self.config
        self._sos_q = signal.butter(2, c.cutoff_hz, fs=c.rate_hz, output="sos")
        self._sos_v = signal.butter(2, c.direction_cutoff_hz, fs=c.rate_hz, output="sos")
        self._lengths: deque[np.ndarray] = deque(maxlen=c.length_frames)
        self._reset()
        self.n_restarts = 0
        self.last_raw_q_rad: np.ndarray | None = None  # unfiltered angles of the last accepted frame

    def _reset(self) -> None:
        self._zi_q: np.ndarray | None = None
        self._zi_v: np.ndarray | None = None
        self._last_t_ns: int | None = None
        self._start_t_ns: int | None = None
        self._previous_slow: np.ndarray | None = None
        self._previous_raw: np.ndarray | None = None

    @property
    def lengths_m(self) -> np.ndarray | None:
        """Running-median segment lengths (m), None before the first frame."""
        return np.median(np.array(self._lengths), axis=0) if self._lengths else None

    def group_delay_s(self) -> float:
        """Low-frequency group delay (s) of the angle filter: the age of what a filtered angle describes."""
        b, a = signal.sos2tf(self._sos_q)
        _, delay = signal.group_delay((b, a), w=[1e-3], fs=self.config.rate_hz)
        return float(delay[0]) / self.config.rate_hz

    def update(self, t_ns: int, positions_m: dict[str, np.ndarray]) -> AngleSample | None:
        """Feed one mocap frame; return the causal estimate once the filters have settled.

        The frame's unfiltered angles are kept in :attr:`last_raw_q_rad` whenever it is accepted.

        Parameters
        ----------
        t_ns : frame stamp (ns); a stamp not after the previous one is ignored.
        positions_m : marker name -> (3,) world position (m); missing or non-finite markers skip the frame.
        """
        if any(name not in positions_m or not np.isfinite(positions_m[name]).all() for name in self.names):
            return None
        if self._last_t_ns is not None and t_ns <= self._last_t_ns:
            return None
        if self._last_t_ns is not None and (t_ns - self._last_t_ns) > self.config.max_gap_s * 1e9:
            self._reset()
            self.n_restarts += 1
        points = np.array([sagittal_from_world(positions_m[name]) for name in self.names])
        self._lengths.append(np.linalg.norm(np.diff(points, axis=0), axis=1))
        raw = joint_angles_from_positions(points[None])[0]
        if self._previous_raw is not None:  # keep angles continuous across +-pi
            raw = self._previous_raw + np.angle(np.exp(1j * (raw - self._previous_raw)))
        self._previous_raw = raw
        self.last_raw_q_rad = raw
        if self._zi_q is None:
            zi = signal.sosfilt_zi(self._sos_q)
            self._zi_q = zi[:, :, None] * raw[None, None, :]
            self._zi_v = signal.sosfilt_zi(self._sos_v)[:, :, None] * raw[None, None, :]
            self._start_t_ns = t_ns
        q, self._zi_q = signal.sosfilt(self._sos_q, raw[None, :], axis=0, zi=self._zi_q)
        slow, self._zi_v = signal.sosfilt(self._sos_v, raw[None, :], axis=0, zi=self._zi_v)
        velocity = np.zeros(self.n)
        if self._previous_slow is not None and self._last_t_ns is not None:
            velocity = (slow[0] - self._previous_slow) / ((t_ns - self._last_t_ns) / 1e9)
        self._previous_slow = slow[0]
        self._last_t_ns = t_ns
        assert self._start_t_ns is not None
        if t_ns - self._start_t_ns < self.config.settle_s * 1e9:
            return None
        return AngleSample(t_ns, q[0], velocity, np.median(np.array(self._lengths), axis=0))

    def accepted(self, t_ns: int) -> bool:
        """True if the frame stamped ``t_ns`` was the last one taken in."""
        return self._last_t_ns == t_ns
