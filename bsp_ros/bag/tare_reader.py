"""Read a tare recording (wrench, and the sensor's orientation over time from /tf_static and /tf) from a bag."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bsp_ros.bag.errors import (
    BagCorruptError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    UnsupportedBagError,
)
from bsp_ros.bag.layout import resolve_bag
from bsp_ros.bag.mcap_scan import scan_mcap
from bsp_ros.bag.reader.rotation import held_warning, usable_transform
from bsp_ros.bag.reader.sink import SessionSink, collect_stream
from bsp_ros.bag.topics import WORLD_FRAME, TopicMap
from msg_adapters import TransformSample
from msg_adapters.rotation_track import TransformBuffer


@dataclass
class TareRead:
    """A tare recording as arrays.

    Attributes
    ----------
    t_ns : (N,) int64 wrench stamps, ns (receive order).
    force_n, torque_nm : (N, 3) wrench in the sensor frame.
    frame_id : the wrench's frame.
    rotations_world_from_sensor : (N, 3, 3) orientation at each wrench stamp, or None when no transform
        connects the sensor to ``world``.
    orientation_source : ``"tf"`` (varying, from /tf), ``"tf_static"`` (fixed), ``"world"`` (the wrench is
        in ``world``) or ``"unknown"``.
    warnings : what the read noticed (damage, lost messages, missing transforms).
    """

    t_ns: np.ndarray
    force_n: np.ndarray
    torque_nm: np.ndarray
    frame_id: str
    rotations_world_from_sensor: np.ndarray | None
    orientation_source: str
    warnings: list[str] = field(default_factory=list)


def read_tare_bag(path: str | Path, topics: TopicMap | None = None, world_frame: str = WORLD_FRAME) -> TareRead:
    """Read the wrench and the sensor's orientation of a tare recording (markers are not needed).

    The orientation at each wrench stamp is the /tf_static + /tf chain ``world -> wrench frame``
    (:class:`msg_adapters.rotation_track.TransformBuffer`, as `bsp identify` reads it): slerped between
    /tf stamps and held beyond them; fixed if no /tf link of the chain turns.

    Raises
    ------
    BagError subclasses
        Missing path, not a bag, empty, no wrench messages, wrong types, several wrench frames.
    """
    topic_map = topics or TopicMap()
    wanted = TopicMap(topic_map.wrench, {}, topic_map.tf_static, topic_map.tf)
    root = Path(path)
    layout = resolve_bag(root)
    sink = SessionSink(wanted)
    present: dict[str, str] = {}
    warnings = list(layout.warnings) + [f"damage: {d}" for d in layout.damage]
    seen = 0
    damage = list(layout.damage)
    complete = True
    for file in layout.files:
        scan = scan_mcap(file, sink)
        seen += scan.messages_seen
        complete = complete and scan.channels_complete
        damage += scan.damage
        present.update({c.topic: c.msgtype for c in scan.channels.values()})
        if scan.crc_errors or scan.truncated:
            warnings.append(f"{file.name}: {scan.crc_errors} CRC errors, truncated={scan.truncated}")
    if sink.wrong:
        topic, found = sorted(sink.wrong.items())[0]
        raise MessageTypeError(topic, wanted.expected_types()[topic], found)
    if sink.unsupported:
        raise UnsupportedBagError("; ".join(sorted(set(sink.unsupported))))
    if (not present or seen == 0) and not damage:
        raise EmptyBagError(f"{root} holds no messages")
    t_ns, values, _, frames, _ = collect_stream(sink.streams.get(wanted.wrench), 6)
    if wanted.wrench not in present:
        if damage and not complete and layout.metadata is None:  # its channel may have been in the damaged part
            raise BagCorruptError(f"{wanted.wrench} is not among the topics that survive ({'; '.join(damage)})")
        raise MissingTopicError(wanted.wrench, present)
    if t_ns.size == 0:
        if damage:
            raise BagCorruptError(f"{wanted.wrench}: no intact message survives ({'; '.join(damage)})")
        raise MissingTopicError(wanted.wrench, present, detail="has no messages")
    if len(frames) > 1:
        raise UnsupportedBagError(f"{wanted.wrench} carries several frame ids {frames}: one is expected")
    frame = frames[0]

    def samples(topic: str) -> list[TransformSample]:
        stream = sink.streams.get(topic)
        if stream is None:
            return []
        return [s for _, batch in sorted(stream.transforms, key=lambda x: x[0]) for s in batch if usable_transform(s)]

    transforms = TransformBuffer()
    transforms.add_static(samples(wanted.tf_static))
    transforms.add(samples(wanted.tf))
    n = t_ns.size
    rotations: np.ndarray | None
    if frame == world_frame:
        rotations = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        source = "world"
    else:
        track = transforms.track(world_frame, frame, t_ns)
        if track is None:
            rotations, source = None, "unknown"
            warnings.append(
                f"no transform connects the wrench frame {frame} to {world_frame}: the sensor's orientation "
                "is unknown, so only the constant load can be estimated"
            )
        else:
            rotations = track.rotations
            source = "tf" if track.turning else "tf_static"
            warning = held_warning(track, t_ns, f"{frame} -> {world_frame}")
            if warning:
                warnings.append(warning)
    return TareRead(
        t_ns=t_ns,
        force_n=np.ascontiguousarray(values[:, :3]),
        torque_nm=np.ascontiguousarray(values[:, 3:]),
        frame_id=frame,
        rotations_world_from_sensor=rotations,
        orientation_source=source,
        warnings=warnings,
    )
