"""The live robot contact track: interpolation at frame stamps as offline, gaps, order and clock jumps."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.contact_point import MAX_POSE_GAP_S, contact_from_robot
from bsp_ros.core.streams import MarkerSeries
from bsp_ros.live.online.contact_track import RobotContactTrack

T0_NS = 1_700_000_000_000_000_000


def _path_m(t_s: np.ndarray) -> np.ndarray:
    """A contact point moving on a circle (m) at t (s): linear interpolation has a known, small error."""
    return np.column_stack([np.full(t_s.size, 0.1), 0.3 * np.cos(0.2 * t_s), 0.3 * np.sin(0.2 * t_s)])


def test_live_contact_points_equal_the_offline_interpolation() -> None:
    robot_ns = T0_NS + np.arange(0, 3_000_000_000, 7_000_000, dtype=np.int64)  # 143 Hz, its own clock grid
    frames_ns = T0_NS + np.arange(5_000_000, 2_900_000_000, 20_000_000, dtype=np.int64)  # 50 Hz markers
    robot_m = _path_m((robot_ns - T0_NS) / 1e9)
    offline = contact_from_robot(
        {"wrist": MarkerSeries(frames_ns, np.zeros((frames_ns.size, 3)))}, MarkerSeries(robot_ns, robot_m)
    )
    track = RobotContactTrack(keep_s=0.5)
    live = []
    poses = iter(zip(robot_ns.tolist(), robot_m, strict=True))
    for t in frames_ns.tolist():
        while not track.covers(t):  # a frame waits for the pose after it
            assert track.add(*next(poses))
        live.append(track.at(t))
    assert np.array_equal(offline.t_ns, frames_ns)
    np.testing.assert_allclose(np.array(live), offline.position_m, rtol=0, atol=1e-15)
    # And both are the path to within linear interpolation's error over a 7 ms step (0.3 m * (0.2 * 0.007)^2 / 8).
    np.testing.assert_allclose(offline.position_m, _path_m((frames_ns - T0_NS) / 1e9), atol=1e-7)


def test_a_robot_gap_leaves_frames_without_a_contact_point() -> None:
    track = RobotContactTrack()
    gap_ns = int(MAX_POSE_GAP_S * 1e9) + 1
    assert track.add(T0_NS, np.zeros(3))
    assert track.add(T0_NS + gap_ns, np.ones(3))
    assert track.covers(T0_NS + 1) and track.at(T0_NS + 1) is None
    assert track.add(T0_NS + gap_ns + 10_000_000, np.full(3, 2.0))
    np.testing.assert_allclose(track.at(T0_NS + gap_ns + 5_000_000), np.full(3, 1.5))
    assert track.at(T0_NS - 1) is None  # before the track
    assert not track.covers(T0_NS + 10 * gap_ns)


def test_out_of_order_poses_are_refused_and_a_clock_jump_starts_over() -> None:
    track = RobotContactTrack()
    assert track.add(T0_NS, np.zeros(3))
    assert track.add(T0_NS + 10_000_000, np.ones(3))
    assert not track.add(T0_NS + 5_000_000, np.ones(3))  # late
    assert not track.add(T0_NS + 20_000_000, np.array([np.nan, 0.0, 0.0]))  # not finite
    assert track.n_refused == 2
    np.testing.assert_allclose(track.at(T0_NS + 10_000_000), np.ones(3))  # exactly at the newest pose
    assert track.add(T0_NS - 5_000_000_000, np.zeros(3))  # back by 5 s: a new clock
    assert track.newest_ns == T0_NS - 5_000_000_000
    assert track.at(T0_NS) is None
