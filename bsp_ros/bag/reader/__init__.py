"""Read a rosbag2 MCAP bag into a Session: the scan's decoding sink, message counts, refusals, the wrench rotation."""

from bsp_ros.bag.reader.read import BagRead, read_session
from bsp_ros.bag.reader.refusals import REQUIRED_MARKERS
from bsp_ros.bag.reader.rotation import HOLD_QUIET_S, held_warning

__all__ = ["HOLD_QUIET_S", "REQUIRED_MARKERS", "BagRead", "held_warning", "read_session"]
