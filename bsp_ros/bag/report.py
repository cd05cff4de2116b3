"""What a bag read found: counts per topic, losses, CRC errors and data anomalies, never silently fixed."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np


@dataclass(kw_only=True)
class TopicReport:
    """Counts and anomalies of one topic.

    Attributes
    ----------
    topic, msgtype : name and message type.
    read : messages returned.
    expected : messages the bag says it holds (metadata.yaml, else the MCAP summary); None if unknown.
    lost : ``expected - read`` when known (messages in damaged or missing parts of the file).
    undecodable : messages whose bytes could not be decoded (not returned).
    non_finite : returned samples with a NaN or Inf value (returned as recorded).
    out_of_order : returned samples whose header stamp is earlier than the previous one's.
    duplicate_stamps : returned samples whose header stamp equals the previous one's.
    nonpositive_stamps : returned samples stamped at or before time 0.
    frame_ids : the ``header.frame_id`` values seen.
    first_stamp_ns, last_stamp_ns : min and max header stamp (None if no samples).
    """

    topic: str
    msgtype: str
    read: int = 0
    expected: int | None = None
    lost: int | None = None
    undecodable: int = 0
    non_finite: int = 0
    out_of_order: int = 0
    duplicate_stamps: int = 0
    nonpositive_stamps: int = 0
    frame_ids: list[str] = field(default_factory=list)
    first_stamp_ns: int | None = None
    last_stamp_ns: int | None = None

    def note_stamps(self, t_ns: np.ndarray) -> None:
        """Count out-of-order, duplicate and non-positive stamps of ``t_ns`` (in returned order)."""
        steps = np.diff(t_ns)
        self.out_of_order = int((steps < 0).sum())
        self.duplicate_stamps = int((steps == 0).sum())
        self.nonpositive_stamps = int((t_ns <= 0).sum())
        if t_ns.size:
            self.first_stamp_ns, self.last_stamp_ns = int(t_ns.min()), int(t_ns.max())

    @property
    def anomalies(self) -> int:
        """Number of returned samples with a questionable value or stamp."""
        return self.non_finite + self.out_of_order + self.duplicate_stamps + self.nonpositive_stamps


@dataclass(kw_only=True)
class ReadReport:
    """Everything a bag read noticed.

    Attributes
    ----------
    path : the bag directory or MCAP file read.
    files : the MCAP files read, in order.
    topics : topic -> its :class:`TopicReport` (the topics read, required or not).
    present : every topic in the bag -> its message type.
    n_segments : 2 or 3, from the marker topics present.
    crc_errors : chunks whose CRC did not match (their messages are not returned).
    chunks_read : chunks decoded.
    chunks_without_crc : chunks written without a CRC (damage there cannot be detected).
    truncated : a file ended before its footer (an interrupted recording or a cut copy).
    damage : one line per damaged place (file, byte offset, what).
    bytes_read, bytes_total : progress over all files, bytes.
    rotation_source : how ``rotation_world_from_sensor`` was found: ``tf`` (/tf_static, /tf), ``topic`` (the
        TransformStamped topic), ``alias``, ``cell`` (the cell file given for the read), ``metadata`` (the cell
        file's mounting `bsp record` wrote into the bag) or ``assumed`` (none: the wrench frame taken as ``world``).
    warnings : human-readable warnings, one per finding.
    """

    path: str
    files: list[str] = field(default_factory=list)
    topics: dict[str, TopicReport] = field(default_factory=dict)
    present: dict[str, str] = field(default_factory=dict)
    n_segments: int = 0
    crc_errors: int = 0
    chunks_read: int = 0
    chunks_without_crc: int = 0
    truncated: bool = False
    damage: list[str] = field(default_factory=list)
    bytes_read: int = 0
    bytes_total: int = 0
    rotation_source: str = "assumed"
    warnings: list[str] = field(default_factory=list)

    @property
    def lost_messages(self) -> int | None:
        """Messages known lost over all topics read; None if some topic's expected count is unknown
        while the file is damaged."""
        total = 0
        for topic in self.topics.values():
            if topic.lost is None:
                if self.damaged:
                    return None
                continue
            total += topic.lost
        return total

    @property
    def damaged(self) -> bool:
        """True if any part of the bag could not be read (CRC error, truncation, undecodable data)."""
        return bool(self.crc_errors or self.truncated or self.damage)

    @property
    def clean(self) -> bool:
        """True if nothing was lost or damaged and no returned sample is questionable."""
        return (
            not self.damaged
            and not self.lost_messages
            and all(t.anomalies == 0 and t.undecodable == 0 for t in self.topics.values())
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready copy (with ``lost_messages``, ``damaged`` and ``clean``)."""
        data = asdict(self)
        data.update(lost_messages=self.lost_messages, damaged=self.damaged, clean=self.clean)
        return data
