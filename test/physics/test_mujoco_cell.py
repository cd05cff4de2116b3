"""The MuJoCo cell against bsp_ros's model (statics), pinocchio (dynamics) and `bsp identify` (a paper session)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from pinocchio_chain import planar_chain

pytest.importorskip("mujoco", reason="the physics-engine cell needs MuJoCo (pip install mujoco, the test extra)")

from mujoco_bag import record, write_bag
from mujoco_cell import CellOptions, draw_arm, paper_sine, run_engine

from bsp_ros.cli import main
from bsp_ros.core import model
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.planning import handle_poses_world, planned_trajectory_from_file, trajectory_from_points
from bsp_ros.core.simulation import (
    GRAVITY_M_S2,
    CellSimulator,
    MarkerSpec,
    MultiSineTrajectory,
    SessionTruth,
    SubjectTruth,
    TrajectorySpec,
    human_arm_cell,
)

STILL = TrajectorySpec((-43.3, 29.5, 0.2), (0.0, 0.0, 0.0), (10.0, 10.0, 10.0), (0.0, 0.0, 0.0))
# Fast sines (peak ~1 rad/s): inertial torques of several % of gravity.
FAST = TrajectorySpec((-40.0, 45.0, 5.0), (20.0, 15.0, 10.0), (2.0, 1.7, 1.5), (0.0, 1.0, 2.0))


def _static_torques(truth: dict, q: np.ndarray) -> np.ndarray:
    """tau_G + tau_p from truth.json alone (static moments, perpendicular moments, springs): (N, 3) Nm."""
    names = ("upper_arm", "forearm", "hand")
    beta = np.array([truth["segments"][s]["static_moment_kgm"] for s in names])
    perpendicular = np.array([truth["segments"][s]["perpendicular_moment_kgm"] for s in names])
    joints = [truth["joints"][j] for j in ("shoulder", "elbow", "wrist")]
    stiffness = np.array([j["stiffness_nm_per_rad"] for j in joints])
    offset = np.array([j["offset_nm"] for j in joints])
    phi = model.absolute_angles_rad(q)
    upper = np.triu(np.ones((3, 3)))
    tau_g = np.einsum("nij,j->ni", model.gravity_regressor(q), beta)
    # A COM off the axis (+ 90 deg counter-clockwise of it) adds -g m d sin(phi_j) to every joint i <= j.
    tau_g -= GRAVITY_M_S2 * (np.sin(phi) * perpendicular) @ upper.T
    return tau_g + stiffness * q + offset


@pytest.mark.parametrize("off_axis", [False, True])
def test_a_still_arm_s_engine_wrench_balances_the_truth_s_gravity_and_springs(off_axis: bool) -> None:
    arm = dataclasses.replace(draw_arm(4, springs=True, off_axis=off_axis), frictionloss_nm=(0.0, 0.0, 0.0))
    options = CellOptions(trajectory=STILL, duration_s=0.2, lead_in_s=1.0)
    cell = record(arm, options)
    run = cell.run
    measured = model.contact_torques_nm(run.q_rad, arm.lengths_m, run.wrench_world())  # -J^T F_end
    expected = _static_torques(cell.truth, run.q_rad)
    assert np.abs(measured).min() > 0.05  # every joint carries load
    assert np.abs(measured - expected).max() < 1e-9
    assert run.out_of_plane() < 1e-9
    assert run.weld_drift_m.max() < 2e-5  # the strap holds the hand at the handle


def test_the_engine_s_joint_torques_minus_gravity_match_pinocchio_s_rnea_on_a_fast_path() -> None:
    pin = pytest.importorskip("pinocchio", reason="pinocchio (pip install pin) builds the independent dynamics")
    arm = dataclasses.replace(draw_arm(5, off_axis=True), frictionloss_nm=(0.0, 0.0, 0.0))
    options = CellOptions(trajectory=FAST, duration_s=3.0, lead_in_s=0.5)
    run = run_engine(arm, options)

    chain = planar_chain(
        pin, arm.lengths_m, arm.masses_kg, arm.com_along_m, arm.com_normal_m, arm.inertia_com_kgm2, options.shoulder_m
    )
    data = chain.createData()

    measured = model.contact_torques_nm(run.q_rad, arm.lengths_m, run.wrench_world())
    rows = range(0, run.t_s.size, 7)
    inertial_pin = np.array(
        [
            pin.rnea(chain, data, run.q_rad[k], run.qdot_rad_s[k], run.qddot_rad_s2[k])
            - pin.computeGeneralizedGravity(chain, data, run.q_rad[k])
            for k in rows
        ]
    )
    inertial_engine = np.array([measured[k] - pin.computeGeneralizedGravity(chain, data, run.q_rad[k]) for k in rows])
    gravity = np.array([pin.computeGeneralizedGravity(chain, data, run.q_rad[k]) for k in rows])
    # The path is really dynamic: inertial torques reach over 5 % of each joint's gravity torque.
    assert (np.abs(inertial_pin).max(axis=0) > 0.05 * np.abs(gravity).max(axis=0)).all()
    assert np.abs(inertial_engine - inertial_pin).max() < 1e-8


def test_the_engine_s_dry_friction_is_the_frictionloss_of_the_truth_at_the_paper_speed() -> None:
    arm = draw_arm(6)
    cell = record(arm, CellOptions(trajectory=paper_sine(0.03), duration_s=25.0))
    run = cell.run
    gravity, inertial = run.torque_split_nm(every=5)
    rows = slice(0, None, 5)
    passive = model.contact_torques_nm(run.q_rad[rows], arm.lengths_m, run.wrench_world()[rows]) - gravity - inertial
    velocity = run.qdot_rad_s[rows]
    for j, joint in enumerate(("shoulder", "elbow", "wrist")):
        moving = np.abs(velocity[:, j]) > 3e-3  # above MuJoCo's (tightened) friction regularisation
        assert moving.mean() > 0.5
        level = passive[moving, j] * np.sign(velocity[moving, j])
        assert np.abs(level - cell.truth["joints"][joint]["coulomb_nm"]).max() < 1e-6
    # NOTES 7: at 0.03 rad/s inertial torques are a few 1e-4 of gravity.
    assert all(1e-5 < r < 2e-3 for r in cell.truth["simulation"]["inertial_to_gravity"]["rms"].values())


def test_a_turning_sensor_s_wrench_and_tf_give_back_the_engine_s_world_wrench() -> None:
    arm = draw_arm(7)
    options = CellOptions(
        trajectory=paper_sine(0.12),
        duration_s=5.0,
        sensor="turning",
        wrench_hz=100.0,
        force_noise_n=0.0,
        torque_noise_nm=0.0,
    )
    cell = record(arm, options)
    rotations = np.stack([s.rotation_parent_from_child() for s in cell.tf_samples])
    force = np.einsum("nij,nj->ni", rotations, cell.session.wrench.force_n)
    torque = np.einsum("nij,nj->ni", rotations, cell.session.wrench.torque_nm)
    engine = cell.run.wrench_world()[::10]
    assert len(cell.tf_samples) == cell.session.wrench.t_ns.size == engine.shape[0]
    assert [s.t_ns for s in cell.tf_samples] == cell.session.wrench.t_ns.tolist()
    assert cell.truth["simulation"]["sensor_angle_error_max_deg"] < 0.05  # the weld's lag behind the handle
    # The pitch the robot knows differs from the hand's by the weld's lag only: 1e-3 of the load.
    load = np.abs(engine).max()
    assert np.abs(np.column_stack((force[:, 1:], torque[:, :1])) - engine).max() < 1e-3 * load
    assert np.ptp(np.degrees(np.arctan2(rotations[:, 2, 1], rotations[:, 1, 1]))) > 5.0  # it really turns


def test_a_paper_session_from_the_engine_is_identified_near_the_truth(tmp_path) -> None:
    arm = draw_arm(1)
    options = CellOptions(trajectory=paper_sine(0.03), duration_s=40.0, wrench_hz=250.0, seed=1)
    bag = write_bag(tmp_path / "engine_session", record(arm, options))
    truth = json.loads((bag / "truth.json").read_text())
    assert SessionTruth.from_dict(truth).static_moments_kgm == pytest.approx(
        model.static_moments_kgm(arm.lengths_m, arm.masses_kg, arm.com_along_m)
    )
    code = main(["identify", str(bag), "--json", str(tmp_path / "e.json"), "--format", "none"])
    estimate = json.loads((tmp_path / "e.json").read_text())
    assert code in (0, 1)  # valid or not: measured by bench/physics_engine.py, not asserted here
    for segment, quantities in estimate["segments"].items():
        q, true = quantities["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert q["source"] == "data"
        assert abs(q["value"] - true) < 4.0 * q["std"], segment
        assert abs(q["value"] - true) < 0.002 * true, segment
        assert quantities["length_m"]["value"] == pytest.approx(truth["segments"][segment]["length_m"], abs=2e-4)
    for joint, quantities in estimate["joints"].items():
        assert quantities["coulomb_nm"]["value"] == pytest.approx(truth["joints"][joint]["coulomb_nm"], rel=0.02)


def test_two_sines_per_joint_in_the_engine_identify_its_inertias(tmp_path) -> None:
    """A faster protocol, two sines per joint within 0.15 rad/s (periods 2-11 s), on the engine's arm (its own
    inertias, friction and sensor), tared (--zero-sd-n 0): the upper arm's and forearm's grouped inertias come
    from the data, within 3 std and 5 % (measured 0.1-0.8 % over seeds 1-3)."""
    motion = MultiSineTrajectory.within_speed(
        (-43.3, 45.0, 0.2), ((2.1, 7.9), (2.7, 9.3), (3.3, 11.1)), 0.15, ((0.0, 1.3), (1.0, 2.9), (2.0, 0.4))
    )
    arm = draw_arm(3)
    bag = write_bag(
        tmp_path / "fast", record(arm, CellOptions(trajectory=motion, duration_s=60.0, wrench_hz=250.0, seed=3))
    )
    out = tmp_path / "e.json"
    code = main(["identify", str(bag), "--json", str(out), "--format", "none", "--zero-sd-n", "0", "--zero-sd-nm", "0"])
    estimate, truth = json.loads(out.read_text()), json.loads((bag / "truth.json").read_text())
    assert code == 0, estimate["quality"]["message"]
    for segment in ("upper_arm", "forearm"):
        q, true = (
            estimate["segments"][segment]["grouped_inertia_kgm2"],
            truth["segments"][segment]["grouped_inertia_kgm2"],
        )
        assert q["source"] == "data", (segment, q)
        assert abs(q["value"] - true) < min(3.0 * q["std"], 0.05 * true), (segment, q, true)
        assert q["std"] < 0.1 * true, (segment, q)  # from the data: the prior alone is 15 %
    for segment, quantities in estimate["segments"].items():
        q, true = quantities["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3.0 * q["std"], segment


def test_springs_the_fixed_model_does_not_fit_are_taken_up_by_the_elastic_family(tmp_path) -> None:
    """A planned session of the engine's arm with joint springs (seed 303, 1 kHz): the default Coulomb model leaves
    a residual at the wrist far above the sensor noise, so its elastic check never runs; given explicitly it is
    invalid and its static moments are off. By default `bsp identify` then fits the elastic family the data choose
    (--passive auto), says so, and is valid within 3 std of the engine's truth."""
    plan = tmp_path / "plan.json"
    assert main(["plan", "--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100",
                 "--wrist-range", "-20", "20", "--duration", "120", "--json", str(plan)]) in (0, 1)  # fmt: skip
    options = CellOptions(trajectory=planned_trajectory_from_file(plan), duration_s=120.0, wrench_hz=1000.0, seed=303)
    bag = write_bag(tmp_path / "springs", record(draw_arm(303, springs=True), options))
    truth = json.loads((bag / "truth.json").read_text())

    def identify(*extra: str) -> tuple[int, dict]:
        out = tmp_path / f"e{len(extra)}.json"
        code = main(["identify", str(bag), "--json", str(out), "--format", "none", *extra])
        return code, json.loads(out.read_text())

    def z(estimate: dict, segment: str) -> float:
        q = estimate["segments"][segment]["static_moment_kgm"]
        return abs(q["value"] - truth["segments"][segment]["static_moment_kgm"]) / q["std"]

    code, fixed = identify("--passive", "coulomb")
    misfits = [f for f in findings_of(fixed["quality"]) if f.code is FindingCode.MODEL_MISFIT]
    assert code == 1 and "wrist" in [f.where for f in misfits]
    assert max(z(fixed, s) for s in fixed["segments"]) > 3.0  # the fixed model is wrong here: right to refuse it
    code, chosen = identify()
    assert code == 0, chosen["quality"]["message"]
    (family,) = [f for f in findings_of(chosen["quality"]) if f.code is FindingCode.ELASTIC_FAMILY_CHOSEN]
    assert family.values["model"] == "coulomb" and "wrist" in family.values["joints"]
    assert chosen["quality"]["warnings"][0] == family.text
    assert chosen["diagnostics"]["passive_model"] != "coulomb"
    assert max(z(chosen, s) for s in chosen["segments"]) < 3.0


def test_the_engine_follows_a_planned_trajectory_and_its_handle_is_the_planner_s_handle_pose() -> None:
    centres = np.radians([[-50.0, 40.0, -5.0], [-35.0, 60.0, 5.0]])
    planned = trajectory_from_points(centres, np.radians([5.0, 5.0, 3.0]), 25.0, 0.1)
    arm = draw_arm(8)
    options = CellOptions(trajectory=planned, duration_s=25.0, lead_in_s=0.2)
    run = run_engine(arm, options)
    handle = handle_poses_world(run.q_command_rad, arm.lengths_m, options.shoulder_m[1:])
    contact = run.markers_m[:, 3]  # the hand marker site sits at the contact point (no skin offset)
    assert np.abs(contact[:, 1:] - handle[:, :2]).max() < 5e-4  # the hand follows the handle (weld lag only)
    assert np.abs(run.q_rad - run.q_command_rad).max() < 1e-3
    assert np.ptp(run.q_rad[:, 1]) > np.radians(20.0)  # it visits both operating points
    assert 0.05 < np.abs(run.qdot_rad_s).max() < 0.1


class _Replay:
    """A JointTrajectory that replays the engine's own joint angles (for bsp_ros's simulator)."""

    def __init__(self, t_s: np.ndarray, q_rad: np.ndarray) -> None:
        self._t, self._q = t_s, q_rad

    n_joints = 3
    peak_speed_rad_s = (0.0, 0.0, 0.0)

    def angles_rad(self, t_s) -> np.ndarray:
        return np.column_stack([np.interp(t_s, self._t, self._q[:, j]) for j in range(3)])

    def velocities_rad_s(self, t_s) -> np.ndarray:
        return np.zeros((np.size(t_s), 3))


def test_skin_marker_sites_sit_where_bsp_ros_puts_skin_markers_for_the_same_angles() -> None:
    offsets = ((0.01, 0.02), (-0.015, 0.01), (0.005, -0.012), (0.02, 0.015))
    arm = draw_arm(9)
    options = CellOptions(trajectory=paper_sine(0.12), duration_s=2.0, skin_offset_m=offsets, lead_in_s=0.1)
    run = run_engine(arm, options)
    spec = human_arm_cell(
        subject=SubjectTruth(arm.lengths_m, arm.masses_kg, arm.com_along_m),
        trajectory=_Replay(run.t_s, run.q_rad),
        markers=MarkerSpec(shoulder_m=options.shoulder_m, skin_offset_m=offsets, noise_m=0.0),
        duration_s=2.0,
    )
    expected = CellSimulator(spec).marker_positions_m(run.t_s)
    for k, name in enumerate(("shoulder", "elbow", "wrist", "hand")):
        assert np.abs(run.markers_m[:, k] - expected[name]).max() < 1e-12, name


def test_two_trunk_postures_in_the_engine_are_identified_together(tmp_path) -> None:
    # Springs about the trunk, the paper's sine at 0.03 rad/s: upright, then with the trunk turned by 25 deg and the
    # robot moving the arm through the same angles relative to it (MuJoCo's own dynamics, sensor and markers).
    arm = draw_arm(2, springs=True)
    bags = []
    for k, tilt_deg in enumerate((0.0, 25.0)):
        options = CellOptions(
            trajectory=paper_sine(0.03),
            duration_s=40.0,
            wrench_hz=250.0,
            seed=3 + k,
            trunk_tilt_rad=np.radians(tilt_deg),
            start_ns=1_700_000_000_000_000_000 + k * 300_000_000_000,
        )
        bags.append(write_bag(tmp_path / f"posture_{k}", record(arm, options)))
    truth = json.loads((bags[0] / "truth.json").read_text())
    model_args = ["--passive", "coulomb+offset+stiffness", "--format", "none"]
    main(["identify", str(bags[0]), "--json", str(tmp_path / "one.json"), *model_args])
    code = main(
        ["identify", *map(str, bags), "--trunk-tilt-deg", "0", "25", "--json", str(tmp_path / "two.json"), *model_args]
    )
    one, two = (json.loads((tmp_path / f"{n}.json").read_text()) for n in ("one", "two"))
    assert code == 0, two["quality"]["message"]
    for segment in ("upper_arm", "forearm", "hand"):
        q, true = two["segments"][segment]["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3.0 * q["std"], (segment, q, true)
    std = [d["segments"]["upper_arm"]["static_moment_kgm"]["std"] for d in (one, two)]
    assert std[1] < std[0] / 2, std
    stiffness = two["joints"]["shoulder"]["stiffness_nm_per_rad"]
    true_stiffness = truth["joints"]["shoulder"]["stiffness_nm_per_rad"]
    assert abs(stiffness["value"] - true_stiffness) < 3.0 * stiffness["std"], (stiffness, true_stiffness)


def test_the_live_spike_gate_passes_the_engine_s_wrench_and_catches_the_spikes_added_to_it() -> None:
    # The recursive mode's Hampel gate (live/online/spike_gate.py) on physics it was not tuned on: the engine's
    # friction steps, springs and inertial torques at 0.12 rad/s and 1 kHz, with the sensor's noise.
    from bsp_ros.live.online.spike_gate import SpikeGate

    run = run_engine(draw_arm(3, springs=True), CellOptions(trajectory=paper_sine(0.12), duration_s=20.0, seed=3))
    rng = np.random.default_rng(3)
    wrench = run.wrench_world() + rng.normal(0.0, [0.05, 0.05, 0.005], (run.t_s.size, 3))
    at = rng.choice(np.arange(100, run.t_s.size - 100), 20, replace=False)
    wrench[at, rng.integers(0, 2, at.size)] += rng.choice([-1.0, 1.0], at.size) * rng.uniform(5.0, 1000.0, at.size)
    gate: SpikeGate[int] = SpikeGate()
    flagged = []
    for i, sample in enumerate(wrench.tolist()):
        judged = gate.push(sample, i)
        if judged is not None and judged[1]:
            flagged.append(judged[0])
    assert sorted(flagged) == sorted(at.tolist())
