"""Joint kinematics from fits centred on each joint state: exact on a quadratic path, no lag, bad states refused."""

from __future__ import annotations

import numpy as np

from bsp_ros.live.online.angle_track import AngleTrack

STEP_NS = 20_000_000  # 50 Hz joint states


def _path(t_s: float) -> np.ndarray:
    """Two joints on quadratic paths (a fit of degree 2 must reproduce them exactly)."""
    return np.array([0.1 + 0.2 * t_s - 0.05 * t_s**2, -0.3 * t_s + 0.02 * t_s**2])


def test_kinematics_of_a_quadratic_path_are_exact_half_a_window_behind() -> None:
    track = AngleTrack(2, half_window_s=0.5)
    done = []
    for k in range(200):
        out = track.add(k * STEP_NS, _path(k * 0.02))
        assert out is not None
        for stamp, *_ in out:
            assert stamp <= k * STEP_NS - 500_000_000  # known once the half window after it has arrived
        done += out
    # From the first state with 80 % of a half window before it, to the last with a half window after it.
    assert [d[0] for d in done] == [k * STEP_NS for k in range(20, 175)]
    for stamp, q, qd, qdd in done:
        t_s = stamp / 1e9
        np.testing.assert_allclose(q, _path(t_s), atol=1e-12)
        np.testing.assert_allclose(qd, [0.2 - 0.1 * t_s, -0.3 + 0.04 * t_s], atol=1e-10)
        np.testing.assert_allclose(qdd, [-0.1, 0.04], atol=1e-9)


def test_a_reversal_gets_its_velocity_sign_without_lag() -> None:
    # q = 0.1 sin(0.5 t): the velocity changes sign at t = pi s; a centred fit says so within a few ms.
    track = AngleTrack(1)
    done = []
    for k in range(400):
        done += track.add(k * STEP_NS, np.array([0.1 * np.sin(0.5 * k * 0.02)])) or []
    t_s = np.array([d[0] / 1e9 for d in done])
    qd = np.array([d[2][0] for d in done])
    sign_change = t_s[np.flatnonzero(np.diff(np.sign(qd)))[0]]
    assert abs(sign_change - np.pi) < 0.03
    # A quadratic fit leaves the cubic term: 0.6 % of the velocity at this frequency, and no lag.
    np.testing.assert_allclose(qd, 0.05 * np.cos(0.5 * t_s), atol=4e-4)


def test_refuses_non_finite_out_of_order_and_duplicate_states() -> None:
    track = AngleTrack(2)
    assert track.add(10, np.array([0.0, 0.0])) == []
    assert track.add(20, np.array([np.nan, 0.0])) is None
    assert track.add(10, np.array([0.0, 0.0])) is None
    assert track.add(5, np.array([0.0, 0.0])) is None
    assert track.add(30, np.array([0.0])) is None


def test_a_gap_leaves_the_states_beside_it_without_kinematics_and_a_clock_jump_starts_over() -> None:
    track = AngleTrack(1)
    stamps = [k * STEP_NS for k in range(100)] + [k * STEP_NS for k in range(130, 230)]  # a 0.6 s dropout
    done = []
    for t in stamps:
        done += track.add(t, np.array([t / 1e9])) or []
    centred = {d[0] for d in done}
    assert 60 * STEP_NS in centred and 170 * STEP_NS in centred
    assert not centred & {k * STEP_NS for k in range(80, 150)}  # windows reaching into the gap
    assert track.add(1_000, np.array([0.0])) == []  # 4.6 s back: a new clock
    assert track.t_ns == [1_000]
