"""Skin markers re-placed per session: offsets drawn within the bound from the seed, recorded, and where they sit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core.simulation import CellSimulator, MarkerSpec, human_arm_cell, paper_mechanical_arm_cell, simulate_cell
from bsp_ros.errors import InputError


def _cell(seed: int, bound_m: float, base_offsets: tuple = (), paper: bool = False):
    spec = paper_mechanical_arm_cell(seed=seed, duration_s=4.0) if paper else human_arm_cell(seed=seed, duration_s=4.0)
    markers = dataclasses.replace(spec.markers, skin_offset_bound_m=bound_m, skin_offset_m=base_offsets, noise_m=0.0)
    return dataclasses.replace(spec, markers=markers)


@pytest.mark.parametrize("paper", [False, True])
def test_skin_offsets_are_drawn_within_the_bound_recorded_and_where_the_markers_sit(paper: bool) -> None:
    spec = _cell(seed=11, bound_m=0.008, paper=paper)
    sim = CellSimulator(spec)
    offsets = np.array(sim.skin_offsets_m)
    assert offsets.shape == (spec.n_segments + 1, 2)
    assert np.abs(offsets).max() <= 0.008 and np.abs(offsets).max() > 0.004  # within, and not all tiny
    assert len({round(v, 12) for v in offsets.ravel()}) == offsets.size  # one draw per marker and axis
    simulation = sim.truth.to_dict()["simulation"]
    assert simulation["skin_offset_bound_m"] == 0.008
    np.testing.assert_array_equal(simulation["skin_offset_m"], offsets)
    # The markers sit at their drawn offsets in the frame of the segment that starts at their joint.
    t = np.linspace(0.0, 4.0, 9)
    q = sim.joint_angles_rad(t)
    phi = np.cumsum(q, axis=1)
    centres = CellSimulator(_cell(seed=11, bound_m=0.0, paper=paper)).marker_positions_m(t)
    for i, (name, xyz) in enumerate(sim.marker_positions_m(t).items()):
        angle = phi[:, min(i, q.shape[1] - 1)]
        axis, normal = np.column_stack([np.cos(angle), np.sin(angle)]), np.column_stack([-np.sin(angle), np.cos(angle)])
        want = centres[name][:, 1:] + offsets[i, 0] * axis + offsets[i, 1] * normal
        np.testing.assert_allclose(xyz[:, 1:], want, atol=1e-15)


def test_the_draw_follows_the_seed_and_leaves_every_other_stream_unchanged() -> None:
    a, b, c = (CellSimulator(_cell(seed, 0.01)) for seed in (3, 3, 4))
    assert a.skin_offsets_m == b.skin_offsets_m != c.skin_offsets_m
    with_draw, without = simulate_cell(_cell(3, 0.01)).session, simulate_cell(_cell(3, 0.0)).session
    np.testing.assert_array_equal(with_draw.wrench.force_n, without.wrench.force_n)
    for name, series in with_draw.markers.items():
        np.testing.assert_array_equal(series.t_ns, without.markers[name].t_ns)
        assert 0.0 < np.abs(series.position_m - without.markers[name].position_m).max() <= 0.01 * np.sqrt(2) + 1e-12


def test_a_draw_adds_to_given_offsets() -> None:
    base = ((0.0, 0.01), (0.0, 0.01), (0.0, 0.01), (0.0, 0.01))
    drawn = np.array(CellSimulator(_cell(5, 0.002, base)).skin_offsets_m)
    assert np.abs(drawn - np.array(base)).max() <= 0.002
    assert CellSimulator(_cell(5, 0.0, base)).skin_offsets_m == base  # no bound: exactly the given ones


@pytest.mark.parametrize("bound", [-0.001, 0.2, float("inf")])
def test_a_bad_bound_is_refused_naming_it(bound: float) -> None:
    with pytest.raises(InputError, match="skin_offset_bound_m"):
        MarkerSpec(skin_offset_bound_m=bound)
