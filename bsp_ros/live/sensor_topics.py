"""Which topics are sensor streams (best effort, ``sensor_data``) when recording and replaying bags."""

from __future__ import annotations

#: Topics (exact names, or prefixes ending in ``/``) of the sensor streams: subscribed best effort when recording,
#: so reliable and best-effort publishers both match, and published best effort when replaying.
SENSOR_TOPIC_PREFIXES: tuple[str, ...] = ("/ft_sensor/wrench", "/mocap/", "/robot/handle_pose")


def is_sensor_topic(topic: str) -> bool:
    """Whether ``topic`` is one of :data:`SENSOR_TOPIC_PREFIXES` (or under a prefix ending in ``/``)."""
    return any(topic == p or (p.endswith("/") and topic.startswith(p)) for p in SENSOR_TOPIC_PREFIXES)
