"""Live, a sensor turning with the handle (/tf at 20 Hz) is rotated per wrench stamp and identified within 3 std.

rclpy cannot subscribe to /tf here: tf2_msgs is not among the PyPI wheels (NOTES.md, section 4), so the node
falls back to its quaternion parameter. This drives the online blocks the node's /tf and wrench callbacks
drive (``WrenchFrames`` and ``WindowedIdentifier``), in stamp order as the messages would arrive.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.live.online.causal_angles import CausalJointAngles
from bsp_ros.live.online.frames import WrenchFrames, WrenchQueue
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bag"))
from turning_sensor import TurningSession, assert_within_3_std, turning_session


@pytest.fixture(scope="module")
def turning() -> TurningSession:
    return turning_session(40.0, seed=11, tf_hz=20.0)


def _run(turning: TurningSession, tf_samples: list, check: bool = True) -> tuple[dict, WrenchFrames]:
    session = turning.session
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=np.eye(3), tf_wait_s=2.0)
    identifier = WindowedIdentifier(3, WindowConfig(window_s=60.0))
    angles = CausalJointAngles(3)
    marker_frames: dict[int, dict[str, np.ndarray]] = {}
    for name, series in session.markers.items():
        for t, p in zip(series.t_ns, series.position_m, strict=True):
            marker_frames.setdefault(int(t), {})[name] = p
    events = [(int(s.t_ns), 0, k) for k, s in enumerate(tf_samples)]
    events += [(t, 1, 0) for t in marker_frames]
    events += [(int(t), 2, k) for k, t in enumerate(session.wrench.t_ns)]
    wrench = session.wrench
    queue = WrenchQueue(frames)

    def add(ready: list) -> None:
        for (t, k), rotation in ready:
            assert rotation is not None
            force, torque = rotation @ wrench.force_n[k], rotation @ wrench.torque_nm[k]
            assert identifier.add_wrench(t, np.array([force[1], force[2], torque[0]]))

    for t, kind, k in sorted(events):
        if kind == 0:
            assert frames.on_transforms([tf_samples[k]]) == []  # a turning sensor never restarts the estimate
            add(queue.release(t))
        elif kind == 1:
            angles.update(t, marker_frames[t])
            if angles.accepted(t):
                identifier.add_joint_state(t, angles.last_raw_q_rad, angles.lengths_m)
        else:
            add(queue.push(wrench.frame_id, t, (t, k), t))
    add(queue.release(int(wrench.t_ns[-1]), newest_ns=int(wrench.t_ns[-1]) + queue.max_wait_ns + 1))
    assert queue.held <= (1 if len(tf_samples) > 1 else 0) and not queue.pending
    return identifier.estimate().document, frames


def test_a_turning_sensor_on_tf_is_rotated_per_wrench_stamp_and_identified(turning: TurningSession) -> None:
    document, frames = _run(turning, turning.tf_samples)
    assert frames.sources == {"ft_sensor": "tf (per sample)"}
    assert_within_3_std(document, turning)
    assert document["quality"]["timing"] == {"wrench_delay_s": 0.0, "wrench_delay_std_s": 0.0, "source": "none"}


def test_the_same_sensor_with_its_first_transform_only_does_not_fit(turning: TurningSession) -> None:
    document, frames = _run(turning, turning.tf_samples[:1])
    assert frames.sources == {"ft_sensor": "tf"}
    quality = document["quality"]
    assert not quality["valid"] and FindingCode.MODEL_MISFIT in [f.code for f in findings_of(quality)], quality


def test_a_wrench_newer_than_the_newest_tf_holds_it_and_older_ones_are_slerped(turning: TurningSession) -> None:
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=np.eye(3), tf_wait_s=2.0)
    first, second = turning.tf_samples[100], turning.tf_samples[101]
    frames.on_transforms([first, second])
    newest = frames.rotation_for("ft_sensor", second.t_ns + 10_000_000, second.t_ns + 10_000_000)
    assert newest is not None
    np.testing.assert_allclose(newest, second.rotation_parent_from_child(), atol=1e-12)
    middle = frames.rotation_for("ft_sensor", second.t_ns, (first.t_ns + second.t_ns) // 2)
    assert middle is not None
    angle = np.arccos((np.trace(first.rotation_parent_from_child().T @ middle) - 1) / 2)
    total = np.arccos((np.trace(first.rotation_parent_from_child().T @ second.rotation_parent_from_child()) - 1) / 2)
    assert angle == pytest.approx(total / 2, rel=1e-6) and total > 1e-4
