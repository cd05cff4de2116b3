"""The simulated cell and the nodes started by hand with the shipped parameters agree on the force sensor's rotation
(one cell file), with or without tf2_msgs: the live estimate is valid, and a session `bsp record`ed from them, with
the topics an engineer lists (/tf_static among them), identifies offline with no extra option."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from node_processes import PLAY_PEER, ROOT, NodeProcesses, Peer, domain_id

from bsp_ros.cli import main
from bsp_ros.live.runtime.ros import has_message
from msg_adapters.diagnostics import read_diagnostic_array

pytestmark = [pytest.mark.dds, pytest.mark.slow]

PARAMS_FILE = ROOT / "bsp_ros" / "config" / "bsp_cell.yaml"
TF_INSTALLED = has_message("tf2_msgs/msg/TFMessage")
# What the engineer records (docs/cell-guide.md, step 6), /tf_static included whether or not tf2_msgs is there.
TOPICS = ["/ft_sensor/wrench", "/mocap/shoulder", "/mocap/elbow", "/mocap/wrist", "/mocap/hand", "/tf_static"]
# Simulated seconds per wall second: the test's only change to the shipped parameters, to keep it short.
SPEED = 3.0
RECORD_AFTER_VALID_S = 8.0  # wall seconds recorded once the live estimate is valid (24 s of the session)


def _start_by_hand(nodes: NodeProcesses, name: str) -> None:
    """``python -m bsp_ros.live.nodes.<name> --ros-args --params-file bsp_cell.yaml`` (README, "the nodes")."""
    # Named for the node: a bare `-p speed:=...` would lose to the params file's value for cell_simulator.
    extra = ["-p", f"cell_simulator:speed:={SPEED}"] if name == "cell_simulator" else []
    with open(nodes.log_dir / f"{name}.log", "ab") as log:
        nodes.processes[name] = subprocess.Popen(
            [
                sys.executable,
                "-m",
                f"bsp_ros.live.nodes.{name}",
                "--ros-args",
                "--params-file",
                str(PARAMS_FILE),
                *extra,
            ],
            env=nodes.env,
            stdout=subprocess.DEVNULL,
            stderr=log,
        )


def _static_moments(document: dict[str, Any]) -> dict[str, float]:
    return {s: q["static_moment_kgm"]["value"] for s, q in document["segments"].items()}


def test_the_cell_started_by_hand_is_valid_live_and_its_recording_identifies_offline_alike(tmp_path: Path) -> None:
    domain = domain_id()
    nodes = NodeProcesses(domain, tmp_path)
    peer = Peer(domain)
    bag = tmp_path / "session_bag"
    recorder = subprocess.Popen(
        [sys.executable, str(PLAY_PEER), "record", *TOPICS, "--out", str(bag), "--domain", str(domain)],
        env=nodes.env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    diagnostics: list[dict[str, str]] = []

    def on_diagnostics(msg: Any) -> None:
        for status in read_diagnostic_array(msg).status:
            if status.name == "bsp_identifier":
                diagnostics.append(dict(status.values))

    try:
        estimates = peer.listen_json("bsp/estimate_json")
        peer.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", on_diagnostics, "default")
        for name in ("joint_angle_estimator", "bsp_identifier", "cell_simulator"):
            _start_by_hand(nodes, name)
        valid = lambda: bool(estimates) and estimates[-1][1]["quality"]["valid"]  # noqa: E731
        assert peer.spin_until(valid, 45), (
            estimates[-1][1]["quality"] if estimates else None,
            nodes.log("bsp_identifier"),
        )
        peer.spin_until(lambda: False, RECORD_AFTER_VALID_S)
        live = next(d for _, d in reversed(estimates) if d["quality"]["valid"])
        recorder.send_signal(signal.SIGINT)
        out, err = recorder.communicate(timeout=30)
    finally:
        if recorder.poll() is None:
            recorder.kill()
        nodes.close()
        peer.close()
    assert recorder.returncode == 0, err
    # Said once, and nothing about a topic it could not record.
    assert "not recorded" not in out + err and "no publisher" not in out + err, out + err
    if not TF_INSTALLED:
        assert out.count("tf2_msgs is not installed; the sensor's rotation is recorded from /ft_sensor/transform") == 1
    # The identifier took the simulator's rotation from what it received, and found nothing to say about it.
    health = diagnostics[-1]
    # The rotation's source as the bag's rotation_source names it: the TransformStamped topic without tf2_msgs.
    assert health["wrench_frame.ft_sensor"] == ("tf" if TF_INSTALLED else "topic"), health
    assert not [k for k in health if k.endswith((".missing", ".disagrees"))], health
    assert "disagree" not in nodes.log("bsp_identifier") and "no transform" not in nodes.log("bsp_identifier")

    result = tmp_path / "offline.json"
    code = main(["identify", str(bag), "--json", str(result), "--format", "none"])  # no extra option
    offline = json.loads(result.read_text())
    assert code == 0 and offline["quality"]["valid"], offline["quality"]
    assert offline["bag"]["rotation_source"] == ("tf" if TF_INSTALLED else "topic")
    live_moments, offline_moments = _static_moments(live), _static_moments(offline)
    print("live", live_moments, "offline", offline_moments)
    for segment, value in live_moments.items():
        assert offline_moments[segment] == pytest.approx(value, rel=0.02), segment
