"""The wrench frame's rotation into world axes: from the TF tree, from a fixed quaternion, or world itself."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.tf import TransformSample, rotation_between

__all__ = ["WrenchFrames", "rotation_from_quaternion_xyzw"]


def rotation_from_quaternion_xyzw(quaternion_xyzw: Iterable[float]) -> np.ndarray:
    """(3, 3) rotation of a unit quaternion ``[x, y, z, w]``; refuses one that is not of unit length.

    Raises
    ------
    ValueError
        Naming the quaternion (wrong length, non-finite, or norm off 1 by more than 1e-3).
    """
    q = np.asarray(list(quaternion_xyzw), dtype=np.float64)
    if q.shape != (4,) or not np.isfinite(q).all():
        raise ValueError(f"a rotation quaternion needs 4 finite numbers [x, y, z, w], got {q.tolist()}")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-3:
        raise ValueError(f"rotation quaternion {q.tolist()} has norm {norm:.4g}, not 1")
    return np.asarray(matrix_from_quaternion(q / norm), dtype=np.float64)


class WrenchFrames:
    """Which rotation takes a wrench frame's vectors into world axes, and where it came from.

    With TF (``use_tf``), the newest transforms of ``/tf_static`` and ``/tf`` decide; a frame without a
    transform after ``tf_wait_s`` is taken as world (CONTRACT.md). Without TF (no tf2_msgs installed) the
    fixed ``parameter_rotation`` applies to every frame other than world.

    Parameters
    ----------
    world_frame : str
        Frame of the markers and of gravity.
    use_tf : bool
        Read the TF tree (False when tf2_msgs cannot be imported).
    parameter_rotation : (3, 3) array
        ``R_world_from_sensor`` to use without TF.
    tf_wait_s : float
        How long to wait for a transform before taking the frame as world, s.
    """

    def __init__(self, world_frame: str, use_tf: bool, parameter_rotation: np.ndarray, tf_wait_s: float) -> None:
        self.world_frame = world_frame
        self.use_tf = use_tf
        self.parameter_rotation = np.asarray(parameter_rotation, dtype=np.float64)
        self.tf_wait_s = tf_wait_s
        self.transforms: dict[str, TransformSample] = {}
        self.rotations: dict[str, np.ndarray] = {}
        self.sources: dict[str, str] = {}
        self._first_ns: int | None = None

    def on_transforms(self, transforms: Iterable[TransformSample]) -> list[str]:
        """Keep the newest transform per child frame; return the frames whose rotation changed (restart)."""
        for transform in transforms:
            self.transforms[transform.child_frame] = transform
        changed = []
        for frame_id, old in list(self.rotations.items()):
            new = rotation_between(self.transforms.values(), self.world_frame, frame_id)
            if new is not None and not np.allclose(new, old, atol=1e-9):
                self.rotations[frame_id] = new
                self.sources[frame_id] = "tf"
                changed.append(frame_id)
        return changed

    def rotation_for(self, frame_id: str, now_ns: int) -> np.ndarray | None:
        """``R_world_from_frame``, or None while waiting for a transform (TF only)."""
        if frame_id in self.rotations:
            return self.rotations[frame_id]
        if frame_id == self.world_frame:
            rotation, source = np.eye(3), "world"
        elif not self.use_tf:
            rotation, source = self.parameter_rotation, "parameter"
        else:
            found = rotation_between(self.transforms.values(), self.world_frame, frame_id)
            if found is None:
                self._first_ns = self._first_ns if self._first_ns is not None else now_ns
                if now_ns - self._first_ns < self.tf_wait_s * 1e9:
                    return None
                rotation, source = np.eye(3), "world (no transform)"
            else:
                rotation, source = found, "tf"
        self.rotations[frame_id] = rotation
        self.sources[frame_id] = source
        return rotation
