"""A faster protocol (peak 0.15 rad/s, two sines per joint, periods 2-11 s) identifies the segment inertias.

On the paper's slow sines the inertias keep their prior. Short periods accelerate the arm at a bounded speed
(a sine's acceleration is its speed times its angular frequency), and two incommensurate periods per joint keep
the acceleration from being proportional to the angle, as a single sine's is (then it looks like a stiffness).
Before the derivative filters followed the motion's band, this session was invalid ("the model does not fit at
the shoulder", 8.8 times the noise) with every parameter within 1.2 std: the 0.5 Hz direction filter shifted
the velocity's zero crossings of the 0.48 Hz component, giving Coulomb friction the wrong sign near reversals.
"""

from __future__ import annotations

import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.pipeline import IdentifyOptions, identify_session

PERIODS_S = ((2.1, 7.9), (2.7, 9.3), (3.3, 11.1))
PHASES_RAD = ((0.0, 1.3), (1.0, 2.9), (2.0, 0.4))


def _session(seed: int) -> sim.SimulatedSession:
    motion = sim.MultiSineTrajectory.within_speed((-43.3, 45.0, 0.2), PERIODS_S, 0.15, PHASES_RAD)
    return sim.simulate_cell(sim.human_arm_cell(trajectory=motion, duration_s=120.0, seed=seed))


def test_the_multisine_stays_within_its_speed() -> None:
    motion = sim.MultiSineTrajectory.within_speed((-43.3, 45.0, 0.2), PERIODS_S, 0.15, PHASES_RAD)
    assert motion.peak_speed_rad_s == pytest.approx((0.15, 0.15, 0.15), rel=1e-3)
    t = [0.0, 0.7, 3.1]
    step = 1e-5
    numeric = (motion.angles_rad([x + step for x in t]) - motion.angles_rad([x - step for x in t])) / (2 * step)
    assert numeric == pytest.approx(motion.velocities_rad_s(t), abs=1e-7)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_faster_protocol_identifies_the_inertias(seed: int) -> None:
    simulated = _session(seed)
    truth = simulated.truth.to_dict()
    # Markers exactly on the joint centres and a tared sensor: what the data alone say about the inertias.
    options = IdentifyOptions(marker_placement_sd_m=0.0, zero_sd_n=0.0, zero_sd_nm=0.0)
    document = identify_session(simulated.session, options)
    assert document["quality"]["valid"], document["quality"]["message"]
    notes = [f.values["detail"] for f in findings_of(document["quality"]) if f.code is FindingCode.DATA_NOTE]
    assert any("direction filter" in detail for detail in notes), notes  # the filters followed the motion
    for segment in ("upper_arm", "forearm"):
        q = document["segments"][segment]["grouped_inertia_kgm2"]
        true = truth["segments"][segment]["grouped_inertia_kgm2"]
        assert q["source"] == "data", (segment, q)
        assert abs(q["value"] - true) < 3.0 * q["std"], (segment, q, true)
        assert abs(q["value"] - true) < 0.05 * true, (segment, q, true)
        assert q["std"] < 0.03 * true, (segment, q)  # identified, not the prior's 15 %
    for segment, entry in document["segments"].items():
        q, true = entry["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3.0 * q["std"] and abs(q["value"] - true) < 0.005 * true, segment
    # With the defaults (skin markers' 2 mm placement and an untared zero in the std) still valid and right.
    default = identify_session(simulated.session)
    assert default["quality"]["valid"], default["quality"]["message"]
    for segment, entry in default["segments"].items():
        q, true = entry["grouped_inertia_kgm2"], truth["segments"][segment]["grouped_inertia_kgm2"]
        assert abs(q["value"] - true) < 3.0 * q["std"], (segment, q, true)
