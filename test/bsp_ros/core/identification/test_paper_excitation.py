"""The paper's method on motion that cannot tell its parameters is invalid and names the joint, as ours is: a
simulated joint held still, and a session shorter than a quarter of a joint's period (one direction only)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, Severity
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.paper import identify_paper


def _invalid_codes(session: sim.SimulatedSession) -> set[tuple[FindingCode, str]]:
    result = identify_paper(identification_data_from_session(session.session))
    return {(f.code, f.where) for f in result.findings if f.severity == Severity.INVALID}


def _session(
    duration_s: float, amplitude_deg: tuple[float, float], seed: int
) -> tuple[sim.SimulatedSession, sim.TrajectorySpec]:
    """The paper's arm and protocol with other amplitudes, and the motion imposed (its known truth)."""
    cell = sim.paper_mechanical_arm_cell(seed=seed, duration_s=duration_s)
    assert isinstance(cell.trajectory, sim.TrajectorySpec)
    trajectory = dataclasses.replace(cell.trajectory, amplitude_deg=amplitude_deg)
    return sim.simulate_cell(dataclasses.replace(cell, trajectory=trajectory)), trajectory


def test_a_still_elbow_is_no_motion() -> None:
    """20 s with the elbow held still (amplitude 0, qdot = 0 exactly): the paper's Eq. 11 read the noise as a
    0.0x Nm elbow Coulomb with a tiny std, and the estimate was valid."""
    session, trajectory = _session(20.0, (5.7, 0.0), seed=11)
    assert np.ptp(trajectory.angles_rad(np.linspace(0.0, 20.0, 401))[:, 1]) == 0.0
    assert (FindingCode.NO_MOTION, "elbow") in _invalid_codes(session)


def test_a_joint_moving_one_way_is_one_direction() -> None:
    """4 s of the shoulder's 21 s sine from its phase 0: it only rises (the first reversal is at 5.25 s)."""
    session, trajectory = _session(4.0, (5.7, 5.7), seed=12)
    assert (trajectory.velocities_rad_s(np.linspace(0.0, 4.0, 401))[:, 0] > 0.0).all()
    codes = _invalid_codes(session)
    assert (FindingCode.ONE_DIRECTION, "shoulder") in codes or (FindingCode.DIRECTION_UNCLEAR, "shoulder") in codes


def test_the_paper_protocol_stays_valid(paper_arm_session: sim.SimulatedSession) -> None:
    """120 s of the paper's protocol: both joints move both ways, the checks find nothing."""
    result = identify_paper(identification_data_from_session(paper_arm_session.session))
    assert result.valid
    assert result.value("coulomb_nm", "elbow") == pytest.approx(0.161, rel=0.05)
