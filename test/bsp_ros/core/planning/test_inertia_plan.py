"""`bsp plan --excite-inertia`: two sines per joint within the therapist's limits identify the grouped inertias.

The plan is checked against the limits it was given, then followed by a simulated arm with rigid-body dynamics
(other seeds than the prediction's): the upper arm's and forearm's grouped inertias come from the data within
3 std and 5 % of the truth, and their reported std agrees with the plan's simulated prediction within 1.5x.
"""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.anthropometry import length_from_height_m
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_inertia_protocol, simulated_inertia_std
from bsp_ros.core.planning.inertia import FAST_PERIOD_MIN_S, inertia_sines
from bsp_ros.core.streams import segments_for
from bsp_ros.errors import InputError

RANGES_DEG = ((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0))
SUBJECT = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3)


def _request(max_speed: float = 0.15, duration_s: float = 120.0) -> PlanRequest:
    lengths = tuple(length_from_height_m("male", name, 1.78) for name in segments_for(3))
    return PlanRequest(
        nominal=NominalArm.from_anthropometry(lengths),
        shoulder_yz_m=(0.0, 1.2),
        limits=JointLimits(RANGES_DEG, max_speed),
        duration_s=duration_s,
    )


@pytest.fixture(scope="module")
def plan():
    return plan_inertia_protocol(_request(), 0.3)


def test_the_motion_keeps_every_limit_and_starts_and_ends_at_rest(plan) -> None:
    t = np.linspace(0.0, 120.0, 24001)
    q, qdot = np.degrees(plan.trajectory.angles_rad(t)), plan.trajectory.velocities_rad_s(t)
    for j, (low, high) in enumerate(plan.request.usable_range_deg()):
        assert low <= q[:, j].min() and q[:, j].max() <= high
    assert np.abs(qdot).max() <= 0.15
    assert np.abs(np.gradient(qdot, t, axis=0)).max() <= 0.3 * 1.05  # the ramps add a few percent at most
    assert np.abs(qdot[[0, -1]]).max() < 1e-15
    sines = inertia_sines(plan.request, 0.3)
    assert np.min(sines.period_s) >= FAST_PERIOD_MIN_S - 1e-9


def test_too_short_a_session_is_refused_naming_the_duration_needed() -> None:
    with pytest.raises(InputError, match=r"--duration \d+ or more"):
        plan_inertia_protocol(_request(duration_s=20.0), 0.3)


@pytest.mark.parametrize("seed", [11, 12])
def test_a_session_of_the_plan_identifies_the_inertias_as_predicted(plan, seed: int) -> None:
    predicted = simulated_inertia_std(plan, SUBJECT, seed=0)
    spec = sim.human_arm_cell(subject=SUBJECT, trajectory=plan.trajectory, duration_s=120.0, seed=seed)
    simulated = sim.simulate_cell(spec)
    truth = simulated.truth.to_dict()
    options = IdentifyOptions(zero_sd_n=0.0, zero_sd_nm=0.0)  # tared, as the prediction assumes
    document = identify_session(simulated.session, options)
    assert document["quality"]["valid"], document["quality"]["message"]
    for segment in ("upper_arm", "forearm"):
        q, true = (
            document["segments"][segment]["grouped_inertia_kgm2"],
            truth["segments"][segment]["grouped_inertia_kgm2"],
        )
        assert q["source"] == "data"
        assert abs(q["value"] - true) < min(3.0 * q["std"], 0.05 * true), (segment, q, true)
        assert 1 / 1.5 < q["std"] / predicted[segment][1] < 1.5, (segment, q["std"], predicted[segment])
