"""bsp/weight_support on rclpy + Fast DDS: J(q)^T F = s tau_G(q) of the simulated arm, only while valid."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pytest
from live_cell import LiveCell

from bsp_ros.core.model import contact_jacobian, gravity_regressor
from msg_adapters.joint_state import read_joint_state
from msg_adapters.wrench import read_wrench_stamped

pytestmark = [pytest.mark.dds, pytest.mark.slow]

SUPPORT_FRACTION = 0.5


def test_weight_support_carries_the_share_of_the_true_gravity_torques_only_after_a_valid_estimate(ros_domains) -> None:
    c = LiveCell(ros_domains(), ["speed:=2.0", "seed:=9"], [f"support_fraction:={SUPPORT_FRACTION}"])
    supports: list[tuple[float, Any]] = []
    angles: dict[int, np.ndarray] = {}
    try:
        c.client.subscribe(
            "geometry_msgs/msg/WrenchStamped",
            "bsp/weight_support",
            lambda m: supports.append((time.monotonic(), read_wrench_stamped(m))),
        )
        c.client.subscribe(
            "sensor_msgs/msg/JointState", "arm/joint_states", lambda m: _keep(angles, read_joint_state(m)), "estimates"
        )
        assert c.spin_until(lambda: len(supports) > 200, 90), (len(supports), c.latest())
        first_valid = next(t for t, d in c.estimates if d["quality"]["valid"])
        assert supports[0][0] >= first_valid - 0.05  # nothing before the first valid estimate
        truth = c.truth
        beta = np.array([truth["segments"][s]["static_moment_kgm"] for s in ("upper_arm", "forearm", "hand")])
        lengths = np.array([truth["segments"][s]["length_m"] for s in ("upper_arm", "forearm", "hand")])
        checked = 0
        for _, sample in supports[-100:]:
            assert sample.frame_id == "world"
            q = angles.get(sample.t_ns)
            if q is None:
                continue
            wrench_yzx = np.array([sample.force_n[1], sample.force_n[2], sample.torque_nm[0]])
            carried = contact_jacobian(q[None, :], lengths)[0].T @ wrench_yzx
            wanted = SUPPORT_FRACTION * gravity_regressor(q[None, :])[0] @ beta
            # The node uses its own estimate and marker-measured lengths: within a few percent of the truth.
            assert np.all(np.abs(carried - wanted) < 0.03 * np.abs(wanted) + 0.01), (q, carried, wanted)
            checked += 1
        assert checked > 20
    finally:
        c.close()


def _keep(angles: dict[int, np.ndarray], sample: Any) -> None:
    angles[sample.t_ns] = sample.position
