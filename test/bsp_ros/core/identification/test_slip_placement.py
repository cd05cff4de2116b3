"""A marker off its joint centre is not a hand that slips: the travel is looked for beside the markers' offsets."""

from __future__ import annotations

import dataclasses

import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint


@pytest.mark.parametrize("seed", [0, 3])
def test_a_contact_marker_2_mm_off_on_a_fast_protocol_names_no_slip(seed: int) -> None:
    """The paper's sines four times faster (periods of 4-6 s, near the travel's 5 s knots) with the contact point's
    marker 2 mm off along the hand's normal (the assumed placement sd): the travel followed that offset's pattern and
    named a slip in every seed."""
    spec = sim.human_arm_cell(seed=seed, duration_s=120.0)
    offsets = ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0), (0.0, 0.002))
    spec = dataclasses.replace(
        spec,
        trajectory=spec.trajectory.speed_scaled(4.0),
        markers=dataclasses.replace(spec.markers, skin_offset_m=offsets),
    )
    data = identification_data_from_session(sim.simulate_cell(spec).session)
    result = identify_joint(data, JointConfig())
    assert result.valid
    assert FindingCode.HAND_SLIPPED not in [f.code for f in result.findings]
