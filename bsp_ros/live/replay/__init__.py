"""`bsp play`: a rosbag2 MCAP bag played onto ROS 2 topics (its plan, scan thread, /clock, report)."""

from bsp_ros.live.replay.plan import RELIABLE_DEPTH, TopicPlan, bag_files, playback_qos
from bsp_ros.live.replay.player import play_bag
from bsp_ros.live.replay.report import PlayReport
from bsp_ros.live.sensor_topics import SENSOR_TOPIC_PREFIXES

__all__ = [
    "RELIABLE_DEPTH",
    "SENSOR_TOPIC_PREFIXES",
    "PlayReport",
    "TopicPlan",
    "bag_files",
    "play_bag",
    "playback_qos",
]
