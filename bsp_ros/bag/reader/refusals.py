"""Why a read refuses a bag: wrong or unsupported topics, no message at all, a required stream missing or empty."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from bsp_ros.bag.errors import (
    BagCorruptError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    UnsupportedBagError,
)
from bsp_ros.bag.mcap_scan import ScanResult
from bsp_ros.bag.reader.counts import Losses
from bsp_ros.bag.reader.sink import SessionSink, Stream, Streams
from bsp_ros.bag.report import ReadReport
from bsp_ros.bag.topics import TopicMap

REQUIRED_MARKERS = ("shoulder", "elbow", "hand")


def check_types(present: Mapping[str, str], expected: Mapping[str, str]) -> None:
    """Raise MessageTypeError if a present topic has a type other than the one expected of it."""
    for topic, msgtype in sorted(present.items()):
        want = expected.get(topic)
        if want is not None and msgtype and msgtype != want:
            raise MessageTypeError(topic, want, [msgtype])


def damage_summary(damage: list[str]) -> str:
    """The damaged places of a bag in one short phrase: how many, and the first (a person reads one line; the
    full list is in the estimate's bag section and the warnings)."""
    if len(damage) <= 1:
        return "".join(damage)
    return f"{len(damage)} damaged places, the first: {damage[0]}"


def refuse_empty_stream(topic: str, report: ReadReport, stream: Stream | None) -> None:
    """Raise the error that says why a required topic returned no message."""
    rep = report.topics.get(topic)
    if report.damaged or (rep is not None and (rep.lost or rep.undecodable)):
        causes = [f"{report.crc_errors} CRC errors"] + (["truncated"] if report.truncated else [])
        if rep is not None and rep.lost:
            causes.append(f"{rep.lost} of the {rep.expected} messages the bag lists are not in its files")
        if rep is not None and rep.undecodable and stream is not None:
            causes.append(f"{rep.undecodable} messages do not decode ({stream.first_error})")
        if report.damage:
            causes.append(damage_summary(report.damage))
        raise BagCorruptError(
            f"{topic}: no intact message survives ({'; '.join(causes)})",
            report.crc_errors,
            report.lost_messages,
        )
    raise MissingTopicError(topic, report.present, detail="has no messages")


def refuse_wrong_channels(sink: SessionSink, present: Mapping[str, str], expected_types: Mapping[str, str]) -> None:
    """Raise if a mapped topic was recorded with another type or encoding than the topic map's."""
    if sink.wrong:
        topic, found = sorted(sink.wrong.items())[0]
        raise MessageTypeError(topic, expected_types[topic], found)
    check_types(present, expected_types)
    if sink.unsupported:
        raise UnsupportedBagError("; ".join(sorted(set(sink.unsupported))))


def refuse_empty_bag(
    root: Path, report: ReadReport, scans: list[ScanResult], expected: dict[str, int] | None, losses: Losses
) -> None:
    """Raise EmptyBagError if the bag has no topic or no message and lost none (BagCorruptError if damaged)."""
    total_expected = sum(expected.values()) if expected is not None else 0
    seen = sum(scan.messages_seen for scan in scans)
    nothing_lost = not (losses.counted or losses.uncounted or losses.unknown)
    if not report.present or (seen == 0 and total_expected == 0 and nothing_lost):
        if report.damaged:
            raise BagCorruptError(
                f"{root}: no intact message survives ({damage_summary(report.damage)})", report.crc_errors, None
            )
        raise EmptyBagError(f"{root} holds no messages")


def require_streams(
    streams: Streams,
    topic_map: TopicMap,
    report: ReadReport,
    decoded: Mapping[str, Stream],
    hand_from_pose: bool,
    topics_may_be_lost: bool,
) -> None:
    """Raise unless the wrench and every required marker have messages, the wrench in one frame.

    Parameters
    ----------
    streams : the collected streams.
    topic_map : their topics.
    report : the read's report.
    decoded : topic -> decoded stream (for why a stream is empty).
    hand_from_pose : the robot's handle pose stands in for the hand marker.
    topics_may_be_lost : the topic list may lack topics lost to damage (a missing topic is then damage).

    Raises
    ------
    MissingTopicError, BagCorruptError, UnsupportedBagError
    """
    required = [m for m in REQUIRED_MARKERS if not (hand_from_pose and m == "hand")]
    for name, topic, count in [("wrench", topic_map.wrench, streams.wrench[0].size)] + [
        (m, topic_map.markers[m], streams.markers[m][0].size if m in streams.markers else 0) for m in required
    ]:
        if topic not in report.present and (name == "wrench" or name not in streams.markers):
            if topics_may_be_lost:
                raise BagCorruptError(
                    f"required topic {topic} is not among the topics that survive the damage "
                    f"({', '.join(sorted(report.present)) or 'none'}; {damage_summary(report.damage)})",
                    report.crc_errors,
                    report.lost_messages,
                )
            raise MissingTopicError(topic, report.present)
        if count == 0:
            refuse_empty_stream(topic, report, decoded.get(topic))
    frames_w = streams.wrench[3]
    if len(frames_w) > 1:
        raise UnsupportedBagError(f"{topic_map.wrench} carries several frame ids {frames_w}: one is expected")


def refuse_damage(root: Path, report: ReadReport) -> None:
    """Raise BagCorruptError if the bag is damaged or lost messages (a strict read)."""
    if report.damaged or report.lost_messages:
        raise BagCorruptError(
            f"{root} is damaged: {report.crc_errors} CRC errors, "
            f"{'truncated, ' if report.truncated else ''}{report.lost_messages} messages lost",
            report.crc_errors,
            report.lost_messages,
        )
