"""rosbag2 bags (MCAP) <-> Session: a fast, damage-reporting reader and a Jazzy-compatible writer."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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

# Each name's module, imported on first use (PEP 562): a command that reads a bag does not load the writer
# (mcap's writer, yaml) nor one that names an error the reader.
_MODULES = {
    **dict.fromkeys(
        (
            "BagCorruptError",
            "BagNotFoundError",
            "BagWriteError",
            "EmptyBagError",
            "MessageTypeError",
            "MissingTopicError",
            "NotABagError",
            "UnsupportedBagError",
        ),
        "errors",
    ),
    **dict.fromkeys(("BagRead", "read_session"), "reader"),
    **dict.fromkeys(("ReadReport", "TopicReport"), "report"),
    **dict.fromkeys(("POSE_TYPE", "TF_TYPE", "WORLD_FRAME", "WRENCH_TYPE", "TopicMap"), "topics"),
    **dict.fromkeys(("TRUTH_FILE", "write_session_bag"), "writer"),
}


def __getattr__(name: str) -> Any:
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


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
