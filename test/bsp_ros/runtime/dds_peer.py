"""A second process for the DDS runtime tests: ``python dds_peer.py MODE DOMAIN [N]``."""

from __future__ import annotations

import json
import sys
import time

from bsp_ros.runtime.dds_backend import DdsContext

WRENCH = "geometry_msgs/msg/WrenchStamped"


def _wrench(ctx: DdsContext, i: int) -> object:
    cls = ctx.message_class
    return cls(WRENCH)(
        header=cls("std_msgs/msg/Header")(
            stamp=cls("builtin_interfaces/msg/Time")(sec=1_700_000_000 + i // 1000, nanosec=(i % 1000) * 1_000_000),
            frame_id="ft_sensor",
        ),
        wrench=cls("geometry_msgs/msg/Wrench")(
            force=cls("geometry_msgs/msg/Vector3")(x=float(i), y=-float(i), z=-9.81),
            torque=cls("geometry_msgs/msg/Vector3")(x=0.5 * i, y=0.0, z=-0.25),
        ),
    )


def subscribe(ctx: DdsContext, count: int) -> None:
    """Receive ``count`` wrenches on /ft_sensor/wrench and print their force.x values as JSON."""
    node = ctx.create_node("wrench_sink")
    got: list[float] = []
    node.create_subscription(WRENCH, "/ft_sensor/wrench", lambda m: got.append(m.wrench.force.x), "default")
    print("READY", flush=True)
    ctx.spin(until=lambda: len(got) >= count or time.monotonic() > deadline)
    print(json.dumps(got), flush=True)


def publish(ctx: DdsContext, count: int) -> None:
    """Wait for a reader, publish ``count`` wrenches at about 1 kHz, wait for acknowledgements."""
    node = ctx.create_node("wrench_source", "cell")
    pub = node.create_publisher(WRENCH, "/ft_sensor/wrench", "default")
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    # The writer can see the reader before the reader has seen the writer; a volatile reader drops what
    # arrives from a writer it does not know yet, so let discovery finish on both sides first.
    time.sleep(0.3)
    for i in range(count):
        pub.publish(_wrench(ctx, i))
        time.sleep(0.001)
    print("ACKED" if pub.wait_for_acks(10.0) else "NOT ACKED", flush=True)


def latch(ctx: DdsContext) -> None:
    """Publish one /tf_static message (transient local), then stay until stdin closes."""
    node = ctx.create_node("bsp_probe", "cell")
    cls = ctx.message_class
    tf = cls("geometry_msgs/msg/TransformStamped")(
        header=cls("std_msgs/msg/Header")(
            stamp=cls("builtin_interfaces/msg/Time")(sec=12, nanosec=34), frame_id="world"
        ),
        child_frame_id="ft_sensor",
        transform=cls("geometry_msgs/msg/Transform")(
            translation=cls("geometry_msgs/msg/Vector3")(x=0.1, y=-0.2, z=0.3),
            rotation=cls("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
    )
    pub = node.create_publisher("tf2_msgs/msg/TFMessage", "/tf_static", "tf_static")
    node.create_subscription("std_msgs/msg/String", "/bsp/probe_in", lambda m: None, "default")
    pub.publish(cls("tf2_msgs/msg/TFMessage")(transforms=[tf]))
    print("PUBLISHED", flush=True)
    sys.stdin.read()


if __name__ == "__main__":
    mode, domain = sys.argv[1], int(sys.argv[2])
    number = int(sys.argv[3]) if len(sys.argv) > 3 else 0
    deadline = time.monotonic() + 30.0
    context = DdsContext(domain, args=[])
    try:
        {"sub": lambda: subscribe(context, number), "pub": lambda: publish(context, number)}.get(
            mode, lambda: latch(context)
        )()
    finally:
        context.shutdown()
