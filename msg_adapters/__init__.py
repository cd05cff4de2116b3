"""ROS messages <-> numpy: attribute access only, so rclpy and rosbags messages both work."""

from msg_adapters._types import TypeLookup, float_sequence
from msg_adapters.diagnostics import (
    DiagnosticArraySample,
    DiagnosticStatusData,
    build_diagnostic_array,
    read_diagnostic_array,
)
from msg_adapters.inertia import InertiaSample, build_inertia_stamped, read_inertia_stamped
from msg_adapters.joint_state import JointStateSample, build_joint_state, read_joint_state
from msg_adapters.pose import (
    PoseSample,
    build_pose_stamped,
    build_quaternion,
    marker_series_from_messages,
    pose_samples_from_series,
    read_pose_stamped,
    read_quaternion,
)
from msg_adapters.rotation import matrix_from_quaternion, quaternion_from_matrix
from msg_adapters.stamps import (
    NS_PER_S,
    build_header,
    build_time,
    ns_to_sec_nanosec,
    read_header,
    stamp_to_ns,
)
from msg_adapters.tf import (
    TransformSample,
    build_tf_message,
    build_transform_stamped,
    read_tf_message,
    read_transform_stamped,
    rotation_between,
)
from msg_adapters.wrench import (
    WrenchSample,
    build_vector3,
    build_wrench_stamped,
    read_vector3,
    read_wrench_stamped,
    wrench_samples_from_series,
    wrench_series_from_messages,
)

__all__ = [
    "NS_PER_S",
    "DiagnosticArraySample",
    "DiagnosticStatusData",
    "InertiaSample",
    "JointStateSample",
    "PoseSample",
    "TransformSample",
    "TypeLookup",
    "WrenchSample",
    "build_diagnostic_array",
    "build_header",
    "build_inertia_stamped",
    "build_joint_state",
    "build_pose_stamped",
    "build_quaternion",
    "build_tf_message",
    "build_time",
    "build_transform_stamped",
    "build_vector3",
    "build_wrench_stamped",
    "float_sequence",
    "marker_series_from_messages",
    "matrix_from_quaternion",
    "ns_to_sec_nanosec",
    "pose_samples_from_series",
    "quaternion_from_matrix",
    "read_diagnostic_array",
    "read_header",
    "read_inertia_stamped",
    "read_joint_state",
    "read_pose_stamped",
    "read_quaternion",
    "read_tf_message",
    "read_transform_stamped",
    "read_vector3",
    "read_wrench_stamped",
    "rotation_between",
    "stamp_to_ns",
    "wrench_samples_from_series",
    "wrench_series_from_messages",
]
