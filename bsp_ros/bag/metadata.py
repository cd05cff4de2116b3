"""rosbag2 ``metadata.yaml`` (version 9, as Jazzy writes it): parse what a reader needs, build one for a writer."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from bsp_ros.bag.errors import NotABagError

METADATA_FILE = "metadata.yaml"
_INFINITE = {"sec": 9223372036, "nsec": 854775807}  # RMW_DURATION_INFINITE as rosbag2 records it


@dataclass(frozen=True)
class TopicEntry:
    """One topic of ``topics_with_message_count``."""

    name: str
    msgtype: str
    serialization_format: str
    message_count: int


@dataclass(frozen=True, kw_only=True)
class BagMetadata:
    """The parts of ``metadata.yaml`` a reader uses."""

    version: int
    storage_identifier: str
    relative_file_paths: tuple[str, ...]
    message_count: int
    topics: dict[str, TopicEntry] = field(default_factory=dict)
    compression_mode: str = ""
    compression_format: str = ""
    custom: dict[str, str] = field(default_factory=dict)


def _loader() -> type[yaml.SafeLoader]:
    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_metadata(path: Path) -> BagMetadata:
    """Parse ``path`` (a ``metadata.yaml``).

    Raises
    ------
    NotABagError
        If the file is not YAML or lacks ``rosbag2_bagfile_information``.
    """
    try:
        data = yaml.load(path.read_text("utf-8"), Loader=_loader())
        info = data["rosbag2_bagfile_information"]
        topics = {}
        for entry in info.get("topics_with_message_count") or []:
            meta = entry["topic_metadata"]
            topics[str(meta["name"])] = TopicEntry(
                str(meta["name"]),
                str(meta["type"]),
                str(meta.get("serialization_format", "cdr")),
                int(entry.get("message_count", 0)),
            )
        return BagMetadata(
            version=int(info.get("version", 0)),
            storage_identifier=str(info.get("storage_identifier", "")),
            relative_file_paths=tuple(str(p) for p in info.get("relative_file_paths") or []),
            message_count=int(info.get("message_count", 0)),
            topics=topics,
            compression_mode=str(info.get("compression_mode") or ""),
            compression_format=str(info.get("compression_format") or ""),
            custom=_custom_data(info.get("custom_data")),
        )
    except (yaml.YAMLError, KeyError, TypeError, ValueError, UnicodeDecodeError) as error:
        raise NotABagError(f"{path} is not a rosbag2 metadata file ({error.__class__.__name__}: {error})") from None


def _custom_data(data: Any) -> dict[str, str]:
    """``custom_data`` as string pairs ({} where absent or not a mapping: rosbag2 writes ``~`` for none)."""
    if not isinstance(data, dict):
        return {}
    return {str(key): str(value) for key, value in data.items()}


def qos_profile(*, transient_local: bool = False, depth: int = 10) -> dict[str, Any]:
    """An offered QoS profile as rosbag2 (metadata version 9) records it: reliable, keep-last ``depth``;
    transient-local durability for latched topics such as ``/tf_static``, else volatile."""
    return {
        "history": "keep_last",
        "depth": depth,
        "reliability": "reliable",
        "durability": "transient_local" if transient_local else "volatile",
        "deadline": dict(_INFINITE),
        "lifespan": dict(_INFINITE),
        "liveliness": "automatic",
        "liveliness_lease_duration": dict(_INFINITE),
        "avoid_ros_namespace_conventions": False,
    }


def dump_qos(profiles: Sequence[Mapping[str, Any]]) -> str:
    """QoS profiles as the YAML string stored in MCAP channel metadata (``offered_qos_profiles``)."""
    return yaml.safe_dump([dict(p) for p in profiles], sort_keys=False).strip()


@dataclass(frozen=True)
class TopicRecord:
    """A topic as written: name, type, its type hash, offered QoS profiles and message count."""

    name: str
    msgtype: str
    type_hash: str
    qos: tuple[Mapping[str, Any], ...]
    message_count: int


def channel_metadata(topic: TopicRecord) -> dict[str, str]:
    """The MCAP channel metadata of ``topic``, as rosbag2's MCAP storage writes it.

    rosbags pairs each ``metadata.yaml`` topic with the MCAP channel of the same name, type and offered QoS
    profiles, and reads nothing of a topic whose channel carries other profiles (without an error). Build
    both from the same :class:`TopicRecord` so they always agree.

    Parameters
    ----------
    topic : the topic as :func:`build_metadata` lists it.

    Returns
    -------
    dict of str
        ``offered_qos_profiles`` (the profiles as a YAML string) and ``topic_type_hash`` (RIHS01).
    """
    return {"offered_qos_profiles": dump_qos(topic.qos), "topic_type_hash": topic.type_hash}


def build_metadata(
    file_name: str, topics: Sequence[TopicRecord], start_ns: int, end_ns: int, custom: Mapping[str, str]
) -> dict[str, Any]:
    """The ``metadata.yaml`` content of a one-file MCAP bag (rosbag2 version 9, Jazzy).

    Parameters
    ----------
    file_name : the ``.mcap`` file name, relative to the bag directory.
    topics : every topic written, in channel order, each with the profiles its MCAP channel carries
        (:func:`channel_metadata`): version 9 lists them as a YAML sequence, the channel as a YAML string.
    start_ns, end_ns : first and last receive time, ns.
    custom : ``custom_data`` string pairs.
    """
    count = sum(t.message_count for t in topics)
    duration = max(0, end_ns - start_ns)
    return {
        "rosbag2_bagfile_information": {
            "version": 9,
            "storage_identifier": "mcap",
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start_ns},
            "message_count": count,
            "topics_with_message_count": [
                {
                    "topic_metadata": {
                        "name": t.name,
                        "type": t.msgtype,
                        "serialization_format": "cdr",
                        "offered_qos_profiles": [dict(q) for q in t.qos],
                        "type_description_hash": t.type_hash,
                    },
                    "message_count": t.message_count,
                }
                for t in topics
            ],
            "compression_format": "",
            "compression_mode": "",
            "relative_file_paths": [file_name],
            "files": [
                {
                    "path": file_name,
                    "starting_time": {"nanoseconds_since_epoch": start_ns},
                    "duration": {"nanoseconds": duration},
                    "message_count": count,
                }
            ],
            "custom_data": dict(custom),
            "ros_distro": "jazzy",
        }
    }


def dump_metadata(metadata: Mapping[str, Any]) -> str:
    """YAML text of ``metadata`` (key order kept)."""
    return yaml.safe_dump(dict(metadata), sort_keys=False, default_flow_style=False)
