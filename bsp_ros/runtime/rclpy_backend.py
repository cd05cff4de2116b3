"""The bsp_ros node API as a thin wrapper around rclpy (ROS 2 Jazzy); importable without rclpy."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

from bsp_ros.errors import InputError, RuntimeBackendError
from bsp_ros.runtime.params import check_parameter, parse_param_args, rclpy_cli_args
from bsp_ros.runtime.qos import QosSpec, rclpy_qos

__all__ = ["RclpyContext", "RclpyNode", "rclpy_available"]

QosLike = str | int | QosSpec
_INT64_MIN, _INT64_MAX = -(2**63), 2**63 - 1


def rclpy_available() -> bool:
    """Return True if rclpy and rosidl_runtime_py can be imported (a sourced ROS 2 environment)."""
    try:
        import rclpy  # noqa: F401
        import rosidl_runtime_py.utilities  # noqa: F401
    except ImportError:
        return False
    return True


def _message_class(type_name: str):
    from rosidl_runtime_py.utilities import get_message

    try:
        return get_message(type_name)
    except (AttributeError, ModuleNotFoundError, ValueError) as exc:
        raise RuntimeBackendError(f"unknown ROS message type {type_name!r}: {exc}") from exc


class _Logger:
    """rclpy's logger with the ``logging`` call style (``%`` arguments)."""

    def __init__(self, logger) -> None:
        self._logger = logger

    def _format(self, msg: str, args: tuple) -> str:
        return msg % args if args else msg

    def debug(self, msg: str, *args: Any) -> None:
        self._logger.debug(self._format(msg, args))

    def info(self, msg: str, *args: Any) -> None:
        self._logger.info(self._format(msg, args))

    def warning(self, msg: str, *args: Any) -> None:
        self._logger.warning(self._format(msg, args))

    def error(self, msg: str, *args: Any) -> None:
        self._logger.error(self._format(msg, args))

    def exception(self, msg: str, *args: Any) -> None:
        self._logger.error(self._format(msg, args))

    def critical(self, msg: str, *args: Any) -> None:
        self._logger.fatal(self._format(msg, args))


class RclpyNode:
    """The bsp_ros node API on an ``rclpy.node.Node`` (same methods as :class:`DdsNode`)."""

    def __init__(self, context: RclpyContext, name: str, namespace: str = "") -> None:
        from rclpy.node import Node

        self.context = context
        self.node = Node(name, namespace=namespace or None, context=context.rclpy_context)
        self.name = self.node.get_name()
        self.namespace = self.node.get_namespace()
        self.fully_qualified_name = self.node.get_fully_qualified_name()
        self._logger = _Logger(self.node.get_logger())
        context._add_node(self)

    def message_class(self, type_name: str):
        """Return the rosidl message class of a ROS type."""
        return _message_class(type_name)

    def create_publisher(self, type_name: str, topic: str, qos: QosLike = 10):
        """Create an rclpy publisher; call ``publish(msg)`` on it."""
        return self.node.create_publisher(_message_class(type_name), topic, rclpy_qos(qos))

    def create_subscription(self, type_name: str, topic: str, callback: Callable[[Any], None], qos: QosLike = 10):
        """Create an rclpy subscription (callbacks run in the context's single-threaded executor)."""
        return self.node.create_subscription(_message_class(type_name), topic, callback, rclpy_qos(qos))

    def create_timer(self, period_s: float, callback: Callable[[], None]):
        """Create an rclpy timer on the node's clock."""
        if not period_s > 0.0:
            raise RuntimeBackendError(f"timer period must be positive, got {period_s!r}")
        return self.node.create_timer(period_s, callback)

    def now_ns(self) -> int:
        """Return the node clock (system time unless ``use_sim_time``) in nanoseconds."""
        return int(self.node.get_clock().now().nanoseconds)

    def get_logger(self) -> _Logger:
        """Return the node's rclpy logger, accepting ``logging``-style ``%`` arguments."""
        return self._logger

    def declare_parameter(
        self,
        name: str,
        default: Any,
        description: str = "",
        unit: str = "",
        lo: float | None = None,
        hi: float | None = None,
    ) -> Any:
        """Declare an rclpy parameter with a ranged ParameterDescriptor and return its value.

        Raises
        ------
        InputError
            If the override has the wrong type or lies outside ``[lo, hi]``, naming it.
        """
        from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
        from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException

        check_parameter(self.name, name, default, default, lo, hi)
        text = description + (f" [{unit}]" if unit else "")
        descriptor = ParameterDescriptor(description=text)
        if lo is not None or hi is not None:
            if isinstance(default, bool) or not isinstance(default, int | float):
                raise RuntimeBackendError(f"parameter {name!r}: a range needs a numeric default")
            if isinstance(default, int):
                low = _INT64_MIN if lo is None else math.ceil(lo)
                high = _INT64_MAX if hi is None else math.floor(hi)
                descriptor.integer_range = [IntegerRange(from_value=low, to_value=high, step=0)]
            else:
                low_f = -sys.float_info.max if lo is None else float(lo)
                high_f = sys.float_info.max if hi is None else float(hi)
                descriptor.floating_point_range = [FloatingPointRange(from_value=low_f, to_value=high_f, step=0.0)]
        try:
            value = self.node.declare_parameter(name, default, descriptor).value
        except InvalidParameterTypeException as exc:
            raise InputError(f"parameter {name!r} of node {self.name!r}: {exc}") from exc
        except InvalidParameterValueException as exc:
            raise InputError(f"parameter {name!r} of node {self.name!r}: {exc}") from exc
        return check_parameter(self.name, name, value, default, lo, hi)

    def get_parameter(self, name: str) -> Any:
        """Return the value of a declared parameter."""
        return self.node.get_parameter(name).value

    def spin(self, until: Callable[[], bool] | float | None = None) -> None:
        """Run the context's executor (see :meth:`RclpyContext.spin`)."""
        self.context.spin(until)

    def shutdown(self) -> None:
        """Shut the context down."""
        self.context.shutdown()

    def destroy_node(self) -> None:
        """Destroy the rclpy node."""
        self.context._remove_node(self)


class RclpyContext:
    """An initialised rclpy context with a single-threaded executor for its nodes.

    Parameters
    ----------
    domain_id : int, optional
        ROS domain id (``ROS_DOMAIN_ID`` when omitted).
    args : sequence of str, optional
        Command line without program name; ``--params-file F`` and ``--param n:=v`` are passed to rclpy
        as ``--ros-args --params-file F -p n:=v``, other ROS arguments pass through.
    """

    backend = "rclpy"

    def __init__(self, domain_id: int | None = None, args: Sequence[str] | None = None) -> None:
        try:
            import rclpy
            from rclpy.executors import SingleThreadedExecutor
            from rclpy.utilities import get_default_context
        except ImportError as exc:
            raise RuntimeBackendError(f"rclpy is not available (source a ROS 2 Jazzy setup): {exc}") from exc
        raw = list(sys.argv[1:] if args is None else args)
        if "--ros-args" in raw:
            # A ROS 2 command line (ros2 run / launch): rclpy parses it itself.
            self.param_args, self.remaining_args = parse_param_args([])
            rclpy_args = raw
        else:
            self.param_args, self.remaining_args = parse_param_args(raw)
            rclpy_args = self.remaining_args + rclpy_cli_args(self.param_args)
        # The default context, so rclpy installs its SIGINT/SIGTERM handlers (ros2 launch stops nodes so).
        try:
            rclpy.init(args=[sys.argv[0] if sys.argv else "bsp_ros", *rclpy_args], domain_id=domain_id)
        except Exception as exc:  # rclpy raises RCLError and others
            raise RuntimeBackendError(f"rclpy.init failed: {exc}") from exc
        self.rclpy_context = get_default_context()
        self.executor = SingleThreadedExecutor(context=self.rclpy_context)
        self._nodes: list[RclpyNode] = []

    def create_node(self, name: str, namespace: str = "") -> RclpyNode:
        """Create a node in this context."""
        return RclpyNode(self, name, namespace)

    def message_class(self, type_name: str):
        """Return the rosidl message class of a ROS type."""
        return _message_class(type_name)

    def _add_node(self, node: RclpyNode) -> None:
        self._nodes.append(node)
        self.executor.add_node(node.node)

    def _remove_node(self, node: RclpyNode) -> None:
        if node in self._nodes:
            self._nodes.remove(node)
            self.executor.remove_node(node.node)
            node.node.destroy_node()

    def ok(self) -> bool:
        """Return True while the rclpy context is valid."""
        return bool(self.rclpy_context.ok())

    def spin(self, until: Callable[[], bool] | float | None = None) -> None:
        """Run callbacks serially; stop on ``until()`` true, after ``until`` seconds, or on shutdown.

        KeyboardInterrupt and ``rclpy.executors.ExternalShutdownException`` end the spin quietly.
        """
        from rclpy.executors import ExternalShutdownException

        deadline = None if until is None or callable(until) else time.monotonic() + float(until)
        try:
            while self.rclpy_context.ok():
                if callable(until) and until():
                    return
                step = 0.1
                if deadline is not None:
                    step = min(step, deadline - time.monotonic())
                    if step <= 0:
                        return
                self.executor.spin_once(timeout_sec=step)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass

    def shutdown(self) -> None:
        """Destroy the nodes and shut rclpy down (the Jazzy main() pattern's ``finally`` part)."""
        import rclpy

        for node in list(self._nodes):
            self._remove_node(node)
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.rclpy_context)

    def __enter__(self) -> RclpyContext:
        return self

    def __exit__(self, *exc: object) -> None:
        self.shutdown()
