"""The recursive identifier: convergence, freezing without excitation, reset."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from bsp_ros.core.identification.recursive import RecursiveIdentifier
from bsp_ros.core.model import contact_torques_nm


def _samples(stamps, wrench, angles, still_after_s: float | None = None) -> Iterator[tuple]:
    """``(t_ns, q_rad, velocity_rad_s, tau_nm)`` of each wrench with the newest joint state at or before it."""
    k = 0
    for i, t in enumerate(stamps):
        while k + 1 < len(angles) and angles[k + 1][0] <= t:
            k += 1
        if angles[k][0] > t:
            continue
        sample = angles[k][1]
        velocity = sample.velocity_rad_s
        if still_after_s is not None and (t - stamps[0]) / 1e9 > still_after_s:
            velocity = np.zeros(3)
        tau = contact_torques_nm(sample.q_rad[None], sample.lengths_m, wrench[i][None])[0]
        yield int(t), sample.q_rad, velocity, tau


def _run(identifier: RecursiveIdentifier, stamps, wrench, angles, still_after_s: float | None = None) -> None:
    for sample in _samples(stamps, wrench, angles, still_after_s):
        identifier.update(*sample)


def test_recursive_estimate_converges_to_the_truth(live_streams) -> None:
    simulated, stamps, wrench, angles, _raw = live_streams
    identifier = RecursiveIdentifier(3)
    _run(identifier, stamps, wrench, angles)
    result = identifier.result()
    assert result.valid, result.message
    truth = simulated.truth
    for j in range(3):
        assert result.values[j] == pytest.approx(truth.static_moments_kgm[j], rel=0.01)
    for joint in ("shoulder", "elbow", "wrist"):
        assert result.value("coulomb_nm", joint) == pytest.approx(
            truth.to_dict()["joints"][joint]["coulomb_nm"], rel=0.1
        )


def test_without_excitation_the_estimate_and_its_covariance_are_frozen(live_streams) -> None:
    _, stamps, wrench, angles, _raw = live_streams
    identifier = RecursiveIdentifier(3)
    _run(identifier, stamps[: len(stamps) // 2], wrench, angles)
    before_values, before_cov = identifier.theta.copy(), identifier.covariance.copy()
    updates = identifier.n_updates
    _run(identifier, stamps, wrench, angles, still_after_s=0.0)  # the arm held still: no direction of motion
    np.testing.assert_array_equal(identifier.theta, before_values)
    np.testing.assert_allclose(identifier.covariance, before_cov)
    assert identifier.n_updates == updates


def test_reset_forgets_everything(live_streams) -> None:
    _, stamps, wrench, angles, _raw = live_streams
    identifier = RecursiveIdentifier(3)
    _run(identifier, stamps[:2000], wrench, angles)
    identifier.reset()
    assert identifier.n_updates == 0 and not identifier.result().valid


def test_samples_folded_in_together_give_the_one_at_a_time_estimate(live_streams) -> None:
    """The live feed folds in the ~10 wrenches a joint state releases at once (one solve, the residuals against the
    estimate before them): the same samples counted, and the estimate within a twentieth of its std of folding
    them in one at a time."""
    _, stamps, wrench, angles, _raw = live_streams
    single, batched = RecursiveIdentifier(3), RecursiveIdentifier(3)
    _run(single, stamps, wrench, angles)
    samples = list(_samples(stamps, wrench, angles))
    folded = sum(batched.update_many(samples[s : s + 10]) for s in range(0, len(samples), 10))
    assert folded == batched.n_updates == single.n_updates
    std = np.sqrt(np.diag(single.covariance))
    assert (np.abs(batched.theta - single.theta) / std).max() < 0.05  # measured: 0.011
    assert batched.result().valid
