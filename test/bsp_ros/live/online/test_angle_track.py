"""Joint states interpolated to wrench stamps, refusing bad ones and restarting on a clock jump."""

from __future__ import annotations

import numpy as np

from bsp_ros.live.online.angle_track import AngleTrack


def test_interpolates_between_the_two_newest_states() -> None:
    track = AngleTrack(2)
    assert track.add(0, np.array([0.0, 1.0]), np.array([1.0, 0.0]))
    assert track.add(10_000_000, np.array([0.1, 1.2]), np.array([3.0, 0.0]))
    q, v = track.at(2_500_000)
    np.testing.assert_allclose(q, [0.025, 1.05])
    np.testing.assert_allclose(v, [1.5, 0.0])
    assert track.at(300_000_000) is None  # farther than 0.1 s from every state


def test_refuses_non_finite_out_of_order_and_duplicate_states() -> None:
    track = AngleTrack(2)
    assert track.add(10, np.array([0.0, 0.0]), np.zeros(2))
    assert not track.add(20, np.array([np.nan, 0.0]), np.zeros(2))
    assert not track.add(10, np.array([0.0, 0.0]), np.zeros(2))
    assert not track.add(5, np.array([0.0, 0.0]), np.zeros(2))
    assert not track.add(30, np.array([0.0]), np.zeros(1))


def test_a_backwards_clock_jump_starts_over() -> None:
    track = AngleTrack(1)
    track.add(5_000_000_000, np.array([1.0]), np.zeros(1))
    assert track.add(1_000_000_000, np.array([2.0]), np.zeros(1))
    q, _ = track.at(1_000_000_000)
    np.testing.assert_allclose(q, [2.0])
    assert len(track.states) == 1
