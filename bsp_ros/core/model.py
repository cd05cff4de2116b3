"""The planar arm chain of docs/contract.md: kinematics, contact-point Jacobian and gravity regressor."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array

GRAVITY_M_S2 = 9.81

#: One sample's values: a float sequence or a 1-D array.
FloatVector = Sequence[float] | np.ndarray


def check_lengths_m(lengths_m: npt.ArrayLike) -> np.ndarray:
    """Return segment lengths (m) of a 2- or 3-segment chain if each is within (0.01, 1.0] m."""
    lengths = check_finite_array("segment lengths (m)", lengths_m, (None,))
    if lengths.size not in (2, 3):
        raise InputError(f"a chain has 2 or 3 segments, got {lengths.size} lengths {lengths.tolist()}")
    if ((lengths <= 0.01) | (lengths > 1.0)).any():
        raise InputError(f"segment lengths must be within (0.01, 1.0] m, got {lengths.tolist()}")
    return lengths


def running_sum(values: np.ndarray, reverse: bool = False) -> np.ndarray:
    """``np.cumsum(values, axis=1)`` (from the last column when ``reverse``) of (N, n, ...) arrays, the same bits.

    Column by column: numpy's cumsum along a short inner axis runs element by element, 15 times slower for a
    chain's few joints over N samples (the model's every evaluation begins with one).
    """
    out = np.empty_like(values)
    order = range(values.shape[1] - 1, -1, -1) if reverse else range(values.shape[1])
    previous = None
    for j in order:
        if previous is None:
            out[:, j] = values[:, j]
        else:
            np.add(out[:, previous], values[:, j], out=out[:, j])
        previous = j
    return out


def absolute_angles_rad(q_rad: npt.ArrayLike) -> np.ndarray:
    """Absolute segment angles from the horizontal +y axis.

    Parameters
    ----------
    q_rad : (N, n) joint angles q1..qn (rad); q1 is absolute, the rest relative.

    Returns
    -------
    (N, n) ``phi_j = q_1 + ... + q_j`` (rad).
    """
    return running_sum(np.atleast_2d(np.asarray(q_rad, dtype=np.float64)))


def joint_positions_m(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike) -> np.ndarray:
    """Sagittal positions of the shoulder, the distal joints and the contact point.

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).

    Returns
    -------
    (N, n + 1, 2) positions ``[y, z]`` (m) relative to the shoulder; the last point is the contact point.
    """
    phi = absolute_angles_rad(q_rad)
    steps = np.asarray(lengths_m, dtype=np.float64)[None, :, None] * np.stack((np.cos(phi), np.sin(phi)), axis=-1)
    origin = np.zeros((phi.shape[0], 1, 2))
    return np.concatenate((origin, running_sum(steps)), axis=1)


def contact_jacobian(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike) -> np.ndarray:
    """Planar Jacobian of the contact point.

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).

    Returns
    -------
    (N, 3, n): rows d(y, z, phi)/dq, with phi = q1 + ... + qn the orientation of the last segment.
    """
    dy, dz = contact_lever_sums(q_rad, lengths_m)
    return np.stack((dy, dz, np.ones_like(dy)), axis=1)


def contact_torques_nm(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike, wrench_yzx: npt.ArrayLike) -> np.ndarray:
    """Joint torques that balance the contact wrench: ``-J(q)^T F_end`` (Eq. 3 right-hand side).

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).
    wrench_yzx : (N, 3) ``[F_y (N), F_z (N), M_x (Nm)]`` the hand exerts on the sensor, in ``world``.

    Returns
    -------
    (N, n) torques (Nm); equal to ``tau_G + tau_p`` in quasi-static equilibrium.
    """
    wrench = np.atleast_2d(np.asarray(wrench_yzx, dtype=np.float64))
    dy, dz = contact_lever_sums(q_rad, lengths_m)
    return -(dy * wrench[:, 0, None] + dz * wrench[:, 1, None] + wrench[:, 2, None])


def contact_lever_sums(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The contact Jacobian's position rows without the (N, 3, n) array: ``d y / d q`` and ``d z / d q``.

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).

    Returns
    -------
    dy, dz : (N, n) each (m per rad): joint j's sums over the distal segments k >= j of ``-l_k sin(phi_k)`` and
    ``l_k cos(phi_k)``; a unit ``F_y`` gives the torques ``-dy``, a unit ``F_z`` ``-dz`` (the moment row is 1).
    """
    phi = absolute_angles_rad(q_rad)
    lengths = np.asarray(lengths_m, dtype=np.float64)
    # d p / d q_j sums the distal segments k >= j: a reversed cumulative sum.
    return running_sum(-lengths * np.sin(phi), reverse=True), running_sum(lengths * np.cos(phi), reverse=True)


def contact_torques_one_nm(q_rad: FloatVector, lengths_m: FloatVector, wrench_yzx: FloatVector) -> list[float]:
    """:func:`contact_torques_nm` of one sample, in plain floats: ~3 us where the array version takes ~40.

    The live recursive filter calls it for every wrench (1 kHz).

    Parameters
    ----------
    q_rad : (n,) joint angles (rad).
    lengths_m : (n,) segment lengths (m).
    wrench_yzx : ``[F_y (N), F_z (N), M_x (Nm)]`` in ``world``.

    Returns
    -------
    (n,) torques (Nm).
    """
    force_y, force_z, moment_x = (float(v) for v in wrench_yzx)
    phi = 0.0
    dy, dz = [], []
    for q, length in zip(q_rad, lengths_m, strict=True):
        phi += float(q)
        dy.append(-float(length) * math.sin(phi))
        dz.append(float(length) * math.cos(phi))
    torques = []
    sum_y = sum_z = 0.0
    for j in range(len(dy) - 1, -1, -1):  # d p / d q_j sums the distal segments k >= j
        sum_y += dy[j]
        sum_z += dz[j]
        torques.append(-(sum_y * force_y + sum_z * force_z + moment_x))
    return torques[::-1]


def gravity_regressor_one(q_rad: FloatVector) -> list[list[float]]:
    """:func:`gravity_regressor` of one sample as nested lists of floats (n, n), for the 1 kHz live filter."""
    cos_phi = []
    phi = 0.0
    for q in q_rad:
        phi += float(q)
        cos_phi.append(GRAVITY_M_S2 * math.cos(phi))
    n = len(cos_phi)
    return [[cos_phi[j] if j >= i else 0.0 for j in range(n)] for i in range(n)]


def gravity_regressor(q_rad: npt.ArrayLike) -> np.ndarray:
    """Regressor of gravity torques in the grouped static moments ``beta`` (docs/contract.md).

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).

    Returns
    -------
    (N, n, n) ``Y`` with ``tau_G[:, i] = Y[:, i, :] @ beta``: ``Y[:, i, j] = g cos(phi_j)`` for j >= i, else 0.
    """
    cos_phi = GRAVITY_M_S2 * np.cos(absolute_angles_rad(q_rad))
    n = cos_phi.shape[1]
    upper = np.triu(np.ones((n, n)))
    return cos_phi[:, None, :] * upper[None, :, :]


def static_moments_kgm(lengths_m: npt.ArrayLike, masses_kg: npt.ArrayLike, com_m: npt.ArrayLike) -> np.ndarray:
    """Grouped static moments from masses and centres of mass (docs/contract.md).

    ``beta_j = m_j l_j + a_j * sum_{k > j} m_k`` (kg m): the first moment about joint j of segment j and
    everything distal to it, with the distal mass lumped at the next joint.

    Parameters
    ----------
    lengths_m, masses_kg, com_m : (n,) segment lengths, masses and COM distances from the proximal joint.

    Returns
    -------
    (n,) static moments (kg m).
    """
    lengths = np.asarray(lengths_m, dtype=np.float64)
    masses = np.asarray(masses_kg, dtype=np.float64)
    com = np.asarray(com_m, dtype=np.float64)
    distal_mass = np.concatenate((np.cumsum(masses[::-1])[::-1][1:], [0.0]))
    return masses * com + lengths * distal_mass


def static_moments_jacobian(lengths_m: npt.ArrayLike, masses_kg: npt.ArrayLike, com_m: npt.ArrayLike) -> np.ndarray:
    """Derivative of :func:`static_moments_kgm` w.r.t. ``[m_1..m_n, l_1..l_n]``: shape (n, 2n)."""
    lengths = np.asarray(lengths_m, dtype=np.float64)
    masses = np.asarray(masses_kg, dtype=np.float64)
    com = np.asarray(com_m, dtype=np.float64)
    n = lengths.size
    d_mass = np.diag(com) + np.triu(np.ones((n, n)), k=1) * lengths[:, None]
    d_com = np.diag(masses)
    return np.hstack((d_mass, d_com))
