"""The contact point from the robot's handle pose, where the cell publishes one, instead of the hand's skin marker."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.streams import MarkerSeries, Session

# Robot poses further apart than this around a marker frame leave that frame without a contact point: the
# handle may have moved anywhere in between (the same bound as a marker gap the angles bridge).
MAX_POSE_GAP_S = 0.1

# The contact point's source, as `quality.contact_point` and the live `arm/contact_point` topic name it.
CONTACT_FROM_ROBOT = "robot_handle_pose"
CONTACT_FROM_MARKER = "hand_marker"


def contact_from_robot(markers: dict[str, MarkerSeries], handle_pose: MarkerSeries) -> MarkerSeries:
    """The robot's contact point at the motion-capture frames, to stand in for the ``hand`` marker.

    The robot's kinematics place the handle to a fraction of a millimetre; a skin marker on the hand sits a few
    millimetres off the contact point, differently every day. The robot's stream has its own rate and
    stamps, so its positions are interpolated (linearly) at the frame stamps of the other markers, which keeps
    the angles on the motion-capture clock and filters.

    Parameters
    ----------
    markers : the skin markers (name -> series in ``world``, m); the frames of all but ``hand`` set the stamps.
    handle_pose : the contact point in ``world`` from the robot, (K,) stamps and (K, 3) positions, m.

    Returns
    -------
    MarkerSeries
        The contact point at every frame within the robot's stream whose neighbouring robot poses lie at most
        ``MAX_POSE_GAP_S`` apart.
    """
    frames = [m.t_ns for name, m in markers.items() if name != "hand" and m.t_ns.size]
    t_robot = np.asarray(handle_pose.t_ns, dtype=np.int64)
    position = np.asarray(handle_pose.position_m, dtype=np.float64)
    finite = np.isfinite(position).all(axis=1)
    # Sorted, one pose per stamp (the first received): np.unique sorts and keeps each stamp's first index.
    t_robot, first = np.unique(t_robot[finite], return_index=True)
    if not frames:
        return MarkerSeries(np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    t_ns = np.unique(np.concatenate(frames))
    keep, contact_m = contact_at(t_robot, position[finite][first], t_ns)
    return MarkerSeries(t_ns[keep], contact_m)


def contact_at(t_robot_ns: np.ndarray, position_m: np.ndarray, t_ns: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The robot's contact point interpolated (linearly) at the stamps ``t_ns``.

    Parameters
    ----------
    t_robot_ns : (K,) int64 robot pose stamps, strictly increasing, ns.
    position_m : (K, 3) contact points in ``world``, m.
    t_ns : (M,) int64 stamps wanted, ns.

    Returns
    -------
    keep : (M,) bool, the stamps within the robot's stream whose neighbouring poses lie at most
        ``MAX_POSE_GAP_S`` apart.
    contact_m : (keep.sum(), 3) the contact point at those stamps, m.
    """
    t_ns = np.asarray(t_ns, dtype=np.int64)
    if t_robot_ns.size < 2:
        return np.zeros(t_ns.size, dtype=bool), np.zeros((0, 3))
    after = np.searchsorted(t_robot_ns, t_ns, side="right")
    inside = (after > 0) & (after < t_robot_ns.size) | (t_ns == t_robot_ns[-1])
    after = np.clip(after, 1, t_robot_ns.size - 1)
    gap_ns = t_robot_ns[after] - t_robot_ns[after - 1]
    keep = inside & (gap_ns <= MAX_POSE_GAP_S * 1e9)
    # Relative to the first pose: int64 ns stamps lose their last digits as float64 seconds since 1970.
    t_s = (t_robot_ns - t_robot_ns[0]) / 1e9
    at_s = (t_ns[keep] - t_robot_ns[0]) / 1e9
    return keep, np.column_stack([np.interp(at_s, t_s, position_m[:, k]) for k in range(3)])


def chain_markers(session: Session) -> dict[str, MarkerSeries]:
    """The markers the joint angles are computed from: the robot's contact point, where the session has one,
    in place of the ``hand`` skin marker."""
    if session.handle_pose is None:
        return session.markers
    return {**session.markers, "hand": contact_from_robot(session.markers, session.handle_pose)}
