"""The recursive mode's per-sample path: guarded wrench samples and causal joint states into the recursive filter."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.dynamics import base_parameters, base_regressor
from bsp_ros.core.fusion import SubjectInfo, anthropometric_prior
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.priors import BasePrior, base_prior_for_subject
from bsp_ros.core.identification.recursive import RecursiveConfig, RecursiveIdentifier
from bsp_ros.core.model import contact_torques_one_nm
from bsp_ros.live.online.angle_track import AngleTrack
from bsp_ros.live.online.guard import StreamGuard

__all__ = ["RecursiveFeed"]


class RecursiveFeed:
    """Feeds :class:`RecursiveIdentifier` one wrench at a time, with angles interpolated to its stamp.

    Non-finite, out-of-order and duplicate wrenches are refused (:class:`StreamGuard`); a backwards clock
    jump or a long gap restarts the filter.

    The arm's inertial torque ``M(q) q'' + C(q, q') q'`` is taken off each wrench's torque, as the windowed and
    offline fits model it: the static moments' share with the filter's current estimate, the perpendicular
    moments and grouped inertias with their anthropometric prior means (the recursive filter identifies static
    moments and passive terms only). Velocities and accelerations come from a quadratic fit over the last half
    second of joint states (:meth:`AngleTrack.rates`); the torque is computed per joint state and interpolated
    to the wrench stamps, since one regressor per 1 kHz wrench would cost more than the filter.

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
        # The lengths the prior was made for, its static moments (kg m) and its perpendicular moments and inertias.
        self._prior: tuple[np.ndarray, np.ndarray, BasePrior] | None = None
        self._inertial: list[tuple[int, np.ndarray]] = []  # the two newest (stamp, inertial torque (n,) Nm)
        self.identifier = RecursiveIdentifier(n_segments, RecursiveConfig(passive=passive))
        self.guard = StreamGuard("wrench")
        self.angles = AngleTrack(n_segments)
        self._terms = len(passive.local)
        self.passive_joints: tuple[str, ...] = tuple(name for key, name in self.identifier.names if key == "coulomb_nm")

    def add_joint_state(
        self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray, lengths_m: np.ndarray | None = None
    ) -> bool:
        """A causally filtered joint state (with the segment lengths, m, for its inertial torque); False if refused."""
        if not self.angles.add(t_ns, q_rad, velocity_rad_s):
            return False
        if self.dynamics and lengths_m is not None:
            rates = self.angles.rates()
            if rates is not None:
                stamp, q, qd, qdd = rates
                self._inertial = [*self._inertial[-1:], (stamp, self.inertial_torque_nm(q, qd, qdd, lengths_m))]
        return True

    def inertial_torque_nm(
        self, q_rad: np.ndarray, qd_rad_s: np.ndarray, qdd_rad_s2: np.ndarray, lengths_m: np.ndarray
    ) -> np.ndarray:
        """``M(q) q'' + C(q, q') q'`` (n,) Nm at one state, with the current static moments and the prior's
        perpendicular moments and grouped inertias."""
        if self._prior is None or np.abs(self._prior[0] - lengths_m).max() > 0.005:
            anthropometric = anthropometric_prior(self.subject, lengths_m)
            masses_kg, com_m = anthropometric.mean[: self.n], anthropometric.mean[self.n :]
            static_kgm = base_parameters(lengths_m, masses_kg, com_m, np.zeros(self.n))[: self.n]
            self._prior = (lengths_m.copy(), static_kgm, base_prior_for_subject(self.subject, lengths_m))
        _, prior_static_kgm, prior = self._prior
        # The filter's static moments once they are plausible (an early, unconverged filter can be far off, and
        # its inertial share would then add more error than it removes), the prior's until then.
        static_kgm = self.identifier.theta[: self.n]
        if not ((static_kgm > 0.5 * prior_static_kgm) & (static_kgm < 2.0 * prior_static_kgm)).all():
            static_kgm = prior_static_kgm
        parameters = np.concatenate((static_kgm, prior.perpendicular_mean_kgm, prior.inertia_mean_kgm2))
        regressor = base_regressor(q_rad[None], qd_rad_s[None], qdd_rad_s2[None], lengths_m, gravity_m_s2=0.0)[0]
        return np.asarray(regressor @ parameters)

    def _inertial_at(self, t_ns: int) -> np.ndarray | None:
        """The inertial torque interpolated at ``t_ns`` between the two newest, held beyond them up to the angles'
        reach; None when there is none near."""
        if not self._inertial:
            return None
        (t0, tau0), (t1, tau1) = self._inertial[0], self._inertial[-1]
        if t_ns - t1 > self.angles.reach_ns or t_ns < t0 - self.angles.reach_ns:
            return None
        w = 0.0 if t1 == t0 else min(max((t_ns - t0) / (t1 - t0), 0.0), 1.0)
        return (1 - w) * tau0 + w * tau1

    def add_wrench(
        self, t_ns: int, wrench_yzx: np.ndarray, lengths_m: np.ndarray | None
    ) -> tuple[bool, np.ndarray | None]:
        """One wrench ``[F_y, F_z, M_x]`` in world (N, Nm).

        Returns
        -------
        (accepted, coulomb_nm)
            Whether the sample was accepted, and the joints' Coulomb amplitudes (Nm) if the filter updated.
        """
        verdict = self.guard.check(t_ns, wrench_yzx)
        if verdict in ("jump", "gap"):
            self.reset()
        if verdict == "refused":
            return False, None
        if lengths_m is None:
            return True, None
        angles = self.angles.at(t_ns)
        if angles is None:  # no angle near this wrench
            return True, None
        q, v = angles
        tau = contact_torques_one_nm(q, lengths_m, wrench_yzx)
        inertial = self._inertial_at(t_ns)
        if inertial is not None:
            tau = [a - b for a, b in zip(tau, inertial.tolist(), strict=True)]
        if not self.identifier.update(t_ns, q, v, tau):
            return True, None
        return True, np.asarray(self.identifier.theta[self.n :: self._terms], dtype=np.float64)

    def reset(self) -> None:
        """Restart the filter (e.g. the wrench frame's rotation changed)."""
        self.identifier.reset()
        self._inertial = []
