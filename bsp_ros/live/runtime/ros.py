"""The thin rclpy layer: rclpy or a clear install hint, message classes by type name, and a private client."""

from __future__ import annotations

import importlib
import os
import time
from collections.abc import Callable
from typing import Any

from bsp_ros.errors import InputError, RuntimeBackendError
from bsp_ros.live.runtime.qos import QosSpec, rclpy_qos

__all__ = [
    "EXECUTOR_ENV",
    "INSTALL_HINT",
    "Client",
    "RosNode",
    "has_message",
    "log_error",
    "make_executor",
    "message_class",
    "require_rclpy",
    "split_type_name",
]

INSTALL_HINT = (
    "install the ROS 2 Jazzy Python packages with `pip install .[live]` (or `pip install bsp_ros[live]`), "
    "or source a ROS 2 Jazzy setup (`source /opt/ros/jazzy/setup.bash`)"
)


def require_rclpy() -> None:
    """Import rclpy or raise a :class:`RuntimeBackendError` saying how to install it."""
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        raise RuntimeBackendError(f"rclpy is not available ({exc}): {INSTALL_HINT}") from exc


def split_type_name(type_name: str) -> tuple[str, str]:
    """``"geometry_msgs/msg/WrenchStamped"`` (or ``geometry_msgs/WrenchStamped``) -> package and message name."""
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise RuntimeBackendError(f"invalid ROS message type {type_name!r}: write pkg/msg/Type")
    return parts[0], parts[2]


def message_class(type_name: str) -> Any:
    """Return the rclpy (rosidl) class of a ROS message type from its installed package.

    Parameters
    ----------
    type_name : str
        E.g. ``"geometry_msgs/msg/WrenchStamped"``.

    Returns
    -------
    type
        The message class (keyword construction).

    Raises
    ------
    RuntimeBackendError
        Naming the type and the package missing or lacking it.
    """
    package, name = split_type_name(type_name)
    try:
        module = importlib.import_module(f"{package}.msg")
    except ImportError as exc:
        wheel = "ros-jazzy-" + package.replace("_", "-")
        raise RuntimeBackendError(
            f"message type {type_name} needs the Python package {package!r}, which is not installed "
            f"(apt's {wheel} on a cell, or `pip install {wheel}` where PyPI has that wheel: tf2_msgs has none): {exc}"
        ) from exc
    try:
        return getattr(module, name)
    except AttributeError:
        raise RuntimeBackendError(f"message type {type_name}: package {package!r} has no message {name!r}") from None


def has_message(type_name: str) -> bool:
    """True if the class of ``type_name`` can be imported (e.g. ``tf2_msgs/msg/TFMessage`` on a cell)."""
    try:
        message_class(type_name)
    except RuntimeBackendError:
        return False
    return True


# Which rclpy executor spins a node: "events" (rclpy.experimental.EventsExecutor: its dispatch in C++ takes less
# than half the CPU per received WrenchStamped, which at 1 kHz is most of a node's load; bench/README.md, live
# latency) or "single" (rclpy.executors.SingleThreadedExecutor, the stable one).
EXECUTOR_ENV = "BSP_EXECUTOR"
EXECUTORS = ("events", "single")


def make_executor(kind: str | None = None, context: Any = None) -> tuple[Any, str]:
    """An rclpy executor for ``context`` (rclpy's default one when omitted), and the name of the one made.

    Parameters
    ----------
    kind : {"events", "single"}, optional
        Omitted: ``$BSP_EXECUTOR``, else ``"events"`` where this rclpy has it and ``"single"`` otherwise.
    context : rclpy.context.Context, optional
        The context the executor serves (rclpy's default when omitted).

    Returns
    -------
    executor, name : rclpy executor, str
    """
    requested = kind if kind is not None else os.environ.get(EXECUTOR_ENV, "")
    if requested and requested not in EXECUTORS:
        raise InputError(f"{EXECUTOR_ENV}={requested!r}: expected one of {', '.join(EXECUTORS)}")
    if requested in ("", "events"):
        try:
            from rclpy.experimental import EventsExecutor
        except ImportError:
            if requested == "events":
                raise InputError(
                    f"{EXECUTOR_ENV}=events: this rclpy has no rclpy.experimental.EventsExecutor"
                ) from None
        else:
            return EventsExecutor(context=context), "events"
    from rclpy.executors import SingleThreadedExecutor

    return SingleThreadedExecutor(context=context), "single"


class Client:
    """A private rclpy context with one node and its executor, for tools and tests (not a node of the suite).

    ``bsp demo``, ``bsp play``, ``bsp record`` and the live tests use it to take part in the ROS graph of
    a domain without touching rclpy's default context.

    Parameters
    ----------
    name : str
        Node name.
    domain_id : int, optional
        ROS domain id (``ROS_DOMAIN_ID`` or 0 when omitted).
    """

    def __init__(self, name: str, domain_id: int | None = None) -> None:
        require_rclpy()
        import rclpy
        from rclpy.context import Context
        from rclpy.node import Node

        self.context = Context()
        try:
            rclpy.init(args=[], context=self.context, domain_id=domain_id)
        except Exception as exc:  # rclpy raises RCLError and others
            raise RuntimeBackendError(f"rclpy.init failed (domain {domain_id}): {exc}") from exc
        self.node = Node(name, context=self.context, start_parameter_services=False, enable_rosout=False)
        # The Python executor: Jazzy's EventsExecutor fails (SystemError) on callbacks that take the message
        # info, which the tools and the benchmark use for receive times.
        self.executor, _ = make_executor("single", context=self.context)
        self.executor.add_node(self.node)
        self._closed = False

    def publisher(self, type_name: str, topic: str, qos: str | int | QosSpec = 10) -> Any:
        """An rclpy publisher; ``publish`` takes a message or serialized CDR bytes."""
        return self.node.create_publisher(message_class(type_name), topic, rclpy_qos(qos))

    def subscribe(
        self,
        type_name: str,
        topic: str,
        callback: Callable[[Any], None],
        qos: str | int | QosSpec = 10,
        raw: bool = False,
    ) -> Any:
        """An rclpy subscription (``raw``: the callback gets serialized CDR bytes)."""
        return self.node.create_subscription(message_class(type_name), topic, callback, rclpy_qos(qos), raw=raw)

    def spin(self, seconds: float) -> None:
        """Run callbacks for ``seconds``."""
        deadline = time.monotonic() + seconds
        while self.context.ok():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self.executor.spin_once(timeout_sec=min(0.05, remaining))

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Run callbacks until ``predicate()`` holds or ``timeout_s`` passed; return whether it held."""
        deadline = time.monotonic() + timeout_s
        while True:
            if predicate():
                return True
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not self.context.ok():
                return False
            self.executor.spin_once(timeout_sec=min(0.05, remaining))

    def close(self) -> None:
        """Destroy the node and shut the private context down."""
        if self._closed:
            return
        self._closed = True
        # The node leaves the executor before it is destroyed, and the executor's own guard conditions go after it:
        # an executor must not hold a node whose handles are being destroyed.
        self.executor.remove_node(self.node)
        self.node.destroy_node()
        self.executor.shutdown()
        self.context.try_shutdown()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


try:
    from rclpy.node import Node as RosNode
except ImportError:  # a node module stays importable (for --help); creating a node says how to install rclpy

    class RosNode:  # type: ignore[no-redef]
        """Stand-in for ``rclpy.node.Node`` when rclpy is missing: constructing it raises the install hint."""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            require_rclpy()


def log_error(name: str, error: BaseException) -> None:
    """Print a node's fatal error on stderr the way rclpy's logger formats it (also before ``rclpy.init``)."""
    import sys

    print(f"[ERROR] [{name}]: {error}", file=sys.stderr, flush=True)
