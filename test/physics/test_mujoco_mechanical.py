"""The method paper's 2-segment mechanical arm in the MuJoCo cell: statics by hand, markers, and `bsp identify`."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics-engine cell needs MuJoCo (pip install mujoco, the test extra)")

from mujoco_bag import record, write_bag
from mujoco_cell import ArmParams, CellOptions, mjcf_text, run_engine
from mujoco_mechanical import PAPER_ARM_COULOMB_NM, mechanical_arm, mechanical_sine

from bsp_ros.cli import main
from bsp_ros.core import model
from bsp_ros.core.simulation import (
    GRAVITY_M_S2,
    CellSimulator,
    MarkerSpec,
    SessionTruth,
    SubjectTruth,
    TrajectorySpec,
    paper_mechanical_arm_cell,
)

STILL = TrajectorySpec((-36.6, 35.8), (0.0, 0.0), (10.0, 10.0), (0.0, 0.0))


def _gravity_and_springs_by_hand(arm: ArmParams, q: np.ndarray) -> np.ndarray:
    """(N, 2) the moments the driver supplies to hold a 2-link arm still at ``q`` (N, 2), Nm: dV/dq plus k q - k q_ref.

    V = g (m1 z1 + m2 z2), each COM at ``l along + d normal`` of its segment: z1 = l1 sin(phi1) + d1 cos(phi1),
    z2 = a1 sin(phi1) + l2 sin(phi12) + d2 cos(phi12), with phi1 = q1 and phi12 = q1 + q2.
    """
    (m1, m2), (l1, l2), (d1, d2) = arm.masses_kg, arm.com_along_m, arm.com_normal_m
    a1 = arm.lengths_m[0]
    phi1, phi12 = q[:, 0], q[:, 0] + q[:, 1]
    dz2_dphi12 = l2 * np.cos(phi12) - d2 * np.sin(phi12)
    tau_2 = GRAVITY_M_S2 * m2 * dz2_dphi12
    tau_1 = GRAVITY_M_S2 * (m1 * (l1 * np.cos(phi1) - d1 * np.sin(phi1)) + m2 * a1 * np.cos(phi1)) + tau_2
    springs = np.asarray(arm.stiffness_nm_per_rad) * (q - np.asarray(arm.springref_rad))
    return np.column_stack((tau_1, tau_2)) + springs


def _contact_torques_by_hand(lengths_m: Sequence[float], q: np.ndarray, wrench_yzx: np.ndarray) -> np.ndarray:
    """(N, 2) ``-J(q)^T [F_y, F_z, M_x]`` of a 2-link chain whose last link ends at the contact point, Nm."""
    a1, a2 = lengths_m
    phi1, phi12 = q[:, 0], q[:, 0] + q[:, 1]
    dp_dq2 = np.column_stack((-a2 * np.sin(phi12), a2 * np.cos(phi12)))
    dp_dq1 = np.column_stack((-a1 * np.sin(phi1), a1 * np.cos(phi1))) + dp_dq2
    force, moment = wrench_yzx[:, :2], wrench_yzx[:, 2]
    return -np.column_stack(((dp_dq1 * force).sum(axis=1) + moment, (dp_dq2 * force).sum(axis=1) + moment))


def test_the_nominal_mechanical_arm_is_table_1_and_a_seed_spreads_it() -> None:
    nominal, paper = mechanical_arm(), SubjectTruth.paper_mechanical_arm()
    assert model.static_moments_kgm(nominal.lengths_m, nominal.masses_kg, nominal.com_along_m) == pytest.approx(
        [0.260 + 1.160 * 0.30, 0.130]
    )
    assert nominal.masses_kg == paper.masses_kg and nominal.com_along_m == paper.com_m
    assert nominal.frictionloss_nm == PAPER_ARM_COULOMB_NM == (0.139, 0.161)
    drawn = [mechanical_arm(seed) for seed in range(20)]
    assert mechanical_arm(3) == drawn[3]  # seeded
    masses = np.array([a.masses_kg for a in drawn]) / np.asarray(paper.masses_kg)
    friction = np.array([a.frictionloss_nm for a in drawn]) / np.asarray(PAPER_ARM_COULOMB_NM)
    assert 0.005 < masses.std() < 0.04 and np.abs(masses - 1.0).max() < 0.1
    assert 0.7 <= friction.min() and friction.max() <= 1.3 and friction.std() > 0.1
    assert mechanical_sine().period_s == (21.0, 23.0) and mechanical_sine(4.0).period_s == (5.25, 5.75)
    assert "<connect " in mjcf_text(nominal, CellOptions(trajectory=STILL))  # the paper's bearing, not a strap


def test_a_still_mechanical_arm_s_engine_wrench_balances_gravity_and_springs_computed_by_hand() -> None:
    arm = dataclasses.replace(
        mechanical_arm(4),
        frictionloss_nm=(0.0, 0.0),
        com_normal_m=(0.004, -0.003),
        stiffness_nm_per_rad=(0.3, 0.5),
        springref_rad=(-0.35, 1.0),
    )
    run = run_engine(arm, CellOptions(trajectory=STILL, duration_s=0.2, lead_in_s=1.0))
    wrench = run.wrench_world()
    measured = _contact_torques_by_hand(arm.lengths_m, run.q_rad, wrench)
    expected = _gravity_and_springs_by_hand(arm, run.q_rad)
    assert np.abs(measured).min() > 0.1  # both joints carry load
    assert np.abs(measured - expected).max() < 1e-9
    assert np.abs(measured - model.contact_torques_nm(run.q_rad, arm.lengths_m, wrench)).max() < 1e-12
    assert np.abs(wrench[:, 2]).max() < 1e-9  # the bearing carries no moment
    assert run.out_of_plane() < 1e-9
    assert run.weld_drift_m.max() < 2e-5  # the bearing holds the forearm's end at the handle


class _Replay:
    """A 2-joint JointTrajectory that replays the engine's own joint angles (for bsp_ros's simulator)."""

    def __init__(self, t_s: np.ndarray, q_rad: np.ndarray) -> None:
        self._t, self._q = t_s, q_rad

    n_joints = 2
    peak_speed_rad_s = (0.0, 0.0)

    def angles_rad(self, t_s: np.ndarray) -> np.ndarray:
        return np.column_stack([np.interp(t_s, self._t, self._q[:, j]) for j in range(2)])

    def velocities_rad_s(self, t_s: np.ndarray) -> np.ndarray:
        return np.zeros((np.size(t_s), 2))


def test_three_skin_marker_sites_sit_where_bsp_ros_puts_a_two_segment_chain_s_skin_markers() -> None:
    offsets = ((0.01, 0.02), (-0.015, 0.01), (0.02, -0.015))
    arm = mechanical_arm(9)
    options = CellOptions(trajectory=mechanical_sine(4.0), duration_s=2.0, skin_offset_m=offsets, lead_in_s=0.1)
    run = run_engine(arm, options)
    spec = paper_mechanical_arm_cell(
        subject=SubjectTruth(arm.lengths_m, arm.masses_kg, arm.com_along_m, arm.inertia_com_kgm2),
        trajectory=_Replay(run.t_s, run.q_rad),
        markers=MarkerSpec(shoulder_m=options.shoulder_m, skin_offset_m=offsets, noise_m=0.0),
        duration_s=2.0,
    )
    expected = CellSimulator(spec).marker_positions_m(run.t_s)
    assert sorted(expected) == ["elbow", "hand", "shoulder"]
    for k, name in enumerate(("shoulder", "elbow", "hand")):
        assert np.abs(run.markers_m[:, k] - expected[name]).max() < 1e-12, name
    with pytest.raises(ValueError, match="3 markers"):
        mjcf_text(arm, dataclasses.replace(options, skin_offset_m=(*offsets, (0.0, 0.0))))


def _identified_session(out: Path, duration_s: float, seed: int) -> tuple[dict, dict]:
    """A session of ``mechanical_arm(seed)`` on the paper's protocol at 250 Hz through `bsp identify`, tared (the
    engine's sensor has no offset: ``--zero-sd-n 0 --zero-sd-nm 0``): (truth, estimate JSON)."""
    arm = mechanical_arm(seed)
    options = CellOptions(trajectory=mechanical_sine(), duration_s=duration_s, wrench_hz=250.0, seed=seed)
    bag = write_bag(out / "session", record(arm, options))
    truth = json.loads((bag / "truth.json").read_text())
    assert SessionTruth.from_dict(truth).static_moments_kgm == pytest.approx(
        model.static_moments_kgm(arm.lengths_m, arm.masses_kg, arm.com_along_m)
    )
    args = ["--format", "none", "--zero-sd-n", "0", "--zero-sd-nm", "0"]
    code = main(["identify", str(bag), "--json", str(out / "e.json"), *args])
    estimate = json.loads((out / "e.json").read_text())
    assert code == 0, estimate["quality"]["message"]
    return truth, estimate


def test_a_mechanical_arm_session_from_the_engine_is_identified_within_1_percent(tmp_path: Path) -> None:
    """50 s of a seeded arm: measured errors 0.04 % (upper arm) and 0.01 % (forearm) for stds of 1.3 % and 4.9 %."""
    truth, estimate = _identified_session(tmp_path, 50.0, 1)
    assert list(estimate["segments"]) == ["upper_arm", "forearm"] and list(estimate["joints"]) == ["shoulder", "elbow"]
    for segment, quantities in estimate["segments"].items():
        q, true = quantities["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert q["source"] == "data"
        assert abs(q["value"] - true) < 3.0 * q["std"], (segment, q, true)
        assert abs(q["value"] - true) < 0.01 * true, (segment, q, true)
        assert q["std"] < 0.1 * true, (segment, q)  # 3 std is a bound that means something
        assert quantities["length_m"]["value"] == pytest.approx(truth["segments"][segment]["length_m"], abs=2e-4)
    for joint, quantities in estimate["joints"].items():
        assert quantities["coulomb_nm"]["value"] == pytest.approx(truth["joints"][joint]["coulomb_nm"], rel=0.03)


def test_markers_on_their_centres_keep_the_assumed_placement_on_the_mechanical_arm(tmp_path: Path) -> None:
    """The force noise enters the offsets' columns through the averaged handle force; left out of its own sample's
    average it no longer correlates with the residual, and the placement stays as assumed (it went to 10x)."""
    _, estimate = _identified_session(tmp_path, 120.0, 2)
    placement = estimate["quality"]["marker_placement"]
    assert placement["scale_from_data"] < 2.0, placement
