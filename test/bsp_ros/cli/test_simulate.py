"""`bsp simulate` nuisance options reach the truth and the bag (bags written into tmp_path)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
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


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        (["--coulomb", "-1", "0.2", "0.1"], "--coulomb value 1 must be finite and within [0, 20] Nm, got -1.0"),
        (["--stiffness", "0", "nan", "0"], "--stiffness value 2 must be finite and within [0, 100] Nm/rad, got nan"),
        (["--neutral", "0", "0", "7"], "--neutral value 3 must be finite and within [-6.28319, 6.28319] rad, got 7.0"),
        (["--viscous", "0", "-0.5", "0"], "--viscous value 2 must be finite and within [0, 100] Nm s/rad, got -0.5"),
        (["--passive-offset", "inf", "0", "0"], "--passive-offset value 1 must be finite and within [-20, 20] Nm"),
        (["--friction-transition", "-1"], "--friction-transition must be finite and within [0, 10] rad/s, got -1.0"),
        (["--stribeck-ratio", "nan"], "--stribeck-ratio must be finite and within [0, 10], got nan"),
        (["--stribeck-speed", "0"], "--stribeck-speed must be finite and within (0, 10] rad/s, got 0.0"),
        (["--handle-mass", "-1"], "--handle-mass must be finite and within [0, 20] kg, got -1.0"),
        (["--skin-offset", "0", "0", "0", "0", "0", "0.5", "0", "0"], "--skin-offset value 6 must be finite and"),
        (["--marker-hz", "0"], "--marker-hz must be finite and within (0, 5000] Hz, got 0.0"),
        (["--body-mass", "400"], "--body-mass must be within [20, 300] kg, got 400.0"),
        (["--tare", "--tare-swing", "0", "120", "0"], "--tare-swing value 2 must be finite and within [0, 90] deg"),
    ],
)
def test_simulator_value_errors_name_the_option_the_value_and_the_range(
    tmp_path: Path, values: list[str], expected: str, capsys
) -> None:
    out = tmp_path / "s"
    assert main(["simulate", "--out", str(out), "--duration", "2", "--seed", "3", *values]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"bsp simulate: error: {expected}" in err
    # The simulator's own field names (coulomb_nm, handle_mass_kg, ...) are not what the user typed.
    assert not re.search(r"[a-z]+_(nm|kg|rad|nms|m|n|deg|s|ratio|per_rad)\b", err)
    assert not out.exists()


def test_simulate_follows_a_bsp_plan_trajectory_for_the_plans_length(tmp_path: Path) -> None:
    plan = tmp_path / "plan.json"
    limits = ["--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100"]
    args = [*limits, "--wrist-range", "-5", "5", "--operating-points", "1", "--max-evaluations", "100"]
    assert main(["plan", *args, "--duration", "30", "--json", str(plan)]) == 0
    out = tmp_path / "planned"
    assert main(["simulate", "--out", str(out), "--trajectory", str(plan)]) == 0
    truth = json.loads((out / "truth.json").read_text())
    knots = json.loads(plan.read_text())["knots"]
    assert truth["trajectory"]["planned"] == knots and truth["simulation"]["duration_s"] == 30.0
    read = read_session(out)
    t_s = (read.session.wrench.t_ns - truth["simulation"]["start_ns"]) * 1e-9
    assert 29.9 < t_s[-1] < 30.0
    # The elbow marker follows the planned shoulder angle (markers on the joint centres).
    from bsp_ros.core.planning import PlannedTrajectory

    planned = PlannedTrajectory(knots["t_s"], knots["q_rad"], knots["qdot_rad_s"])
    shoulder, elbow = read.session.markers["shoulder"], read.session.markers["elbow"]
    q1 = np.arctan2(
        elbow.position_m[:, 2] - shoulder.position_m[:, 2], elbow.position_m[:, 1] - shoulder.position_m[:, 1]
    )
    want = planned.angles_rad((elbow.t_ns - truth["simulation"]["start_ns"]) * 1e-9)[:, 0]
    assert np.abs(q1 - want).max() < 0.01 and np.ptp(want) > 0.3


def test_speed_scale_divides_the_periods_and_inertia_is_on_by_default(tmp_path: Path) -> None:
    fast = _simulate(tmp_path / "fast", "--speed-scale", "4")
    slow = _simulate(tmp_path / "slow", "--no-inertia")
    assert fast["trajectory"]["shoulder"]["period_s"] == pytest.approx(22.0 / 4)
    assert slow["trajectory"]["shoulder"]["period_s"] == 22.0
    assert fast["simulation"]["inertia"] is True and slow["simulation"]["inertia"] is False
    assert fast["segments"]["forearm"]["inertia_com_kgm2"] > 0


def test_turning_sensor_timing_and_skin_options_reach_the_bag_and_the_truth(tmp_path: Path) -> None:
    truth = _simulate(
        tmp_path / "s",
        *("--sensor-turns", "--wrench-filter-delay-s", "0.02", "--wrench-filter", "moving-average"),
        *("--wrench-average", "--wrench-clock-offset-s", "0.01", "--skin-offset-mm", "5", "--seed", "8"),
    )
    sim = truth["simulation"]
    assert sim["sensor_turns_with_handle"] is True and sim["wrench_filter_kind"] == "moving_average"
    assert sim["wrench_delay_s"] == pytest.approx(0.02 + 0.005 + 0.01)
    assert sim["skin_offset_bound_m"] == 0.005 and np.abs(sim["skin_offset_m"]).max() <= 0.005
    topics = read_metadata(tmp_path / "s" / "metadata.yaml").topics
    assert "/tf_static" not in topics and topics["/tf"].message_count == topics["/ft_sensor/wrench"].message_count


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--speed-scale", "0"], "--speed-scale"),
        (["--speed-scale", "nan"], "--speed-scale"),
        (["--wrench-filter-delay-s", "-0.1"], "--wrench-filter-delay-s"),
        (["--wrench-clock-offset-s", "5"], "--wrench-clock-offset-s"),
        (["--skin-offset-mm", "-1"], "--skin-offset-mm"),
        (["--skin-offset", "0.01"], "--skin-offset-mm MM"),
        (["--trajectory", "/nonexistent/plan.json"], "/nonexistent/plan.json"),
        (["--tare", "--sensor-turns"], "--sensor-turns"),
        (["--trunk-tilt-deg", "95"], "--trunk-tilt-deg"),
        (["--trunk-tilt-deg", "nan"], "--trunk-tilt-deg"),
        (["--start-offset-s", "-1"], "--start-offset-s"),
        (["--tare", "--trunk-tilt-deg", "20"], "--trunk-tilt-deg"),
    ],
)
def test_bad_new_options_end_in_one_line_naming_the_option_and_exit_2(
    tmp_path: Path, args: list[str], needle: str, capsys
) -> None:
    assert main(["simulate", "--out", str(tmp_path / "s"), "--duration", "2", *args]) == 2
    err = capsys.readouterr().err
    assert needle in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "s").exists()


def test_help_shows_every_default(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    from bsp_ros.cli import build_parser

    sub = build_parser()._subparsers._group_actions[0].choices["simulate"]  # type: ignore[union-attr]
    for action in sub._actions:
        if action.help and action.dest != "help":
            assert "default" in " ".join(action.help.split()) or action.required, action.option_strings
    assert "(default: on)" in text and "--speed-scale X" in text
