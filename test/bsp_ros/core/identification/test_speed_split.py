"""A session at two speeds: the speed-dependent resistance a simulated arm was given is measured apart from its
passive part, and its static moments stay right."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.speed_split import speed_dependence_block, speed_groups
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.planning.two_speed import TwoSpeedPath

# The simulated markers sit on the joint centres: no placement uncertainty to add.
EXACT = JointConfig(marker_placement_sd_m=0.0)
ELBOW = 1
DURATION_S = 60.0
# A stretch reflex of the elbow flexors (the MuJoCo patient's): 4 Nm s/rad above 0.02 rad/s of extension.
GAIN_NM_S_PER_RAD, THRESHOLD_RAD_S = 4.0, 0.02


@pytest.fixture(scope="module")
def session() -> sim.SimulatedSession:
    """60 s of a drawn arm on the paper's sines: the first half at their speed (elbow peak 0.01 rad/s), the
    second four times faster (0.04 rad/s), the rate changing over 2 s at the middle."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(11))
    path = TwoSpeedPath(sim.human_arm_cell().trajectory, (1.0, 4.0), DURATION_S / 2, DURATION_S)
    return sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=11, duration_s=DURATION_S, trajectory=path))


@pytest.fixture(scope="module")
def data(session: sim.SimulatedSession) -> IdentificationData:
    return identification_data_from_session(session.session)


def reflex_nm(data: IdentificationData) -> np.ndarray:
    """(N, n) the reflex's measured torque: resisting elbow extension (negative velocity), so with its sign."""
    out = np.zeros_like(data.tau_nm)
    out[:, ELBOW] = -GAIN_NM_S_PER_RAD * np.clip(-data.velocity_rad_s[:, ELBOW] - THRESHOLD_RAD_S, 0.0, None)
    return out


def found(result: IdentificationResult, code: FindingCode, where: str) -> dict:
    matches = [f.values for f in result.findings if f.code is code and f.where == where]
    assert len(matches) == 1, [(f.code, f.where) for f in result.findings]
    return dict(matches[0])


def assert_static_moments_right(result: IdentificationResult, session: sim.SimulatedSession) -> None:
    truth = session.truth.static_moments_kgm
    assert result.valid, result.message
    z = np.abs(result.values[:3] - truth) / result.std[:3]
    assert (z < 3.0).all(), z


def test_the_two_speeds_are_found_at_the_joints_that_sweep_the_same_angles_at_both(data: IdentificationData) -> None:
    elbow = speed_groups(data.t_ns, data.q_rad[:, ELBOW], data.velocity_rad_s[:, ELBOW])
    assert elbow is not None
    assert elbow.slow_rad_s == pytest.approx(0.0095, rel=0.1) and elbow.fast_rad_s == pytest.approx(0.038, rel=0.1)
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    assert elbow.fast[t_s > 32].mean() > 0.9 and not elbow.fast[t_s < 28].any()
    one_speed = data.t_ns.size // 2
    assert speed_groups(data.t_ns[:one_speed], data.q_rad[:one_speed, 1], data.velocity_rad_s[:one_speed, 1]) is None


def test_a_reflex_at_the_fast_speed_is_measured_and_the_static_moments_come_from_the_slow_part(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    reflex = reflex_nm(data)
    result = identify_joint(dataclasses.replace(data, tau_nm=data.tau_nm + reflex), EXACT)
    # The truth averaged as the split averages: over the fast strokes' samples moving in that direction.
    groups = speed_groups(data.t_ns, data.q_rad[:, ELBOW], data.velocity_rad_s[:, ELBOW])
    assert groups is not None
    extending = groups.fast & (data.velocity_rad_s[:, ELBOW] < 0)
    truth_nm = float(-reflex[extending, ELBOW].mean())
    assert truth_nm > 0.02
    values = found(result, FindingCode.SPEED_DEPENDENT_RESISTANCE, "elbow")
    assert values["exceeds"] and values["static_from_slow"] and values["direction"] == -1
    assert abs(values["negative_nm"] - truth_nm) < 3 * values["negative_std_nm"]
    assert values["negative_nm"] > 3 * values["negative_std_nm"]
    assert abs(values["positive_nm"]) < 3 * values["positive_std_nm"]
    spastic = found(result, FindingCode.SPASTICITY, "elbow")
    assert spastic["increase_nm"] == values["negative_nm"] and spastic["direction"] == -1
    block = speed_dependence_block(result.findings)
    assert block["elbow"]["static_moments_from"] == "slow" and block["elbow"]["negative"]["exceeds_3_std"]
    assert_static_moments_right(result, session)
    # The elbow's fast strokes left its torque equation only.
    rows = result.diagnostics["rows_used"]
    assert isinstance(rows, dict) and rows["elbow"] < 0.7 * rows["shoulder"]


def test_a_relaxed_arm_at_two_speeds_shows_no_speed_dependent_part(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    result = identify_joint(data, EXACT)
    values = found(result, FindingCode.SPEED_DEPENDENT_RESISTANCE, "elbow")
    assert not values["exceeds"] and not values["static_from_slow"]
    for direction in ("positive", "negative"):
        assert abs(values[f"{direction}_nm"]) < 3 * values[f"{direction}_std_nm"]
    assert FindingCode.SPASTICITY not in [f.code for f in result.findings]
    assert speed_dependence_block(result.findings)["elbow"]["static_moments_from"] == "session"
    assert_static_moments_right(result, session)


def test_a_session_at_one_speed_has_no_speed_dependence_block() -> None:
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(12))
    one_speed = sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=12, duration_s=DURATION_S))
    result = identify_joint(identification_data_from_session(one_speed.session), EXACT)
    assert result.valid, result.message
    assert FindingCode.SPEED_DEPENDENT_RESISTANCE not in [f.code for f in result.findings]
    assert speed_dependence_block(result.findings) == {}
