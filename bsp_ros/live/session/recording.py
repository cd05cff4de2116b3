"""The recorder's sessions on disk: each running session's input messages go into its own bag as they arrive.

Where tf2_msgs is installed a bag records /tf_static and /tf; where it is not, the cell's TransformStamped topic in
their place (a sensor that turns with the handle sends its rotation there) and, in ``metadata.yaml``'s
``custom_data``, the sensor mounting the cell states: the bag then reads as one `bsp record` made, its rotation from
the transforms recorded, else from that mounting.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bsp_ros.bag import TopicMap
from bsp_ros.bag.cell_metadata import custom_data_from_cell
from bsp_ros.bag.topics import EMG_TYPE, POSE_TYPE, TF_TYPE, TRANSFORM_TYPE, WRENCH_TYPE
from bsp_ros.cell import CellDescription
from bsp_ros.live.session.control import EndCause, Reply, SessionControl, SessionEnd, SessionStart
from bsp_ros.live.session.spool import SessionSpool, SpoolSummary, spool_dir_name

__all__ = ["Change", "SessionRecording", "topic_types"]

# /tf_static messages kept between sessions (each session's bag starts with them: they are sent once, latched).
STATIC_KEPT = 100
IDENTITY_XYZW = (0.0, 0.0, 0.0, 1.0)


def topic_types(topics: TopicMap, with_tf: bool = True) -> dict[str, str]:
    """Topic -> message type of every input a session records: the tf topics ``with_tf`` (tf2_msgs installed), else
    the TransformStamped topic ``topics.transform`` in their place; the EMG envelopes where ``topics.emg`` names
    them (a bag holds the topic only where messages came)."""
    types = {topic: POSE_TYPE for topic in (*topics.markers.values(), topics.handle_pose) if topic}
    if with_tf:
        types.update({topics.tf_static: TF_TYPE, topics.tf: TF_TYPE})
    elif topics.transform:
        types[topics.transform] = TRANSFORM_TYPE
    if topics.emg:
        types[topics.emg] = EMG_TYPE
    types[topics.wrench] = WRENCH_TYPE
    return types


@dataclass(frozen=True, kw_only=True)
class Change:
    """What a call changed: a session started (and its bag), one finished (its bag complete), one discarded."""

    started: SessionStart | None = None
    path: Path | None = None
    finished: tuple[SessionEnd, SpoolSummary] | None = None
    discarded: tuple[SessionEnd, Path] | None = None


class SessionRecording:
    """Sessions as bags: a :class:`SessionControl` decides, this opens, fills and closes each session's bag.

    Parameters
    ----------
    control : the session state (subject, starts and ends).
    recordings_dir : the folder the session bags go into (one ``live_<UTC time>`` bag per session).
    topics : the input topic names (``topics.transform``: the TransformStamped topic recorded without tf2_msgs;
        ``topics.world_frame``: the frame the mounting is stated in).
    with_tf : whether /tf_static and /tf are heard (tf2_msgs installed).
    rotation_xyzw : (4,) the sensor's mounting, rotation world <- wrench frame, written into each bag's metadata
        where ``with_tf`` is False: read where the bag records no transform, as the live identifier takes it where
        none arrives (None or the identity: nothing written).
    cell : the cell description the recorder was given: named in the bag's metadata where ``rotation_xyzw`` is its
        mounting (a parameter that overrides the mounting is named as such).
    """

    def __init__(
        self,
        control: SessionControl,
        recordings_dir: Path,
        topics: TopicMap,
        with_tf: bool,
        rotation_xyzw: Sequence[float] | None = None,
        cell: CellDescription | None = None,
    ) -> None:
        self.control = control
        self.recordings_dir = Path(recordings_dir)
        self.topics = topics
        self.types = topic_types(topics, with_tf)
        given = None if with_tf or rotation_xyzw is None else np.asarray(rotation_xyzw, dtype=float)
        # The identity is no information: without it the bag reads as `bsp identify` reads a bag without tf.
        self.rotation_xyzw = None if given is None or np.allclose(given, IDENTITY_XYZW) else given
        self.mounting_from = "session_recorder parameter wrench_frame_rotation_xyzw"
        if cell is not None and given is not None and np.allclose(given, cell.rotation_xyzw, atol=1e-9):
            self.mounting_from = cell.source
        self.spool: SessionSpool | None = None
        self.static_kept: deque[tuple[int, bytes]] = deque(maxlen=STATIC_KEPT)
        # The newest TransformStamped: each bag starts with it (a fixed sensor may send its transform seldom).
        self.transform_kept: tuple[int, bytes] | None = None
        self.sensor_frame = ""  # the running session's wrench frame

    def on_message(self, topic: str, t_ns: int, data: bytes) -> Change:
        """A raw message of an input topic received at ``t_ns`` (ns, node clock); the wrench may start a session."""
        change = Change()
        if topic == self.topics.tf_static:
            self.static_kept.append((t_ns, data))
        if topic == self.topics.transform and topic in self.types:
            self.transform_kept = (t_ns, data)
        if topic == self.topics.wrench:
            started = self.control.on_input(t_ns)
            if started is not None:
                change = self._open(started)
            if self.spool is not None and not self.sensor_frame:
                self.sensor_frame = str(self.spool.decode(topic, data).header.frame_id)
        if self.spool is not None:
            self.spool.add(topic, t_ns, data)
        return change

    def start(self, now_ns: int, retest: bool = False) -> tuple[Reply, Change]:
        """The start service."""
        reply = self.control.start(now_ns, retest)
        return reply, self._open(reply.started) if reply.started is not None else Change()

    def stop(self, now_ns: int, cause: EndCause = EndCause.STOP) -> tuple[Reply, Change]:
        """The stop service, the end message (``cause``), or the recorder's shutdown."""
        reply = self.control.stop(now_ns, cause)
        return reply, self._close(reply.ended) if reply.ended is not None else Change()

    def reset(self, now_ns: int) -> tuple[Reply, Change]:
        """The reset service: the running session's bag is deleted and a new session's opened."""
        reply = self.control.reset(now_ns)
        if reply.ended is None or reply.started is None:
            return reply, Change()
        discarded = self._close(reply.ended)
        opened = self._open(reply.started)
        return reply, Change(started=opened.started, path=opened.path, discarded=discarded.discarded)

    def tick(self, now_ns: int) -> Change:
        """Periodically: end a session by silence or time limit, and flush the open bag's chunk to the OS."""
        ended = self.control.due(now_ns)
        if ended is not None:
            return self._close(ended)
        if self.spool is not None:
            self.spool.flush()
        return Change()

    def _open(self, started: SessionStart) -> Change:
        path = self.recordings_dir / spool_dir_name(started.started_ns)
        suffix = 1
        while path.exists():
            suffix += 1
            path = self.recordings_dir / f"{spool_dir_name(started.started_ns)}_{suffix}"
        latched = frozenset({self.topics.tf_static})
        self.spool = SessionSpool(path, self.types, latched)
        self.sensor_frame = ""
        for t_ns, data in self.static_kept:
            self.spool.add(self.topics.tf_static, t_ns, data)
        if self.transform_kept is not None:
            self.spool.add(self.topics.transform, *self.transform_kept)
        return Change(started=started, path=path)

    def _close(self, ended: SessionEnd) -> Change:
        spool, self.spool = self.spool, None
        assert spool is not None
        if ended.cause is EndCause.RESET:
            spool.discard()
            return Change(discarded=(ended, spool.path))
        return Change(finished=(ended, spool.finish(self._mounting())))

    def _mounting(self) -> dict[str, str]:
        """The ``custom_data`` stating the sensor's mounting for the session's wrench frame ({}: nothing to state)."""
        if self.rotation_xyzw is None or not self.sensor_frame or self.sensor_frame == self.topics.world_frame:
            return {}
        x, y, z, w = (float(v) for v in self.rotation_xyzw)
        cell = CellDescription(
            source=self.mounting_from,
            world_frame=self.topics.world_frame,
            sensor_frame=self.sensor_frame,
            rotation_xyzw=(x, y, z, w),
        )
        return custom_data_from_cell(cell)
