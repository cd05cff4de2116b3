"""bsp_identifier's wrench delay, in process: unset it applies 0 and says so on /diagnostics; a known delay (s)
shifts each wrench stamp back, as `bsp identify --wrench-delay-s` shifts a session's."""

from __future__ import annotations

import numpy as np
import pytest
from ros_domains import next_domain_id

from msg_adapters.wrench import WrenchSample, build_wrench_stamped

pytestmark = [pytest.mark.dds]

T0_NS = 1_700_000_000_000_000_000


def _node(*params: str):
    rclpy = pytest.importorskip("rclpy")
    from bsp_ros.live.nodes.bsp_identifier import BspIdentifierNode

    # The rotation from the parameter at once (by default the node waits tf_wait_s for a transform first).
    args = [
        "--ros-args",
        "-p",
        "wrench_frame_rotation_xyzw:=[0.0, 0.0, 0.0, 1.0]",
        "-p",
        "wrench_frame_source:=parameter",
    ]
    rclpy.init(args=[*args, *(a for p in params for a in ("-p", p))], domain_id=next_domain_id())
    return rclpy, BspIdentifierNode()


def _health(node) -> dict[str, str]:
    """The values of the node's next /diagnostics status."""
    sent = []
    node.diag_pub.publish = sent.append
    node.on_update()
    return {kv.key: kv.value for kv in sent[-1].status[0].values}


@pytest.mark.parametrize(
    ("params", "delay_ns", "said"),
    [((), 0, "unset: 0 s applied"), (("wrench_delay_s:=0.02",), 20_000_000, "0.02 s (parameter")],
)
def test_the_wrench_delay_is_applied_and_said(params: tuple[str, ...], delay_ns: int, said: str) -> None:
    rclpy, node = _node(*params)
    try:
        assert node.settings.wrench_delay_s == (None if not params else 0.02)
        sample = WrenchSample(T0_NS, "ft_sensor", np.array([0.0, 1.0, -20.0]), np.array([0.5, 0.0, 0.0]))
        node.on_wrench(build_wrench_stamped(node.types, sample))
        assert node.identifier.mode.window.wrench.last_t_ns == T0_NS - delay_ns
        assert _health(node)["wrench_delay"].startswith(said)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
