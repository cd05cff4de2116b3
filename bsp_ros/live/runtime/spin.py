"""A node's process: ``--help``, rclpy init, the executor, spin, and a clean shutdown (the ros2/demos shape)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from bsp_ros.errors import BspError
from bsp_ros.live.runtime.parameters import Param, help_text, wants_help
from bsp_ros.live.runtime.ros import log_error, make_executor, require_rclpy
from bsp_ros.live.runtime.threads import single_threaded_blas

__all__ = ["run_node"]


def run_node(
    name: str, node_class: Callable[[], Any], summary: str, params: Sequence[Param], args: list[str] | None
) -> int:
    """Run one node until Ctrl-C or shutdown; the body of every node's ``main``.

    Parameters
    ----------
    name : str
        Node name (for ``--help`` and errors before the node exists).
    node_class : callable
        Makes the node (after ``rclpy.init``).
    summary : str
        First lines of ``--help``.
    params : sequence of Param
        The node's parameters, listed by ``--help``.
    args : list of str or None
        A command line like ``sys.argv`` (``--ros-args ...`` included).

    Returns
    -------
    int
        Exit code: 0, or the :class:`BspError`'s code with its message on stderr.
    """
    if wants_help(args):
        print(help_text(name, summary, params))
        return 0
    try:
        require_rclpy()
        import rclpy
        from rclpy.executors import ExternalShutdownException

        rclpy.init(args=args)
    except BspError as exc:
        log_error(name, exc)
        return exc.exit_code
    single_threaded_blas()
    node = None
    executor = None
    try:
        executor, executor_name = make_executor()
        node = node_class()
        node.get_logger().info(f"spinning on the {executor_name} executor")
        executor.add_node(node)
        if executor_name == "events":
            # Jazzy's EventsExecutor.spin() busy-waits (100% CPU on an idle node) and ignores SIGINT;
            # spin_once in a loop does neither (as of the rclpy 7.1.6 wheels).
            while rclpy.ok():
                executor.spin_once(timeout_sec=0.1)
        else:
            executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except BspError as exc:
        log_error(name, exc)
        return exc.exit_code
    except Exception:
        if rclpy.ok():
            raise
        # A callback cut short by the shutdown (SIGINT/SIGTERM: its publisher's context is gone) is no error.
    finally:
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
