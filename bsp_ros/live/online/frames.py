"""The wrench frame's rotation into world axes: from the TF tree, from a fixed quaternion, or world itself."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.cell import DISAGREE_DEG, angle_between_deg
from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.rotation_track import TransformBuffer
from msg_adapters.tf import TransformSample

__all__ = [
    "DISAGREE_DEG",
    "NO_TRANSFORM",
    "FrameSource",
    "WrenchFrames",
    "WrenchQueue",
    "frame_source",
    "rotation_from_quaternion_xyzw",
]

#: The source of a frame whose transform did not come within ``tf_wait_s``: the stated rotation stands in.
NO_TRANSFORM = "parameter (no transform)"


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


@dataclass(frozen=True)
class FrameSource:
    """Where the wrench frame's rotation comes from: /tf_static and /tf (``tf``), a TransformStamped topic
    (``topic``), or else the fixed parameter quaternion; ``description`` says which, for the log and
    /diagnostics."""

    tf: bool
    topic: bool
    description: str

    @property
    def transforms(self) -> bool:
        """Stamped transforms feed the rotation (turning or fixed, slerped per wrench)."""
        return self.tf or self.topic


def frame_source(choice: str, tf_installed: bool, topic: str) -> FrameSource:
    """The source a ``wrench_frame_source`` parameter names: ``tf``, ``topic`` (the TransformStamped ``topic``),
    ``parameter``, or ``auto`` (tf where tf2_msgs is installed, else the TransformStamped ``topic``). Where a
    transform source sends nothing, the parameter's rotation stands in (:class:`WrenchFrames`).

    Raises
    ------
    ValueError
        ``tf`` without tf2_msgs installed.
    """
    if choice == "tf" and not tf_installed:
        raise ValueError(
            "wrench_frame_source is tf but tf2_msgs/msg/TFMessage is not installed; "
            f"use wrench_frame_source:=topic (TransformStamped on {topic}) or :=parameter (wrench_frame_rotation_xyzw)"
        )
    if choice == "topic":
        return FrameSource(False, True, f"topic {topic} (TransformStamped)")
    if choice == "auto" and not tf_installed:
        return FrameSource(False, True, f"topic {topic} (TransformStamped; tf2_msgs is not installed)")
    if choice in ("tf", "auto"):
        return FrameSource(True, False, "tf (/tf_static, /tf)")
    return FrameSource(False, False, "parameter wrench_frame_rotation_xyzw")


class WrenchFrames:
    """Which rotation takes a wrench frame's vectors into world axes at a wrench's stamp, and where it came from.

    With TF (``use_tf``), the /tf_static and /tf transforms go into one
    :class:`msg_adapters.rotation_track.TransformBuffer`, as `bsp identify` reads a bag: a chain whose /tf
    links turn (a sensor on the robot's flange turning with the handle) is slerped at each wrench stamp
    between its /tf samples; a wrench newer than the newest /tf sample holds that one (the next transform
    has not come yet: :class:`WrenchQueue` makes it wait instead). A fixed chain (/tf_static) gives one
    rotation. A frame without a transform after ``tf_wait_s`` takes the stated ``parameter_rotation`` (the cell
    file's mounting; world where it is the identity). Without transforms (``use_tf`` False) that rotation applies
    to every frame other than world. A fixed transform more than :data:`DISAGREE_DEG` from the stated rotation is
    used and noted in :attr:`disagreement_deg`.

    Parameters
    ----------
    world_frame : str
        Frame of the markers and of gravity.
    use_tf : bool
        Stamped transforms feed the rotation (/tf_static and /tf, or a TransformStamped topic).
    parameter_rotation : (3, 3) array
        The stated ``R_world_from_sensor``: used without transforms, or where none came within ``tf_wait_s``.
    tf_wait_s : float
        How long to wait for a transform before taking the frame as world, s.
    history_s : float
        /tf samples kept per link, s.
    transform_source : str
        Where the stamped transforms come from, as the frame's source names it (``tf`` for /tf_static and /tf,
        ``topic`` for the TransformStamped topic): the words a bag read the same way gives its ``rotation_source``.
    """

    def __init__(
        self,
        world_frame: str,
        use_tf: bool,
        parameter_rotation: np.ndarray,
        tf_wait_s: float,
        history_s: float = 10.0,
        transform_source: str = "tf",
    ) -> None:
        self.world_frame = world_frame
        self.transform_source = transform_source
        self.use_tf = use_tf
        self.parameter_rotation = np.asarray(parameter_rotation, dtype=np.float64)
        self.tf_wait_s = tf_wait_s
        self.buffer = TransformBuffer(max_age_ns=int(history_s * 1e9))
        self.rotations: dict[str, np.ndarray] = {}  # fixed rotations, per frame
        self.turning: set[str] = set()  # frames whose rotation is evaluated per wrench stamp
        self.sources: dict[str, str] = {}
        self.disagreement_deg: dict[str, float] = {}  # frames whose fixed transform is off the stated rotation
        self._first_ns: int | None = None

    def _fixed(self, frame_id: str, rotation: np.ndarray) -> None:
        """Take a fixed ``rotation`` of ``frame_id`` from the transforms, noting how far it is off the stated one."""
        self.rotations[frame_id] = rotation
        self.sources[frame_id] = self.transform_source
        angle = angle_between_deg(rotation, self.parameter_rotation)
        if angle > DISAGREE_DEG:
            self.disagreement_deg[frame_id] = angle
        else:
            self.disagreement_deg.pop(frame_id, None)

    def on_transforms(self, transforms: Iterable[TransformSample], static: bool = False) -> list[str]:
        """Add transforms (``static``: from /tf_static); return the frames whose fixed rotation changed.

        A fixed rotation that changes (a sensor re-mounted, a /tf_static republished) restarts the estimate:
        the samples buffered before were rotated the old way. A frame whose /tf chain turns changes nothing
        already buffered (each wrench had its rotation at its stamp) and is never reported.
        """
        samples = list(transforms)
        (self.buffer.add_static if static else self.buffer.add)(samples)
        changed = []
        for frame_id, old in list(self.rotations.items()):
            source = self.sources.get(frame_id)
            if source not in (self.transform_source, NO_TRANSFORM):
                continue
            track = self.buffer.track(self.world_frame, frame_id, [0])
            if track is None:
                continue
            if track.turning:
                del self.rotations[frame_id]
                self.turning.add(frame_id)
                self.sources[frame_id] = f"{self.transform_source} (per sample)"
            elif source == NO_TRANSFORM or not np.allclose(track.rotations[0], old, atol=1e-9):
                self._fixed(frame_id, np.asarray(track.rotations[0]))
                if not np.allclose(track.rotations[0], old, atol=1e-9):
                    changed.append(frame_id)
        return changed

    def rotation_for(self, frame_id: str, now_ns: int, t_ns: int | None = None) -> np.ndarray | None:
        """``R_world_from_frame`` at the wrench stamp ``t_ns`` (None: the newest), or None while waiting for a
        transform (TF only)."""
        if frame_id in self.turning:
            stamp = now_ns if t_ns is None else t_ns
            track = self.buffer.track(self.world_frame, frame_id, [stamp])
            if track is not None:
                return np.asarray(track.rotations[0])
        if frame_id in self.rotations:
            return self.rotations[frame_id]
        if frame_id == self.world_frame:
            rotation, source = np.eye(3), "world"
        elif not self.use_tf:
            rotation, source = self.parameter_rotation, "parameter"
        else:
            track = self.buffer.track(self.world_frame, frame_id, [now_ns if t_ns is None else t_ns])
            if track is None:
                self._first_ns = self._first_ns if self._first_ns is not None else now_ns
                if now_ns - self._first_ns < self.tf_wait_s * 1e9:
                    return None
                rotation, source = self.parameter_rotation, NO_TRANSFORM
            elif track.turning:
                self.turning.add(frame_id)
                self.sources[frame_id] = f"{self.transform_source} (per sample)"
                return np.asarray(track.rotations[0])
            else:
                self._fixed(frame_id, np.asarray(track.rotations[0]))
                return self.rotations[frame_id]
        self.rotations[frame_id] = rotation
        self.sources[frame_id] = source
        return rotation

    def waits(self, frame_id: str, t_ns: int) -> bool:
        """Whether a wrench of ``frame_id`` at ``t_ns`` is newer than the newest /tf sample of its turning chain."""
        if frame_id not in self.turning:
            return False
        track = self.buffer.track(self.world_frame, frame_id, [t_ns])
        return track is not None and track.span_ns is not None and t_ns > track.span_ns[1]


class WrenchQueue:
    """Wrench samples of a turning sensor wait for the /tf sample after their stamp, then are rotated in order.

    A wrench newer than the newest /tf sample would otherwise hold that orientation: an error of the turn
    rate times the /tf period that follows the direction of motion, so it biases the friction estimate
    (seen: 7 std at the shoulder with /tf at 20 Hz). Waiting (as tf2's message filter does) slerps each
    wrench between the transforms around it, as `bsp identify` does offline. A wrench waits at most
    ``max_wait_s`` of wrench stamps (a /tf publisher that stopped): then it holds the newest orientation.

    Parameters
    ----------
    frames : the wrench frames.
    max_wait_s : longest wait, s of stamps.
    """

    def __init__(self, frames: WrenchFrames, max_wait_s: float = 0.5) -> None:
        self.frames = frames
        self.max_wait_ns = int(max_wait_s * 1e9)
        self.pending: deque[tuple[str, int, Any]] = deque()
        self.held = 0  # released after the longest wait, holding the newest orientation

    def push(self, frame_id: str, t_ns: int, item: Any, now_ns: int) -> list[tuple[Any, np.ndarray | None]]:
        """Queue one wrench (``item``: what the caller needs back); return those ready, oldest first, with their
        rotation (None while waiting for a first transform, see :meth:`WrenchFrames.rotation_for`)."""
        self.pending.append((frame_id, t_ns, item))
        return self.release(now_ns, newest_ns=t_ns)

    def release(self, now_ns: int, newest_ns: int | None = None) -> list[tuple[Any, np.ndarray | None]]:
        """The queued wrenches the transforms now cover (call after new transforms), oldest first."""
        out = []
        while self.pending:
            frame_id, t_ns, item = self.pending[0]
            expired = newest_ns is not None and newest_ns - t_ns > self.max_wait_ns
            if self.frames.waits(frame_id, t_ns) and not expired:
                break
            self.held += int(expired and self.frames.waits(frame_id, t_ns))
            self.pending.popleft()
            out.append((item, self.frames.rotation_for(frame_id, now_ns, t_ns)))
        return out
