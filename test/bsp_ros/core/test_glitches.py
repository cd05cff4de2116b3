"""Glitch injection: each function changes exactly what it names and leaves its input alone."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import glitches
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell
from bsp_ros.errors import InputError


@pytest.fixture(scope="module")
def simulated() -> SimulatedSession:
    return simulate_cell(human_arm_cell(duration_s=5.0, seed=2))


def test_swap_exchanges_two_markers_in_one_frame_only(simulated: SimulatedSession) -> None:
    session = simulated.session
    swapped = glitches.swap_markers(session, "elbow", "hand", 100)
    elbow, hand = session.markers["elbow"].position_m, session.markers["hand"].position_m
    np.testing.assert_array_equal(swapped.markers["elbow"].position_m[100], hand[100])
    np.testing.assert_array_equal(swapped.markers["hand"].position_m[100], elbow[100])
    changed = (swapped.markers["elbow"].position_m != elbow).any(axis=1)
    assert np.flatnonzero(changed).tolist() == [100]
    assert not (session.markers["elbow"].position_m != elbow).any()


def test_displace_moves_one_frame_by_the_offset(simulated: SimulatedSession) -> None:
    session = simulated.session
    moved = glitches.displace_marker(session, "hand", -1, (0.0, 0.06, 0.0))
    delta = moved.markers["hand"].position_m - session.markers["hand"].position_m
    assert np.flatnonzero(delta.any(axis=1)).tolist() == [session.markers["hand"].t_ns.size - 1]
    np.testing.assert_allclose(delta[-1], (0.0, 0.06, 0.0))


def test_spikes_hit_count_distinct_samples_with_the_given_force(simulated: SimulatedSession) -> None:
    session = simulated.session
    spiked = glitches.wrench_spikes(session, 10, 1000.0, seed=3)
    changed = (spiked.wrench.force_n != session.wrench.force_n).any(axis=1)
    assert changed.sum() == 10
    np.testing.assert_allclose(np.linalg.norm(spiked.wrench.force_n[changed], axis=1), 1000.0)
    np.testing.assert_array_equal(spiked.wrench.torque_nm, session.wrench.torque_nm)


def test_set_sample_writes_one_component(simulated: SimulatedSession) -> None:
    glitched = glitches.set_wrench_sample(simulated.session, 7, 1e30, component=4)
    assert glitched.wrench.torque_nm[7, 1] == 1e30
    assert (glitched.wrench.torque_nm != simulated.session.wrench.torque_nm).sum() == 1


def test_bad_arguments_are_named(simulated: SimulatedSession) -> None:
    with pytest.raises(InputError, match="no marker 'knee'"):
        glitches.displace_marker(simulated.session, "knee", 0, (0, 0, 0))
    with pytest.raises(InputError, match="index 99999"):
        glitches.set_wrench_sample(simulated.session, 99999, 1.0)
