"""Our default identification: all joints in one weighted, bounded least-squares problem."""

from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.identify import identify_joint

__all__ = ["JointConfig", "identify_joint"]
