"""Masses and COMs: the anthropometric prior fused with identified static moments."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.fusion import SubjectInfo, anthropometric_prior, fuse_static_moments, implausible_static_moments
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.errors import InputError


@pytest.fixture(scope="module")
def documents_and_truths():
    """Six subjects drawn from the prior, identified with paper-like noise."""
    out = []
    for seed in range(6):
        subject = sim.SubjectTruth.from_anthropometry("female", 62.0, 1.66, 3, rng=np.random.default_rng(100 + seed))
        session = sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=100 + seed))
        options = IdentifyOptions(subject=SubjectInfo(62.0, 1.66, "female"), marker_placement_sd_m=0.0)
        document = identify_session(session.session, options)
        out.append((document, session.truth.to_dict()))
    return out


def test_truth_lies_within_three_std_for_99_percent_of_parameters(documents_and_truths) -> None:
    z = []
    for document, truth in documents_and_truths:
        for group in ("segments", "joints"):
            for owner, quantities in document[group].items():
                for key, q in quantities.items():
                    z.append((q["value"] - truth[group][owner][key]) / q["std"])
    z = np.abs(np.array(z))
    # Lengths, static, first moments, masses, COMs, perpendicular moments, the three inertias; Coulomb.
    assert len(z) == 6 * (3 * 9 + 3)
    assert (z < 3).mean() >= 0.99, np.sort(z)[-5:]
    assert np.median(z) > 0.2  # honest, not inflated to pass


def test_mass_and_com_are_marked_data_plus_prior_and_static_moments_data(documents_and_truths) -> None:
    document, _ = documents_and_truths[0]
    forearm = document["segments"]["forearm"]
    assert forearm["static_moment_kgm"]["source"] == "data"
    assert forearm["length_m"]["source"] == "data"
    assert forearm["mass_kg"]["source"] in ("data+prior", "prior")
    assert forearm["com_m"]["source"] in ("data+prior", "prior")


def test_data_narrows_the_prior() -> None:
    lengths = np.array([0.29, 0.27, 0.09])
    prior = anthropometric_prior(SubjectInfo(75.0, None, "male"), lengths)
    beta = np.array([0.82, 0.28, 0.032])
    posterior = fuse_static_moments(prior, lengths, beta, np.diag((1e-4 * beta) ** 2))
    assert (posterior.prior_share <= 1.0 + 1e-9).all()
    assert posterior.prior_share[2] < 0.5  # the hand's mass and COM share m3 l3 = beta_hand
    np.testing.assert_allclose(posterior.first_moments_kgm[2], 0.032, rtol=1e-3)


def test_without_body_mass_the_prior_is_population_wide_and_says_so() -> None:
    prior = anthropometric_prior(SubjectInfo(), np.array([0.29, 0.27, 0.09]))
    assert any("no body mass given" in note for note in prior.notes)
    with_mass = anthropometric_prior(SubjectInfo(78.0), np.array([0.29, 0.27, 0.09]))
    assert (np.diag(prior.covariance)[:3] > np.diag(with_mass.covariance)[:3]).all()


@pytest.mark.parametrize(
    ("kwargs", "named"),
    [
        ({"body_mass_kg": -70.0}, "body mass"),
        ({"body_mass_kg": 1000.0}, "body mass"),
        ({"body_mass_kg": float("nan")}, "body mass"),
        ({"height_m": 17.5}, "height"),
        ({"sex": "robot"}, "sex"),
    ],
)
def test_absurd_subject_data_is_refused_with_the_value_named(kwargs, named) -> None:
    with pytest.raises(InputError, match=named):
        SubjectInfo(**kwargs)


def test_a_static_moment_is_implausible_only_beyond_its_std() -> None:
    """Far above the prior's static moment with a small std is a fault (a lost transform); the same value whose
    3 std reach back into the plausible range is an honest, wide estimate (one posture, full elastic family)."""
    subject = SubjectInfo(body_mass_kg=70.0, sex="male")
    lengths = np.array([0.30, 0.27])
    assert implausible_static_moments(subject, lengths, np.array([1.0, 0.3])) == []
    high = implausible_static_moments(subject, lengths, np.array([1.0, 3.0]))
    assert [(f.code, f.where) for f in high] == [(FindingCode.STATIC_MOMENT_IMPLAUSIBLE, "forearm")]
    limit = high[0].values["typical_kgm"] * high[0].values["factor"]  # the plausible upper limit
    wide, narrow = (3.0 - limit) / 2.9, (3.0 - limit) / 3.1  # 3 std reach into the range / stop short of it
    assert implausible_static_moments(subject, lengths, np.array([1.0, 3.0]), beta_std_kgm=np.array([0.0, wide])) == []
    assert implausible_static_moments(subject, lengths, np.array([1.0, 3.0]), beta_std_kgm=np.array([0.0, narrow]))


@pytest.mark.parametrize("seed", range(5))
def test_the_posterior_is_scipys_bounded_least_squares_minimum(seed: int) -> None:
    """Gauss-Newton inside the bounds against scipy's dogbox (what the fusion called before), on static moments
    drawn around the prior's with one to twenty percent std."""
    from scipy.optimize import least_squares

    from bsp_ros.core.model import static_moments_jacobian, static_moments_kgm

    rng = np.random.default_rng(seed)
    lengths = np.array([0.30, 0.27, 0.09]) * rng.uniform(0.9, 1.1, 3)
    prior = anthropometric_prior(SubjectInfo(body_mass_kg=float(rng.uniform(55, 95))), lengths)
    beta_mean = static_moments_kgm(lengths, prior.mean[:3], prior.mean[3:])
    beta_std = beta_mean * rng.uniform(0.01, 0.2, 3)
    beta = beta_mean * (1 + rng.normal(scale=0.1, size=3))
    posterior = fuse_static_moments(prior, lengths, beta, np.diag(beta_std**2))
    data_whiten, prior_whiten = np.diag(1 / beta_std), np.linalg.inv(np.linalg.cholesky(prior.covariance))

    def residual(x):
        model = static_moments_kgm(lengths, x[:3], x[3:])
        return np.concatenate((data_whiten @ (model - beta), prior_whiten @ (x - prior.mean)))

    def jacobian(x):
        return np.vstack((data_whiten @ static_moments_jacobian(lengths, x[:3], x[3:]), prior_whiten))

    bounds = (np.full(6, 1e-6), np.concatenate((np.full(3, 50.0), 1.5 * lengths)))
    reference = least_squares(residual, prior.mean, jac=jacobian, bounds=bounds, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    np.testing.assert_allclose(posterior.mean, reference.x, rtol=1e-7)


def test_a_first_moment_is_labelled_by_its_own_share_of_the_prior() -> None:
    """Static moments known to 1 % give every first moment from the data, ones the data cannot tell (+-300 %: an
    elastic model on one posture) leave them to the prior; with only the upper arm's blind, the others' static
    moments still move its mass through the body mass the segments share."""
    lengths = np.array([0.288, 0.275, 0.088])
    prior = anthropometric_prior(SubjectInfo(), lengths)
    n = lengths.size
    truth = prior.mean
    beta = np.array([truth[k] * truth[n + k] for k in range(n)])
    beta[:2] += lengths[:2] * np.array([truth[1] + truth[2], truth[2]])
    precise = fuse_static_moments(prior, lengths, beta, np.diag((0.01 * beta) ** 2))
    assert precise.first_moments_prior_share.max() < 0.1
    assert [precise.first_moment_source(j) for j in range(n)] == ["data+prior"] * n
    blind = fuse_static_moments(prior, lengths, beta, np.diag((3.0 * beta) ** 2))
    assert [blind.first_moment_source(j) for j in range(n)] == ["prior"] * n
    # The upper arm's own static moment blind, the others precise: its mass moves with the body mass they tell.
    sd = np.array([0.8 * beta[0], 0.01 * beta[1], 0.01 * beta[2]])
    partly = fuse_static_moments(prior, lengths, beta, np.diag(sd**2))
    assert 0.3 < partly.first_moments_prior_share[0] < 0.9
