"""The rotation track of `bsp identify`, `bsp tare` and the live identifier, against scipy and rotation_between."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.rotation_track import TransformBuffer, matrices_from_quaternions, slerp_quaternions
from msg_adapters.tf import TransformSample, rotation_between

RNG = np.random.default_rng(19)


def _sample(t_ns: int, parent: str, child: str, rotation: np.ndarray) -> TransformSample:
    return TransformSample(t_ns, parent, child, np.zeros(3), quaternion_from_matrix(rotation))


def test_slerp_matches_scipy_inside_and_holds_the_ends() -> None:
    stamps = np.array([0, 40_000_000, 90_000_000, 100_000_000], dtype=np.int64)
    rotations = Rotation.random(4, random_state=3)
    quats = rotations.as_quat()
    quats[1] *= -1.0  # the same rotation with the other sign: the shortest path must not care
    t = np.array([-5, 0, 13_000_000, 40_000_000, 61_000_000, 99_999_999, 100_000_000, 170_000_000], dtype=np.int64)
    got = matrices_from_quaternions(slerp_quaternions(stamps, quats, t))
    want = Slerp(stamps.astype(float), rotations)(np.clip(t, stamps[0], stamps[-1]).astype(float)).as_matrix()
    np.testing.assert_allclose(got, want, atol=1e-12)


def test_a_chain_of_static_and_turning_links_composes_like_rotation_between_at_each_tf_stamp() -> None:
    mount = Rotation.random(random_state=1).as_matrix()  # world <- base (/tf_static)
    tool = Rotation.random(random_state=2).as_matrix()  # flange <- ft_sensor (/tf_static)
    stamps = np.arange(10, dtype=np.int64) * 100_000_000 + 1_000_000_000
    turns = [Rotation.from_euler("x", 0.2 * np.sin(k / 3.0)).as_matrix() for k in range(stamps.size)]
    buffer = TransformBuffer()
    statics = [_sample(0, "world", "base", mount), _sample(0, "flange", "ft_sensor", tool)]
    buffer.add_static(statics)
    dynamic = [_sample(int(t), "base", "flange", r) for t, r in zip(stamps, turns, strict=True)]
    buffer.add(reversed(dynamic))  # out of order on arrival: the stamps decide
    track = buffer.track("world", "ft_sensor", stamps)
    assert track is not None and track.turning and track.source == "tf"
    assert track.span_ns == (int(stamps[0]), int(stamps[-1])) and not track.held.any()
    for k in range(stamps.size):
        want = rotation_between([*statics, dynamic[k]], "world", "ft_sensor")
        assert want is not None
        np.testing.assert_allclose(track.rotations[k], want, atol=1e-12)
    # Between two /tf samples the turning link is slerped; the fixed links stay.
    middle = buffer.track("world", "ft_sensor", [int(stamps[3] + 50_000_000)])
    assert middle is not None
    half = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([turns[3], turns[4]])))(0.5).as_matrix()
    np.testing.assert_allclose(middle.rotations[0], mount @ half @ tool, atol=1e-12)
    # The inverse direction is the transpose.
    back = buffer.track("ft_sensor", "world", stamps)
    assert back is not None
    np.testing.assert_allclose(back.rotations, np.transpose(track.rotations, (0, 2, 1)), atol=1e-12)


def test_stamps_outside_the_turning_links_are_held_and_counted() -> None:
    buffer = TransformBuffer()
    r0, r1 = Rotation.from_euler("x", [[0.0], [0.1]]).as_matrix()
    buffer.add([_sample(1_000_000_000, "world", "ft", r0), _sample(2_000_000_000, "world", "ft", r1)])
    t = np.array([0, 1_500_000_000, 2_750_000_000], dtype=np.int64)
    track = buffer.track("world", "ft", t)
    assert track is not None
    np.testing.assert_allclose(track.rotations[0], r0, atol=1e-12)
    np.testing.assert_allclose(track.rotations[2], r1, atol=1e-12)
    assert track.held.tolist() == [True, False, True]
    assert track.held_summary(t) == (2, 1.0)


def test_a_fixed_chain_is_one_rotation_even_when_republished_on_tf() -> None:
    fixed = Rotation.random(random_state=5).as_matrix()
    buffer = TransformBuffer()
    buffer.add(_sample(t, "world", "ft", fixed) for t in (1, 2, 3))
    track = buffer.track("world", "ft", [0, 2, 9])
    assert track is not None and not track.turning and track.source == "tf" and track.span_ns is None
    assert track.session_rotation.shape == (3, 3)
    np.testing.assert_allclose(track.session_rotation, fixed, atol=1e-12)
    static = TransformBuffer()
    static.add_static([_sample(0, "world", "ft", fixed)])
    only_static = static.track("world", "ft", [5])
    assert only_static is not None and only_static.source == "tf_static" and not only_static.turning


def test_unconnected_frames_and_a_new_parent() -> None:
    buffer = TransformBuffer()
    buffer.add([_sample(1, "robot", "ft", np.eye(3))])
    assert buffer.track("world", "ft", [1]) is None and not buffer.connected("world", "ft")
    turned = Rotation.from_euler("z", 0.3).as_matrix()
    buffer.add([_sample(2, "world", "ft", turned)])  # re-parented: the robot samples no longer apply
    track = buffer.track("world", "ft", [1, 2])
    assert track is not None and not track.turning
    np.testing.assert_allclose(track.rotations, np.broadcast_to(turned, (2, 3, 3)), atol=1e-12)


def test_live_history_keeps_the_newest_samples_only() -> None:
    buffer = TransformBuffer(max_age_ns=1_000)
    angles = RNG.uniform(-0.2, 0.2, 50)
    for k, angle in enumerate(angles):
        buffer.add([_sample(k * 100, "world", "ft", Rotation.from_euler("x", angle).as_matrix())])
    stamps = buffer._links["ft"].stamps
    assert stamps is not None and min(stamps) == 3_900 and len(stamps) == 11
    track = buffer.track("world", "ft", [4_900])
    assert track is not None
    np.testing.assert_allclose(track.rotations[0], Rotation.from_euler("x", angles[-1]).as_matrix(), atol=1e-12)
