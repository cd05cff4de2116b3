"""`bsp simulate` nuisance options reach the truth and the bag (bags written into tmp_path)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bsp_ros.bag import read_session
from bsp_ros.bag.metadata import read_metadata
from bsp_ros.cli import main


def _simulate(out: Path, *extra: str) -> dict:
    assert main(["simulate", "--out", str(out), "--duration", "5", *extra]) == 0
    return json.loads((out / "truth.json").read_text())


def test_elastic_friction_and_sensor_options_are_recorded_in_the_truth(tmp_path: Path) -> None:
    truth = _simulate(
        tmp_path / "s",
        *("--passive-offset", "0.05", "-0.2", "0", "--stiffness", "0", "1.2", "0", "--neutral", "0", "1.87", "0"),
        *("--friction-transition", "0.002", "--force-offset", "3", "0", "0", "--handle-mass", "0.3"),
        *("--handle-com", "0", "0", "0.05", "--skin-offset", "0", "0.01", "0", "0.01", "0", "0.01", "0", "0.01"),
        *("--spikes", "0.001", "--spike-size", "500"),
    )
    elbow = truth["joints"]["elbow"]
    assert (elbow["offset_nm"], elbow["stiffness_nm_per_rad"], elbow["neutral_rad"]) == (-0.2, 1.2, 1.87)
    assert truth["friction"]["transition_rad_s"] == 0.002
    sim = truth["simulation"]
    assert (sim["force_bias_n"], sim["handle_mass_kg"], sim["handle_com_m"]) == ([3, 0, 0], 0.3, [0, 0, 0.05])
    assert sim["skin_offset_m"] == [[0.0, 0.01]] * 4
    assert (sim["spike_fraction"], sim["spike_n"]) == (0.001, 500.0)


def test_per_joint_option_with_the_wrong_count_names_the_option(tmp_path: Path, capsys) -> None:
    assert main(["simulate", "--out", str(tmp_path / "s"), "--passive-offset", "0.1"]) == 2
    assert "--passive-offset needs 3 values" in capsys.readouterr().err


def test_no_tf_static_bag_reads_with_an_assumed_rotation(tmp_path: Path) -> None:
    _simulate(tmp_path / "s", "--no-tf-static")
    assert "/tf_static" not in read_metadata(tmp_path / "s" / "metadata.yaml").topics
    read = read_session(tmp_path / "s")
    assert read.report.rotation_source == "assumed"


def test_swinging_tare_bag_has_wrench_and_tf_but_no_markers(tmp_path: Path) -> None:
    truth = _simulate(tmp_path / "t", "--tare", "--handle-mass", "0.3", "--tare-swing", "20", "20", "0")
    topics = read_metadata(tmp_path / "t" / "metadata.yaml").topics
    assert sorted(topics) == ["/ft_sensor/wrench", "/tf"]
    assert topics["/tf"].message_count == 250
    assert truth["schema"] == "bsp_ros/tare_truth/1" and truth["handle_mass_kg"] == 0.3


def test_tare_options_without_tare_are_refused(tmp_path: Path, capsys) -> None:
    assert main(["simulate", "--out", str(tmp_path / "s"), "--tare-swing", "1", "1", "1"]) == 2
    assert "add --tare" in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--handle-mass", "--friction-transition"])
def test_silly_nuisance_values_are_refused(tmp_path: Path, flag: str, capsys) -> None:
    assert main(["simulate", "--out", str(tmp_path / "s"), flag, "-1"]) == 2
    assert flag.lstrip("-").replace("-", "_") in capsys.readouterr().err
