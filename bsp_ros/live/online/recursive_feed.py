"""The recursive mode's per-sample path: guarded wrench samples and joint kinematics into the recursive filter."""

from __future__ import annotations

import bisect
import collections

import numpy as np

from bsp_ros.core.dynamics import base_regressor_one
from bsp_ros.core.fusion import SubjectInfo, anthropometric_prior
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.priors import BasePrior, base_prior_for_subject
from bsp_ros.core.identification.recursive import RecursiveConfig, RecursiveIdentifier
from bsp_ros.core.model import contact_torques_one_nm, static_moments_kgm
from bsp_ros.live.online.angle_track import AngleTrack
from bsp_ros.live.online.guard import StreamGuard, absurd_wrench_yzx
from bsp_ros.live.online.spike_gate import SpikeGate

__all__ = ["RecursiveFeed"]

# A wrench between two joint states further apart than this (a marker dropout) gets no angles.
MAX_STATE_GAP_NS = 200_000_000
# Wrenches wait for the kinematics at their stamp at most this long (joint states stopped: they are dropped).
MAX_WAIT_NS = 5_000_000_000


class RecursiveFeed:
    """Feeds :class:`RecursiveIdentifier` one wrench at a time, with the joint kinematics at its stamp.

    Non-finite, absurd (beyond any arm's force), out-of-order and duplicate wrenches are refused
    (:class:`StreamGuard`); a backwards clock jump or a long gap restarts the filter. Spikes (far off the median of
    the wrenches around them, :class:`SpikeGate`) are taken but kept out of the filter, as `bsp identify` drops them:
    the filter weighs every sample it takes, and no later check can take one back.

    Angles, velocities (for the direction of friction) and accelerations come from fits centred on each joint
    state (:class:`AngleTrack`), so the filter runs half a fit window (0.5 s) behind the wrench stream: a
    wrench waits until the kinematics around its stamp are known, then they are interpolated to it. The joint
    state that makes them known folds the waiting wrenches in (one solve); the next wrench carries the new
    estimate out, so that its own callback only publishes.

    The arm's inertial torque ``M(q) q'' + C(q, q') q'`` is taken off each wrench's torque, as the windowed and
    offline fits model it: the static moments' share with the filter's current estimate (the prior's until it is
    plausible), the perpendicular moments and grouped inertias with their anthropometric prior means (the
    recursive filter identifies static moments and passive terms only). It is computed per joint state and
    interpolated, since one regressor per 1 kHz wrench would cost more than the filter.

    Parameters
    ----------
    n_segments : int
        Segments of the arm.
    passive : PassiveModel
        Passive joint moment model.
    subject : SubjectInfo
        Body data for the inertia prior (None: the population's).
    dynamics : bool
        False: quasi-static, as the method paper models it (no inertial torque).
    """

    def __init__(
        self, n_segments: int, passive: PassiveModel, subject: SubjectInfo | None = None, dynamics: bool = True
    ) -> None:
        self.n = n_segments
        self.subject = subject or SubjectInfo()
        self.dynamics = dynamics
        self.identifier = RecursiveIdentifier(n_segments, RecursiveConfig(passive=passive))
        self.guard = StreamGuard("wrench", absurd=absurd_wrench_yzx)
        self.spike_gate: SpikeGate[tuple[int, np.ndarray, np.ndarray]] = SpikeGate()
        self.angles = AngleTrack(n_segments)
        self._terms = len(passive.local)
        self.passive_joints: tuple[str, ...] = tuple(name for key, name in self.identifier.names if key == "coulomb_nm")
        # The lengths the prior was made for, its static moments (kg m) and its perpendicular moments and inertias.
        self._prior: tuple[np.ndarray, np.ndarray, BasePrior] | None = None
        # Per joint state, oldest first: stamp (ns), and angles, velocities, inertial torques (n,) each, in plain
        # floats (each 1 kHz wrench is interpolated between two of them).
        self._stamps: collections.deque[int] = collections.deque()
        self._rows: collections.deque[tuple[list[float], list[float], list[float]]] = collections.deque()
        self._pending: collections.deque[tuple[int, np.ndarray, np.ndarray]] = collections.deque()
        self._updated = False  # the filter took samples since add_wrench last reported its estimate

    def add_joint_state(
        self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray, lengths_m: np.ndarray | None = None
    ) -> bool:
        """A causally filtered joint state (with the segment lengths, m, for its inertial torque); False if refused.
        (The causal direction velocity is not used: the centred fits give a velocity without its lag.)"""
        done = self.angles.add(t_ns, q_rad)
        if done is None:
            return False
        if self._stamps and t_ns <= self._stamps[-1]:  # the track restarted on a clock jump
            self._stamps.clear()
            self._rows.clear()
        for stamp, q, qd, qdd in done:
            inertial = np.zeros(self.n)
            if self.dynamics and lengths_m is not None:
                inertial = self.inertial_torque_nm(q, qd, qdd, lengths_m)
            self._stamps.append(stamp)
            self._rows.append((q.tolist(), qd.tolist(), inertial.tolist()))
        while self._stamps and self._stamps[0] < t_ns - MAX_WAIT_NS:
            self._stamps.popleft()
            self._rows.popleft()
        if self._stamps:
            self._release(self._stamps[-1])
        return True

    def inertial_torque_nm(
        self, q_rad: np.ndarray, qd_rad_s: np.ndarray, qdd_rad_s2: np.ndarray, lengths_m: np.ndarray
    ) -> np.ndarray:
        """``M(q) q'' + C(q, q') q'`` (n,) Nm at one state, with the current static moments and the prior's
        perpendicular moments and grouped inertias."""
        if self._prior is None or np.abs(self._prior[0] - lengths_m).max() > 0.005:
            anthropometric = anthropometric_prior(self.subject, lengths_m)
            masses_kg, com_m = anthropometric.mean[: self.n], anthropometric.mean[self.n :]
            static_kgm = static_moments_kgm(lengths_m, masses_kg, com_m)
            self._prior = (lengths_m.copy(), static_kgm, base_prior_for_subject(self.subject, lengths_m))
        _, prior_static_kgm, prior = self._prior
        # The filter's static moments once they are plausible (an early, unconverged filter can be far off, and
        # its inertial share would then add more error than it removes), the prior's until then.
        static_kgm = self.identifier.theta[: self.n]
        if not ((static_kgm > 0.5 * prior_static_kgm) & (static_kgm < 2.0 * prior_static_kgm)).all():
            static_kgm = prior_static_kgm
        parameters = np.concatenate((static_kgm, prior.perpendicular_mean_kgm, prior.inertia_mean_kgm2))
        regressor = base_regressor_one(q_rad, qd_rad_s, qdd_rad_s2, lengths_m, gravity_m_s2=0.0)
        return np.asarray(regressor) @ parameters

    def kinematics_at(self, t_ns: int) -> tuple[list[float], list[float], list[float]] | None:
        """Angles (rad), velocities (rad/s) and inertial torques (Nm), (n,) each, interpolated at ``t_ns`` between
        the joint states around it; None outside them or across a gap."""
        after = bisect.bisect_left(self._stamps, t_ns)
        if after == len(self._stamps) or (after == 0 and self._stamps[0] != t_ns):
            return None
        if self._stamps[after] == t_ns:
            return self._rows[after]
        t0, t1 = self._stamps[after - 1], self._stamps[after]
        if t1 - t0 > MAX_STATE_GAP_NS:
            return None
        w = (t_ns - t0) / (t1 - t0)
        (q0, v0, i0), (q1, v1, i1) = self._rows[after - 1], self._rows[after]

        def blend(x0: list[float], x1: list[float]) -> list[float]:
            return [(1 - w) * a + w * b for a, b in zip(x0, x1, strict=True)]

        return blend(q0, q1), blend(v0, v1), blend(i0, i1)

    def add_wrench(
        self, t_ns: int, wrench_yzx: np.ndarray, lengths_m: np.ndarray | None
    ) -> tuple[bool, np.ndarray | None]:
        """One wrench ``[F_y, F_z, M_x]`` in world (N, Nm); it joins the filter once the kinematics at its stamp
        are known, with the wrenches before it that waited.

        Returns
        -------
        (accepted, coulomb_nm)
            Whether the sample was accepted, and the joints' Coulomb amplitudes (Nm) if the filter took samples
            since the last wrench.
        """
        verdict = self.guard.check(t_ns, wrench_yzx)
        if verdict in ("jump", "gap"):
            self.reset()
        if verdict == "refused":
            return False, None
        if lengths_m is not None:
            wrench = np.asarray(wrench_yzx, dtype=np.float64)
            judged = self.spike_gate.push(wrench.tolist(), (t_ns, wrench, lengths_m))
            if judged is not None and not judged[1]:
                self._pending.append(judged[0])
        # Usually the joint states have released everything before this wrench; not a wrench that came later
        # than the kinematics at its stamp, nor those left waiting when the joint states stopped.
        self._release(self._stamps[-1] if self._stamps else None, t_ns - MAX_WAIT_NS)
        if not self._updated:
            return True, None
        self._updated = False
        return True, np.asarray(self.identifier.theta[self.n :: self._terms], dtype=np.float64)

    def _release(self, known_until_ns: int | None, expired_ns: int | None = None) -> None:
        """Fold in the waiting wrenches whose kinematics are known (stamped up to ``known_until_ns``), together:
        one solve. Those stamped before ``expired_ns`` leave the queue too, folded if they have kinematics."""
        ready = []
        while self._pending and (
            (expired_ns is not None and self._pending[0][0] < expired_ns)
            or (known_until_ns is not None and self._pending[0][0] <= known_until_ns)
        ):
            stamp, wrench, lengths = self._pending.popleft()
            kinematics = self.kinematics_at(stamp)
            if kinematics is None:  # no joint state near it, or it waited too long
                continue
            q, velocity, inertial = kinematics
            tau = contact_torques_one_nm(q, lengths, wrench)
            ready.append((stamp, q, velocity, [a - b for a, b in zip(tau, inertial, strict=True)]))
        if ready and self.identifier.update_many(ready):
            self._updated = True

    def reset(self) -> None:
        """Restart the filter (e.g. the wrench frame's rotation changed)."""
        self.identifier.reset()
        self.spike_gate.reset()
        self._pending.clear()
        self._updated = False
