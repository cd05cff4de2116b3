"""``geometry_msgs/msg/TransformStamped`` and ``tf2_msgs/msg/TFMessage`` <-> numpy, and TF chain rotations."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from msg_adapters._types import TypeLookup
from msg_adapters.pose import IDENTITY_XYZW, build_quaternion, read_quaternion
from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.stamps import build_header, read_header
from msg_adapters.wrench import build_vector3, read_vector3


@dataclass(frozen=True)
class TransformSample:
    """One stamped transform: the pose of ``child_frame`` in ``parent_frame``.

    Attributes
    ----------
    t_ns : header stamp in nanoseconds.
    parent_frame : ``header.frame_id``.
    child_frame : ``child_frame_id``.
    translation_m : (3,) float64, origin of the child in the parent, m.
    rotation_xyzw : (4,) float64, quaternion taking child-frame vectors into the parent frame.
    """

    t_ns: int
    parent_frame: str
    child_frame: str
    translation_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation_xyzw: np.ndarray = field(default_factory=lambda: np.array(IDENTITY_XYZW))

    def rotation_parent_from_child(self) -> np.ndarray:
        """The (3, 3) rotation taking child-frame vectors into the parent frame."""
        return matrix_from_quaternion(self.rotation_xyzw)


def read_transform_stamped(msg: Any) -> TransformSample:
    """Read a ``TransformStamped`` into a :class:`TransformSample`."""
    t_ns, parent = read_header(msg.header)
    return TransformSample(
        t_ns,
        parent,
        str(msg.child_frame_id),
        read_vector3(msg.transform.translation),
        read_quaternion(msg.transform.rotation),
    )


def build_transform_stamped(types: TypeLookup, sample: TransformSample) -> Any:
    """Build a ``geometry_msgs/msg/TransformStamped`` from a :class:`TransformSample`."""
    transform = types("geometry_msgs/msg/Transform")(
        translation=build_vector3(types, sample.translation_m),
        rotation=build_quaternion(types, sample.rotation_xyzw),
    )
    return types("geometry_msgs/msg/TransformStamped")(
        header=build_header(types, sample.t_ns, sample.parent_frame),
        child_frame_id=str(sample.child_frame),
        transform=transform,
    )


def read_tf_message(msg: Any) -> list[TransformSample]:
    """Read every transform of a ``tf2_msgs/msg/TFMessage``, in order."""
    return [read_transform_stamped(t) for t in msg.transforms]


def build_tf_message(types: TypeLookup, samples: Sequence[TransformSample]) -> Any:
    """Build a ``tf2_msgs/msg/TFMessage`` holding ``samples`` in order."""
    return types("tf2_msgs/msg/TFMessage")(transforms=[build_transform_stamped(types, s) for s in samples])


def _rotations_to_ancestors(frame: str, parents: dict[str, tuple[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Map ``frame`` and each of its ancestors ``a`` to the rotation ``R_a_from_frame``."""
    chain = {frame: np.eye(3)}
    current, rotation = frame, np.eye(3)
    while current in parents:
        parent, r_parent_from_current = parents[current]
        if parent in chain:  # a cycle: stop where it closes
            break
        rotation = r_parent_from_current @ rotation
        chain[parent] = rotation
        current = parent
    return chain


def rotation_between(transforms: Iterable[TransformSample], target: str, source: str) -> np.ndarray | None:
    """Compose a TF tree into the rotation taking ``source`` vectors into ``target`` (no translation).

    Parameters
    ----------
    transforms : transforms of ``/tf_static`` and ``/tf``; for a child frame given several times the last
        one wins (as in a tf2 buffer at the latest time).
    target, source : frame ids.

    Returns
    -------
    (3, 3) float64 ``R_target_from_source``, or None when the two frames are not connected.
    """
    parents: dict[str, tuple[str, np.ndarray]] = {}
    for sample in transforms:
        parents[sample.child_frame] = (sample.parent_frame, sample.rotation_parent_from_child())
    from_source = _rotations_to_ancestors(source, parents)
    from_target = _rotations_to_ancestors(target, parents)
    for ancestor, r_ancestor_from_source in from_source.items():
        if ancestor in from_target:
            return np.asarray(from_target[ancestor].T @ r_ancestor_from_source, dtype=np.float64)
    return None
