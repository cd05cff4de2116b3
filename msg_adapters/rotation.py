"""Quaternions (ROS order x, y, z, w) <-> rotation matrices, via scipy."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation


def matrix_from_quaternion(quaternion_xyzw: npt.ArrayLike) -> np.ndarray:
    """Return the (3, 3) rotation matrix of a quaternion ``(x, y, z, w)`` (normalised first).

    Raises
    ------
    ValueError
        If the quaternion is zero or not finite.
    """
    q = np.asarray(quaternion_xyzw, dtype=np.float64)
    if q.shape != (4,) or not np.isfinite(q).all() or not np.any(q):
        raise ValueError(f"quaternion must be 4 finite numbers, not all zero, got {q.tolist()}")
    return np.asarray(Rotation.from_quat(q).as_matrix(), dtype=np.float64)


def quaternion_from_matrix(rotation: npt.ArrayLike) -> np.ndarray:
    """Return the unit quaternion ``(x, y, z, w)`` (w >= 0) of a (3, 3) rotation matrix.

    Raises
    ------
    ValueError
        If ``rotation`` is not a finite (3, 3) proper rotation (orthonormal within 1e-6, det +1).
    """
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape != (3, 3) or not np.isfinite(r).all():
        raise ValueError(f"rotation must be a finite (3, 3) matrix, got shape {r.shape}")
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0.0:
        raise ValueError("rotation must be orthonormal with determinant +1")
    q = np.asarray(Rotation.from_matrix(r).as_quat(), dtype=np.float64)
    return -q if q[3] < 0.0 else q
