"""The topic names a cell records (each a parameter), the message types docs/contract.md fixes for them, and the
sensor rotation a cell states (its cell file) for a bag that records none."""

from __future__ import annotations

from dataclasses import dataclass, field

from bsp_ros.bag.emg_cdr import EMG_TYPE
from bsp_ros.core.streams import MARKERS_3

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TRANSFORM_TYPE = "geometry_msgs/msg/TransformStamped"
WORLD_FRAME = "world"


def _default_markers() -> dict[str, str]:
    return {name: f"/mocap/{name}" for name in MARKERS_3}


@dataclass(frozen=True)
class StatedRotation:
    """The sensor's mounting as a cell states it, not as a transform recorded it.

    Attributes
    ----------
    world_frame, sensor_frame : the rotation's frames.
    rotation_xyzw : (4,) rotation ``world <- sensor`` as a unit quaternion ``[x, y, z, w]``.
    source : ``cell`` (given for the read, `bsp identify --cell`) or ``metadata`` (written into the bag by
        `bsp record` from its cell file).
    where : what states it, for messages (``cell file X: ft_sensor.rotation_xyzw``).
    """

    world_frame: str
    sensor_frame: str
    rotation_xyzw: tuple[float, float, float, float]
    source: str
    where: str


@dataclass(frozen=True, kw_only=True)
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
    transform : the TransformStamped topic of the sensor frame in ``world`` (where tf2_msgs is missing, the
        rotation's topic; '' none): read where TF does not connect the wrench frame.
    stated : the sensor's mounting a cell file states (`bsp identify --cell`), used where the bag records no
        rotation.
    world_frame : the frame of the markers and of gravity.
    emg : the muscles' EMG envelopes (``std_msgs/msg/Float32MultiArray``, optional; '' none): where a bag has them,
        the stretches they show active are left out as the torque's bursts are.
    """

    wrench: str = "/ft_sensor/wrench"
    markers: dict[str, str] = field(default_factory=_default_markers)
    tf_static: str = "/tf_static"
    tf: str = "/tf"
    handle_pose: str = "/robot/handle_pose"
    transform: str = "/ft_sensor/transform"
    stated: StatedRotation | None = None
    world_frame: str = WORLD_FRAME
    emg: str = "/emg/envelope"

    def expected_types(self) -> dict[str, str]:
        """Topic -> required message type, for every topic of the map.

        A topic named for two roles keeps the wrench (or tf) type, not the marker one: a marker topic given as
        the wrench topic then fails the reader's type check (MessageTypeError) instead of having its poses
        decoded as wrenches.
        """
        types = {topic: POSE_TYPE for topic in (*self.markers.values(), self.handle_pose)}
        if self.transform:
            types[self.transform] = TRANSFORM_TYPE
        if self.emg:
            types[self.emg] = EMG_TYPE
        types.update({self.tf_static: TF_TYPE, self.tf: TF_TYPE, self.wrench: WRENCH_TYPE})
        return types
