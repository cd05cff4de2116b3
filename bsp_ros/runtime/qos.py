"""The ROS 2 QoS profiles bsp_ros uses, as Cyclone DDS ``Qos`` and as rclpy ``QoSProfile``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from cyclonedds.qos import Policy, Qos
from cyclonedds.util import duration

from bsp_ros.errors import RuntimeBackendError

__all__ = ["PROFILES", "QosSpec", "dds_qos", "qos_spec", "rclpy_qos"]

_DDS_LENGTH_UNLIMITED = -1


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


#: Profiles by name. ``sensor_data`` is rclpy's ``qos_profile_sensor_data``; ``default`` is an int depth 10
#: in rclpy; ``tf_static``/``tf`` are tf2_ros' static and dynamic broadcaster profiles, and
#: ``tf_static_listener`` the static listener's deeper history (several static broadcasters).
PROFILES: dict[str, QosSpec] = {
    "sensor_data": QosSpec(reliable=False, depth=5),
    "default": QosSpec(reliable=True, depth=10),
    "estimates": QosSpec(reliable=True, depth=10),
    "tf": QosSpec(reliable=True, depth=100),
    "tf_static": QosSpec(reliable=True, depth=1, transient_local=True),
    "tf_static_listener": QosSpec(reliable=True, depth=100, transient_local=True),
    "discovery_info": QosSpec(reliable=True, depth=1, transient_local=True),
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


def dds_qos(qos: str | int | QosSpec, *, reader_depth: int | None = None, user_data: bytes = b"") -> Qos:
    """Return the Cyclone DDS ``Qos`` rmw_cyclonedds would build for a ROS 2 profile.

    Parameters
    ----------
    qos : str or int or QosSpec
        The profile (see :func:`qos_spec`).
    reader_depth : int, optional
        A deeper history for a reader (the buffer between arrival and take; does not affect matching).
    user_data : bytes
        Endpoint user data, e.g. ``b"typehash=RIHS01_...;"``.

    Returns
    -------
    Qos
        Keep-last history, reliability (reliable blocks without limit, as in rmw_cyclonedds), durability
        with a matching durability service, no auto-dispose, and the user data.
    """
    spec = qos_spec(qos)
    depth = max(spec.depth, reader_depth or 0)
    history = Policy.History.KeepLast(depth)
    policies: list[Any] = [
        history,
        Policy.WriterDataLifecycle(autodispose=False),
        (
            Policy.Reliability.Reliable(max_blocking_time=duration(infinite=True))
            if spec.reliable
            else Policy.Reliability.BestEffort
        ),
    ]
    if spec.transient_local:
        policies += [
            Policy.Durability.TransientLocal,
            Policy.DurabilityService(
                cleanup_delay=0,
                history=history,
                max_samples=_DDS_LENGTH_UNLIMITED,
                max_instances=_DDS_LENGTH_UNLIMITED,
                max_samples_per_instance=_DDS_LENGTH_UNLIMITED,
            ),
        ]
    else:
        policies.append(Policy.Durability.Volatile)
    if user_data:
        policies.append(Policy.Userdata(user_data))
    return Qos(*policies)


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
    try:
        from rclpy.qos import (
            DurabilityPolicy,
            HistoryPolicy,
            QoSProfile,
            ReliabilityPolicy,
            qos_profile_sensor_data,
        )
    except ImportError as exc:
        raise RuntimeBackendError(f"rclpy is not available: {exc}") from exc
    if qos == "sensor_data":
        return qos_profile_sensor_data
    spec = qos_spec(qos)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=spec.depth,
        reliability=ReliabilityPolicy.RELIABLE if spec.reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if spec.transient_local else DurabilityPolicy.VOLATILE,
    )
