"""Which topics of a bag are played, with what type, writer QoS and expected count (the playback plan)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from bsp_ros.bag.errors import NotABagError
from bsp_ros.bag.layout import resolve_bag
from bsp_ros.bag.mcap_scan import ChannelInfo, scan_mcap
from bsp_ros.bag.metadata import METADATA_FILE, read_metadata
from bsp_ros.errors import InputError
from bsp_ros.live.replay.report import PlayReport
from bsp_ros.live.runtime.qos import QosSpec
from bsp_ros.live.sensor_topics import is_sensor_topic

#: Writer history of reliable volatile topics: deep, so a fast replay does not overwrite unacknowledged samples.
RELIABLE_DEPTH = 1000
_LATCHED_DEPTH_MAX = 1000


@dataclass(frozen=True)
class TopicPlan:
    """How one bag topic is published.

    Attributes
    ----------
    topic, msgtype : name and ROS message type.
    qos : writer QoS.
    latched : published ahead of the timeline (transient-local), not again when looping.
    expected : messages the bag lists for it (metadata.yaml or the MCAP summary), None if unknown.
    """

    topic: str
    msgtype: str
    qos: QosSpec
    latched: bool
    expected: int | None


def playback_qos(topic: str, latched: bool, latched_count: int = 1) -> QosSpec:
    """The writer QoS a ROS 2 user expects for a replayed topic.

    Parameters
    ----------
    topic : topic name.
    latched : the topic was recorded transient-local (``/tf_static`` always is).
    latched_count : messages of a latched topic (its history depth, so late joiners get all of them).

    Returns
    -------
    QosSpec
        ``sensor_data`` (best effort, depth 5) for the wrench and marker streams; reliable transient-local
        for latched topics; reliable volatile (depth :data:`RELIABLE_DEPTH`) for everything else.
    """
    if latched:
        return QosSpec(reliable=True, depth=min(max(1, latched_count), _LATCHED_DEPTH_MAX), transient_local=True)
    if is_sensor_topic(topic):
        return QosSpec(reliable=False, depth=5)
    return QosSpec(reliable=True, depth=RELIABLE_DEPTH)


def bag_files(path: str | Path) -> tuple[list[Path], Path | None]:
    """The MCAP files of a bag and its ``metadata.yaml`` (None if absent).

    Parameters
    ----------
    path : bag directory, its ``metadata.yaml`` or an ``.mcap`` file.

    Returns
    -------
    (files, metadata_path)

    Raises
    ------
    BagError subclasses
        As :func:`bsp_ros.bag.layout.resolve_bag` (other storage or file compression: unsupported).
    """
    layout = resolve_bag(path)
    if not layout.files:
        raise NotABagError(f"{path}: {METADATA_FILE} lists no file")
    return layout.files, layout.metadata_path


def _transient_local(durability: object) -> bool:
    """A recorded durability policy: a name (metadata version 9) or rmw's enum value (older rosbag2 writes
    ``durability: 1``, RMW_QOS_POLICY_DURABILITY_TRANSIENT_LOCAL)."""
    if isinstance(durability, int) and not isinstance(durability, bool):
        return durability == 1
    return str(durability or "").lower().startswith("transient_local")


def _latched_from_metadata(meta: Path) -> set[str]:
    """Topics whose offered QoS in ``metadata.yaml`` is transient-local."""
    try:
        info = yaml.safe_load(meta.read_text("utf-8"))["rosbag2_bagfile_information"]
        latched = set()
        for entry in info.get("topics_with_message_count") or []:
            topic = entry["topic_metadata"]
            profiles = topic.get("offered_qos_profiles") or []
            if isinstance(profiles, str):  # rosbag2 before version 9 stores a YAML string
                profiles = yaml.safe_load(profiles) or []
            if profiles and all(_transient_local(p.get("durability")) for p in profiles):
                latched.add(str(topic["name"]))
        return latched
    except (yaml.YAMLError, KeyError, TypeError, AttributeError):
        return set()


class _ChannelSink:
    """Collects channels only (a pre-pass over a bag without metadata)."""

    def wants(self, channel: ChannelInfo) -> bool:
        return False

    def feed(self, *args: Any) -> None:  # pragma: no cover - never fed
        return


def plan_topics(
    files: Sequence[Path], meta: Path | None, topics: Sequence[str] | None, report: PlayReport
) -> list[TopicPlan]:
    """Topics, types, QoS and expected counts of a bag (from metadata.yaml, else a channel pre-pass)."""
    types: dict[str, str] = {}
    encodings: dict[str, str] = {}
    expected: dict[str, int | None] = {}
    latched = _latched_from_metadata(meta) if meta is not None else set()
    if meta is not None:
        metadata = read_metadata(meta)
        for name, entry in metadata.topics.items():
            types[name] = entry.msgtype
            encodings[name] = entry.serialization_format
            expected[name] = entry.message_count
    else:
        counts: dict[str, int] | None = {}
        for file in files:
            scan = scan_mcap(file, _ChannelSink())
            for channel in scan.channels.values():
                types.setdefault(channel.topic, channel.msgtype)
                encodings.setdefault(channel.topic, channel.encoding)
            if counts is not None and scan.summary_counts is not None:
                for name, count in scan.summary_counts.items():
                    counts[name] = counts.get(name, 0) + count
            else:
                counts = None
        for name in types:
            expected[name] = None if counts is None else counts.get(name, 0)
    if "/tf_static" in types:
        latched.add("/tf_static")
    if topics:
        unknown = [t for t in topics if t not in types]
        if unknown:
            raise InputError(f"topics {unknown} are not in the bag; it has {sorted(types)}")
    plans = []
    for name, msgtype in types.items():
        if topics and name not in topics:
            continue
        if encodings.get(name, "cdr") != "cdr":
            report.skipped[name] = f"encoded as {encodings[name]!r}, not cdr"
            continue
        listed = expected.get(name)
        is_latched = name in latched
        qos = playback_qos(name, is_latched, listed or 1)
        plans.append(TopicPlan(name, msgtype, qos, is_latched, listed))
    return plans
