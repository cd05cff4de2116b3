"""The MCAP scanner: every intact message of one file's wanted channels, raw, with the damage it found."""

from bsp_ros.bag.mcap_scan.interface import ChannelInfo, MessageSink, ProgressCallback, ScanResult
from bsp_ros.bag.mcap_scan.records import MCAP_MAGIC, check_mcap_magic
from bsp_ros.bag.mcap_scan.scan import scan_mcap

__all__ = [
    "MCAP_MAGIC",
    "ChannelInfo",
    "MessageSink",
    "ProgressCallback",
    "ScanResult",
    "check_mcap_magic",
    "scan_mcap",
]
