"""A hand in a compliant strap: joints that stick where the movement turns, found and kept out, on MuJoCo's arm.

The physics engine's strap (``test/physics/mujoco_patient.py``, a soft weld) is the truth: its joints' own speeds say
where they stood still, and the arm's parameters what the estimate must recover. The same arm and seed with the
cell's stiff weld is the rigid grip that must show no stick.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics-engine cell needs MuJoCo (pip install mujoco, the test extra)")

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "physics"))

from mujoco_bag import result_z
from mujoco_cell import CellOptions, draw_arm, paper_sine
from mujoco_patient import CompliantStrap, Patient, PatientSession, patient_session

from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.excitation import deadband_rad_s
from bsp_ros.core.identification.joint.grip import MIN_MOVING_SHARE, direction_share, find_sticks

OPTIONS = CellOptions(trajectory=paper_sine(0.03), duration_s=60.0, wrench_hz=250.0, seed=0)


# A session of the engine and its identification data.
Sessions = tuple[PatientSession, IdentificationData]


def _session(strap: bool) -> Sessions:
    session = patient_session(draw_arm(0), OPTIONS, Patient(strap=CompliantStrap() if strap else None))
    return session, identification_data_from_session(session.cell.session)


@pytest.fixture(scope="module")
def strapped() -> Sessions:
    return _session(strap=True)


@pytest.fixture(scope="module")
def rigid() -> Sessions:
    return _session(strap=False)


def _engine_slow(session: PatientSession, data: IdentificationData) -> np.ndarray:
    """(N, 3) where the engine's own joint speed was below a tenth of its typical (95th percentile) speed."""
    run = session.cell.run
    t_s = (data.t_ns - OPTIONS.start_ns) * 1e-9
    speed = np.abs(np.column_stack([np.interp(t_s, run.t_s, run.qdot_rad_s[:, j]) for j in range(3)]))
    return np.asarray(speed < 0.1 * np.percentile(speed, 95, axis=0))


def test_the_strap_makes_elbow_and_wrist_stick_where_the_engine_stood_still(
    strapped: Sessions, rigid: Sessions
) -> None:
    session, data = strapped
    sticks = find_sticks(data.t_ns, data.velocity_rad_s, deadband_rad_s(data, JointConfig()))
    assert list(sticks.sticking) == [False, True, True]
    assert (sticks.dwell_ratio[1:] > 3.0).all() and sticks.dwell_ratio[0] < 1.5
    slow = _engine_slow(session, data)
    for j in (1, 2):
        # What is kept out (the sticks and the direction filter's reach) is where the engine's joint stood still.
        assert slow[sticks.stuck[:, j], j].mean() > 0.7
        # The sticks hold most of the engine's still time (the rest: its turns, which a rigid grip has too).
        assert 0.5 * slow[:, j].mean() < sticks.stuck_share[j] < slow[:, j].mean()
    _, firm = rigid
    none = find_sticks(firm.t_ns, firm.velocity_rad_s, deadband_rad_s(firm, JointConfig()))
    assert not none.sticking.any() and not none.stuck.any() and (none.dwell_ratio < 1.5).all()


def test_a_strapped_arm_is_valid_right_and_named_and_a_rigid_grip_names_nothing(
    strapped: Sessions, rigid: Sessions
) -> None:
    session, data = strapped
    result = identify_joint(data)
    grip = [f for f in result.findings if f.code is FindingCode.GRIP_COMPLIANT]
    assert result.valid and len(grip) == 1 and grip[0].where == "wrist"
    assert grip[0].values["n_joints"] == 2 and "the hand gave in the strap" in grip[0].text
    z = result_z(result, session.cell.truth)
    assert len(z) == 6 and max(z.values()) < 3.0, z
    firm_session, firm = rigid
    plain = identify_joint(firm)
    assert plain.valid and FindingCode.GRIP_COMPLIANT not in [f.code for f in plain.findings]
    assert max(result_z(plain, firm_session.cell.truth).values()) < 3.0


def test_the_direction_rule_judges_the_samples_where_a_joint_did_not_stick(strapped: Sessions) -> None:
    _, data = strapped
    # A stricter rule than the default, which the wrist's share of clear directions over the whole session (60 %)
    # fails and its share over the samples where it did not stick passes.
    strict = JointConfig(min_row_share=0.65)
    assert identify_joint(data, strict).valid
    blind = identify_joint(data, JointConfig(min_row_share=0.65, check_activity=False))
    assert (FindingCode.DIRECTION_UNCLEAR, "wrist") in [(f.code, f.where) for f in blind.findings]
    assert not blind.valid


def test_too_little_left_beside_the_sticks_is_judged_on_the_whole_session() -> None:
    rows, stuck = np.zeros(100, dtype=bool), np.zeros(100, dtype=bool)
    rows[:30], stuck[30:] = True, True
    assert direction_share(rows, 100, stuck) == pytest.approx(1.0)
    assert direction_share(rows, 100, None) == pytest.approx(0.3)
    rows[20:30] = False  # 20 % of the session: too little, stuck or not
    assert 0.2 < MIN_MOVING_SHARE and direction_share(rows, 100, stuck) == pytest.approx(0.2)


def test_smooth_motions_do_not_stick_and_a_stick_slip_does() -> None:
    t_s = np.arange(0.0, 120.0, 0.01)
    t_ns = (t_s * 1e9).astype(np.int64)
    w1, w2 = 2 * np.pi / 20.0, 2 * np.pi / 7.0
    sine = 0.03 * np.cos(w1 * t_s)
    two_sines = 0.03 * np.cos(w1 * t_s) + 0.02 * np.cos(w2 * t_s + 0.7)
    # The sine's motion held still for 2 s after each turn, then caught up at three times the speed.
    held = sine.copy()
    for turn_s in np.arange(5.0, 120.0, 10.0):
        still = (t_s >= turn_s) & (t_s < turn_s + 2.0)
        catch = (t_s >= turn_s + 2.0) & (t_s < turn_s + 3.0)
        missed = sine[still].sum()
        held[still] = 0.0
        held[catch] += missed / catch.sum()
    for velocity, sticks in ((sine, False), (two_sines, False), (held, True)):
        v = velocity[:, None]
        found = find_sticks(t_ns, v, 0.1 * np.percentile(np.abs(v), 95, axis=0))
        assert bool(found.sticking[0]) is sticks and bool(found.stuck.any()) is sticks
