"""The wrench sensor's rotation into the world frame from /tf_static and /tf, and the warning when it is held."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from bsp_ros.bag.report import ReadReport
from msg_adapters import TransformSample
from msg_adapters.rotation_track import RotationTrack, TransformBuffer


def wrench_rotation(
    transforms: TransformBuffer,
    t_ns: np.ndarray,
    wrench_frame: str,
    world_frame: str,
    frame_aliases: Mapping[str, str],
    report: ReadReport,
) -> np.ndarray:
    """R_world_from_wrench: (3, 3) for a fixed chain, (N, 3, 3) at each wrench stamp when a /tf link turns.

    A turning chain is slerped between its /tf samples (:class:`msg_adapters.rotation_track.TransformBuffer`);
    wrench samples before its first or after its last /tf sample hold the nearest orientation (see
    :func:`held_warning`).

    Parameters
    ----------
    transforms : the bag's /tf_static and /tf samples.
    t_ns : (N,) wrench stamps, ns.
    wrench_frame, world_frame : the chain's ends.
    frame_aliases : frame id -> frame it coincides with, used when no transform connects the wrench frame.
    report : the read's report (its rotation source and warnings are set).

    Returns
    -------
    np.ndarray
    """
    if wrench_frame == world_frame:
        report.rotation_source = "tf"
        return np.eye(3)
    source = wrench_frame
    track = transforms.track(world_frame, source, t_ns)
    if track is None and wrench_frame in frame_aliases:
        source = frame_aliases[wrench_frame]
        track = transforms.track(world_frame, source, t_ns) if source != world_frame else None
        if source == world_frame or track is not None:
            report.rotation_source = "alias"
            report.warnings.append(f"wrench frame {wrench_frame} taken as {source} (frame mapping option)")
            return np.eye(3) if track is None else track.session_rotation
    if track is None:
        report.rotation_source = "assumed"
        report.warnings.append(
            f"no transform connects the wrench frame {wrench_frame} to {world_frame}: "
            f"the wrench is taken as given in {world_frame}"
        )
        return np.eye(3)
    report.rotation_source = "tf"
    warning = held_warning(track, t_ns, f"{wrench_frame} -> {world_frame}")
    if warning:
        report.warnings.append(warning)
    return track.session_rotation


# Wrench samples at most this far outside the /tf track hold its nearest orientation without a warning: the
# streams of a recording start and stop a fraction of a second apart.
HOLD_QUIET_S = 0.5


def held_warning(track: RotationTrack, t_ns: np.ndarray, what: str) -> str:
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
        f"the rotation {what} turns (from /tf) but {count} of {np.asarray(t_ns).size} wrench samples lie outside "
        f"its /tf samples (up to {longest_s:.3g} s): the nearest orientation is held there"
    )


def usable_transform(sample: TransformSample) -> bool:
    """A transform with a finite, non-zero quaternion (others cannot give a rotation)."""
    q = sample.rotation_xyzw
    return bool(np.isfinite(q).all() and np.any(q != 0.0))
