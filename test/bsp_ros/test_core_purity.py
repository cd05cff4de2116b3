"""The pure core imports no middleware, no message package and no bag library."""

from __future__ import annotations

import subprocess
import sys

CORE = [
    "bsp_ros.model",
    "bsp_ros.joint_angles",
    "bsp_ros.identification.joint",
    "bsp_ros.identification.paper",
    "bsp_ros.identification.recursive",
    "bsp_ros.fusion",
    "bsp_ros.anthropometry",
    "bsp_ros.simulation",
    "bsp_ros.pipeline",
    "bsp_ros.online.windowed",
    "bsp_ros.online.causal_angles",
    "bsp_ros.identification.robust",
    "bsp_ros.identification.sensitivity",
    "bsp_ros.tare",
    "bsp_ros.glitches",
    "bsp_ros.weight_support",
    "bsp_ros.mdc",
    "bsp_ros.planning",
]
FORBIDDEN = (
    "rclpy",
    "geometry_msgs",
    "sensor_msgs",
    "nav_msgs",
    "trajectory_msgs",
    "cyclonedds",
    "rosbags",
    "mcap",
)


def test_core_modules_import_no_middleware() -> None:
    code = (
        f"import importlib, sys\nfor m in {CORE!r}: importlib.import_module(m)\n"
        f"print(sorted({{m.split('.')[0] for m in sys.modules if m.startswith({FORBIDDEN!r})}}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
