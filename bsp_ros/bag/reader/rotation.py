"""The wrench sensor's rotation into the world frame (/tf_static and /tf, the TransformStamped topic, else the
rotation a cell states), and the warnings when it is held or disagrees with the cell."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bsp_ros.bag.report import ReadReport
from bsp_ros.bag.topics import StatedRotation
from bsp_ros.cell import DISAGREE_DEG, angle_between_deg
from msg_adapters import TransformSample
from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.rotation_track import RotationTrack, TransformBuffer


def wrench_rotation(
    transforms: TransformBuffer,
    t_ns: np.ndarray,
    wrench_frame: str,
    world_frame: str,
    frame_aliases: Mapping[str, str],
    report: ReadReport,
    topic_transforms: TransformBuffer | None = None,
    stated: StatedRotation | None = None,
) -> np.ndarray:
    """R_world_from_wrench: (3, 3) for a fixed chain, (N, 3, 3) at each wrench stamp when a /tf link turns.

    In order: the TF chain (/tf_static, /tf), the TransformStamped topic, a frame alias, the rotation a cell states
    (``stated``: the cell file given, else the one `bsp record` wrote into the bag's metadata), else the identity
    (``assumed``). A turning chain is slerped between its samples
    (:class:`msg_adapters.rotation_track.TransformBuffer`); wrench samples before its first or after its last sample
    hold the nearest orientation (see :func:`held_warning`). A recorded fixed rotation more than
    :data:`DISAGREE_DEG` off the stated one is used, with a warning.

    Parameters
    ----------
    transforms : the bag's /tf_static and /tf samples.
    t_ns : (N,) wrench stamps, ns.
    wrench_frame, world_frame : the chain's ends.
    frame_aliases : frame id -> frame it coincides with, used when no transform connects the wrench frame.
    report : the read's report (its rotation source and warnings are set).
    topic_transforms : the TransformStamped topic's samples (None: the bag has none).
    stated : the sensor's mounting a cell states, for a bag whose transforms do not connect the wrench frame.

    Returns
    -------
    np.ndarray
    """
    if wrench_frame == world_frame:
        report.rotation_source = "tf"
        return np.eye(3)
    for buffer, source, what in ((transforms, "tf", "/tf"), (topic_transforms, "topic", "TransformStamped")):
        track = None if buffer is None else buffer.track(world_frame, wrench_frame, t_ns)
        if track is not None:
            report.rotation_source = source
            warning = held_warning(track, t_ns, f"{wrench_frame} -> {world_frame}", what)
            report.warnings += [warning] if warning else []
            _compare_with_stated(track, stated, wrench_frame, world_frame, report)
            return track.session_rotation
    aliased = _aliased(transforms, t_ns, wrench_frame, world_frame, frame_aliases, report)
    if aliased is not None:
        return aliased
    if stated is not None and (stated.sensor_frame, stated.world_frame) == (wrench_frame, world_frame):
        report.rotation_source = stated.source
        report.warnings.append(
            f"no transform {world_frame} -> {wrench_frame} was recorded: the sensor's rotation "
            f"{[round(v, 6) for v in stated.rotation_xyzw]} is the one {stated.where} states"
        )
        return np.asarray(matrix_from_quaternion(stated.rotation_xyzw), dtype=np.float64)
    if stated is not None:
        report.warnings.append(
            f"{stated.where} states the rotation {stated.world_frame} -> {stated.sensor_frame}, not of the wrench "
            f"frame {world_frame} -> {wrench_frame}: not used"
        )
    report.rotation_source = "assumed"
    report.warnings.append(
        f"no transform connects the wrench frame {wrench_frame} to {world_frame}: "
        f"the wrench is taken as given in {world_frame}"
    )
    return np.eye(3)


def _aliased(
    transforms: TransformBuffer,
    t_ns: np.ndarray,
    wrench_frame: str,
    world_frame: str,
    frame_aliases: Mapping[str, str],
    report: ReadReport,
) -> np.ndarray | None:
    """The rotation of the frame ``frame_aliases`` maps the wrench frame to (None: no alias, or it connects not)."""
    if wrench_frame not in frame_aliases:
        return None
    source = frame_aliases[wrench_frame]
    track = transforms.track(world_frame, source, t_ns) if source != world_frame else None
    if source != world_frame and track is None:
        return None
    report.rotation_source = "alias"
    report.warnings.append(f"wrench frame {wrench_frame} taken as {source} (frame mapping option)")
    return np.eye(3) if track is None else track.session_rotation


def _compare_with_stated(
    track: RotationTrack, stated: StatedRotation | None, wrench_frame: str, world_frame: str, report: ReadReport
) -> None:
    """Warn where a recorded fixed rotation is more than :data:`DISAGREE_DEG` off the one the cell states."""
    if stated is None or track.turning or (stated.sensor_frame, stated.world_frame) != (wrench_frame, world_frame):
        return
    angle = angle_between_deg(track.session_rotation, matrix_from_quaternion(stated.rotation_xyzw))
    if angle > DISAGREE_DEG:
        report.warnings.append(
            f"the recorded rotation {world_frame} -> {wrench_frame} is {angle:.1f} deg off the one {stated.where} "
            f"states (more than {DISAGREE_DEG:g} deg): the recorded one is used; check the cell file's "
            "ft_sensor.rotation_xyzw"
        )


# Wrench samples at most this far outside the /tf track hold its nearest orientation without a warning: the
# streams of a recording start and stop a fraction of a second apart.
HOLD_QUIET_S = 0.5


def held_warning(track: RotationTrack, t_ns: np.ndarray, what: str, origin: str = "/tf") -> str:
    """A warning when wrench samples lie more than :data:`HOLD_QUIET_S` outside a turning /tf track ('' if not).

    They are held at the track's nearest orientation, not dropped: the reader returns the streams as
    recorded, and at the ends of a recording the turning handle (moved at the arm's ~2 deg/s) errs by
    less than the sensor noise over the fraction of a second the streams start and stop apart. A longer
    hold (a /tf publisher that started late or died) is named so the user can judge the estimate.
    """
    count, longest_s = track.held_summary(t_ns)
    if count == 0 or longest_s <= HOLD_QUIET_S:
        return ""
    return (
        f"the rotation {what} turns (from {origin}) but {count} of {np.asarray(t_ns).size} wrench samples lie outside "
        f"its {origin} samples (up to {longest_s:.3g} s): the nearest orientation is held there"
    )


def usable_transform(sample: TransformSample) -> bool:
    """A transform with a finite, non-zero quaternion (others cannot give a rotation)."""
    q = sample.rotation_xyzw
    return bool(np.isfinite(q).all() and np.any(q != 0.0))
