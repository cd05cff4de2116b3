"""The recursive mode's per-sample path: guarded wrench samples and causal joint states into the recursive filter."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.recursive import RecursiveConfig, RecursiveIdentifier
from bsp_ros.core.model import contact_torques_one_nm
from bsp_ros.live.online.angle_track import AngleTrack
from bsp_ros.live.online.guard import StreamGuard

__all__ = ["RecursiveFeed"]


class RecursiveFeed:
    """Feeds :class:`RecursiveIdentifier` one wrench at a time, with angles interpolated to its stamp.

    Non-finite, out-of-order and duplicate wrenches are refused (:class:`StreamGuard`); a backwards clock
    jump or a long gap restarts the filter.

    Parameters
    ----------
    n_segments : int
        Segments of the arm.
    passive : PassiveModel
        Passive joint moment model.
    """

    def __init__(self, n_segments: int, passive: PassiveModel) -> None:
        self.n = n_segments
        self.identifier = RecursiveIdentifier(n_segments, RecursiveConfig(passive=passive))
        self.guard = StreamGuard("wrench")
        self.angles = AngleTrack(n_segments)
        self._terms = len(passive.local)
        self.passive_joints: tuple[str, ...] = tuple(name for key, name in self.identifier.names if key == "coulomb_nm")

    def add_joint_state(self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray) -> bool:
        """A causally filtered joint state; False if refused."""
        return self.angles.add(t_ns, q_rad, velocity_rad_s)

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
            self.identifier.reset()
        if verdict == "refused":
            return False, None
        if lengths_m is None:
            return True, None
        angles = self.angles.at(t_ns)
        if angles is None:  # no angle near this wrench
            return True, None
        q, v = angles
        tau = contact_torques_one_nm(q, lengths_m, wrench_yzx)
        if not self.identifier.update(t_ns, q, v, tau):
            return True, None
        return True, np.asarray(self.identifier.theta[self.n :: self._terms], dtype=np.float64)

    def reset(self) -> None:
        """Restart the filter (e.g. the wrench frame's rotation changed)."""
        self.identifier.reset()
