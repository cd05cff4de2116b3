"""The planning core imports no middleware and no message package (numpy/scipy only)."""

from __future__ import annotations

import subprocess
import sys

FORBIDDEN = ("rclpy", "geometry_msgs", "trajectory_msgs", "nav_msgs", "cyclonedds", "rosbags", "mcap", "msg_adapters")


def test_planning_imports_no_middleware() -> None:
    code = (
        "import sys\nimport bsp_ros.core.planning\n"
        f"print(sorted({{m.split('.')[0] for m in sys.modules if m.startswith({FORBIDDEN!r})}}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout
