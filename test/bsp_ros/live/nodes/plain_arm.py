"""The plain-rclpy cell's arm (numpy only, no bsp_ros code): its truth, motion and wrench.

The arm moves in the sagittal plane y-z (docs/contract.md), without friction, at up to about 1 rad/s^2: the wrench
the hand exerts on the sensor balances the arm's weight and its rigid-body inertia,
``J(q)^T w = -dV/dq - Q(q, q', q'')`` with ``V = g sum_k S_k sin(phi_k)``, ``S`` the grouped static moments,
``phi`` the absolute segment angles and ``Q`` the generalized inertial forces of the segments' masses and
inertias (written here from the segments' centre-of-mass accelerations, not from any bsp_ros model).
"""

from __future__ import annotations

import math

import numpy as np

G = 9.81
LENGTHS_M = np.array([0.30, 0.27, 0.08])
MASSES_KG = np.array([2.0, 1.2, 0.45])
COM_M = np.array([0.13, 0.12, 0.05])
INERTIA_COM_KGM2 = np.array([0.018, 0.009, 0.0005])  # about each centre of mass, normal to the plane
SHOULDER_M = np.array([0.0, 0.0, 1.2])
MARKERS = ("shoulder", "elbow", "wrist", "hand")


def static_moments_kgm() -> np.ndarray:
    """S_j = m_j l_j + a_j * (mass of the distal segments)."""
    distal = np.concatenate([np.cumsum(MASSES_KG[::-1])[::-1][1:], [0.0]])
    return MASSES_KG * COM_M + LENGTHS_M * distal


OFFSET_RAD = np.array([-0.4, 0.7, 0.1])
AMPLITUDE_RAD = np.array([0.6, 0.6, 0.5])
OMEGA_RAD_S = 2 * math.pi * np.array([0.11, 0.17, 0.23])
PHASE_RAD = np.array([0.0, 1.0, 2.0])


def angles_rad(t_s: float) -> np.ndarray:
    return OFFSET_RAD + AMPLITUDE_RAD * np.sin(OMEGA_RAD_S * t_s + PHASE_RAD)


def motion(t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint angles (rad), velocities (rad/s) and accelerations (rad/s^2) at ``t_s``."""
    phase = OMEGA_RAD_S * t_s + PHASE_RAD
    return (
        angles_rad(t_s),
        AMPLITUDE_RAD * OMEGA_RAD_S * np.cos(phase),
        -AMPLITUDE_RAD * OMEGA_RAD_S**2 * np.sin(phase),
    )


def _along(phi: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def _normal(phi: np.ndarray) -> np.ndarray:
    return np.stack([-np.sin(phi), np.cos(phi)], axis=-1)


def inertial_forces(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Generalized inertial forces (Nm): sum_k m_k (dp_k/dq_j) . a_k + I_k (dphi_k/dq_j) phi_k''.

    p_k is segment k's centre of mass, a_k its acceleration: each segment's tip and centre of mass move on
    circles about its proximal joint, ``l (phi'' n(phi) - phi'^2 u(phi))``, summed down the chain.
    """
    phi, phid, phidd = np.cumsum(q), np.cumsum(qd), np.cumsum(qdd)
    u, n = _along(phi), _normal(phi)
    tip_acc = LENGTHS_M[:, None] * (phidd[:, None] * n - (phid**2)[:, None] * u)
    com_acc = COM_M[:, None] * (phidd[:, None] * n - (phid**2)[:, None] * u)
    acc = np.cumsum(tip_acc, axis=0) - tip_acc + com_acc  # proximal tips, then this segment's centre of mass
    forces = np.zeros(3)
    for j in range(3):
        for k in range(j, 3):
            # Moving q_j turns segments j..k about joint j: p_k moves along the normal of each segment between.
            dp = np.sum(LENGTHS_M[j:k, None] * n[j:k], axis=0) + COM_M[k] * n[k]
            forces[j] += MASSES_KG[k] * dp @ acc[k] + INERTIA_COM_KGM2[k] * phidd[k]
    return forces


def points_m(q: np.ndarray) -> np.ndarray:
    """Shoulder, elbow, wrist, contact point in world (x = 0)."""
    phi = np.cumsum(q)
    steps = np.stack([np.zeros(3), LENGTHS_M * np.cos(phi), LENGTHS_M * np.sin(phi)], axis=1)
    return SHOULDER_M + np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])


def wrench_yzx(q: np.ndarray, qd: np.ndarray | None = None, qdd: np.ndarray | None = None) -> np.ndarray:
    """[F_y, F_z, M_x] the hand exerts on the sensor at the contact point, in world (at rest without qd, qdd)."""
    phi = np.cumsum(q)
    moments = static_moments_kgm()
    # Planar Jacobian of the contact point (y, z, angle) with respect to q: column j sums segments k >= j.
    jac = np.zeros((3, 3))
    for j in range(3):
        jac[0, j] = -np.sum(LENGTHS_M[j:] * np.sin(phi[j:]))
        jac[1, j] = np.sum(LENGTHS_M[j:] * np.cos(phi[j:]))
        jac[2, j] = 1.0
    generalized_gravity = np.array([-G * np.sum(moments[j:] * np.cos(phi[j:])) for j in range(3)])
    inertial = np.zeros(3) if qd is None or qdd is None else inertial_forces(q, qd, qdd)
    return np.linalg.solve(jac.T, generalized_gravity - inertial)
