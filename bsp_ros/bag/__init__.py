"""rosbag2 bags (MCAP) <-> Session: a fast, damage-reporting reader and a Jazzy-compatible writer."""

from bsp_ros.bag.errors import (
    BagCorruptError,
    BagNotFoundError,
    BagWriteError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    NotABagError,
    UnsupportedBagError,
)
from bsp_ros.bag.reader import BagRead, read_session
from bsp_ros.bag.report import ReadReport, TopicReport
from bsp_ros.bag.topics import POSE_TYPE, TF_TYPE, WORLD_FRAME, WRENCH_TYPE, TopicMap
from bsp_ros.bag.writer import TRUTH_FILE, write_session_bag

__all__ = [
    "POSE_TYPE",
    "TF_TYPE",
    "TRUTH_FILE",
    "WORLD_FRAME",
    "WRENCH_TYPE",
    "BagCorruptError",
    "BagNotFoundError",
    "BagRead",
    "BagWriteError",
    "EmptyBagError",
    "MessageTypeError",
    "MissingTopicError",
    "NotABagError",
    "ReadReport",
    "TopicMap",
    "TopicReport",
    "UnsupportedBagError",
    "read_session",
    "write_session_bag",
]
