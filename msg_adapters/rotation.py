"""Quaternions (ROS order x, y, z, w) <-> rotation matrices (scipy's ``Rotation`` for the inverse, on demand)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def matrices_from_quaternions(quaternions_xyzw: np.ndarray) -> np.ndarray:
    """(N, 4) unit quaternions ``(x, y, z, w)`` -> (N, 3, 3) rotation matrices (normalised first).

    The closed form in numpy: every bag with a transform meets it, and scipy.spatial takes 0.3 s to import.
    """
    q = np.asarray(quaternions_xyzw, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty((*q.shape[:-1], 3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - z * w)
    out[..., 0, 2] = 2 * (x * z + y * w)
    out[..., 1, 0] = 2 * (x * y + z * w)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - x * w)
    out[..., 2, 0] = 2 * (x * z - y * w)
    out[..., 2, 1] = 2 * (y * z + x * w)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


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
    return matrices_from_quaternions(q)


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
    from scipy.spatial.transform import Rotation

    q = np.asarray(Rotation.from_matrix(r).as_quat(), dtype=np.float64)
    return -q if q[3] < 0.0 else q
