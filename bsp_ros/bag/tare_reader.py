"""Read a tare recording: the wrench, and the sensor's orientation over time found as `bsp identify` finds it
(/tf_static and /tf, the cell's TransformStamped topic, else the mounting a cell file or the bag's metadata states)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bsp_ros.bag.cell_metadata import stated_from_custom_data
from bsp_ros.bag.errors import (
    BagCorruptError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    UnsupportedBagError,
)
from bsp_ros.bag.layout import BagLayout, resolve_bag
from bsp_ros.bag.mcap_scan import scan_mcap
from bsp_ros.bag.reader.rotation import held_warning, usable_transform
from bsp_ros.bag.reader.sink import SessionSink, Stream, collect_stream
from bsp_ros.bag.topics import WORLD_FRAME, StatedRotation, TopicMap
from bsp_ros.cell import DISAGREE_DEG, angle_between_deg
from msg_adapters import TransformSample
from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.rotation_track import RotationTrack, TransformBuffer

__all__ = ["ORIENTATION_SOURCES", "TareRead", "read_tare_bag"]

#: Where a tare's orientation comes from: ``tf`` (turning, from /tf), ``tf_static`` (a fixed TF chain), ``topic``
#: (the TransformStamped topic), ``cell`` (the cell file given for the read), ``metadata`` (the cell's mounting
#: `bsp record` wrote into the bag), ``world`` (the wrench is in ``world``) or ``unknown``.
ORIENTATION_SOURCES = ("tf", "tf_static", "topic", "cell", "metadata", "world", "unknown")


@dataclass(frozen=True, kw_only=True)
class TareRead:
    """A tare recording as arrays.

    Attributes
    ----------
    t_ns : (N,) int64 wrench stamps, ns (receive order).
    force_n, torque_nm : (N, 3) wrench in the sensor frame, N and Nm.
    frame_id : the wrench's frame.
    rotations_world_from_sensor : (N, 3, 3) orientation at each wrench stamp, or None when neither a transform nor
        a stated mounting connects the sensor to ``world``.
    orientation_source : one of :data:`ORIENTATION_SOURCES`.
    warnings : what the read noticed (damage, lost messages, missing or disagreeing transforms).
    """

    t_ns: np.ndarray
    force_n: np.ndarray
    torque_nm: np.ndarray
    frame_id: str
    rotations_world_from_sensor: np.ndarray | None
    orientation_source: str
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class _Scan:
    """What the scan of a bag's files found: the topics present, the messages seen, the damage."""

    present: dict[str, str]
    seen: int
    damage: tuple[str, ...]
    complete: bool
    warnings: tuple[str, ...]


def read_tare_bag(path: str | Path, topics: TopicMap | None = None, world_frame: str = WORLD_FRAME) -> TareRead:
    """Read the wrench and the sensor's orientation of a tare recording (markers are not needed).

    The orientation at each wrench stamp comes, in order, from the /tf_static + /tf chain ``world -> wrench
    frame``, the TransformStamped topic ``topics.transform`` (a cell without tf2_msgs: `bsp record` records it in
    place of TF), the mounting ``topics.stated`` (`bsp tare --cell FILE`), or the mounting `bsp record` wrote into
    ``metadata.yaml``'s ``custom_data`` (:class:`msg_adapters.rotation_track.TransformBuffer`, as `bsp identify`
    reads a session: slerped between stamped transforms and held beyond them). A recorded fixed rotation more than
    :data:`bsp_ros.cell.DISAGREE_DEG` off the stated mounting is used, with a warning.

    Parameters
    ----------
    path : bag directory, its ``metadata.yaml``, or an ``.mcap`` file.
    topics : the wrench, TF and transform topics, and the stated mounting (default: docs/contract.md's names).
    world_frame : the frame of gravity (z up).

    Returns
    -------
    TareRead

    Raises
    ------
    BagError subclasses
        Missing path, not a bag, empty, no wrench messages, wrong types, several wrench frames.
    """
    topic_map = topics or TopicMap()
    wanted = TopicMap(
        wrench=topic_map.wrench,
        markers={},
        tf_static=topic_map.tf_static,
        tf=topic_map.tf,
        handle_pose="",
        transform=topic_map.transform,
        emg="",
    )
    root = Path(path)
    layout = resolve_bag(root)
    sink = SessionSink(wanted)
    scan = _scan(layout, sink)
    t_ns, values, frame = _wrench(root, sink, wanted, scan)
    stated, problem = _stated(topic_map, layout)
    rotations, source, noticed = _orientation(sink, wanted, stated, frame, world_frame, t_ns)
    return TareRead(
        t_ns=t_ns,
        force_n=np.ascontiguousarray(values[:, :3]),
        torque_nm=np.ascontiguousarray(values[:, 3:]),
        frame_id=frame,
        rotations_world_from_sensor=rotations,
        orientation_source=source,
        warnings=scan.warnings + ((problem,) if problem else ()) + tuple(noticed),
    )


def _scan(layout: BagLayout, sink: SessionSink) -> _Scan:
    """Scan every file of ``layout`` into ``sink``; refuse wrong types and unsupported encodings."""
    present: dict[str, str] = {}
    warnings = [*layout.warnings, *(f"damage: {d}" for d in layout.damage)]
    seen, damage, complete = 0, list(layout.damage), True
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
        raise MessageTypeError(topic, sink.expected[topic], found)
    if sink.unsupported:
        raise UnsupportedBagError("; ".join(sorted(set(sink.unsupported))))
    return _Scan(present=present, seen=seen, damage=tuple(damage), complete=complete, warnings=tuple(warnings))


def _wrench(root: Path, sink: SessionSink, wanted: TopicMap, scan: _Scan) -> tuple[np.ndarray, np.ndarray, str]:
    """The wrench stamps (N,), values (N, 6) and its one frame; a bag without them is refused, naming why."""
    damage = "; ".join(scan.damage)
    if (not scan.present or scan.seen == 0) and not scan.damage:
        raise EmptyBagError(f"{root} holds no messages")
    t_ns, values, _, frames, _ = collect_stream(sink.streams.get(wanted.wrench), 6)
    if wanted.wrench not in scan.present:
        if scan.damage and not scan.complete:  # its channel may have been in the damaged part
            raise BagCorruptError(f"{wanted.wrench} is not among the topics that survive ({damage})")
        raise MissingTopicError(wanted.wrench, scan.present)
    if t_ns.size == 0:
        if scan.damage:
            raise BagCorruptError(f"{wanted.wrench}: no intact message survives ({damage})")
        raise MissingTopicError(wanted.wrench, scan.present, detail="has no messages")
    if len(frames) > 1:
        raise UnsupportedBagError(f"{wanted.wrench} carries several frame ids {frames}: one is expected")
    return t_ns, values, frames[0]


def _stated(topic_map: TopicMap, layout: BagLayout) -> tuple[StatedRotation | None, str]:
    """The mounting a cell file states for the read, else the one in the bag's metadata; and a problem to warn of."""
    if topic_map.stated is not None:
        return topic_map.stated, ""
    if layout.metadata is None:
        return None, ""
    return stated_from_custom_data(layout.metadata.custom)


def _samples(stream: Stream | None) -> list[TransformSample]:
    """A transform topic's usable samples, in receive order."""
    if stream is None:
        return []
    return [s for _, batch in sorted(stream.transforms, key=lambda x: x[0]) for s in batch if usable_transform(s)]


def _orientation(
    sink: SessionSink,
    wanted: TopicMap,
    stated: StatedRotation | None,
    frame: str,
    world_frame: str,
    t_ns: np.ndarray,
) -> tuple[np.ndarray | None, str, list[str]]:
    """The (N, 3, 3) orientations at ``t_ns`` (None: unknown), their source and the warnings of finding them."""
    n = t_ns.size
    if frame == world_frame:
        return np.broadcast_to(np.eye(3), (n, 3, 3)).copy(), "world", []
    tf = TransformBuffer()
    tf.add_static(_samples(sink.streams.get(wanted.tf_static)))
    tf.add(_samples(sink.streams.get(wanted.tf)))
    topic = TransformBuffer()
    topic.add(_samples(sink.streams.get(wanted.transform)) if wanted.transform else [])
    what = f"{frame} -> {world_frame}"
    for buffer, origin in ((tf, "/tf"), (topic, wanted.transform)):
        track = buffer.track(world_frame, frame, t_ns)
        if track is None:
            continue
        source = ("tf" if track.turning else "tf_static") if buffer is tf else "topic"
        noticed = (held_warning(track, t_ns, what, origin), _disagreement(track, stated, frame, world_frame))
        warnings = [w for w in noticed if w]
        return track.rotations, source, warnings
    if stated is not None and (stated.sensor_frame, stated.world_frame) == (frame, world_frame):
        rotation = np.asarray(matrix_from_quaternion(stated.rotation_xyzw), dtype=np.float64)
        xyzw = [round(v, 6) for v in stated.rotation_xyzw]
        warning = f"no transform {world_frame} -> {frame} was recorded: the sensor's rotation {xyzw} is the one "
        return np.broadcast_to(rotation, (n, 3, 3)).copy(), stated.source, [warning + f"{stated.where} states"]
    warnings = []
    if stated is not None:
        warnings.append(
            f"{stated.where} states the rotation {stated.world_frame} -> {stated.sensor_frame}, not of the wrench "
            f"frame {world_frame} -> {frame}: not used"
        )
    warnings.append(
        f"no transform connects the wrench frame {frame} to {world_frame} and no cell states its mounting: the "
        "sensor's orientation is unknown, so only the constant load can be estimated (give --cell FILE)"
    )
    return None, "unknown", warnings


def _disagreement(track: RotationTrack, stated: StatedRotation | None, frame: str, world_frame: str) -> str:
    """A warning where a recorded fixed rotation is more than :data:`DISAGREE_DEG` off the stated mounting."""
    if stated is None or track.turning or (stated.sensor_frame, stated.world_frame) != (frame, world_frame):
        return ""
    angle = angle_between_deg(track.session_rotation, matrix_from_quaternion(stated.rotation_xyzw))
    if angle <= DISAGREE_DEG:
        return ""
    return (
        f"the recorded rotation {world_frame} -> {frame} is {angle:.1f} deg off the one {stated.where} states "
        f"(more than {DISAGREE_DEG:g} deg): the recorded one is used; check the cell file's ft_sensor.rotation_xyzw"
    )
