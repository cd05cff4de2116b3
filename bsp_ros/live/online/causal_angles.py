"""Causal joint angles from streaming marker frames: what a live node can know at each instant."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from bsp_ros.core.joint_angles import joint_angles_from_positions, sagittal_from_world
from bsp_ros.core.streams import markers_for
from bsp_ros.live.online.streaming_filter import StreamingFilter
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True, kw_only=True)
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
    max_length_error_m : a frame whose segment length is further than this from the running median is
        rejected as inconsistent with the rigid chain (a swapped or mislabelled marker).
    max_speed_rad_s : a frame whose angles jump further from the previous accepted frame than this speed
        allows (plus ``jump_margin_rad``) is rejected: no arm moves so in a rehab cell.
    jump_margin_rad : allowance for marker noise in that jump test.
    """

    rate_hz: float = 50.0
    cutoff_hz: float = 5.0
    direction_cutoff_hz: float = 0.5
    max_gap_s: float = 0.1
    settle_s: float = 2.0
    length_frames: int = 3000
    max_length_error_m: float = 0.005
    max_speed_rad_s: float = 3.0
    jump_margin_rad: float = 0.03

    def __post_init__(self) -> None:
        check_positive("rate_hz", self.rate_hz, 10_000.0)
        check_positive("cutoff_hz", self.cutoff_hz, self.rate_hz / 2)
        check_positive("direction_cutoff_hz", self.direction_cutoff_hz, self.cutoff_hz)
        check_finite_scalar("max_gap_s", self.max_gap_s, 0.0, 10.0)
        check_finite_scalar("settle_s", self.settle_s, 0.0, 60.0)
        check_positive("length_frames", self.length_frames)
        check_positive("max_length_error_m", self.max_length_error_m, 1.0)
        check_positive("max_speed_rad_s", self.max_speed_rad_s, 1000.0)
        check_positive("jump_margin_rad", self.jump_margin_rad, 10.0)


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
    than ``max_gap_s`` restarts the filters so that no angle is interpolated across it. A frame
    inconsistent with the rigid chain (segment length off the running median, or an angle jump) is
    skipped too and counted in :attr:`n_rejected`: a run of them longer than ``max_gap_s`` ends in a
    restart, after which the jump test starts afresh.
    """

    # Frames of length history needed before the length test is trusted.
    _MIN_LENGTH_FRAMES = 50

    def __init__(self, n_segments: int, config: CausalAnglesConfig | None = None) -> None:
        self.config = config or CausalAnglesConfig()
        self.names = markers_for(n_segments)
        self.n = n_segments
        c = self.config
        self._sos_q = signal.butter(2, c.cutoff_hz, fs=c.rate_hz, output="sos")
        self._filter_q = StreamingFilter(self._sos_q)
        self._filter_v = StreamingFilter(signal.butter(2, c.direction_cutoff_hz, fs=c.rate_hz, output="sos"))
        # Ring buffer of the newest frames' segment lengths, and their median, recomputed at most every
        # 1% of the buffer: one frame barely moves a median over thousands, so recomputing it every frame is
        # work for nothing.
        self._length_rows = np.zeros((c.length_frames, n_segments))
        self._length_count = 0
        self._median_m: np.ndarray | None = None
        self._median_at = 0
        self._reset()
        self.n_restarts = 0
        self.n_rejected = 0
        self.last_raw_q_rad: np.ndarray | None = None  # unfiltered angles of the last accepted frame

    def _reset(self) -> None:
        self._filter_q.reset()
        self._filter_v.reset()
        self._last_t_ns: int | None = None
        self._start_t_ns: int | None = None
        self._previous_slow: np.ndarray | None = None
        self._previous_raw: np.ndarray | None = None

    @property
    def lengths_m(self) -> np.ndarray | None:
        """Running-median segment lengths (m) of the newest ``length_frames`` frames, None before the first."""
        return self._median_m

    def _add_lengths(self, lengths_m: np.ndarray) -> None:
        size = self._length_rows.shape[0]
        self._length_rows[self._length_count % size] = lengths_m
        self._length_count += 1
        held = min(self._length_count, size)
        if self._median_m is None or self._length_count - self._median_at >= max(1, held // 100):
            self._median_m = np.median(self._length_rows[:held], axis=0)
            self._median_at = self._length_count

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
        points = np.empty((len(self.names), 2))
        for k, name in enumerate(self.names):
            position = positions_m.get(name)
            if position is None or not np.isfinite(position).all():
                return None
            points[k] = sagittal_from_world(position)
        if self._last_t_ns is not None and t_ns <= self._last_t_ns:
            return None
        if self._last_t_ns is not None and (t_ns - self._last_t_ns) > self.config.max_gap_s * 1e9:
            self._reset()
            self.n_restarts += 1
        lengths = np.hypot(*np.diff(points, axis=0).T)
        off_chain = (
            self._median_m is not None
            and self._length_count >= self._MIN_LENGTH_FRAMES
            and bool((np.abs(lengths - self._median_m) > self.config.max_length_error_m).any())
        )
        # Lengths of every frame feed the median, so that a re-placed marker is accepted once it is the norm.
        self._add_lengths(lengths)
        raw = joint_angles_from_positions(points[None])[0]
        if self._previous_raw is not None:  # keep angles continuous across +-pi
            raw = self._previous_raw + np.angle(np.exp(1j * (raw - self._previous_raw)))
            assert self._last_t_ns is not None
            allowed = self.config.max_speed_rad_s * (t_ns - self._last_t_ns) / 1e9 + self.config.jump_margin_rad
            off_chain = off_chain or bool((np.abs(raw - self._previous_raw) > allowed).any())
        if off_chain:
            self.n_rejected += 1
            return None
        self._previous_raw = raw
        self.last_raw_q_rad = raw
        if self._start_t_ns is None:
            self._start_t_ns = t_ns
        q = self._filter_q.step(raw)
        slow = self._filter_v.step(raw)
        velocity = np.zeros(self.n)
        if self._previous_slow is not None and self._last_t_ns is not None:
            velocity = (slow - self._previous_slow) / ((t_ns - self._last_t_ns) / 1e9)
        self._previous_slow = slow
        self._last_t_ns = t_ns
        if t_ns - self._start_t_ns < self.config.settle_s * 1e9:
            return None
        assert self._median_m is not None
        return AngleSample(t_ns, q, velocity, self._median_m)

    def accepted(self, t_ns: int) -> bool:
        """True if the frame stamped ``t_ns`` was the last one taken in."""
        return self._last_t_ns == t_ns
