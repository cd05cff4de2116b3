"""Plans shared by the planning tests (each takes a few seconds: planned once per test session)."""

from __future__ import annotations

import pytest
from planning_cases import RANGES_DEG, SHOULDER_YZ_M, nominal_arm

from bsp_ros.core.planning import JointLimits, Plan, PlanRequest, plan_protocol


@pytest.fixture(scope="session")
def plan() -> Plan:
    return plan_protocol(
        PlanRequest(nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=JointLimits(RANGES_DEG))
    )


@pytest.fixture(scope="session")
def wrist_limited_plan() -> Plan:
    limits = JointLimits((RANGES_DEG[0], RANGES_DEG[1], (-5.0, 5.0)))
    return plan_protocol(PlanRequest(nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=limits, n_points=1))
