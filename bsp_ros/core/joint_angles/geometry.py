"""Planar chain geometry: sagittal projection and joint angles from joint positions."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def sagittal_from_world(position_m: npt.ArrayLike) -> np.ndarray:
    """Project world positions onto the sagittal plane: (..., 3) ``[x, y, z]`` -> (..., 2) ``[y, z]``."""
    return np.asarray(position_m, dtype=np.float64)[..., 1:3]


def joint_angles_from_positions(points_yz: npt.ArrayLike) -> np.ndarray:
    """Joint angles of a planar chain from its joint and contact-point positions.

    Parameters
    ----------
    points_yz : (N, n + 1, 2) sagittal positions of shoulder, distal joints and contact point (m).

    Returns
    -------
    (N, n) ``q1`` absolute from +y, the others relative to the previous segment, in (-pi, pi] (rad).
    """
    points = np.asarray(points_yz, dtype=np.float64)
    step = np.diff(points, axis=1)
    phi = np.arctan2(step[..., 1], step[..., 0])
    relative = np.diff(phi, axis=1)
    relative = np.angle(np.exp(1j * relative))  # wrap to (-pi, pi]
    return np.concatenate((phi[:, :1], relative), axis=1)
