"""The topic names a cell records (each a parameter) and the message types docs/contract.md fixes for them."""

from __future__ import annotations

from dataclasses import dataclass, field

from bsp_ros.core.streams import MARKERS_3

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
WORLD_FRAME = "world"


def _default_markers() -> dict[str, str]:
    return {name: f"/mocap/{name}" for name in MARKERS_3}


@dataclass(frozen=True)
class TopicMap:
    """Topic names of one cell.

    Attributes
    ----------
    wrench : the WrenchStamped topic.
    markers : marker name (``shoulder``, ``elbow``, ``wrist``, ``hand``) -> its PoseStamped topic.
        ``wrist`` is optional: without it the chain has 2 segments.
    tf_static, tf : the TFMessage topics.
    handle_pose : the robot's PoseStamped of the contact point in ``world`` (optional): where a bag has it, it
        stands for the ``hand`` marker.
    """

    wrench: str = "/ft_sensor/wrench"
    markers: dict[str, str] = field(default_factory=_default_markers)
    tf_static: str = "/tf_static"
    tf: str = "/tf"
    handle_pose: str = "/robot/handle_pose"

    def expected_types(self) -> dict[str, str]:
        """Topic -> required message type, for every topic of the map.

        A topic named for two roles keeps the wrench (or tf) type, not the marker one: a marker topic given as
        the wrench topic then fails the reader's type check (MessageTypeError) instead of having its poses
        decoded as wrenches.
        """
        types = {topic: POSE_TYPE for topic in (*self.markers.values(), self.handle_pose)}
        types.update({self.tf_static: TF_TYPE, self.tf: TF_TYPE, self.wrench: WRENCH_TYPE})
        return types
