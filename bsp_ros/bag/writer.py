"""Write a Session as a Jazzy-compatible rosbag2 bag: one chunked, CRC-checked MCAP file and metadata.yaml."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

from bsp_ros import __version__
from bsp_ros.bag.cdr import encode_fixed
from bsp_ros.bag.errors import BagWriteError
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

    # Serialized payloads per topic (rows of equal length), header stamps and receive times.
    payloads: list[tuple[str, str, list[bytes], np.ndarray, np.ndarray, bool]] = []
    w = session.wrench
    t_w = np.asarray(w.t_ns, dtype=np.int64)
    rows = encode_fixed(t_w, w.frame_id, np.hstack([np.asarray(w.force_n), np.asarray(w.torque_nm)]))
    payloads.append(
        (
            topic_map.wrench,
            WRENCH_TYPE,
            [r.tobytes() for r in rows],
            t_w,
            _receive_times(t_w, transport_delay_ns, delay_jitter_ns, rng),
            False,
        )
    )
    poses = [(topic_map.markers[name], session.markers[name]) for name in MARKERS_3 if name in session.markers]
    if session.handle_pose is not None:
        poses.append((topic_map.handle_pose, session.handle_pose))
    for topic, series in poses:
        t_m = np.asarray(series.t_ns, dtype=np.int64)
        values = np.hstack([np.asarray(series.position_m, dtype=np.float64), np.tile(_IDENTITY_XYZW, (t_m.size, 1))])
        rows = encode_fixed(t_m, world_frame, values)
        payloads.append(
            (
                topic,
                POSE_TYPE,
                [r.tobytes() for r in rows],
                t_m,
                _receive_times(t_m, transport_delay_ns, delay_jitter_ns, rng),
                False,
            )
        )
    starts = [int(p[3].min()) for p in payloads if p[3].size]
    t0 = min(starts) if starts else 1
    if tf_samples:
        tf_stamps = np.array([s.t_ns for s in tf_samples], dtype=np.int64)
        tf_rows = [
            bytes(typestore.serialize_cdr(build_tf_message(lambda n: typestore.types[n], [s]), TF_TYPE))
            for s in tf_samples
        ]
        payloads.append((topic_map.tf, TF_TYPE, tf_rows, tf_stamps, np.maximum.accumulate(tf_stamps), False))
    if transform_samples:
        transform_stamps = np.array([s.t_ns for s in transform_samples], dtype=np.int64)
        transform_rows = [
            bytes(typestore.serialize_cdr(build_transform_stamped(lambda n: typestore.types[n], s), TRANSFORM_TYPE))
            for s in transform_samples
        ]
        receive = np.maximum.accumulate(transform_stamps)
        payloads.append((topic_map.transform, TRANSFORM_TYPE, transform_rows, transform_stamps, receive, False))
    if tf_static and w.frame_id != world_frame:
        try:
            rotation_xyzw = quaternion_from_matrix(session.rotation_world_from_sensor)
        except ValueError as error:
            raise BagWriteError(f"rotation_world_from_sensor cannot go on /tf_static: {error}") from None
        translation = np.asarray(sensor_translation_m, dtype=np.float64)
        if translation.shape != (3,) or not np.isfinite(translation).all():
            raise BagWriteError(f"sensor_translation_m must be 3 finite numbers, got {translation.tolist()}")
        transform = TransformSample(t0, world_frame, w.frame_id, translation, rotation_xyzw)
        tf_msg = build_tf_message(lambda n: typestore.types[n], [transform])
        data = bytes(typestore.serialize_cdr(tf_msg, TF_TYPE))
        payloads.insert(0, (topic_map.tf_static, TF_TYPE, [data], np.array([t0]), np.array([t0]), True))

    # Merge every message by receive time (ties: /tf_static first, then topic order, then sequence).
    log_all = np.concatenate([p[4] for p in payloads])
    topic_all = np.concatenate([np.full(p[4].size, i) for i, p in enumerate(payloads)])
    index_all = np.concatenate([np.arange(p[4].size) for p in payloads])
    order = np.lexsort((index_all, topic_all, log_all))

    out.mkdir(parents=True)
    mcap_name = f"{out.name}_0.mcap"
    records: list[TopicRecord] = []
    try:
        with (out / mcap_name).open("xb") as stream:
            writer = Writer(
                stream,
                chunk_size=chunk_bytes,
                compression=CompressionType.NONE,
                enable_crcs=True,
                enable_data_crcs=True,
            )
            writer.start(profile="ros2", library=f"bsp_ros {__version__} (mcap python)")
            schema_ids: dict[str, int] = {}
            channel_ids: list[int] = []
            for topic, msgtype, messages, _, _, latched in payloads:
                if msgtype not in schema_ids:
                    msgdef, _ = typestore.generate_msgdef(msgtype, ros_version=2)
                    schema_ids[msgtype] = writer.register_schema(msgtype, "ros2msg", msgdef.encode("utf-8"))
                qos = (qos_profile(transient_local=latched, depth=1 if latched else 10),)
                record = TopicRecord(topic, msgtype, typestore.hash_rihs01(msgtype), qos, len(messages))
                channel_ids.append(writer.register_channel(topic, "cdr", schema_ids[msgtype], channel_metadata(record)))
                records.append(record)
            stamps_all = [p[3] for p in payloads]
            for k, i in zip(topic_all[order].tolist(), index_all[order].tolist(), strict=True):
                writer.add_message(
                    channel_ids[k],
                    log_time=int(payloads[k][4][i]),
                    data=payloads[k][2][i],
                    publish_time=int(stamps_all[k][i]),
                    sequence=i,
                )
            start_ns = int(log_all.min()) if log_all.size else 0
            end_ns = int(log_all.max()) if log_all.size else 0
            custom = {"writer": f"bsp_ros {__version__}", **(custom_data or {})}
            metadata = build_metadata(mcap_name, records, start_ns, end_ns, custom)
            info = dump_metadata(metadata["rosbag2_bagfile_information"])
            writer.add_metadata("rosbag2", {"serialized_metadata": info, "ROS_DISTRO": "jazzy"})
            writer.finish()
        _write_atomic(out / METADATA_FILE, dump_metadata(metadata))
        if truth_dict is not None:
            _write_atomic(out / TRUTH_FILE, json.dumps(_json_ready(truth_dict), indent=2) + "\n")
    except BaseException:
        # Leave no half-written bag that a later read would take for a whole one.
        for file in out.iterdir():
            file.unlink()
        out.rmdir()
        raise
    return out


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
