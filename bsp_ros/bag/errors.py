"""Errors of bag reading and writing: one BagError subclass per failure, each with a stable ``code``."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from bsp_ros.errors import BagError


class BagNotFoundError(BagError):
    """The path given does not exist."""

    code = "not-found"

    def __init__(self, path: str) -> None:
        super().__init__(f"no bag at {path}: the path does not exist")
        self.path = path


class NotABagError(BagError):
    """The path exists but is neither a rosbag2 directory nor an MCAP file."""

    code = "not-a-bag"


class EmptyBagError(BagError):
    """The bag holds no messages at all."""

    code = "empty"


class MissingTopicError(BagError):
    """A required topic is absent (or has no messages); the message lists the topics present."""

    code = "missing-topic"

    def __init__(self, topic: str, present: Mapping[str, str], detail: str = "is not in the bag") -> None:
        listing = ", ".join(f"{name} [{kind}]" for name, kind in sorted(present.items())) or "none"
        super().__init__(f"required topic {topic} {detail}; topics present: {listing}")
        self.topic = topic
        self.present = dict(present)


class MessageTypeError(BagError):
    """A topic carries a message type other than the one expected."""

    code = "wrong-type"

    def __init__(self, topic: str, expected: str, found: Iterable[str]) -> None:
        found_list = sorted(set(found))
        super().__init__(f"topic {topic} carries {', '.join(found_list)}, expected {expected}")
        self.topic = topic
        self.expected = expected
        self.found = found_list


class BagCorruptError(BagError):
    """The bag is damaged (CRC errors, truncation, undecodable records) and strict reading was asked for,
    or the damage left a required stream with no messages."""

    code = "corrupt"

    def __init__(self, message: str, crc_errors: int = 0, lost_messages: int | None = None) -> None:
        super().__init__(message)
        self.crc_errors = crc_errors
        self.lost_messages = lost_messages


class UnsupportedBagError(BagError):
    """The bag uses a storage format, compression or encoding this reader does not handle."""

    code = "unsupported"


class BagWriteError(BagError):
    """A bag cannot be written (target exists, bad session)."""

    code = "write"
