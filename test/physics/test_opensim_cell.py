"""OpenSim's arm26 as an independent cell: its statics against our model, two-joint coupling, `bsp identify` on it."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

if importlib.util.find_spec("opensim") is None:
    pytest.skip("opensim has wheels for CPython 3.11 only (pip install opensim)", allow_module_level=True)

import opensim_cell as cell

from bsp_ros.cli import main as bsp_main
from bsp_ros.core.model import contact_torques_nm, gravity_regressor
from bsp_ros.core.simulation import SessionTruth


def _angles_and_lengths(run: cell.CellRun) -> tuple[np.ndarray, np.ndarray]:
    """docs/contract.md angles and in-plane lengths of the noise-free joint centres (x projected away)."""
    steps = np.diff(run.points_m[:, :, 1:], axis=1)  # (K, 2 segments, [y, z])
    phi = np.arctan2(steps[..., 1], steps[..., 0])
    return np.column_stack((phi[:, 0], phi[:, 1] - phi[:, 0])), np.linalg.norm(steps, axis=2).mean(axis=0)


def _model_gravity_nm(truth: dict, q_rad: np.ndarray) -> np.ndarray:
    """Our planar model's gravity torques from the truth's grouped static and perpendicular moments."""
    segments = [truth["segments"][name] for name in cell.SEGMENTS]
    beta = np.array([s["static_moment_kgm"] for s in segments])
    gamma = np.array([s["perpendicular_moment_kgm"] for s in segments])
    # A COM offset normal to the axis adds -g gamma sin(phi) = g gamma cos(phi + 90 deg).
    return gravity_regressor(q_rad) @ beta + gravity_regressor(q_rad + np.array([math.pi / 2, 0.0])) @ gamma


def _curve_z(curve: dict, true_curve: dict) -> np.ndarray:
    """|estimate - truth| / std at the estimated passive curve's points inside the truth curve's range."""
    angle = np.asarray(curve["angle_deg"])
    inside = (angle >= min(true_curve["angle_deg"])) & (angle <= max(true_curve["angle_deg"]))
    reference = np.interp(angle[inside], true_curve["angle_deg"], true_curve["moment_nm"])
    return np.abs(np.asarray(curve["moment_nm"])[inside] - reference) / np.asarray(curve["std_nm"])[inside]


def test_planar_arm26_statics_match_our_model() -> None:
    arm = cell.Arm26(cell.CellOptions(muscles=False, planar=True, inertia=False))
    run = cell.run_cell(arm, cell.PAPER_PROTOCOL, cell.SessionOptions(duration_s=25.0, physics_hz=2.0))
    q, lengths = _angles_and_lengths(run)
    model = _model_gravity_nm(run.truth, q)
    scale = np.abs(model).max(axis=0)
    # OpenSim's own inverse dynamics, and the torques of the wrench the cell writes (-J^T F with our Jacobian).
    assert np.abs(run.torque_nm - model).max(axis=0) / scale == pytest.approx([0, 0], abs=1e-5)
    assert np.abs(contact_torques_nm(q, lengths, run.wrench_world) - model).max(axis=0) / scale == pytest.approx(
        [0, 0], abs=1e-5
    )
    assert np.abs(q - run.q_rad).max() < 1e-9  # the prescribed angles are the markers' angles


def test_oblique_arm26_departs_from_the_plane_by_under_one_percent() -> None:
    arm = cell.Arm26(cell.CellOptions(muscles=False, inertia=False))
    assert arm.axis_tilt_deg == pytest.approx([3.38, 3.52], abs=0.01)  # arm26's axes, not ours
    run = cell.run_cell(arm, cell.PAPER_PROTOCOL, cell.SessionOptions(duration_s=25.0, physics_hz=2.0))
    q, lengths = _angles_and_lengths(run)
    model = _model_gravity_nm(run.truth, q)
    error = np.abs(contact_torques_nm(q, lengths, run.wrench_world) - model).max(axis=0) / np.abs(model).max(axis=0)
    # Measured 0.13 % (shoulder) and 0.77 % (elbow): the planar model's error on this arm, not zero.
    assert 1e-4 < error.max() < 0.01
    assert np.ptp(run.points_m[:, 2, 0]) > 1e-3  # the hand leaves the plane by millimetres
    # Without muscles the truth has no passive moment (the benchmark once scored it against the muscles' curve).
    for joint in cell.JOINTS:
        assert np.abs(run.truth["joints"][joint]["passive_curve"]["moment_nm"]).max() == 0.0
    assert np.abs(run.passive_nm).max() == 0.0


def test_sensor_stream_is_the_world_wrench_in_sensor_axes() -> None:
    arm = cell.Arm26(cell.CellOptions(force_scale=0.2))
    options = cell.SessionOptions(duration_s=12.0, force_noise_n=0.0, torque_noise_nm=0.0, wrench_jitter_s=0.0)
    run = cell.run_cell(arm, cell.PAPER_PROTOCOL, options)
    w = run.session.wrench
    rotation = run.session.rotation_world_from_sensor
    force_world, torque_world = w.force_n @ rotation.T, w.torque_nm @ rotation.T
    assert np.abs(force_world[:, 0]).max() < 1e-12 and np.abs(torque_world).max() < 1e-12  # F_x = 0, bearing
    # The spline through the 20 Hz OpenSim evaluations against OpenSim itself at stamps between them.
    picks = np.array([37, 311, 777, 1013])
    t_s = (w.t_ns[picks] - options.start_ns) * 1e-9
    traj = cell.PAPER_PROTOCOL
    torque, _, jac = arm.dynamics(
        traj.angles_rad(t_s), traj.velocities_rad_s(t_s), cell.accelerations_rad_s2(traj, t_s)
    )
    direct = cell.wrench_from_torques(torque, jac)
    assert np.abs(force_world[picks, 1:] - direct[:, :2]).max() < 1e-4  # N; the sensor noise is 0.05 N


def test_passive_share_scales_with_muscle_force() -> None:
    scale = cell.force_scale_for_share(0.1)
    assert 0.05 < scale < 0.2  # arm26 relaxed: ~0.8-1.2 x gravity
    assert cell.passive_share(cell.Arm26(cell.CellOptions(force_scale=scale))) == pytest.approx(0.1, rel=1e-6)


def test_relaxed_muscles_couple_the_joints_and_store_energy() -> None:
    arm = cell.Arm26()
    q0 = np.radians([-36.6, 35.8])
    step = math.radians(2.0)
    around = q0 + step * np.array([[-1, 0], [1, 0], [0, -1], [0, 1]])
    tau = arm.passive_moment_nm(around)
    d_elbow_d_shoulder = (tau[1, 1] - tau[0, 1]) / (2 * step)
    d_shoulder_d_elbow = (tau[3, 0] - tau[2, 0]) / (2 * step)
    # TRIlong and BIClong cross both joints: the elbow's passive moment moves with the shoulder angle...
    assert abs(d_elbow_d_shoulder) * step * 5 > 0.05 * abs(tau[:, 1]).mean()  # > 5 % over +-10 deg
    # ...and elastic muscles (force a function of length alone) derive from a potential: a symmetric stiffness.
    assert d_elbow_d_shoulder == pytest.approx(d_shoulder_d_elbow, rel=0.02)


def test_wrong_wrap_region_is_refused() -> None:
    arm = cell.Arm26()
    with pytest.raises(ValueError, match="BIClong"):
        arm.passive_moment_nm([[math.radians(29.65) + arm.offsets_rad[0], 0.6]])


@pytest.fixture(scope="module")
def muscle_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """60 s of the paper's protocol, passive moments 10 % of gravity, the cell's noise (seeded), as a bag."""
    arm = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(0.1)))
    run = cell.run_cell(arm, cell.PAPER_PROTOCOL, cell.SessionOptions(duration_s=60.0, seed=3))
    return cell.write_bag(tmp_path_factory.mktemp("arm26") / "session", run, seed=3)


@pytest.mark.parametrize(
    "passive",
    [
        None,
        pytest.param(
            "coulomb+offset+stiffness",
            marks=pytest.mark.xfail(
                strict=True,
                reason="known regression of the dynamic model: the forearm's free perpendicular moment takes up the "
                "two-joint muscles' shoulder dependence (invalid, |z| 6.7, where the quasi-static model was within 3 "
                "std); needs the coupled passive terms of the passive-moments issue",
            ),
        ),
    ],
)
def test_bsp_identify_reads_the_arm26_bag(muscle_bag: Path, tmp_path: Path, passive: str | None) -> None:
    out = tmp_path / "estimate.json"
    argv = ["identify", str(muscle_bag), "--json", str(out), "--format", "none"]
    code = bsp_main(argv + ([] if passive is None else ["--passive", passive]))
    truth = json.loads((muscle_bag / "truth.json").read_text())
    assert SessionTruth.from_dict(truth).static_moments_kgm == pytest.approx(
        [truth["segments"][s]["static_moment_kgm"] for s in cell.SEGMENTS]
    )
    estimate = json.loads(out.read_text())
    assert code == (0 if estimate["quality"]["valid"] else 1)
    for name in cell.SEGMENTS:
        low, high = truth["segments"][name]["length_range_m"]
        assert low - 1e-3 < estimate["segments"][name]["length_m"]["value"] < high + 1e-3
        moment = estimate["segments"][name]["static_moment_kgm"]
        z = abs(moment["value"] - truth["segments"][name]["static_moment_kgm"]) / moment["std"]
        # What holds today (measured, bench/musculoskeletal.py): a valid estimate is within 3 std, and the
        # elastic model is within 3 std here; Coulomb alone is biased by the muscles (|z| ~15-20) but says invalid.
        assert not estimate["quality"]["valid"] or z < 3.0
        if passive is not None:
            assert z < 3.0


def test_a_passive_curve_the_posture_cannot_identify_carries_that_in_its_std(tmp_path: Path) -> None:
    """Full-strength muscles (passive moments 1.5x gravity) on the paper's one-posture protocol, --passive auto:
    the data choose no elastic terms, so the shoulder's curve is 0 by that model, and at one posture a curve's
    level is confounded with gravity. Its std must say so: before, it held only the candidates' differences
    (0 +- 1.7 Nm against a true 5.3 Nm, |z| 3.7, marked valid)."""
    arm = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(1.5)))
    run = cell.run_cell(arm, cell.PAPER_PROTOCOL, cell.SessionOptions(duration_s=60.0, seed=0))
    bag = cell.write_bag(tmp_path / "session", run, seed=0)
    out = tmp_path / "estimate.json"
    bsp_main(["identify", str(bag), "--json", str(out), "--format", "none", "--passive", "auto"])
    estimate, truth = json.loads(out.read_text()), json.loads((bag / "truth.json").read_text())
    for joint in cell.JOINTS:
        curve = estimate["joints"][joint].get("passive_curve")
        if not estimate["quality"]["valid"] or curve is None:
            continue
        z = _curve_z(curve, truth["joints"][joint]["passive_curve"])
        assert z.max() < 3.0, (joint, z.round(2).tolist())


def test_a_tilted_trunk_turns_only_gravity() -> None:
    tilt = math.radians(25.0)
    upright = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(0.1)))
    tilted = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(0.1), trunk_tilt_rad=tilt))
    q = cell.planned_protocol(upright, 60.0, optimise=False).angles_rad(np.linspace(0.0, 60.0, 5))
    q_tilted = q + np.array([tilt, 0.0])
    assert np.allclose(upright.coordinates_rad(q), tilted.coordinates_rad(q_tilted))
    np.testing.assert_allclose(upright.passive_moment_nm(q), tilted.passive_moment_nm(q_tilted), atol=1e-9)
    # Gravity in our model on the world angles: the truth's static moments hold in both postures.
    truth = cell.run_cell(upright, cell.PAPER_PROTOCOL, cell.SessionOptions(duration_s=5.0, physics_hz=2.0)).truth
    for arm, angles in ((upright, q), (tilted, q_tilted)):
        model = _model_gravity_nm(truth, angles)
        assert np.abs(arm.gravity_torque_nm(angles) - model).max() < 0.01 * np.abs(model).max()
    assert np.abs(tilted.gravity_torque_nm(q_tilted) - upright.gravity_torque_nm(q)).max() > 0.5  # it did turn


@pytest.mark.parametrize("protocol", ["planned", "paper"])
def test_two_postures_of_arm26_separate_its_two_joint_muscles_from_gravity(tmp_path: Path, protocol: str) -> None:
    # Passive moments 10 % of gravity. On arm26's planned ranges (elevation 42-70 deg) one posture leaves the
    # shoulder's elastic terms collinear with gravity (invalid, the upper arm "at its bound"); with the trunk
    # tilted by 25 deg for a second recording `bsp identify` gets both static moments. A drift check drawn across
    # the gap between the recordings made this invalid ("the wrench drifts ... 0.76 N over 659 s"). On the
    # paper's protocol the elbow's passive curve came out 7 % off at 5-9 of its std: the planar model's error of
    # arm26's oblique arm, which the curves' std now holds (the markers' lateral excursion).
    bags = []
    if protocol == "planned":
        motion = cell.planned_protocol(cell.Arm26(), 60.0)  # bsp_ros.core.planning's plan (a few seconds)
    else:
        motion = cell.PAPER_PROTOCOL
    for k, tilt_deg in enumerate((0.0, 25.0)):
        tilt = math.radians(tilt_deg)
        arm = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(0.1), trunk_tilt_rad=tilt))
        trajectory = cell.TrunkTilted(motion, tilt) if tilt else motion
        options = cell.SessionOptions(duration_s=60.0, seed=5 + k, start_ns=cell.DEFAULT_START_NS + k * 600 * 10**9)
        bags.append(cell.write_bag(tmp_path / f"posture_{k}", cell.run_cell(arm, trajectory, options), seed=5 + k))
    truth = json.loads((bags[0] / "truth.json").read_text())
    out = tmp_path / "both.json"
    code = bsp_main(
        ["identify", *map(str, bags), "--trunk-tilt-deg", "0", "25", "--json", str(out), "--format", "none"]
    )
    estimate = json.loads(out.read_text())
    assert code == 0, estimate["quality"]["message"]
    for segment in cell.SEGMENTS:
        q, true = estimate["segments"][segment]["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3.0 * q["std"], (segment, q, true)
        assert abs(q["value"] - true) < 0.03 * true, (segment, q, true)
    curves = 0
    for joint in cell.JOINTS:
        curve = estimate["joints"][joint].get("passive_curve")
        if not curve:
            continue
        z = _curve_z(curve, truth["joints"][joint]["passive_curve"])
        assert z.max() < 3.0, (joint, z.max())
        curves += 1
    assert curves == 2  # the default model fell back to the elastic family, which reports the curves


@pytest.fixture(scope="module")
def planned_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """120 s of one posture's planned protocol, passive moments 10 % of gravity (seed 2), as a bag."""
    motion = cell.planned_protocol(cell.Arm26(), 120.0)
    arm = cell.Arm26(cell.CellOptions(force_scale=cell.force_scale_for_share(0.1)))
    run = cell.run_cell(arm, motion, cell.SessionOptions(duration_s=120.0, seed=2))
    return cell.write_bag(tmp_path_factory.mktemp("arm26_planned") / "session", run, seed=2)


@pytest.mark.parametrize("passive", ["auto", "coulomb+offset+stiffness+nonlinear+coupling"])
def test_static_moments_that_hang_on_the_passive_curves_shape_carry_it_in_their_std(
    planned_bag: Path, tmp_path: Path, passive: str
) -> None:
    """One posture, a planned protocol, passive moments 10 % of gravity. The full elastic family (a complete cubic
    potential) follows gravity's potential to third order, so the data tell the forearm's static moment from the
    two-joint muscles only by the curves' assumed shape: before the shape probe it was +116 % at 4.2-4.7 std and
    marked valid (seeds 1 and 2 of bench/musculoskeletal.py). A valid estimate must hold the truth within 3 std."""
    bag = planned_bag
    out = tmp_path / "estimate.json"
    bsp_main(["identify", str(bag), "--json", str(out), "--format", "none", "--passive", passive])
    estimate, truth = json.loads(out.read_text()), json.loads((bag / "truth.json").read_text())
    assert estimate["diagnostics"]["passive_model"] == "coulomb+offset+stiffness+nonlinear+coupling"
    forearm = estimate["segments"]["forearm"]["static_moment_kgm"]
    error = forearm["value"] - truth["segments"]["forearm"]["static_moment_kgm"]
    assert abs(error) > 0.5 * truth["segments"]["forearm"]["static_moment_kgm"]  # the case: far off, in one posture
    assert estimate["quality"]["valid"], estimate["quality"]["message"]
    assert abs(error) < 3.0 * forearm["std"], (forearm, error)
    for joint in cell.JOINTS:
        curve = estimate["joints"][joint]["passive_curve"]
        assert _curve_z(curve, truth["joints"][joint]["passive_curve"]).max() < 3.0, joint
