"""`bsp tare` on simulated tare bags, and `bsp identify --tare` end to end (bags written into tmp_path)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from bsp_ros.cli import main

NUISANCE = ("--force-offset", "3", "-3", "3", "--handle-mass", "0.3", "--handle-com", "0", "0.02", "0.05")


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("tare")
    out = {
        "swing": root / "tare_swing",
        "rest": root / "tare_rest",
        "session": root / "session",
    }
    swing = ("--tare", "--duration", "20", "--tare-swing", "20", "20", "0", "--seed", "4")
    assert main(["simulate", "--out", str(out["swing"]), *swing, *NUISANCE]) == 0
    assert main(["simulate", "--out", str(out["rest"]), "--tare", "--duration", "10", "--seed", "4", *NUISANCE]) == 0
    assert main(["simulate", "--out", str(out["session"]), "--duration", "60", "--seed", "4", *NUISANCE]) == 0
    return out


def test_swinging_tare_file_holds_offset_and_handle(bags, tmp_path) -> None:
    assert main(["tare", str(bags["swing"]), "--out", str(tmp_path / "t.yaml")]) == 0
    doc = yaml.safe_load((tmp_path / "t.yaml").read_text())
    truth = json.loads((bags["swing"] / "truth.json").read_text())
    assert doc["schema"] == "bsp_ros/core/tare/1" and doc["load"] == "separated" and doc["frame_id"] == "ft_sensor"
    assert doc["recording"]["n_samples"] == 2000 and doc["recording"]["source"] == "tare_swing"
    force = doc["force_offset_n"]
    assert np.all(np.abs(np.subtract(force["value"], truth["force_offset_n"])) < 4 * np.array(force["std"]))
    mass = doc["payload"]["mass_kg"]
    assert abs(mass["value"] - 0.3) < 4 * mass["std"]
    np.testing.assert_allclose(doc["payload"]["com_m"]["value"], truth["handle_com_m"], atol=0.002)


def test_tare_at_rest_gives_a_constant_load(bags, tmp_path) -> None:
    assert main(["tare", str(bags["rest"]), "--out", str(tmp_path / "t.yaml")]) == 0
    doc = yaml.safe_load((tmp_path / "t.yaml").read_text())
    assert doc["load"] == "constant" and doc["payload"] is None
    assert doc["recording"]["rotation_world_from_sensor"] is not None  # from /tf_static


def test_identify_with_a_tare_is_within_half_a_percent(bags, tmp_path) -> None:
    assert main(["tare", str(bags["swing"]), "--out", str(tmp_path / "t.yaml")]) == 0
    out = tmp_path / "e.json"
    code = main(["identify", str(bags["session"]), "--tare", str(tmp_path / "t.yaml"), "--json", str(out)])
    estimate, truth = json.loads(out.read_text()), json.loads((bags["session"] / "truth.json").read_text())
    assert code == 0 and estimate["quality"]["valid"]
    assert estimate["quality"]["tare"]["applied"] and estimate["quality"]["tare"]["file"] == "t.yaml"
    for segment, q in estimate["segments"].items():
        true = truth["segments"][segment]["static_moment_kgm"]
        assert q["static_moment_kgm"]["value"] == pytest.approx(true, rel=0.005), segment
        assert abs(q["static_moment_kgm"]["value"] - true) < 3 * q["static_moment_kgm"]["std"], segment


def test_identify_without_a_tare_says_so_with_the_sensitivity(bags, tmp_path) -> None:
    """Untared, the std holds the assumed zero (1 N, 0.02 Nm per axis): its share is G Sigma G^T, at least the
    force part the sensitivity block shows, and the std without it (--zero-sd-n 0 --zero-sd-nm 0) adds up."""
    out, bare = tmp_path / "e.json", tmp_path / "bare.json"
    main(["identify", str(bags["session"]), "--json", str(out), "--format", "none"])
    main(
        [
            "identify",
            str(bags["session"]),
            "--json",
            str(bare),
            "--format",
            "none",
            "--zero-sd-n",
            "0",
            "--zero-sd-nm",
            "0",
        ]
    )
    estimate, without = json.loads(out.read_text()), json.loads(bare.read_text())
    quality = estimate["quality"]
    assert quality["tare"]["applied"] is False and quality["tare"]["file"] is None
    assert quality["tare"]["zero_sd"] == {"force_n": 1.0, "moment_nm": 0.02}
    assert "std_added" not in without["quality"]["tare"]
    sensitivity = quality["offset_sensitivity"]
    assert sensitivity["offset_n"] == 0.1 and set(sensitivity["static_moment_kgm"]) == {"upper_arm", "forearm", "hand"}
    for segment, per_tenth in sensitivity["static_moment_kgm"].items():
        added = quality["tare"]["std_added"][f"static_moment_kgm/{segment}"]
        force_part = 10.0 * float(np.linalg.norm(per_tenth))  # 1 N on each sensor axis
        assert added >= force_part * (1 - 1e-6)
        std, std_bare = (e["segments"][segment]["static_moment_kgm"]["std"] for e in (estimate, without))
        assert std**2 == pytest.approx(std_bare**2 + added**2, rel=1e-6), segment


def test_tare_of_another_sensor_frame_is_refused(bags, tmp_path, capsys) -> None:
    assert main(["tare", str(bags["rest"]), "--out", str(tmp_path / "t.yaml")]) == 0
    doc = yaml.safe_load((tmp_path / "t.yaml").read_text())
    doc["frame_id"] = "other_sensor"
    (tmp_path / "o.yaml").write_text(yaml.safe_dump(doc))
    assert main(["identify", str(bags["session"]), "--tare", str(tmp_path / "o.yaml"), "--format", "none"]) == 2
    assert "other_sensor" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["nope"], 10, "nope"),
        (["SESSION", "--wrench-topic", "/other/wrench"], 13, "/other/wrench"),
        (["SHORT"], 3, "at least 5 s"),
        (["--live"], 2, "--duration"),
        (["--live", "--duration", "2"], 2, "at least 5 s, got 2"),
        ([], 2, "give a TARE recording"),
        (["SESSION", "--duration", "9"], 2, "--live only"),
    ],
)
def test_bad_input_gets_its_exit_code_and_a_clear_message(bags, tmp_path, capsys, args, code, message) -> None:
    short = tmp_path / "short"
    if "SHORT" in args:
        assert main(["simulate", "--out", str(short), "--tare", "--duration", "3"]) == 0
    paths = {"SESSION": str(bags["session"]), "SHORT": str(short)}
    argv = ["tare", *[paths.get(a, a) for a in args], "--out", str(tmp_path / "t.yaml")]
    assert main(argv) == code
    assert message in capsys.readouterr().err
    assert not (tmp_path / "t.yaml").exists()


def test_an_existing_tare_file_is_not_overwritten(bags, tmp_path, capsys) -> None:
    (tmp_path / "t.yaml").write_text("keep")
    assert main(["tare", str(bags["rest"]), "--out", str(tmp_path / "t.yaml")]) == 2
    assert (tmp_path / "t.yaml").read_text() == "keep"


def test_offline_tare_does_not_import_rclpy(bags, tmp_path) -> None:
    code = (
        "import sys; from bsp_ros.cli import main; "
        f"assert main(['tare', {str(bags['rest'])!r}, '--out', {str(tmp_path / 't.yaml')!r}]) == 0; "
        "print('rclpy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "False"


# Publishes at 100 Hz until its stdin closes (the test is done), for at most argv[1] seconds.
_PUBLISHER = """
import select, sys, time
import rclpy
from geometry_msgs.msg import WrenchStamped
rclpy.init()
node = rclpy.create_node("tare_test_sensor")
pub = node.create_publisher(WrenchStamped, "/ft_sensor/wrench", 10)
end = time.monotonic() + float(sys.argv[1])
k = 0
while time.monotonic() < end and not select.select([sys.stdin], [], [], 0.01)[0]:
    msg = WrenchStamped()
    msg.header.stamp = node.get_clock().now().to_msg()
    msg.header.frame_id = "ft_sensor"
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = 1.0 + 0.01 * (k % 3 - 1), 2.0, 3.0
    msg.wrench.torque.z = 0.1
    pub.publish(msg)
    k += 1
node.destroy_node()
rclpy.try_shutdown()
"""


def test_live_tare_collects_the_running_wrench_topic(tmp_path, monkeypatch) -> None:
    pytest.importorskip("rclpy")
    domain = str(1 + os.getpid() % 10)  # below the node tests' domains (11 and up)
    monkeypatch.setenv("ROS_DOMAIN_ID", domain)
    publisher = subprocess.Popen(
        [sys.executable, "-c", _PUBLISHER, "30"], env={**os.environ, "ROS_DOMAIN_ID": domain}, stdin=subprocess.PIPE
    )
    try:
        # The recording lasts --duration from the first message, however long the publisher takes to start.
        assert main(["tare", "--live", "--duration", "6", "--out", str(tmp_path / "live.yaml")]) == 0
        assert publisher.poll() is None  # it published all along
        publisher.communicate(timeout=20)  # closes its stdin: it stops
        assert publisher.returncode == 0
    finally:
        if publisher.poll() is None:
            publisher.kill()
            publisher.wait()
    doc = yaml.safe_load((tmp_path / "live.yaml").read_text())
    assert doc["load"] == "constant" and doc["frame_id"] == "ft_sensor"
    assert doc["recording"]["source"] == "live /ft_sensor/wrench" and doc["recording"]["n_samples"] > 300
    np.testing.assert_allclose(doc["force_offset_n"]["value"], [1.0, 2.0, 3.0], atol=0.005)
    np.testing.assert_allclose(doc["torque_offset_nm"]["value"], [0.0, 0.0, 0.1], atol=1e-9)


def test_identify_table_names_the_tare_or_the_sensitivity() -> None:
    from bsp_ros.cli.identify import tare_line
    from bsp_ros.core.estimate_schema import Quality

    assert (
        tare_line(Quality.from_json({"tare": {"applied": True, "file": "t.yaml"}}))
        == "tare: t.yaml applied (its uncertainty is in the std)"
    )
    quality = {
        "tare": {"applied": False, "file": None},
        "offset_sensitivity": {"static_moment_percent": {"upper_arm": 0.33, "forearm": None, "hand": 1.17}},
    }
    assert tare_line(Quality.from_json(quality)) == (
        "tare: none applied: 0.1 N of sensor offset moves a static moment by up to 1.2% (bsp tare, then --tare FILE)"
    )


def test_tare_bag_without_any_transform_gives_a_constant_load_and_says_why(tmp_path, capsys) -> None:
    bag = tmp_path / "tare_no_tf"
    assert main(["simulate", "--out", str(bag), "--tare", "--duration", "6", "--no-tf-static", *NUISANCE]) == 0
    assert main(["tare", str(bag), "--out", str(tmp_path / "t.yaml")]) == 0
    doc = yaml.safe_load((tmp_path / "t.yaml").read_text())
    assert doc["load"] == "constant" and doc["recording"]["rotation_world_from_sensor"] is None
    assert "no transform connects the wrench frame ft_sensor to world" in capsys.readouterr().err


def test_a_recording_with_the_arm_attached_is_refused_unless_forced(bags, tmp_path, capsys) -> None:
    out = tmp_path / "arm.tare.yaml"
    assert main(["tare", str(bags["session"]), "--out", str(out)]) == 3
    err = capsys.readouterr().err
    assert err.startswith("bsp tare: error: the load changed during the recording") and "--force" in err
    assert err.count("\n") == 1
    assert not out.exists()  # nothing a session could be identified with
    assert main(["tare", str(bags["session"]), "--out", str(out), "--force"]) == 0
    assert "warning: tare: the load changed during the recording" in capsys.readouterr().err
    assert yaml.safe_load(out.read_text())["recording"]["unsteadiness"] > 5


def test_live_without_a_duration_names_the_option_not_none(tmp_path, capsys) -> None:
    assert main(["tare", "--live", "--out", str(tmp_path / "t.yaml")]) == 2
    err = capsys.readouterr().err
    assert "--live needs --duration S" in err and "None" not in err
    assert main(["tare", "--live", "--duration", "2", "--out", str(tmp_path / "t.yaml")]) == 2
    assert "--duration must be at least 5 s, got 2" in capsys.readouterr().err
