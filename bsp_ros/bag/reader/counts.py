"""Count each topic's messages read against what the bag lists, and what damage lost where the list is unknown."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from bsp_ros.bag.mcap_scan import ScanResult
from bsp_ros.bag.metadata import BagMetadata
from bsp_ros.bag.reader.sink import Stream
from bsp_ros.bag.report import ReadReport, TopicReport


def expected_message_counts(metadata: BagMetadata | None, scans: list[ScanResult]) -> dict[str, int] | None:
    """Topic -> messages the bag lists: from ``metadata.yaml``, else every file's MCAP summary (None if unknown)."""
    if metadata is not None and metadata.topics:
        return {name: entry.message_count for name, entry in metadata.topics.items()}
    if scans and all(scan.summary_counts is not None for scan in scans):
        counts: dict[str, int] = {}
        for scan in scans:
            for topic, count in (scan.summary_counts or {}).items():
                counts[topic] = counts.get(topic, 0) + count
        return counts
    return None


@dataclass
class Losses:
    """What the scans know of the messages lost to damage, for topics whose expected count is unknown.

    Attributes
    ----------
    counted : topic -> messages listed in the message indexes of damaged chunks.
    uncounted : topics that lost an unknown number of messages (damaged chunks without message indexes).
    unknown : some loss cannot be attributed to a topic (truncation, damaged chunks of unknown channels,
        channels defined only in lost parts): any topic may have lost messages.
    """

    counted: dict[str, int] = field(default_factory=dict)
    uncounted: set[str] = field(default_factory=set)
    unknown: bool = False

    @classmethod
    def of_scans(cls, scans: Iterable[ScanResult]) -> Losses:
        """The losses the scans of a bag's files found."""
        losses = cls()
        for scan in scans:
            losses.add(scan)
        return losses

    def add(self, scan: ScanResult) -> None:
        """Add the losses one file's scan found."""
        for topic, count in scan.lost_in_bad_chunks.items():
            self.counted[topic] = self.counted.get(topic, 0) + count
        self.uncounted |= scan.uncounted_loss
        self.unknown = self.unknown or scan.truncated or scan.uncounted_loss_any
        self.unknown = self.unknown or any(t.startswith("<channel ") for t in scan.lost_in_bad_chunks)

    def of(self, topic: str, damaged: bool) -> int | None:
        """Messages of ``topic`` lost, None if unknown (never 0 where messages may have been lost)."""
        if topic in self.uncounted or (damaged and self.unknown):
            return None
        if topic in self.counted:
            return self.counted[topic]
        return 0 if damaged else None


def _start_topic_report(stream: Stream | None, topic: str, msgtype: str, expected: int | None) -> TopicReport:
    report = TopicReport(topic=topic, msgtype=msgtype, expected=expected)
    if stream is not None:
        report.undecodable = stream.undecodable
    return report


def _finish_counts(report: TopicReport, read: int, lost_to_damage: int | None, warnings: list[str]) -> None:
    report.read = read
    if report.expected is not None:
        missing = report.expected - read - report.undecodable
        if missing < 0:
            warnings.append(f"{report.topic}: {read} messages read but the bag lists only {report.expected}")
        report.lost = max(0, missing)
    else:
        report.lost = lost_to_damage
    if report.lost:
        warnings.append(f"{report.topic}: {report.lost} of {report.expected or '?'} messages lost")
    if report.undecodable:
        warnings.append(f"{report.topic}: {report.undecodable} messages could not be decoded and are not returned")


@dataclass
class TopicCounter:
    """Makes each topic's report of a read: its messages read against those the bag lists, noted in ``report``.

    Attributes
    ----------
    report : the read's report (each topic's report and the warnings are added to it).
    streams : topic -> decoded stream (for its undecodable count).
    expected_types : topic -> the type the topic map expects (for a topic the bag does not type).
    expected : topic -> messages the bag lists, None if unknown.
    losses : what the scans know of the messages lost to damage.
    """

    report: ReadReport
    streams: Mapping[str, Stream]
    expected_types: Mapping[str, str]
    expected: dict[str, int] | None
    losses: Losses

    def count(self, topic: str, read: int) -> TopicReport:
        """Add ``topic``'s report with ``read`` messages read (its lost and undecodable counts, and warnings)."""
        expected = None if self.expected is None else self.expected.get(topic, 0)
        stream = self.streams.get(topic)
        rep = _start_topic_report(stream, topic, self.report.present.get(topic, self.expected_types[topic]), expected)
        _finish_counts(rep, read, self.losses.of(topic, self.report.damaged), self.report.warnings)
        self.report.topics[topic] = rep
        return rep
