"""The robot's contact point at the motion-capture frames (core/contact_point.py)."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.contact_point import chain_markers, contact_from_robot
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries

T0_NS = 1_700_000_000_000_000_000


def _path(t_s: np.ndarray) -> np.ndarray:
    return np.column_stack([np.full(t_s.size, 0.1), 0.5 + 0.1 * np.sin(0.3 * t_s), 0.2 * np.cos(0.2 * t_s)])


def _robot(t_s: np.ndarray) -> MarkerSeries:
    return MarkerSeries(T0_NS + np.round(t_s * 1e9).astype(np.int64), _path(t_s))


def _frames(t_s: np.ndarray) -> dict[str, MarkerSeries]:
    t_ns = T0_NS + np.round(t_s * 1e9).astype(np.int64)
    return {name: MarkerSeries(t_ns, np.zeros((t_s.size, 3))) for name in ("shoulder", "elbow", "hand")}


def test_the_robot_pose_is_interpolated_at_the_marker_frames() -> None:
    robot = _robot(np.arange(0.0, 10.0, 0.004))  # 250 Hz
    frames_s = 0.0071 + np.arange(0.0, 9.9, 0.02)  # 50 Hz, another phase
    contact = contact_from_robot(_frames(frames_s), robot)
    assert np.array_equal(contact.t_ns, T0_NS + np.round(frames_s * 1e9).astype(np.int64))
    # Linear interpolation over 4 ms of a path with 0.03 m/s^2 curvature: well under a micrometre.
    assert np.abs(contact.position_m - _path(frames_s)).max() < 1e-6


def test_frames_outside_the_robot_stream_or_in_its_gaps_get_no_contact_point() -> None:
    t_s = np.arange(1.0, 9.0, 0.01)
    gap = (t_s > 4.0) & (t_s < 4.5)  # the robot stream stops for half a second
    robot = _robot(t_s[~gap])
    frames_s = np.arange(0.0, 10.0, 0.02)
    contact = contact_from_robot(_frames(frames_s), robot)
    at_s = (contact.t_ns - T0_NS) / 1e9
    assert at_s.min() >= 1.0 - 1e-9 and at_s.max() <= 8.99 + 1e-9
    assert not ((at_s > 4.0 + 1e-6) & (at_s < 4.5 - 1e-6)).any()
    assert np.abs(contact.position_m - _path(at_s)).max() < 1e-5


def test_the_chain_takes_the_robot_contact_point_for_the_hand_marker() -> None:
    frames = _frames(np.arange(0.0, 2.0, 0.02))
    wrench = WrenchSeries(np.array([T0_NS]), np.zeros((1, 3)), np.zeros((1, 3)))
    assert chain_markers(Session(wrench, frames)) is frames
    robot = _robot(np.arange(0.0, 2.0, 0.01))
    chain = chain_markers(Session(wrench, frames, handle_pose=robot))
    assert chain["shoulder"] is frames["shoulder"]
    assert np.abs(chain["hand"].position_m - _path((chain["hand"].t_ns - T0_NS) / 1e9)).max() < 1e-6
