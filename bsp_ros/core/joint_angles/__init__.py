"""Joint angles, segment lengths and direction-of-motion velocities from motion-capture markers."""

from bsp_ros.core.joint_angles.config import KinematicsConfig, MarkerKinematics
from bsp_ros.core.joint_angles.filtering import direction_noise_gain, kinematics_from_angles, kinematics_from_markers
from bsp_ros.core.joint_angles.geometry import joint_angles_from_positions, sagittal_from_world
from bsp_ros.core.joint_angles.resample import resample_kinematics, resample_motion, resample_with_motion, valid_stamps

__all__ = [
    "KinematicsConfig",
    "MarkerKinematics",
    "direction_noise_gain",
    "joint_angles_from_positions",
    "kinematics_from_angles",
    "kinematics_from_markers",
    "resample_kinematics",
    "resample_motion",
    "resample_with_motion",
    "sagittal_from_world",
    "valid_stamps",
]
