"""The ROS 2 QoS profiles bsp_ros uses, by name, and their rclpy ``QoSProfile``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bsp_ros.errors import RuntimeBackendError

__all__ = ["PROFILES", "QosSpec", "qos_spec", "rclpy_qos"]


@dataclass(frozen=True)
class QosSpec:
    """The QoS settings a ROS 2 profile fixes (history is always keep-last).

    Attributes
    ----------
    reliable : bool
        Reliable (True) or best effort (False).
    depth : int
        Keep-last history depth, at least 1.
    transient_local : bool
        Transient-local (late joiners get the last ``depth`` samples) or volatile.
    """

    reliable: bool
    depth: int
    transient_local: bool = False


#: Profiles by name. ``sensor_data`` is rclpy's ``qos_profile_sensor_data`` (publishers); ``default`` is an int depth 10
#: in rclpy; ``tf_static``/``tf`` are tf2_ros' static and dynamic broadcaster profiles, and
#: ``tf_static_listener`` the static listener's deeper history (several static broadcasters).
PROFILES: dict[str, QosSpec] = {
    "sensor_data": QosSpec(reliable=False, depth=5),
    # A node's subscription to a sensor stream: best effort (matches any publisher) with a deep history,
    # so that a Python executor busy for a few ms behind a 1 kHz stream is not overtaken (depth 5 would be).
    "sensor_input": QosSpec(reliable=False, depth=1000),
    # A node's subscription to another node's 100 Hz joint states: reliable like their publisher, 1 s deep, so that
    # an executor busy with an estimate (tens of ms; bsp_identifier computes in its timer) is not overtaken.
    "state_input": QosSpec(reliable=True, depth=100),
    "default": QosSpec(reliable=True, depth=10),
    "estimates": QosSpec(reliable=True, depth=10),
    "tf": QosSpec(reliable=True, depth=100),
    "tf_static": QosSpec(reliable=True, depth=1, transient_local=True),
    "tf_static_listener": QosSpec(reliable=True, depth=100, transient_local=True),
}


def qos_spec(qos: str | int | QosSpec) -> QosSpec:
    """Return the :class:`QosSpec` of a profile name, an int depth (reliable, volatile) or a spec.

    Parameters
    ----------
    qos : str or int or QosSpec
        Profile name of :data:`PROFILES`, a history depth as rclpy accepts it, or a spec.

    Returns
    -------
    QosSpec
        The settings.
    """
    if isinstance(qos, QosSpec):
        spec = qos
    elif isinstance(qos, bool):
        raise RuntimeBackendError(f"QoS must be a profile name, a depth or a QosSpec, got {qos!r}")
    elif isinstance(qos, int):
        spec = QosSpec(reliable=True, depth=qos)
    elif isinstance(qos, str) and qos in PROFILES:
        spec = PROFILES[qos]
    else:
        raise RuntimeBackendError(f"unknown QoS profile {qos!r}: use one of {sorted(PROFILES)} or a depth")
    if spec.depth < 1:
        raise RuntimeBackendError(f"QoS history depth must be at least 1, got {spec.depth}")
    return spec


def rclpy_qos(qos: str | int | QosSpec) -> Any:
    """Return the ``rclpy.qos.QoSProfile`` of a profile (needs rclpy).

    Parameters
    ----------
    qos : str or int or QosSpec
        The profile (see :func:`qos_spec`); ``"sensor_data"`` gives ``rclpy.qos.qos_profile_sensor_data``.

    Returns
    -------
    rclpy.qos.QoSProfile
        The profile for ``create_publisher``/``create_subscription``.
    """
    from bsp_ros.live.runtime.ros import require_rclpy

    require_rclpy()
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

    if qos == "sensor_data":
        return qos_profile_sensor_data
    spec = qos_spec(qos)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=spec.depth,
        reliability=ReliabilityPolicy.RELIABLE if spec.reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if spec.transient_local else DurabilityPolicy.VOLATILE,
    )
