"""`bsp simulate` then `bsp identify` end to end on bags written into tmp_path."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from bsp_ros.cli import main
from bsp_ros.core.findings import FindingCode, findings_of


@pytest.fixture(scope="module")
def human_bag(tmp_path_factory) -> Path:
    bag = tmp_path_factory.mktemp("bags") / "session_a"
    # Quasi-static (--no-inertia), the model today's estimator fits: with inertia (bsp simulate's default) it
    # flags the inertial torques, which correlate with the angle, as an elastic passive moment.
    args = ["--subject", "human", "--duration", "120", "--seed", "21", "--no-inertia"]
    assert main(["simulate", "--out", str(bag), *args]) == 0
    return bag


def _identify(bag: Path, out: Path, *extra: str) -> tuple[int, dict]:
    code = main(["identify", str(bag), "--json", str(out), "--format", "none", *extra])
    return code, json.loads(out.read_text()) if out.exists() else {}


def test_identified_parameters_match_the_truth_within_the_core_tolerances(human_bag, tmp_path) -> None:
    code, estimate = _identify(human_bag, tmp_path / "e.json", "--body-mass", "75", "--height", "1.78")
    truth = json.loads((human_bag / "truth.json").read_text())
    assert code == 0
    assert estimate["schema"] == "bsp_ros/core/estimate/1"
    assert estimate["quality"]["valid"]
    for segment, quantities in estimate["segments"].items():
        true = truth["segments"][segment]
        assert quantities["static_moment_kgm"]["value"] == pytest.approx(true["static_moment_kgm"], rel=0.005)
        assert quantities["length_m"]["value"] == pytest.approx(true["length_m"], abs=1e-3)
        for key in ("static_moment_kgm", "mass_kg", "com_m", "first_moment_kgm", "length_m"):
            q = quantities[key]
            # The contract's three keys; the quantities the identification decided add their uncertainty budget.
            assert set(q) == {"value", "std", "source"} | ({"budget"} if key == "static_moment_kgm" else set())
            assert abs(q["value"] - true[key]) < 3 * q["std"], (segment, key)
    for joint, quantities in estimate["joints"].items():
        assert quantities["coulomb_nm"]["value"] == pytest.approx(truth["joints"][joint]["coulomb_nm"], rel=0.10)
    assert estimate["session"]["source"] == human_bag.name
    assert estimate["bag"]["crc_errors"] == 0 and estimate["bag"]["lost_messages"] == 0


def test_the_paper_method_runs_from_the_cli(human_bag, tmp_path) -> None:
    code, estimate = _identify(human_bag, tmp_path / "p.json", "--method", "paper")
    assert code == 0
    assert estimate["method"] == "paper"
    assert FindingCode.PAPER_SPLIT_ARBITRARY in [f.code for f in findings_of(estimate["quality"])]


def test_a_missing_bag_has_its_own_exit_code(tmp_path) -> None:
    assert main(["identify", str(tmp_path / "nope")]) == 10


def test_a_directory_that_is_not_a_bag_has_its_own_exit_code(tmp_path) -> None:
    (tmp_path / "notes.txt").write_text("not a bag")
    assert main(["identify", str(tmp_path)]) == 11


def test_a_missing_topic_names_it(human_bag, tmp_path, capsys) -> None:
    code = main(["identify", str(human_bag), "--marker-topic", "elbow=/vicon/elbow", "--format", "none"])
    assert code == 13
    assert "/vicon/elbow" in capsys.readouterr().err


def test_a_truncated_bag_is_identified_from_its_intact_part_and_says_so(human_bag, tmp_path) -> None:
    damaged = tmp_path / "damaged"
    shutil.copytree(human_bag, damaged)
    mcap = next(damaged.glob("*.mcap"))
    data = mcap.read_bytes()
    mcap.write_bytes(data[: int(len(data) * 0.7)])
    code, estimate = _identify(damaged, tmp_path / "d.json")
    assert code == 0
    assert estimate["bag"]["truncated"]
    assert estimate["bag"]["lost_messages"] > 0
    (damage,) = [f for f in findings_of(estimate["quality"]) if f.code is FindingCode.BAG_DAMAGED]
    assert estimate["quality"]["warnings"][0] == damage.text  # the first note a reader sees


@pytest.mark.parametrize(("option", "value"), [("--body-mass", "-70"), ("--height", "nan"), ("--passive", "foo")])
def test_silly_subject_data_is_refused_naming_the_option_and_value(human_bag, capsys, option, value) -> None:
    try:
        code = main(["identify", str(human_bag), option, value])
    except SystemExit as stop:  # argparse's own refusal of a value its type rejects
        code = stop.code
    err = capsys.readouterr().err.splitlines()[-1]
    assert code == 2
    assert err.startswith("bsp identify: error: ") and option in err and value in err


def _write_modified(tmp_path: Path, name: str, change) -> Path:
    import dataclasses

    from bsp_ros.bag import write_session_bag
    from bsp_ros.core import simulation as sim

    simulated = sim.simulate_cell(sim.human_arm_cell(seed=8, duration_s=60.0))
    wrench = change(simulated.session.wrench)
    session = dataclasses.replace(simulated.session, wrench=wrench)
    return write_session_bag(tmp_path / name, session, simulated.truth.to_dict())


def test_a_bag_with_nan_wrenches_is_identified_without_them_and_says_how_many(tmp_path) -> None:
    import dataclasses

    def with_nan(wrench):
        force = wrench.force_n.copy()
        force[1000:1050] = float("nan")
        return dataclasses.replace(wrench, force_n=force)

    bag = _write_modified(tmp_path, "nan_bag", with_nan)
    code, estimate = _identify(bag, tmp_path / "n.json")
    assert code == 0
    notes = [f.values["detail"] for f in findings_of(estimate["quality"]) if f.code is FindingCode.DATA_NOTE]
    assert any("50 samples with NaN/Inf removed" in detail for detail in notes), notes


def test_a_bag_whose_clock_jumps_back_is_refused_with_a_clear_message(tmp_path, capsys) -> None:
    import dataclasses

    def jumped(wrench):
        t_ns = wrench.t_ns.copy()
        t_ns[3000:] -= 20_000_000_000
        return dataclasses.replace(wrench, t_ns=t_ns)

    bag = _write_modified(tmp_path, "jump_bag", jumped)
    assert main(["identify", str(bag), "--format", "none"]) == 3
    assert "jump back by" in capsys.readouterr().err


def test_a_rotated_sensor_bag_without_tf_static_is_invalid_naming_the_transform(human_bag, tmp_path, capsys) -> None:
    from bag_surgery import rewrite_without_crcs

    lost = tmp_path / "lost_tf"
    shutil.copytree(human_bag, lost)
    rewrite_without_crcs(lost, drop_topics=("/tf_static",))
    code, estimate = _identify(lost, tmp_path / "l.json")
    assert code == 1
    assert not estimate["quality"]["valid"]
    assumed = findings_of(estimate["quality"])[0]
    assert assumed.code is FindingCode.ROTATION_ASSUMED and assumed.values["frame"] == "ft_sensor"  # the misfit's cause
    # The verdict a user reads: the cause in plain words and what to do, then the estimator's reasons.
    first, *reasons = capsys.readouterr().err.splitlines()
    assert first == (
        "bsp identify: estimate INVALID: the force sensor's orientation was not recorded; record the sensor's "
        "transform with the session, or give its mounting with --cell FILE"
    )
    assert reasons[0].startswith("  because: missing transform world -> ft_sensor") and len(first) < 200


def test_a_bit_flip_in_a_bag_without_crcs_is_counted_and_harmless(human_bag, tmp_path) -> None:
    from bag_surgery import flip_bit_of_value, rewrite_without_crcs

    plain = tmp_path / "plain"
    shutil.copytree(human_bag, plain)
    rewrite_without_crcs(plain)
    _, clean = _identify(plain, tmp_path / "c.json")
    from bsp_ros.bag import read_session

    y = float(read_session(plain).session.markers["hand"].position_m[2000, 1])
    flip_bit_of_value(plain, "/mocap/hand", 2000, y, 52)
    code, estimate = _identify(plain, tmp_path / "f.json")
    assert code == 0
    assert estimate["bag"]["implausible_samples_removed"] == {"marker_hand": 1}
    for segment, quantities in clean["segments"].items():
        q = quantities["static_moment_kgm"]
        assert abs(estimate["segments"][segment]["static_moment_kgm"]["value"] - q["value"]) < 3 * q["std"]
    for joint, quantities in clean["joints"].items():
        q = quantities["coulomb_nm"]
        assert abs(estimate["joints"][joint]["coulomb_nm"]["value"] - q["value"]) < 3 * q["std"]
