"""Inverse dynamics of the planar arm by a Newton-Euler recursion (the simulator's physics, no estimator code)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from bsp_ros.core.simulation.checks import GRAVITY_M_S2


@dataclass(frozen=True)
class PlanarChain:
    """A planar serial chain in the world y-z plane, rotating about x (docs/contract.md angle conventions).

    Attributes
    ----------
    lengths_m : (n,) joint-to-joint lengths a_j, m (the last: to the contact point).
    masses_kg : (n,) segment masses, kg.
    com_along_m : (n,) COM distance from the proximal joint along the segment axis, m.
    com_normal_m : (n,) COM offset normal to the axis, m, + 90 deg counter-clockwise.
    inertia_com_kgm2 : (n,) inertia about the COM for rotation about x, kg m^2.
    gravity_m_s2 : magnitude of gravity, along -z.
    """

    lengths_m: tuple[float, ...]
    masses_kg: tuple[float, ...]
    com_along_m: tuple[float, ...]
    com_normal_m: tuple[float, ...]
    inertia_com_kgm2: tuple[float, ...]
    gravity_m_s2: float = GRAVITY_M_S2

    @property
    def n(self) -> int:
        """Number of segments."""
        return len(self.lengths_m)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x component of the cross product of (..., 2) y-z vectors."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _perp(v: np.ndarray) -> np.ndarray:
    """``e_x x v`` for (..., 2) y-z vectors: v turned 90 deg counter-clockwise."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def inverse_dynamics_nm(
    chain: PlanarChain, q_rad: npt.ArrayLike, qdot_rad_s: npt.ArrayLike, qddot_rad_s2: npt.ArrayLike
) -> np.ndarray:
    """Joint torques that move the chain along ``q(t)`` against gravity with no load at its end.

    ``tau = M(q) q'' + C(q, q') q' + tau_G(q)``, computed by the Newton-Euler recursion: velocities and
    accelerations outward from the fixed shoulder, forces and moments inward from the free end.

    Parameters
    ----------
    chain : the segments.
    q_rad, qdot_rad_s, qddot_rad_s2 : (N, n) joint angles (q1 absolute from +y, then relative), rad,
        their velocities, rad/s, and accelerations, rad/s^2.

    Returns
    -------
    (N, n) float64 ndarray
        Torque about +x that joint i must apply to the distal part of the chain, Nm (the driver's
        torque: positive holds a forward-reaching arm up).
    """
    q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
    qd = np.atleast_2d(np.asarray(qdot_rad_s, dtype=np.float64))
    qdd = np.atleast_2d(np.asarray(qddot_rad_s2, dtype=np.float64))
    count, n = q.shape
    phi, omega, alpha = np.cumsum(q, axis=1), np.cumsum(qd, axis=1), np.cumsum(qdd, axis=1)
    axis = np.stack([np.cos(phi), np.sin(phi)], axis=-1)  # (N, n, 2) unit vectors along the segments
    lengths = np.asarray(chain.lengths_m)[None, :, None]
    along = np.asarray(chain.com_along_m)[None, :, None]
    normal = np.asarray(chain.com_normal_m)[None, :, None]
    link = lengths * axis  # joint j -> joint j + 1
    com = along * axis + normal * _perp(axis)  # joint j -> COM j
    gravity = np.array([0.0, -chain.gravity_m_s2])

    # Outward: linear acceleration of each joint and COM (2D: alpha x r = alpha perp(r), w x (w x r) = -w^2 r).
    w2, al = (omega**2)[..., None], alpha[..., None]
    joint_acc = np.zeros((count, n + 1, 2))
    com_acc = np.empty((count, n, 2))
    for j in range(n):
        joint_acc[:, j + 1] = joint_acc[:, j] + al[:, j] * _perp(link[:, j]) - w2[:, j] * link[:, j]
        com_acc[:, j] = joint_acc[:, j] + al[:, j] * _perp(com[:, j]) - w2[:, j] * com[:, j]

    # Inward: f_j, n_j = force and moment the proximal part exerts on segment j at joint j.
    masses = np.asarray(chain.masses_kg)
    inertia = np.asarray(chain.inertia_com_kgm2)
    force_next = np.zeros((count, 2))
    moment_next = np.zeros(count)
    tau = np.empty((count, n))
    for j in range(n - 1, -1, -1):
        force = masses[j] * (com_acc[:, j] - gravity) + force_next
        # Moments about COM j: I alpha = n_j - n_{j+1} + (joint_j - c_j) x f_j - (joint_{j+1} - c_j) x f_{j+1}.
        moment = (
            inertia[j] * alpha[:, j]
            + moment_next
            + _cross(com[:, j], force)
            + _cross(link[:, j] - com[:, j], force_next)
        )
        tau[:, j] = moment
        force_next, moment_next = force, moment
    return tau
