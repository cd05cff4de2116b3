"""Write a Session as a Jazzy-compatible rosbag2 bag: one chunked, CRC-checked MCAP file and metadata.yaml."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import numpy.typing as npt
from mcap.writer import Writer
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from bsp_ros import __version__
from bsp_ros.bag.cdr import encode_fixed
from bsp_ros.bag.emg_cdr import EMG_TYPE, encode_envelope
from bsp_ros.bag.errors import BagWriteError
from bsp_ros.bag.mcap_writer import started_mcap_writer
from bsp_ros.bag.metadata import (
    METADATA_FILE,
    TopicRecord,
    build_metadata,
    channel_metadata,
    dump_metadata,
    qos_profile,
)
from bsp_ros.bag.topics import POSE_TYPE, TF_TYPE, TRANSFORM_TYPE, WORLD_FRAME, WRENCH_TYPE, TopicMap
from bsp_ros.core.streams import MARKERS_3, Session
from msg_adapters import TransformSample, build_tf_message, quaternion_from_matrix
from msg_adapters.tf import build_transform_stamped

TRUTH_FILE = "truth.json"
DEFAULT_CHUNK_BYTES = 64 * 1024
_IDENTITY_XYZW = np.array([0.0, 0.0, 0.0, 1.0])


def _receive_times(stamps: np.ndarray, delay_ns: int, jitter_ns: int, rng: np.random.Generator) -> np.ndarray:
    """Header stamps plus a transport delay (and uniform jitter), made non-decreasing per topic."""
    log = stamps.astype(np.int64) + np.int64(delay_ns)
    if jitter_ns > 0 and stamps.size:
        log = log + rng.integers(0, jitter_ns, size=stamps.size, dtype=np.int64)
    return np.maximum.accumulate(log) if log.size else log


def _check_session(session: Session, world_frame: str) -> None:
    w = session.wrench
    if not w.frame_id or w.frame_id != w.frame_id.strip():
        raise BagWriteError(f"wrench frame id {w.frame_id!r} is not a usable frame name")
    n = np.asarray(w.t_ns).size
    if np.shape(w.force_n) != (n, 3) or np.shape(w.torque_nm) != (n, 3):
        raise BagWriteError(f"wrench arrays must be ({n}, 3), got {np.shape(w.force_n)}, {np.shape(w.torque_nm)}")
    unknown = [name for name in session.markers if name not in MARKERS_3]
    if unknown:
        raise BagWriteError(f"unknown marker {unknown[0]!r}; markers are {list(MARKERS_3)}")
    poses = {**session.markers, **({} if session.handle_pose is None else {"handle pose": session.handle_pose})}
    for name, series in poses.items():
        m = np.asarray(series.t_ns).size
        if np.shape(series.position_m) != (m, 3):
            raise BagWriteError(f"marker {name} positions must be ({m}, 3), got {np.shape(series.position_m)}")
    emg = session.emg
    if emg is not None:
        shape = (np.asarray(emg.t_ns).size, len(emg.channels))
        if np.shape(emg.envelope) != shape or any("," in name for name in emg.channels):
            raise BagWriteError(
                f"EMG envelopes must be {shape} (samples, channels) under channel names without commas, got "
                f"{np.shape(emg.envelope)} for {list(emg.channels)}"
            )


def write_session_bag(
    out_dir: str | Path,
    session: Session,
    truth_dict: Mapping[str, Any] | None = None,
    *,
    topics: TopicMap | None = None,
    world_frame: str = WORLD_FRAME,
    sensor_translation_m: npt.ArrayLike = (0.0, 0.0, 0.0),
    transport_delay_ns: int = 1_000_000,
    delay_jitter_ns: int = 200_000,
    seed: int = 0,
    chunk_bytes: int = DEFAULT_CHUNK_BYTES,
    tf_static: bool = True,
    tf_samples: Sequence[TransformSample] = (),
    transform_samples: Sequence[TransformSample] = (),
    custom_data: Mapping[str, str] | None = None,
) -> Path:
    """Write ``session`` as a rosbag2 (Jazzy, metadata version 9) bag directory with one MCAP file.

    Topics and types are docs/contract.md's: the wrench in its sensor frame, markers in ``world_frame``,
    and ``/tf_static`` (offered transient-local, so ``ros2 bag play`` republishes it latched) with the
    ``world_frame -> sensor`` transform from ``session.rotation_world_from_sensor``. Chunks are
    ``chunk_bytes`` long, uncompressed, each with a CRC. Receive (log) times are the header stamps plus
    ``transport_delay_ns`` and a uniform jitter in ``[0, delay_jitter_ns)``, non-decreasing per topic;
    publish times are the header stamps. Values are written bit-exact (NaN included).

    Parameters
    ----------
    out_dir : the bag directory to create (must not exist). Its name also names the ``.mcap``:
        never put a subject identifier in it.
    session : the streams to write.
    truth_dict : JSON-ready ground truth, written to ``truth.json`` inside ``out_dir``.
    topics : topic names (default: docs/contract.md's).
    world_frame : the ``world`` frame id.
    sensor_translation_m : (3,) sensor origin in ``world`` for ``/tf_static``, m.
    transport_delay_ns, delay_jitter_ns : receive delay after the header stamp, ns (>= 0).
    seed : seed of the jitter draw.
    chunk_bytes : target MCAP chunk size, bytes (a killed recorder loses at most one chunk).
    tf_static : False leaves ``/tf_static`` out (a bag that lost it, or a cell that publishes the sensor
        orientation on ``/tf`` only).
    tf_samples : transforms written on ``/tf``, one TFMessage each, stamped and received at their stamp
        (e.g. a sensor whose orientation changes during a tare recording).
    transform_samples : transforms written on ``topics.transform`` as TransformStamped, stamped and received at
        their stamp (a cell without tf2_msgs).
    custom_data : more ``custom_data`` pairs for ``metadata.yaml`` (e.g. the cell's stated sensor mounting).

    Returns
    -------
    Path of the bag directory.

    Raises
    ------
    BagWriteError
        If ``out_dir`` exists or the session's arrays are inconsistent.
    """
    out = Path(out_dir)
    if out.exists():
        raise BagWriteError(f"{out} exists already: refusing to overwrite a bag")
    if transport_delay_ns < 0 or delay_jitter_ns < 0 or chunk_bytes < 1024:
        raise BagWriteError("transport delay and jitter must be >= 0 ns and chunk_bytes >= 1024")
    _check_session(session, world_frame)
    topic_map = topics or TopicMap()
    typestore = get_typestore(Stores.ROS2_JAZZY)
    rng = np.random.default_rng(seed)

    payloads = _stream_payloads(session, topic_map, world_frame, transport_delay_ns, delay_jitter_ns, rng)
    starts = [int(p.stamps_ns.min()) for p in payloads if p.stamps_ns.size]
    t0 = min(starts) if starts else 1
    payloads += _transform_payloads(tf_samples, transform_samples, topic_map, typestore)
    if tf_static and session.wrench.frame_id != world_frame:
        static = _tf_static_payload(session, world_frame, sensor_translation_m, t0, topic_map.tf_static, typestore)
        payloads.insert(0, static)

    _write_bag_directory(out, payloads, typestore, chunk_bytes, custom_data, truth_dict)
    return out


def _write_bag_directory(
    out: Path,
    payloads: Sequence[_TopicPayload],
    typestore: Typestore,
    chunk_bytes: int,
    custom_data: Mapping[str, str] | None,
    truth_dict: Mapping[str, Any] | None,
) -> None:
    """Create ``out`` with the MCAP file, ``metadata.yaml`` and (if given) ``truth.json``, or nothing at all.

    Parameters
    ----------
    out : the bag directory (must not exist).
    payloads : the topics' messages, in the order their channels are registered.
    typestore : the Jazzy typestore (message definitions and type hashes).
    chunk_bytes : target MCAP chunk size, bytes.
    custom_data : more ``custom_data`` pairs for ``metadata.yaml``.
    truth_dict : JSON-ready ground truth, or None for no ``truth.json``.
    """
    out.mkdir(parents=True)
    mcap_name = f"{out.name}_0.mcap"
    try:
        with (out / mcap_name).open("xb") as stream:
            metadata = _write_mcap(stream, mcap_name, payloads, typestore, chunk_bytes, custom_data)
        _write_atomic(out / METADATA_FILE, dump_metadata(metadata))
        if truth_dict is not None:
            _write_atomic(out / TRUTH_FILE, json.dumps(_json_ready(truth_dict), indent=2) + "\n")
    except BaseException:
        # Leave no half-written bag that a later read would take for a whole one.
        for file in out.iterdir():
            file.unlink()
        out.rmdir()
        raise


@dataclass(frozen=True, eq=False)
class _TopicPayload:
    """One topic's serialized messages, ready for the MCAP file.

    Attributes
    ----------
    topic : topic name.
    msgtype : ROS 2 message type (``pkg/msg/Type``).
    messages : each message's CDR bytes, in stamp order.
    stamps_ns : (n,) int64 header stamps, ns (the MCAP publish times).
    log_ns : (n,) int64 receive times, ns (the MCAP log times), non-decreasing.
    latched : True for a transient-local topic (``/tf_static``).
    """

    topic: str
    msgtype: str
    messages: list[bytes]
    stamps_ns: np.ndarray
    log_ns: np.ndarray
    latched: bool = False


def _stream_payloads(
    session: Session,
    topic_map: TopicMap,
    world_frame: str,
    delay_ns: int,
    jitter_ns: int,
    rng: np.random.Generator,
) -> list[_TopicPayload]:
    """The wrench, then each marker in ``MARKERS_3`` order, then the handle pose, encoded as fixed-size CDR rows;
    then the EMG envelopes where the session has them (received at their time: the message has no stamp).

    Poses go out in ``world_frame`` with an identity orientation. Receive times are the stamps plus ``delay_ns``
    and a jitter in ``[0, jitter_ns)`` ns drawn from ``rng`` topic after topic in this order, so a seed gives the
    same bag.
    """
    w = session.wrench
    t_w = np.asarray(w.t_ns, dtype=np.int64)
    rows = encode_fixed(t_w, w.frame_id, np.hstack([np.asarray(w.force_n), np.asarray(w.torque_nm)]))
    log_w = _receive_times(t_w, delay_ns, jitter_ns, rng)
    payloads = [_TopicPayload(topic_map.wrench, WRENCH_TYPE, [r.tobytes() for r in rows], t_w, log_w)]
    poses = [(topic_map.markers[name], session.markers[name]) for name in MARKERS_3 if name in session.markers]
    if session.handle_pose is not None:
        poses.append((topic_map.handle_pose, session.handle_pose))
    for topic, series in poses:
        t_m = np.asarray(series.t_ns, dtype=np.int64)
        values = np.hstack([np.asarray(series.position_m, dtype=np.float64), np.tile(_IDENTITY_XYZW, (t_m.size, 1))])
        rows = encode_fixed(t_m, world_frame, values)
        log_m = _receive_times(t_m, delay_ns, jitter_ns, rng)
        payloads.append(_TopicPayload(topic, POSE_TYPE, [r.tobytes() for r in rows], t_m, log_m))
    if session.emg is not None and topic_map.emg:
        # The message carries no stamp: its log time is its time, as a recorder's receive time would be.
        t_e = np.asarray(session.emg.t_ns, dtype=np.int64)
        rows_e = [encode_envelope(session.emg.channels, row) for row in np.asarray(session.emg.envelope)]
        payloads.append(_TopicPayload(topic_map.emg, EMG_TYPE, rows_e, t_e, np.maximum.accumulate(t_e)))
    return payloads


def _transform_payloads(
    tf_samples: Sequence[TransformSample],
    transform_samples: Sequence[TransformSample],
    topic_map: TopicMap,
    typestore: Typestore,
) -> list[_TopicPayload]:
    """``/tf`` (one TFMessage per sample) and the TransformStamped topic, each received at its stamp.

    A topic without samples is left out.
    """
    payloads = []
    if tf_samples:
        tf_stamps = np.array([s.t_ns for s in tf_samples], dtype=np.int64)
        tf_rows = [
            bytes(typestore.serialize_cdr(build_tf_message(lambda n: typestore.types[n], [s]), TF_TYPE))
            for s in tf_samples
        ]
        payloads.append(_TopicPayload(topic_map.tf, TF_TYPE, tf_rows, tf_stamps, np.maximum.accumulate(tf_stamps)))
    if transform_samples:
        transform_stamps = np.array([s.t_ns for s in transform_samples], dtype=np.int64)
        transform_rows = [
            bytes(typestore.serialize_cdr(build_transform_stamped(lambda n: typestore.types[n], s), TRANSFORM_TYPE))
            for s in transform_samples
        ]
        receive = np.maximum.accumulate(transform_stamps)
        payloads.append(_TopicPayload(topic_map.transform, TRANSFORM_TYPE, transform_rows, transform_stamps, receive))
    return payloads


def _tf_static_payload(
    session: Session,
    world_frame: str,
    sensor_translation_m: npt.ArrayLike,
    t0_ns: int,
    topic: str,
    typestore: Typestore,
) -> _TopicPayload:
    """The latched ``world_frame -> sensor`` transform, stamped and received at ``t0_ns``.

    Parameters
    ----------
    session : its ``rotation_world_from_sensor`` (3, 3) is the transform's rotation.
    world_frame : the parent frame id.
    sensor_translation_m : (3,) sensor origin in ``world_frame``, m.
    t0_ns : the first stream message's header stamp, ns.
    topic : the ``/tf_static`` topic name.
    typestore : the Jazzy typestore that serializes the message.

    Raises
    ------
    BagWriteError
        If the rotation is no rotation or the translation is not 3 finite numbers.
    """
    try:
        rotation_xyzw = quaternion_from_matrix(session.rotation_world_from_sensor)
    except ValueError as error:
        raise BagWriteError(f"rotation_world_from_sensor cannot go on /tf_static: {error}") from None
    translation = np.asarray(sensor_translation_m, dtype=np.float64)
    if translation.shape != (3,) or not np.isfinite(translation).all():
        raise BagWriteError(f"sensor_translation_m must be 3 finite numbers, got {translation.tolist()}")
    transform = TransformSample(t0_ns, world_frame, session.wrench.frame_id, translation, rotation_xyzw)
    tf_msg = build_tf_message(lambda n: typestore.types[n], [transform])
    data = bytes(typestore.serialize_cdr(tf_msg, TF_TYPE))
    return _TopicPayload(topic, TF_TYPE, [data], np.array([t0_ns]), np.array([t0_ns]), latched=True)


def _write_mcap(
    stream: BinaryIO,
    mcap_name: str,
    payloads: Sequence[_TopicPayload],
    typestore: Typestore,
    chunk_bytes: int,
    custom_data: Mapping[str, str] | None,
) -> dict[str, Any]:
    """Write ``payloads`` into ``stream`` as one MCAP file, merged by receive time.

    Chunks are ``chunk_bytes`` long (bytes), uncompressed, CRC-checked. Messages go out in receive-time order; ties
    keep ``/tf_static`` first, then the payloads' order, then each topic's sequence.

    Returns
    -------
    The bag's ``metadata.yaml`` document (also stored in the file's ``rosbag2`` metadata record).
    """
    log_all = np.concatenate([p.log_ns for p in payloads])
    topic_all = np.concatenate([np.full(p.log_ns.size, i) for i, p in enumerate(payloads)])
    index_all = np.concatenate([np.arange(p.log_ns.size) for p in payloads])
    order = np.lexsort((index_all, topic_all, log_all))
    writer = started_mcap_writer(stream, chunk_bytes)
    records, channel_ids = _register_channels(writer, payloads, typestore)
    for k, i in zip(topic_all[order].tolist(), index_all[order].tolist(), strict=True):
        payload = payloads[k]
        writer.add_message(
            channel_ids[k],
            log_time=int(payload.log_ns[i]),
            data=payload.messages[i],
            publish_time=int(payload.stamps_ns[i]),
            sequence=i,
        )
    start_ns = int(log_all.min()) if log_all.size else 0
    end_ns = int(log_all.max()) if log_all.size else 0
    custom = {"writer": f"bsp_ros {__version__}", **(custom_data or {})}
    metadata = build_metadata(mcap_name, records, start_ns, end_ns, custom)
    info = dump_metadata(metadata["rosbag2_bagfile_information"])
    writer.add_metadata("rosbag2", {"serialized_metadata": info, "ROS_DISTRO": "jazzy"})
    writer.finish()
    return metadata


def _register_channels(
    writer: Writer, payloads: Sequence[_TopicPayload], typestore: Typestore
) -> tuple[list[TopicRecord], list[int]]:
    """Register each payload's schema (once per type) and channel, with the QoS ``ros2 bag play`` offers again.

    Returns
    -------
    The topics' records for ``metadata.yaml`` and their MCAP channel ids, both in the payloads' order.
    """
    schema_ids: dict[str, int] = {}
    records: list[TopicRecord] = []
    channel_ids: list[int] = []
    for payload in payloads:
        msgtype = payload.msgtype
        if msgtype not in schema_ids:
            msgdef, _ = typestore.generate_msgdef(msgtype, ros_version=2)
            schema_ids[msgtype] = writer.register_schema(msgtype, "ros2msg", msgdef.encode("utf-8"))
        qos = (qos_profile(transient_local=payload.latched, depth=1 if payload.latched else 10),)
        record = TopicRecord(payload.topic, msgtype, typestore.hash_rihs01(msgtype), qos, len(payload.messages))
        channel_ids.append(writer.register_channel(payload.topic, "cdr", schema_ids[msgtype], channel_metadata(record)))
        records.append(record)
    return records, channel_ids


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, "utf-8")
    os.replace(tmp, path)


def _json_ready(value: Any) -> Any:
    """``value`` with numpy scalars/arrays turned into Python numbers and lists; NaN/Inf refused."""
    if isinstance(value, Mapping):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_ready(value.tolist())
    if isinstance(value, np.generic):
        return _json_ready(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        raise BagWriteError(f"truth holds a non-finite number {value!r}: JSON cannot carry it")
    return value
