"""bsp_identifier's input callbacks, in process: unfiltered angles that come before the segment lengths are kept."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from ros_domains import next_domain_id

from bsp_ros.core.streams import joints_for, segments_for
from msg_adapters.joint_state import JointStateSample, build_joint_state

pytestmark = [pytest.mark.dds]

T0_NS = 1_700_000_000_000_000_000
FRAME_NS = 20_000_000  # 50 Hz, as the simulated cell's markers


@pytest.fixture
def identifier() -> Iterator[object]:
    rclpy = pytest.importorskip("rclpy")
    from bsp_ros.live.nodes.bsp_identifier import BspIdentifierNode

    frame = "wrench_frame_rotation_xyzw:=[0.0, 0.0, 0.0, 1.0]"
    rclpy.init(args=["--ros-args", "-p", frame], domain_id=next_domain_id())
    node = BspIdentifierNode()
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def _state(node: object, t_ns: int, names: tuple[str, ...], position: np.ndarray) -> object:
    sample = JointStateSample(t_ns, "", names, position, np.zeros(0), np.zeros(0))
    return build_joint_state(node.types, sample)  # type: ignore[attr-defined]


def test_angles_received_before_the_first_segment_lengths_join_the_window(identifier) -> None:
    # The lengths have their own topic: its first message can match later than the angles' topic, or be taken
    # after the angles of the same frame. Before the fix, every angle until the next lengths (1 s later) was lost.
    q_rad = np.array([0.3, 0.8, -0.1])
    lengths_m = np.array([0.31, 0.27, 0.09])
    early = [T0_NS + k * FRAME_NS for k in range(60)]
    for t_ns in early:
        identifier.on_raw_angles(_state(identifier, t_ns, joints_for(3), q_rad + 1e-3 * (t_ns - T0_NS) / FRAME_NS))
    assert identifier.identifier.mode.window.angles.last_t_ns is None  # nothing without lengths
    identifier.on_lengths(_state(identifier, early[-1], segments_for(3), lengths_m))
    late = early[-1] + FRAME_NS
    identifier.on_raw_angles(_state(identifier, late, joints_for(3), q_rad))

    t_ns, rows = identifier.identifier.mode.window.angles.since(0)
    np.testing.assert_array_equal(t_ns, [*early, late])
    np.testing.assert_allclose(rows[:, :3], [q_rad + 1e-3 * k for k in range(60)] + [q_rad])
    np.testing.assert_array_equal(rows[:, 3:], np.tile(lengths_m, (61, 1)))
    assert identifier.identifier.counts["joint_states"] == 61
