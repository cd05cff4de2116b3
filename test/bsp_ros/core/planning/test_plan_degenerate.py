"""Degenerate plans: a range or an amplitude the estimator would call still is refused naming it, and the simulated
check of a plan whose sessions cannot be identified reports no static moment instead of raising."""

from __future__ import annotations

import argparse
import dataclasses
import math

import numpy as np
import pytest

from bsp_ros.cli.plan_passive import passive_check_lines
from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol
from bsp_ros.core.planning.choice import AutoChoice
from bsp_ros.core.planning.simulated import simulated_plan_check
from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.errors import InputError

SUBJECT = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 2)
STILL_DEG = JointConfig(passive=PassiveModel.parse("coulomb")).min_range_deg  # the estimator's no-motion range


def _request(ranges_deg: tuple[tuple[float, float], ...], **changes: object) -> PlanRequest:
    fields: dict[str, object] = {
        "nominal": NominalArm.from_anthropometry(list(SUBJECT.lengths_m)),
        "shoulder_yz_m": (0.0, 1.2),
        "limits": JointLimits(ranges_deg, max_speed_rad_s=0.03),
        "duration_s": 12.0,
        "passive": PassiveModel.parse("coulomb"),
        "n_points": 1,
        "max_evaluations": 10,
    }
    return PlanRequest(**{**fields, **changes})  # type: ignore[arg-type]


def test_a_range_the_estimator_calls_still_is_refused_naming_it() -> None:
    with pytest.raises(InputError, match=r"the elbow range is 0\.1 deg wide: .* less than 0\.2 deg as still"):
        plan_protocol(_request(((-70.0, -10.0), (50.0, 50.1))))


def test_a_range_of_exactly_the_no_motion_range_is_planned() -> None:
    """-28.66 to -28.46 deg is 0.19999999999999929 deg in floating point: not refused as narrower than 0.2."""
    plan = plan_protocol(_request(((-28.66, -28.46), (10.0, 100.0))))
    assert 2.0 * plan.amplitudes_deg[0] == pytest.approx(STILL_DEG, rel=1e-6)


def test_an_amplitude_the_estimator_calls_still_is_refused_naming_it() -> None:
    request = _request(((-70.0, -10.0), (10.0, 100.0)), amplitude_deg=(0.01, 2.0))
    with pytest.raises(InputError, match=r"the shoulder amplitude 0\.01 deg is too small: .* spans 0\.02 deg"):
        plan_protocol(request)


def test_a_narrow_range_is_planned_with_motion_the_estimator_sees() -> None:
    """A 0.3 deg elbow range: its default amplitude, and the optimiser's smallest, was a quarter of it (0.075 deg, a
    0.15 deg oscillation every session would call still); it is now at least half the no-motion range."""
    request = _request(((-70.0, -10.0), (50.0, 50.3)))
    assert 2.0 * request.amplitudes_deg()[1] == pytest.approx(STILL_DEG, rel=1e-12)
    plan = plan_protocol(request)
    assert 2.0 * plan.amplitudes_deg[1] >= STILL_DEG - 1e-12
    q_deg = np.degrees(plan.trajectory.angles_rad(np.linspace(0.0, plan.trajectory.duration_s, 2001)))
    assert np.ptp(q_deg[:, 1]) >= STILL_DEG - 1e-9
    assert np.ptp(q_deg[:, 1]) <= 0.3 + 1e-9


def test_the_check_of_a_still_session_reports_no_static_moment() -> None:
    """A plan's check session in which the arm does not move is not valid and its estimate leaves the static
    moments null: the check holds NaN for them (it raised a TypeError), and bsp plan's lines say so."""
    plan = plan_protocol(_request(((-70.0, -10.0), (10.0, 100.0)), amplitude_deg=(2.0, 2.0)))
    q0 = plan.trajectory.angles_rad(np.array([0.0]))
    still = PlannedTrajectory([0.0, plan.trajectory.duration_s], np.repeat(q0, 2, axis=0), np.zeros((2, 2)))
    check = simulated_plan_check(dataclasses.replace(plan, trajectory=still), SUBJECT)
    assert not check.valid
    assert set(check.static_moments) == {"upper_arm", "forearm"}
    assert all(math.isnan(v) and math.isnan(sd) for v, sd in check.static_moments.values())
    assert all(math.isinf(std) for std in check.curve_rms_std_nm.values())
    args = argparse.Namespace(sex="male", body_mass=75.0, height=1.78)
    still_plan = dataclasses.replace(plan, trajectory=still, check=check)
    text, warning = passive_check_lines(still_plan, args)
    assert "static moments of the simulated session: upper_arm not identified, forearm not identified" in text
    assert warning is not None and "was not valid" in warning


def test_a_check_estimate_without_a_choice_says_it_was_not_valid() -> None:
    estimate: dict[str, object] = {"quality": {"valid": False, "message": "no motion at the elbow"}, "diagnostics": {}}
    with pytest.raises(InputError, match=r"records no passive model: it is not valid \(no motion at the elbow\)"):
        AutoChoice.from_estimate(estimate, PassiveModel.parse("auto"))
