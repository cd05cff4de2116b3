"""The model choice's spread under marker placement: each candidate's response to an offset, against a refit."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.placement_covariance import covariance_from_columns, offset_columns
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.selection import (
    Candidate,
    Selection,
    placement_response,
    select_passive,
    spread_covariance,
)
from bsp_ros.core.identification.stacked import build_problem, fit_problem

AUTO = PassiveModel.parse("auto")
SD_M = np.full(4, 0.002)


@functools.cache
def _selected() -> tuple[IdentificationData, np.ndarray, Selection]:
    """A 60 s session of an arm with springs (several models stay open) and its selection."""
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), offset_nm=(0.3, 0.3, 0.1), stiffness_nm_per_rad=(0.5, 0.5, 0.2)
    )
    spec = sim.human_arm_cell(seed=4, duration_s=60.0, passive=passive)
    data = identification_data_from_session(sim.simulate_cell(spec).session)
    rows = usable_samples(data, JointConfig(passive=AUTO)).rows
    return data, rows, select_passive(data, AUTO, rows, None, None)


def _refit(candidate: Candidate, data: IdentificationData, rows: np.ndarray, shift_nm: np.ndarray) -> np.ndarray:
    """The candidate's parameters refitted on the torques moved by ``shift_nm`` (N, n)."""
    moved = dataclasses.replace(data, tau_nm=data.tau_nm + shift_nm)
    return fit_problem(build_problem(moved, candidate.model, rows, None, None)).values


def test_each_open_model_moves_with_an_offset_as_its_response_says() -> None:
    data, rows, selection = _selected()
    chosen = selection.chosen
    assert chosen.problem is not None and chosen.fit is not None
    columns = offset_columns(data, chosen.problem, chosen.fit, SD_M)
    others = [c for c in selection.open_models if c is not selection.probe]
    assert others, "the session leaves no model open"
    # A fit with a parameter held at its bound (a stiffness >= 0) answers as a smaller model: left out here.
    unbounded = [c for c in [chosen, *others] if c.fit is not None and np.all(c.fit.values != 0.0)]
    assert len(unbounded) >= 2
    for candidate in unbounded:
        assert candidate.fit is not None
        response = placement_response(candidate, columns)
        for k in (3, 5, 7):  # normal offsets of the elbow, wrist and contact markers: the largest lever effects
            step = 0.2  # of the assumed sd: small enough for the robust weights to stay
            shift = step * np.nan_to_num(columns[:, :, k])
            moved = (_refit(candidate, data, rows, shift) - candidate.fit.values) / step
            scale = np.abs(response[:, k]).max()
            np.testing.assert_allclose(moved, response[:, k], atol=0.05 * scale, err_msg=candidate.model.label)


def test_the_placement_only_widens_the_spread_and_by_the_difference_it_makes() -> None:
    data, _, selection = _selected()
    chosen = selection.chosen
    assert chosen.problem is not None and chosen.fit is not None
    columns = offset_columns(data, chosen.problem, chosen.fit, SD_M)
    without, _ = spread_covariance(selection)
    with_placement, _ = spread_covariance(selection, columns)
    assert np.all(np.diag(with_placement) >= np.diag(without) - 1e-15)
    # Per parameter, at most the largest variance placement adds to any open model's difference.
    mine = placement_response(chosen, columns)
    added = np.zeros(len(chosen.problem.names))
    for candidate in selection.open_models:
        if candidate is selection.probe:
            continue
        assert candidate.problem is not None
        index = {name: i for i, name in enumerate(candidate.problem.names)}
        shared = [i for i, name in enumerate(chosen.problem.names) if name in index]
        difference = placement_response(candidate, columns)[[index[chosen.problem.names[i]] for i in shared]]
        added[shared] = np.maximum(added[shared], np.sum((difference - mine[shared]) ** 2, axis=1))
    assert np.all(np.diag(with_placement) <= np.diag(without) + added + 1e-15)
    assert np.any(np.diag(with_placement) > np.diag(without) * 1.01)


def test_placement_response_of_the_chosen_model_gives_its_placement_covariance() -> None:
    data, _, selection = _selected()
    chosen = selection.chosen
    assert chosen.problem is not None and chosen.fit is not None
    columns = offset_columns(data, chosen.problem, chosen.fit, SD_M)
    response = placement_response(chosen, columns)
    np.testing.assert_allclose(response @ response.T, covariance_from_columns(chosen.problem, chosen.fit, columns))
