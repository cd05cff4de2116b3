"""Planar rigid-body dynamics of the arm chain in its base (identifiable) inertial parameters."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from bsp_ros.core.model import GRAVITY_M_S2, FloatVector, running_sum

# Base parameters per segment j, found as in robot identification (the masses of a planar chain with a fixed
# first joint only ever act through the segments proximal to them, so they group):
#   static moment  beta_j  = m_j l_j + a_j M_j          (first moment along the segment axis, kg m)
#   perpendicular  gamma_j = m_j d_j                    (first moment normal to the axis, kg m)
#   inertia        zeta_j  = I_j + a_j^2 M_j            (about the proximal joint, kg m^2)
# with M_j the mass distal to segment j, d_j the COM's offset normal to the axis (+ 90 deg counter-clockwise)
# and I_j the segment's own inertia about its proximal joint.
BASE_KINDS = ("static_moment_kgm", "perpendicular_moment_kgm", "grouped_inertia_kgm2")


@dataclass(frozen=True)
class ChainMotion:
    """Joint angles, velocities and accelerations of the chain on common stamps.

    Attributes
    ----------
    q_rad : (N, n) joint angles (rad).
    qd_rad_s : (N, n) joint velocities (rad/s).
    qdd_rad_s2 : (N, n) joint accelerations (rad/s^2).
    """

    q_rad: np.ndarray
    qd_rad_s: np.ndarray
    qdd_rad_s2: np.ndarray


# A planar vector per sample as its two components, each (N,) contiguous: the chain's few segments times N samples
# in (N, n, 2) arrays made every product a strided pass over pairs, 3-5 times slower (the same arithmetic).
Vector = tuple[np.ndarray, np.ndarray]


def pair_cross(a: Vector, b: Vector) -> np.ndarray:
    """Planar cross product (moment about +x) of vectors given as their components ``(y, z)``."""
    return a[0] * b[1] - a[1] * b[0]


def pair_turned(v: Vector) -> Vector:
    """Vectors turned 90 deg counter-clockwise (the angular velocity's cross product), as components ``(y, z)``."""
    return -v[1], v[0]


class _ChainFrames(NamedTuple):
    """What every torque of a planar chain is built from, per segment j (lists of n) and sample: absolute rates
    (N,), the segment's axis and normal, the position and acceleration of its proximal joint (from the shoulder),
    and its share of the acceleration of the joints beyond it (n - 1 of these), each vector a component pair."""

    omega: list[np.ndarray]
    alpha: list[np.ndarray]
    axis: list[Vector]
    normal: list[Vector]
    points: list[Vector]
    accel: list[Vector]
    steps: list[Vector]


def _chain_frames(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, lengths: npt.ArrayLike) -> _ChainFrames:
    """:class:`_ChainFrames` of (N, n) angles, velocities and accelerations: P_0 is the fixed shoulder,
    P_{j+1} = P_j + a_j e_j, and its acceleration gains a_j (alpha_j n_j - omega_j^2 e_j)."""
    count, n = q.shape
    segment_m = np.asarray(lengths, dtype=np.float64)
    # Absolute angles and rates segment by segment (running_sum's additions, in its order).
    phi, omega, alpha = (running_sum(np.ascontiguousarray(x.T)[None])[0] for x in (q, qd, qdd))
    cos, sin = np.cos(phi), np.sin(phi)
    axis = [(cos[j], sin[j]) for j in range(n)]  # unit vector along each segment
    normal = [pair_turned(a) for a in axis]
    zero = np.zeros(count)
    points, accel, steps = [(zero, zero)], [(zero, zero)], []
    for j in range(1, n):
        step = segment_m[j - 1]
        w2, a = omega[j - 1] ** 2, alpha[j - 1]
        (ey, ez), (ny, nz) = axis[j - 1], normal[j - 1]
        steps.append((step * (a * ny - w2 * ey), step * (a * nz - w2 * ez)))
        points.append((points[-1][0] + step * ey, points[-1][1] + step * ez))
        accel.append((accel[-1][0] + steps[-1][0], accel[-1][1] + steps[-1][1]))
    return _ChainFrames(list(omega), list(alpha), axis, normal, points, accel, steps)


def _inertial_force(alpha: np.ndarray, omega: np.ndarray, h: Vector) -> Vector:
    """The inertial force ``alpha x h - omega^2 h`` of a first moment ``h`` turning with the segment."""
    w2 = omega**2
    turned = pair_turned(h)
    return alpha * turned[0] - w2 * h[0], alpha * turned[1] - w2 * h[1]


def base_regressor(
    q_rad: npt.ArrayLike,
    qd_rad_s: npt.ArrayLike,
    qdd_rad_s2: npt.ArrayLike,
    lengths_m: npt.ArrayLike,
    gravity_m_s2: float = GRAVITY_M_S2,
) -> np.ndarray:
    """Joint torques of gravity and inertia, linear in the base parameters.

    ``M(q) q'' + C(q, q') q' + tau_G(q) = Y @ [beta_1..beta_n, gamma_1..gamma_n, zeta_1..zeta_n]``: the
    left-hand side of ``M q'' + C q' + tau_G + tau_p = -J^T F`` (docs/contract.md, extended to dynamics). With
    ``q' = q'' = 0`` the beta columns are :func:`bsp_ros.core.model.gravity_regressor`.

    Parameters
    ----------
    q_rad, qd_rad_s, qdd_rad_s2 : (N, n) joint angles (rad), velocities (rad/s), accelerations (rad/s^2).
    lengths_m : (n,) segment lengths a_j (m).
    gravity_m_s2 : g (m/s^2), acting along -z.

    Returns
    -------
    (N, n, 3n) regressor ``Y[t, i, k]``: torque at joint i per unit of base parameter k.
    """
    q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
    qd = np.atleast_2d(np.asarray(qd_rad_s, dtype=np.float64))
    qdd = np.atleast_2d(np.asarray(qdd_rad_s2, dtype=np.float64))
    lengths = np.asarray(lengths_m, dtype=np.float64)
    count, n = q.shape
    omega, alpha, axis, normal, points, accel, _ = _chain_frames(q, qd, qdd, lengths)
    regressor = np.zeros((count, n, 3 * n))
    for j in range(n):
        for column, h in ((j, axis[j]), (n + j, normal[j])):
            # A first moment h of segment j: its inertial force alpha x h - omega^2 h acts at P_j's lever
            # about joint i, h x a(P_j) is the moment of P_j's acceleration, and g h_y that of gravity.
            force = _inertial_force(alpha[j], omega[j], h)
            own = pair_cross(h, accel[j]) + gravity_m_s2 * h[0]
            for i in range(j + 1):
                lever = (points[j][0] - points[i][0], points[j][1] - points[i][1])
                regressor[:, i, column] = pair_cross(lever, force) + own
        regressor[:, : j + 1, 2 * n + j] = alpha[j][:, None]
    return regressor


def base_regressor_one(
    q_rad: FloatVector,
    qd_rad_s: FloatVector,
    qdd_rad_s2: FloatVector,
    lengths_m: FloatVector,
    gravity_m_s2: float = GRAVITY_M_S2,
) -> list[list[float]]:
    """:func:`base_regressor` of one sample as nested lists of floats (n, 3n), for the live recursive filter.

    In plain floats: the vectorised chain costs ~120 us for one sample, this ~9 us (the same bits).

    Parameters
    ----------
    q_rad, qd_rad_s, qdd_rad_s2 : (n,) joint angles (rad), velocities (rad/s), accelerations (rad/s^2).
    lengths_m : (n,) segment lengths a_j (m).
    gravity_m_s2 : g (m/s^2), acting along -z.

    Returns
    -------
    (n, 3n) ``Y[i][k]``: torque at joint i per unit of base parameter k.
    """
    n = len(lengths_m)
    phi = omega = alpha = 0.0
    omegas, alphas, axes = [], [], []
    for q, qd, qdd in zip(q_rad, qd_rad_s, qdd_rad_s2, strict=True):
        phi, omega, alpha = phi + float(q), omega + float(qd), alpha + float(qdd)
        omegas.append(omega)
        alphas.append(alpha)
        axes.append((math.cos(phi), math.sin(phi)))
    # P_0 is the shoulder; P_(j+1) = P_j + a_j e_j, whose acceleration gains a_j (alpha_j n_j - omega_j^2 e_j).
    points, accels = [(0.0, 0.0)], [(0.0, 0.0)]
    for j in range(1, n):
        step, (ey, ez) = float(lengths_m[j - 1]), axes[j - 1]
        w2, a = omegas[j - 1] ** 2, alphas[j - 1]
        points.append((points[-1][0] + step * ey, points[-1][1] + step * ez))
        accels.append((accels[-1][0] + step * (-a * ez - w2 * ey), accels[-1][1] + step * (a * ey - w2 * ez)))
    regressor = [[0.0] * (3 * n) for _ in range(n)]
    for j in range(n):
        ey, ez = axes[j]
        w2, a = omegas[j] ** 2, alphas[j]
        for column, (hy, hz) in ((j, (ey, ez)), (n + j, (-ez, ey))):
            force_y, force_z = -a * hz - w2 * hy, a * hy - w2 * hz
            own = hy * accels[j][1] - hz * accels[j][0] + gravity_m_s2 * hy
            for i in range(j + 1):
                ly, lz = points[j][0] - points[i][0], points[j][1] - points[i][1]
                regressor[i][column] = ly * force_z - lz * force_y + own
        for i in range(j + 1):
            regressor[i][2 * n + j] = a
    return regressor


def base_torque_angle_derivatives(
    q_rad: np.ndarray,
    qd_rad_s: np.ndarray,
    qdd_rad_s2: np.ndarray,
    lengths_m: np.ndarray,
    base_values: np.ndarray,
    gravity_m_s2: float = GRAVITY_M_S2,
) -> np.ndarray:
    """How the torques ``base_regressor(...) @ base_values`` change with each segment's absolute angle, velocities
    and accelerations held.

    Turning segment s by ``d phi_s`` turns every vector fixed in it (its axis, first moment, inertial force) by
    90 deg times ``d phi_s``, and moves the points and accelerations of the segments beyond it: the derivative in
    closed form, n evaluations' cost where finite differences of moved markers took 2 (n + 1).

    Parameters
    ----------
    q_rad, qd_rad_s, qdd_rad_s2 : (N, n) joint angles (rad), velocities (rad/s), accelerations (rad/s^2).
    lengths_m : (n,) segment lengths (m).
    base_values : (3n,) ``[beta, gamma, zeta]`` (kg m, kg m, kg m^2).
    gravity_m_s2 : g (m/s^2), acting along -z.

    Returns
    -------
    (N, n, n) ``d tau_i / d phi_s`` (Nm/rad), joints i then segments s.
    """
    n = q_rad.shape[1]
    omega, alpha, axis, normal, points, accel, steps = _chain_frames(q_rad, qd_rad_s, qdd_rad_s2, lengths_m)
    beta, gamma = base_values[:n], base_values[n : 2 * n]
    h = [
        (beta[j] * axis[j][0] + gamma[j] * normal[j][0], beta[j] * axis[j][1] + gamma[j] * normal[j][1])
        for j in range(n)
    ]
    force = [_inertial_force(alpha[j], omega[j], h[j]) for j in range(n)]
    derivative = np.zeros((q_rad.shape[0], n, n))
    for s in range(n):
        # Segment s turned: its own first moment and force turn; the points and accelerations beyond it move.
        turned_h, turned_force = pair_turned(h[s]), pair_turned(force[s])
        moved = (lengths_m[s] * normal[s][0], lengths_m[s] * normal[s][1])  # d points_j for j > s
        moved_accel = pair_turned(steps[s]) if s < n - 1 else None  # d accel_j for j > s
        for i in range(n):
            total = np.zeros(q_rad.shape[0])
            for j in range(i, n):
                if i <= s < j:  # only the lever from joint i to a point beyond s moves (j >= i)
                    total += pair_cross(moved, force[j])
                if j == s:
                    lever = (points[j][0] - points[i][0], points[j][1] - points[i][1])
                    total += pair_cross(lever, turned_force)
                    total += pair_cross(turned_h, accel[j]) + gravity_m_s2 * turned_h[0]
                if j > s and moved_accel is not None:
                    total += pair_cross(h[j], moved_accel)
            derivative[:, i, s] = total
    return derivative


def base_parameters(
    lengths_m: npt.ArrayLike,
    masses_kg: npt.ArrayLike,
    com_m: npt.ArrayLike,
    inertia_com_kgm2: npt.ArrayLike,
    com_normal_m: npt.ArrayLike | None = None,
) -> np.ndarray:
    """Base parameters ``[beta, gamma, zeta]`` (..., 3n) of a chain from its standard parameters.

    Parameters
    ----------
    lengths_m, masses_kg, com_m : (..., n) segment lengths, masses and COM distances along the axis (leading
        dimensions broadcast: many draws of a prior at once).
    inertia_com_kgm2 : (..., n) inertias about each COM for rotation in the plane (kg m^2).
    com_normal_m : (..., n) COM offsets normal to the axis (m); zero when None.
    """
    lengths = np.asarray(lengths_m, dtype=np.float64)
    masses = np.asarray(masses_kg, dtype=np.float64)
    along = np.asarray(com_m, dtype=np.float64)
    normal = np.zeros_like(along) if com_normal_m is None else np.asarray(com_normal_m, dtype=np.float64)
    # Mass distal to each segment: the reversed cumulative sum, shifted by one.
    total_from = np.flip(np.cumsum(np.flip(masses, axis=-1), axis=-1), axis=-1)
    distal = np.concatenate((total_from[..., 1:], np.zeros_like(total_from[..., :1])), axis=-1)
    own = np.asarray(inertia_com_kgm2, dtype=np.float64) + masses * (along**2 + normal**2)
    return np.concatenate((masses * along + lengths * distal, masses * normal, own + lengths**2 * distal), axis=-1)


def inertial_torque_nm(motion: ChainMotion, lengths_m: npt.ArrayLike, parameters: npt.ArrayLike) -> np.ndarray:
    """``M q'' + C q'`` alone (N, n) Nm: the base regressor without gravity, times the base parameters."""
    regressor = base_regressor(motion.q_rad, motion.qd_rad_s, motion.qdd_rad_s2, lengths_m, gravity_m_s2=0.0)
    return np.asarray(regressor @ np.asarray(parameters, dtype=np.float64))
