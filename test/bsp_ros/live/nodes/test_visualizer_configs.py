"""The RViz config and the Foxglove layout in docs/ read, and show what arm_visualizer and bsp_identifier publish."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import yaml

from bsp_ros.live.nodes.arm_visualizer import MARKERS_TOPIC, PARAMETERS

ROOT = Path(__file__).resolve().parents[4]
WORLD = next(p.default for p in PARAMETERS if p.name == "world_frame")
NAMESPACES = {"segments", "joints", "com", "com_std", "com_range", "support", "verdict"}


def test_the_rviz_config_shows_the_arm_markers_and_the_segment_frames_in_world() -> None:
    config: dict[str, Any] = yaml.safe_load((ROOT / "docs" / "rviz" / "bsp_cell.rviz").read_text(encoding="utf-8"))
    manager = config["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == WORLD
    displays = {d["Class"]: d for d in manager["Displays"]}
    markers = displays["rviz_default_plugins/MarkerArray"]
    assert markers["Topic"]["Value"] == "/" + MARKERS_TOPIC and set(markers["Namespaces"]) == NAMESPACES
    assert "rviz_default_plugins/TF" in displays


def test_the_foxglove_layout_shows_the_arm_the_precision_signal_the_support_and_the_estimate() -> None:
    layout = json.loads((ROOT / "docs" / "foxglove" / "bsp_cell.json").read_text(encoding="utf-8"))
    panels = layout["configById"]
    text = json.dumps(layout)
    for needed in ("/" + MARKERS_TOPIC, "/bsp/precision_reached.data", "/bsp/weight_support.", "/bsp/estimate_json"):
        assert needed in text, needed
    assert panels["3D!bsp_arm"]["followTf"] == WORLD

    def leaves(node: Any) -> set[str]:
        return {node} if isinstance(node, str) else leaves(node["first"]) | leaves(node["second"])

    assert leaves(layout["layout"]) == set(panels)  # every panel placed, none missing
