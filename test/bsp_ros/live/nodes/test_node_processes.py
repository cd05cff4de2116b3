"""Node executables as users start them: --help, refused parameters, a params file, and a clean exit."""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from node_processes import ROOT

from bsp_ros.live.runtime.ros import EXECUTOR_ENV, Client

NODES = ("bsp_identifier", "cell_simulator", "joint_angle_estimator", "session_recorder")


def _env(domain: int, executor: str | None = None) -> dict[str, str]:
    env = {
        **os.environ,
        "ROS_DOMAIN_ID": str(domain),
        "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
    }
    env.pop(EXECUTOR_ENV, None)
    if executor is not None:
        env[EXECUTOR_ENV] = executor
    return env


def _holders(path: Path) -> list[int]:
    """The processes with ``path`` open (Linux /proc), this one left out."""
    target = str(path.resolve())
    pids = []
    for fds in Path("/proc").glob("[0-9]*/fd"):
        try:
            if int(fds.parent.name) != os.getpid() and any(os.readlink(fd) == target for fd in fds.iterdir()):
                pids.append(int(fds.parent.name))
        except OSError:  # gone meanwhile, or not ours to read
            continue
    return pids


@pytest.mark.parametrize("name", NODES)
def test_help_prints_every_parameter_and_starts_nothing(name: str, ros_domain: int) -> None:
    out = subprocess.run(
        [sys.executable, "-m", f"bsp_ros.live.nodes.{name}", "--help"],
        env=_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(f"usage: {name}")
    for param in importlib.import_module(f"bsp_ros.live.nodes.{name}").PARAMETERS:
        line = next(line for line in out.stdout.splitlines() if line.strip().startswith(param.name + " "))
        assert f"default {param.default!r}" in line and param.description[:20] in line, line
    assert "[INFO]" not in out.stderr  # no node came up


def test_a_parameter_out_of_range_is_refused_naming_it(ros_domain: int) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "bsp_ros.live.nodes.bsp_identifier", "--ros-args", "-p", "update_hz:=1000.0"],
        env=_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert "update_hz" in out.stderr and "Traceback" not in out.stderr


def test_a_tare_file_that_is_not_a_tare_is_refused_naming_it(ros_domain: int, tmp_path: Path) -> None:
    bad = tmp_path / "tare.yaml"
    bad.write_text("schema: something/else\n")
    out = subprocess.run(
        [sys.executable, "-m", "bsp_ros.live.nodes.bsp_identifier", "--ros-args", "-p", f"tare_file:={bad}"],
        env=_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert "tare_file" in out.stderr and str(bad) in out.stderr and "Traceback" not in out.stderr


def test_an_integer_for_a_float_parameter_is_refused_with_a_hint(ros_domain: int) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "bsp_ros.live.nodes.bsp_identifier", "--ros-args", "-p", "window_s:=20"],
        env=_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert "window_s" in out.stderr and "decimal point" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize(
    ("param", "needle"),
    [
        ("marker_jump_name:=knee", "marker_jump_name 'knee'"),
        ("marker_jump_m:=[0.1, 0.2]", "marker_jump_m"),
        ("hand_marker_offset_mm:=[25.0]", "hand_marker_offset_mm needs 2 offsets"),
    ],
)
def test_a_bad_marker_fault_is_refused_naming_it(param: str, needle: str, ros_domain: int) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "bsp_ros.live.nodes.cell_simulator", "--ros-args", "-p", param],
        env=_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert needle in out.stderr and "Traceback" not in out.stderr


def test_an_unknown_executor_is_refused_naming_it(ros_domain: int) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "bsp_ros.live.nodes.joint_angle_estimator"],
        env=_env(ros_domain, "threads"),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert f"{EXECUTOR_ENV}='threads'" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.dds
@pytest.mark.parametrize("executor", ["events", "single"])
@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_a_stopped_identifier_exits_cleanly_without_leaked_semaphores(
    stop: signal.Signals, executor: str, ros_domain: int, tmp_path: Path
) -> None:
    # The cell's params file, as `ros2 launch` passes it; the node is up once it publishes its health.
    config = ROOT / "bsp_ros" / "config" / "bsp_cell.yaml"
    log = tmp_path / "stderr.log"
    with log.open("wb") as stderr:
        process = subprocess.Popen(
            [sys.executable, "-m", "bsp_ros.live.nodes.bsp_identifier", "--ros-args", "--params-file", str(config)],
            env=_env(ros_domain, executor),
            stdout=subprocess.DEVNULL,
            stderr=stderr,
        )
    health: list[object] = []
    try:
        with Client("health_listener", ros_domain) as client:
            client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", health.append, "default")
            assert client.spin_until(lambda: bool(health) or process.poll() is not None, 60), log.read_text()
        assert process.poll() is None, log.read_text()
        process.send_signal(stop)
        assert process.wait(30) == 0, log.read_text()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(10)
    # multiprocessing's resource tracker outlives the node by a moment and would warn then: wait until nothing holds
    # the log open.
    deadline = time.monotonic() + 10.0
    while _holders(log) and time.monotonic() < deadline:
        time.sleep(0.02)
    text = log.read_text()
    assert "leaked semaphore" not in text and "Traceback" not in text, text
    assert f"spinning on the {executor} executor" in text, text
