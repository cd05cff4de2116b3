"""QoS profiles: a busy executor's state subscription is not overtaken by a 100 Hz stream."""

from __future__ import annotations

import time

import pytest

from bsp_ros.live.runtime.qos import qos_spec
from bsp_ros.live.runtime.ros import Client

pytestmark = [pytest.mark.dds]


def _taken_after_busy(domain: int, profile: str, count: int) -> int:
    """Messages a subscription with ``profile`` takes of ``count`` published at 100 Hz while its executor does not
    spin (as `bsp_identifier`'s while an estimate is computed in its timer), then spins."""
    client = Client("qos_probe", domain)
    try:
        taken: list[object] = []
        publisher = client.publisher("sensor_msgs/msg/JointState", "arm/joint_angles_raw", "estimates")
        client.subscribe("sensor_msgs/msg/JointState", "arm/joint_angles_raw", taken.append, profile)
        cls = publisher.msg_type
        client.spin_until(lambda: publisher.get_subscription_count() > 0, 10.0)
        for k in range(count):  # the executor is busy: nothing is taken meanwhile
            message = cls()
            message.position = [float(k)]
            publisher.publish(message)
            time.sleep(0.01)
        # Until all came, or none for 1 s: a history that dropped some has nothing more to give.
        last_count, last_change = 0, time.monotonic()

        def settled() -> bool:
            nonlocal last_count, last_change
            if len(taken) != last_count:
                last_count, last_change = len(taken), time.monotonic()
            return len(taken) >= count or time.monotonic() - last_change > 1.0

        client.spin_until(settled, 5.0)
        client.spin(0.3)
        return len(taken)
    finally:
        client.close()


def test_joint_states_wait_for_an_estimate_of_half_a_second_in_the_state_input_history(ros_domain: int) -> None:
    assert qos_spec("state_input").reliable
    assert _taken_after_busy(ros_domain, "state_input", 50) == 50
    # The publishers' own depth-10 profile keeps only the newest ten: the test can tell the two apart.
    assert _taken_after_busy(ros_domain, "estimates", 50) < 50
