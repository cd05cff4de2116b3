"""Recordings of one arm identified together: a second trunk posture separates elastic moments from gravity."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.recordings import combine_recordings
from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings, identify_session
from bsp_ros.core.simulation.subject import PassiveTruth
from bsp_ros.errors import InputError

TILT_RAD = math.radians(25.0)
ELASTIC = IdentifyOptions(passive=PassiveModel.parse("coulomb+offset+stiffness"))
SEGMENTS = ("upper_arm", "forearm", "hand")


@functools.cache
def _recording(tilt_rad: float, seed: int) -> sim.SimulatedSession:
    """The paper's human protocol (shoulder +-6 deg) on an arm with springs at every joint; with the trunk tilted,
    the robot moves the arm through the same postures relative to the trunk, 5 minutes later."""
    base = sim.human_arm_cell(seed=seed, duration_s=90.0)
    centre = list(base.trajectory.center_deg)
    centre[0] += math.degrees(tilt_rad)
    passive = PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06),
        stiffness_nm_per_rad=(0.5, 0.3, 0.05),
        neutral_rad=(math.radians(-43.3), math.radians(29.5), 0.0),
    )
    return sim.simulate_cell(
        dataclasses.replace(
            base,
            passive=passive,
            trajectory=dataclasses.replace(base.trajectory, center_deg=tuple(centre)),
            trunk_tilt_rad=tilt_rad,
            start_ns=base.start_ns + (300_000_000_000 if tilt_rad else 0),
        )
    )


def _z(document: dict, truth: dict, segment: str) -> float:
    q = document["segments"][segment]["static_moment_kgm"]
    return (q["value"] - truth["segments"][segment]["static_moment_kgm"]) / q["std"]


def test_a_second_trunk_posture_separates_the_springs_from_gravity() -> None:
    upright, tilted = _recording(0.0, 3), _recording(TILT_RAD, 4)
    truth = upright.truth.to_dict()
    alone = identify_session(upright.session, ELASTIC)
    both = identify_recordings([upright.session, tilted.session], ELASTIC, [0.0, TILT_RAD])
    assert both["quality"]["valid"], both["quality"]["message"]
    for segment in SEGMENTS:
        assert abs(_z(both, truth, segment)) < 3.0, segment
    # On +-6 deg of shoulder motion a spring looks like gravity; 25 deg of trunk tilt tells them apart: the std's
    # data terms shrink (the untared sensor zero's prior is the same in both).
    budgets = [d["segments"]["upper_arm"]["static_moment_kgm"]["budget"] for d in (alone, both)]
    data_std = [float(np.hypot(b["sensor_noise"], b["marker_placement"])) for b in budgets]
    assert data_std[1] < data_std[0] / 2.5, data_std
    stiffness = both["joints"]["shoulder"]["stiffness_nm_per_rad"]
    assert abs(stiffness["value"] - 0.5) < min(3 * stiffness["std"], 0.025), stiffness
    assert [r["trunk_tilt_deg"] for r in both["session"]["recordings"]] == pytest.approx([0.0, 25.0])


def test_the_same_recordings_taken_as_one_posture_are_not_valid_and_right() -> None:
    upright, tilted = _recording(0.0, 3), _recording(TILT_RAD, 4)
    truth = upright.truth.to_dict()
    wrong = identify_recordings([upright.session, tilted.session], ELASTIC, [0.0, 0.0])
    right = wrong["quality"]["valid"] and all(abs(_z(wrong, truth, s)) < 3.0 for s in SEGMENTS)
    assert not right, wrong["quality"]["message"]


def test_combining_checks_the_recordings() -> None:
    upright, tilted = _recording(0.0, 3), _recording(TILT_RAD, 4)
    a = identification_data_from_session(upright.session)
    b = identification_data_from_session(tilted.session)
    assert combine_recordings([a], [0.0]) is a
    both = combine_recordings([b, a], [TILT_RAD, 0.0])  # given out of order: sorted by time
    assert np.all(np.diff(both.t_ns) > 0) and both.t_ns.size == a.t_ns.size + b.t_ns.size
    np.testing.assert_allclose(both.passive_q_rad[: a.t_ns.size], a.q_rad)
    np.testing.assert_allclose(both.passive_q_rad[a.t_ns.size :, 0], b.q_rad[:, 0] - TILT_RAD)
    np.testing.assert_allclose(both.passive_q_rad[a.t_ns.size :, 1:], b.q_rad[:, 1:])
    with pytest.raises(InputError, match="overlap in time"):
        combine_recordings([a, a], [0.0, 0.0])
    with pytest.raises(InputError, match="one per recording"):
        combine_recordings([a, b], [0.0])
    with pytest.raises(InputError, match="within \\+-90 deg"):
        combine_recordings([a, b], [0.0, 2.0])
    moved = dataclasses.replace(b, lengths_m=b.lengths_m + np.array([0.0, 0.006, 0.0]))
    assert any("segment 2's length differs by 6" in w for w in combine_recordings([a, moved], [0.0, 0.0]).warnings)
