"""What `bsp record` and `bsp play` make of the cell file without middleware: the topics recorded in place of TF, and
what the nodes need that a playback dropped."""

from __future__ import annotations

from dataclasses import replace

from bsp_ros.cell import read_cell_file
from bsp_ros.live.recorder import TopicSpec, parse_topic_specs, transform_topic_for_tf
from bsp_ros.live.replay.report import PlayReport, dropped_for_nodes

CELL = read_cell_file()
TOPICS = ["/ft_sensor/wrench", "/mocap/elbow", "/tf_static", "/tf"]


def test_without_tf2_msgs_the_transform_topic_is_recorded_in_place_of_tf() -> None:
    specs, note = transform_topic_for_tf(parse_topic_specs(TOPICS), CELL.transform_topic, tf_installed=False)
    assert specs == [
        TopicSpec("/ft_sensor/wrench"),
        TopicSpec("/mocap/elbow"),
        TopicSpec("/ft_sensor/transform", "geometry_msgs/msg/TransformStamped"),
    ]
    assert note.startswith("/tf_static, /tf: tf2_msgs is not installed") and "/ft_sensor/transform" in note
    # Listed already: not twice.
    listed = parse_topic_specs([*TOPICS, "/ft_sensor/transform"])
    assert [s.topic for s in transform_topic_for_tf(listed, CELL.transform_topic, False)[0]].count(
        "/ft_sensor/transform"
    ) == 1


def test_with_tf2_msgs_or_without_tf_topics_nothing_changes() -> None:
    specs = parse_topic_specs(TOPICS)
    assert transform_topic_for_tf(specs, CELL.transform_topic, tf_installed=True) == (specs, "")
    plain = parse_topic_specs(TOPICS[:2])
    assert transform_topic_for_tf(plain, CELL.transform_topic, tf_installed=False) == (plain, "")
    kept, note = transform_topic_for_tf(specs, "", tf_installed=False)
    assert [s.topic for s in kept] == TOPICS[:2] and "names no transform topic" in note


def test_what_the_nodes_need_and_a_playback_dropped_is_named() -> None:
    report = PlayReport(path="bag", skipped={"/mocap/elbow": "its type x is not installed", "/camera": "not cdr"})
    assert dropped_for_nodes(report, CELL) == ["/mocap/elbow (its type x is not installed)"]
    bridged = PlayReport(path="bag", bridged={"/tf_static": "/ft_sensor/transform"}, published={"/tf_static": 1})
    (line,) = dropped_for_nodes(bridged, CELL)
    assert "the sensor's rotation" in line and "world -> ft_sensor" in line
    assert dropped_for_nodes(replace(bridged, bridge_sent=1), CELL) == []
