"""Marker placement: the linearised effect of a skin marker off its joint centre against the simulator's."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.dynamics import base_parameters, base_regressor
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.placement import placement_columns
from bsp_ros.core.planning import PlannedTrajectory


def _data(spec: sim.CellSpec, offsets: tuple[tuple[float, float], ...]):
    markers = dataclasses.replace(spec.markers, noise_m=0.0, skin_offset_m=offsets)
    return identification_data_from_session(sim.simulate_cell(dataclasses.replace(spec, markers=markers)).session)


@pytest.mark.parametrize("marker", [0, 1, 2, 3])
def test_a_2_mm_normal_offset_moves_the_torque_equation_as_predicted(marker: int) -> None:
    spec = sim.human_arm_cell(seed=3, inertia=False)
    exact = _data(spec, ((0.0, 0.0),) * 4)
    moved_offsets = [(0.0, 0.0)] * 4
    moved_offsets[marker] = (0.0, 0.002)
    moved = _data(spec, tuple(moved_offsets))
    subject = spec.subject
    theta = base_parameters(subject.lengths_m, subject.masses_kg, subject.com_m, [0.0, 0.0, 0.0])
    zeros = np.zeros_like(exact.q_rad)
    columns = placement_columns(exact.q_rad, zeros, zeros, exact.lengths_m, exact.tau_nm, theta)

    def residual(d):  # the torque equation's misfit at the true parameters, on the chain the markers give
        return d.tau_nm - base_regressor(d.q_rad, 0 * d.q_rad, 0 * d.q_rad, d.lengths_m) @ theta

    n = min(exact.t_ns.size, moved.t_ns.size)
    actual = (residual(moved)[:n] - residual(exact)[:n]).mean(axis=0)
    predicted = (columns[:n, :, 2 * marker + 1] * 0.002).mean(axis=0)
    assert np.abs(actual).max() > 0.02  # a 2 mm offset matters (Nm)
    np.testing.assert_allclose(predicted, actual, atol=0.05 * np.abs(actual).max())


@pytest.mark.parametrize(("marker", "axis"), [(1, 0), (1, 1), (2, 0), (2, 1)])
def test_over_a_wide_elbow_range_each_sample_moves_as_predicted(marker: int, axis: int) -> None:
    """The elbow turning 80 deg: a marker fixed in the forearm (or hand) off its joint centre changes the marker
    distance along the segment before it by up to the whole offset, which the chain of median distances the
    torques are computed on does not follow. The columns hold that sample by sample."""
    trajectory = PlannedTrajectory(
        [0.0, 60.0], np.radians([[-60.0, 20.0, -15.0], [-20.0, 100.0, 15.0]]), np.zeros((2, 3))
    )
    spec = sim.human_arm_cell(seed=3, inertia=False, trajectory=trajectory, duration_s=60.0)
    exact = _data(spec, ((0.0, 0.0),) * 4)
    moved_offsets = [(0.0, 0.0)] * 4
    moved_offsets[marker] = (0.002, 0.0) if axis == 0 else (0.0, 0.002)
    moved = _data(spec, tuple(moved_offsets))
    subject = spec.subject
    theta = base_parameters(subject.lengths_m, subject.masses_kg, subject.com_m, [0.0, 0.0, 0.0])
    zeros = np.zeros_like(exact.q_rad)
    columns = placement_columns(exact.q_rad, zeros, zeros, exact.lengths_m, exact.tau_nm, theta)

    def residual(d):
        return d.tau_nm - base_regressor(d.q_rad, 0 * d.q_rad, 0 * d.q_rad, d.lengths_m) @ theta

    n = min(exact.t_ns.size, moved.t_ns.size)
    actual = residual(moved)[:n] - residual(exact)[:n]
    predicted = columns[:n, :, 2 * marker + axis] * 0.002
    # The part of the change no constant (a median length, a static moment's share) takes up, sample by sample.
    actual, predicted = actual - actual.mean(axis=0), predicted - predicted.mean(axis=0)
    assert np.sqrt(np.mean(actual**2)) > 0.005  # the varying part matters (Nm)
    error = np.sqrt(np.mean((predicted - actual) ** 2)) / np.sqrt(np.mean(actual**2))
    assert error < 0.05, error
