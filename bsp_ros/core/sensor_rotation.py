"""How the sensor's orientation behaved over a session: fixed or per sample, and how far it turned."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from bsp_ros.core.estimate_blocks import RotationBlock
from bsp_ros.errors import InputError

__all__ = ["rotation_block", "rotation_range_deg"]


def rotation_range_deg(rotation_world_from_sensor: npt.ArrayLike) -> float:
    """How far the sensor turned over a session, deg.

    Parameters
    ----------
    rotation_world_from_sensor : (3, 3) a fixed orientation, or (N, 3, 3) one per sample.

    Returns
    -------
    The peak-to-peak spread of the orientations' rotation vectors about their mean orientation along
    their main axis of turning (a sensor turning about one axis: exactly its range of angle); 0 for a
    fixed orientation.
    """
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    if rotation.shape == (3, 3):
        return 0.0
    if rotation.ndim != 3 or rotation.shape[1:] != (3, 3):
        raise InputError(f"rotation_world_from_sensor must be (3, 3) or (N, 3, 3), got {rotation.shape}")
    if rotation.shape[0] < 2:
        return 0.0
    from scipy.spatial.transform import Rotation  # on demand: a slow import, needed for turning sensors only

    rotations = Rotation.from_matrix(rotation)
    vectors = (rotations.mean().inv() * rotations).as_rotvec()  # (N, 3) about the mean, rad
    centred = vectors - vectors.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    return float(np.degrees(np.ptp(vectors @ vt[0])))


def rotation_block(rotation_world_from_sensor: npt.ArrayLike, source: str) -> RotationBlock:
    """``quality.rotation`` of an estimate: where the rotation came from and how much it varied.

    Parameters
    ----------
    rotation_world_from_sensor : (3, 3) or (N, 3, 3) as in :class:`bsp_ros.core.streams.Session`.
    source : where it came from (``tf``, ``tf_static``, ``alias``, ``assumed``, ``parameter``, ``session``).
    """
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    return RotationBlock(sources=(source,), per_sample=rotation.ndim == 3, range_deg=rotation_range_deg(rotation))
