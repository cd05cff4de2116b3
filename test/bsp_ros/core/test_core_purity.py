"""The pure core imports no middleware, no message package and no bag library."""

from __future__ import annotations

import subprocess
import sys

# Every module of the core package, and the online building blocks the nodes drive.
CORE_PACKAGES = ["bsp_ros.core", "bsp_ros.live.online"]
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
        "import importlib, pkgutil, sys\n"
        f"for p in {CORE_PACKAGES!r}:\n"
        "    package = importlib.import_module(p)\n"
        "    for info in pkgutil.walk_packages(package.__path__, p + '.'): importlib.import_module(info.name)\n"
        f"print(sorted({{m.split('.')[0] for m in sys.modules if m.startswith({FORBIDDEN!r})}}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
