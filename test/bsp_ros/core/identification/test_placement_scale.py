"""The markers' placement the data show: offsets fitted without bias, and a placement wider than assumed in the std."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import placement_scale as placement_scale_module
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.identify import identify_joint
from bsp_ros.core.identification.joint.placement_covariance import (
    covariance_from_columns,
    covariance_from_products,
    offset_columns,
    placement_effect,
)
from bsp_ros.core.identification.joint.placement_scale import placement_scale, scale_from_offsets
from bsp_ros.core.identification.joint.refit import refit_held
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.stacked import augmented, fit_problem, reweighted_values
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.quantities import quantities_of

ASSUMED_SD_M = np.full(4, 0.002)
SKIN = np.ones(4, dtype=bool)


def _direction(seed: int) -> np.ndarray:
    v = np.random.default_rng([seed, 11]).standard_normal(3)
    return v / np.linalg.norm(v)


def _spec(seed: int, offset_m: float) -> sim.CellSpec:
    """The human arm cell with each marker ``offset_m`` off its joint centre, in a seeded direction (as
    bench/realism.py's "skin markers 1 cm")."""
    spec = sim.human_arm_cell(seed=seed, duration_s=120.0)
    offsets = tuple(tuple(float(v) for v in offset_m * _direction(seed + k)[:2]) for k in range(4))
    return dataclasses.replace(spec, markers=dataclasses.replace(spec.markers, skin_offset_m=offsets))


@functools.cache
def _simulated(seed: int, offset_m: float) -> sim.SimulatedSession:
    return sim.simulate_cell(_spec(seed, offset_m))


def _fit(data: IdentificationData):
    problem = usable_samples(data, JointConfig()).problem
    return problem, fit_problem(problem)


@pytest.mark.parametrize("seed", [1, 20])
def test_offsets_fitted_with_the_parameters_are_near_zero_when_the_markers_sit_on_the_centres(seed: int) -> None:
    """With the handle force from the measured torques, the wrench noise in the columns correlated with the
    residual's: the offsets (prior 1 sd) came out 6-8 sd from zero on every seed, as if the markers sat 12-16 mm off."""
    data = identification_data_from_session(_simulated(seed, 0.0).session)
    problem, fit = _fit(data)
    columns = offset_columns(data, problem, fit, ASSUMED_SD_M)
    m = columns.shape[2]
    names = [(f"marker_offset_{k}_sd", "markers") for k in range(m)]
    offsets = reweighted_values(augmented(problem, columns, names, np.zeros(m), np.ones(m))).values[-m:]
    assert np.abs(offsets).max() < 1.5, offsets


@pytest.mark.parametrize("seed", [1, 20])
def test_markers_on_their_centres_keep_the_assumed_placement(seed: int) -> None:
    data = identification_data_from_session(_simulated(seed, 0.0).session)
    problem, fit = _fit(data)
    found = placement_scale(problem, offset_columns(data, problem, fit, ASSUMED_SD_M), ASSUMED_SD_M, SKIN)
    assert found.scale < 1.2 and found.note is None, (found.scale, found.likelihood_ratio)
    np.testing.assert_allclose(found.sd_m, ASSUMED_SD_M * found.scale)


@pytest.mark.parametrize("seed", [20, 21])
def test_markers_1_cm_off_widen_the_placement_and_the_std_holds_the_truth(seed: int) -> None:
    """Five times the assumed 2 mm. Before the check both sessions were valid with the elbow's Coulomb amplitude
    3.3 and 4.2 std off."""
    simulated = _simulated(seed, 0.01)
    document = identify_session(simulated.session, IdentifyOptions(subject=SubjectInfo(75.0, 1.78, "male")))
    quality = document["quality"]
    assert quality["valid"], quality["message"]
    placement = quality["marker_placement"]
    assert placement["scale_from_data"] > 2.0, placement
    assert placement["assumed_sd_mm"] == [2.0] * 4
    assert FindingCode.PLACEMENT_WIDER in [f.code for f in findings_of(quality)], quality["warnings"]
    truth = simulated.truth.to_dict()
    z = {}
    for group, owner, key, q in quantities_of(document):
        true = truth[group].get(owner, {}).get(key)
        if q["source"] in ("data", "data+prior") and isinstance(true, float) and q["std"]:
            z[f"{key}/{owner}"] = abs(q["value"] - true) / q["std"]
    assert {"length_m/hand", "static_moment_kgm/forearm", "coulomb_nm/elbow"} <= set(z)
    assert max(z.values()) <= 3.0, sorted(z.items(), key=lambda kv: -kv[1])[:3]


def test_a_refit_holds_the_placement_its_check_found() -> None:
    """A live window's refits between checks keep the checked placement, like the other systematic shares."""
    data = identification_data_from_session(_simulated(20, 0.01).session)
    checked = identify_joint(data)
    assert checked.held is not None
    assert (checked.held.placement_sd_m > 2 * ASSUMED_SD_M).all()
    refit = refit_held(data, checked.held)
    assert refit.held is not None
    np.testing.assert_array_equal(refit.held.placement_sd_m, checked.held.placement_sd_m)
    assert refit.diagnostics["marker_placement"] == checked.diagnostics["marker_placement"]
    # The same placement share: the refit of the same samples has the check's std (its other shares held).
    np.testing.assert_allclose(refit.std, checked.std, rtol=0.05)


def test_a_robot_contact_point_keeps_its_own_sd() -> None:
    data = identification_data_from_session(_simulated(20, 0.01).session)
    problem, fit = _fit(data)
    skin = np.array([True, True, True, False])
    sd_m = np.array([0.002, 0.002, 0.002, 0.0005])
    found = placement_scale(problem, offset_columns(data, problem, fit, sd_m), sd_m, skin)
    assert found.scale > 2.0
    assert found.sd_m[-1] == 0.0005
    np.testing.assert_allclose(found.sd_m[:3], 0.002 * found.scale)


def test_the_handle_force_averages_the_other_samples_noise_out_and_keeps_each_recording_apart() -> None:
    from bsp_ros.core.identification.joint.placement_covariance import AVERAGE_S, averaged_torques

    rng = np.random.default_rng(5)
    t_ns = np.arange(400, dtype=np.int64) * 10_000_000  # 100 Hz
    slow = np.sin(2 * np.pi * 0.2 * t_ns * 1e-9)[:, None] * np.ones((1, 3))
    level = np.where(np.arange(400) < 200, 0.0, 5.0)[:, None]  # a second recording at another torque
    noise = rng.normal(0.0, 0.05, (400, 3))
    base = identification_data_from_session(_simulated(1, 0.0).session)
    data = dataclasses.replace(
        base.window(0, 400), t_ns=t_ns, tau_nm=slow + level + noise, recording_index=(np.arange(400) >= 200).astype(int)
    )
    averaged = averaged_torques(data)
    k = int(AVERAGE_S / 0.01) + 1
    inner = np.r_[k : 200 - k, 200 + k : 400 - k]
    off = averaged[inner] - (slow + level)[inner]
    assert np.std(off) < 1.3 * 0.05 / np.sqrt(k - 1)  # the noise of the k - 1 other samples, averaged
    clean = averaged_torques(dataclasses.replace(data, tau_nm=slow + level))
    assert np.abs(clean[inner] - (slow + level)[inner]).max() < 0.01  # the 0.2 Hz signal kept
    # The 5 Nm step between the recordings is not smeared (half of it would be 2.5 Nm off at the edge).
    assert np.abs(averaged[199] - (slow + level)[199]).max() < 0.25
    assert np.abs(averaged[200] - (slow + level)[200]).max() < 0.25


def test_a_samples_own_noise_is_not_in_its_handle_force() -> None:
    """Errors in variables: a sample's noise in its own column would correlate with the same noise in the residual
    (0.05^2 / k = 4.9e-5 Nm^2 per sample on average); the average of the other samples carries none of it."""
    from bsp_ros.core.identification.joint.placement_covariance import averaged_torques

    rng = np.random.default_rng(11)
    n = 20_000
    noise = rng.normal(0.0, 0.05, (n, 3))
    base = identification_data_from_session(_simulated(1, 0.0).session)
    data = dataclasses.replace(
        base.window(0, 400), t_ns=np.arange(n, dtype=np.int64) * 10_000_000, tau_nm=noise, recording_index=None
    )
    products = (averaged_torques(data) * noise).mean(axis=0)
    assert np.abs(products).max() < 1.5e-5, products


def test_a_friction_the_model_lacks_is_not_taken_for_misplaced_markers() -> None:
    """Free offsets also take up a Stribeck-like friction; the check that names it makes the estimate invalid, and
    the placement is not judged: widened, the std held the 41 % Coulomb error of a model the check rejected."""
    spec = sim.human_arm_cell(seed=0, duration_s=120.0)
    spec = dataclasses.replace(
        spec, passive=dataclasses.replace(spec.passive, stribeck_ratio=1.5, stribeck_speed_rad_s=0.01)
    )
    document = identify_session(sim.simulate_cell(spec).session)
    quality = document["quality"]
    codes = [f.code for f in findings_of(quality)]
    assert not quality["valid"] and FindingCode.UNMODELLED_EFFECT in codes, quality["message"]
    assert "marker_placement" not in quality
    assert FindingCode.PLACEMENT_WIDER not in codes


@pytest.mark.parametrize("seed", [0, 2])
def test_a_drift_is_not_taken_for_misplaced_markers(seed: int) -> None:
    """The offsets are fitted beside a drift's and a spring's columns: before, they took up a drift's slow residual,
    modelled (seed 0) or too small to move the parameters (seed 2, scale 10: "20 mm"), and widened a right
    estimate's std (bench/realism.py, "F/T drift 5 mN/s")."""
    spec = sim.human_arm_cell(seed=seed, duration_s=120.0)
    sensor = dataclasses.replace(spec.sensor, force_drift_n_per_s=tuple(float(v) for v in 0.005 * _direction(seed)))
    document = identify_session(sim.simulate_cell(dataclasses.replace(spec, sensor=sensor)).session)
    quality = document["quality"]
    assert quality["valid"], quality["message"]
    assert quality["marker_placement"]["scale_from_data"] < 1.5, quality["marker_placement"]


def test_the_placement_covariance_from_the_wider_statistics_equals_the_pass_over_every_sample() -> None:
    # placement_effect takes X^T W D from the offsets' augmented statistics (used rows only); covariance_from_columns
    # computes it over every sample with zero weights off the used rows: the same linear covariance, two routes.
    data = identification_data_from_session(_simulated(1, 0.01).session)
    problem, fit = _fit(data)
    effect = placement_effect(data, problem, fit, ASSUMED_SD_M)
    direct = covariance_from_columns(problem, fit, effect.columns)
    assert np.abs(direct).max() > 0
    linear = covariance_from_products(fit, effect.products)
    np.testing.assert_allclose(linear, direct, rtol=1e-9, atol=1e-12 * np.abs(direct).max())
    factor = np.linspace(1.0, 3.0, effect.columns.shape[2])  # a wider placement: the columns scaled
    np.testing.assert_allclose(
        covariance_from_products(fit, effect.products * factor),
        covariance_from_columns(problem, fit, effect.columns * factor),
        rtol=1e-9,
        atol=1e-12 * np.abs(direct).max(),
    )


def _drawn_offsets(seed: int, scale: float, weak_sd: float, weak_bias: float) -> tuple[np.ndarray, np.ndarray]:
    """Eight free offsets (in assumed sd) drawn at ``scale`` times the assumed placement, measured with sd 0.1 in
    seven directions and ``weak_sd`` in one oblique direction, along which a model error adds ``weak_bias``."""
    rng = np.random.default_rng([seed, 57])
    basis, _ = np.linalg.qr(rng.standard_normal((8, 8)))
    covariance = basis @ np.diag([*np.full(7, 0.1**2), weak_sd**2]) @ basis.T
    truth = rng.normal(0.0, scale, 8)
    measured = truth + rng.multivariate_normal(np.zeros(8), covariance) + weak_bias * basis[:, -1]
    return measured, covariance


@pytest.mark.parametrize("seed", range(4))
def test_a_model_error_along_an_offset_direction_the_data_barely_see_does_not_widen_the_placement(seed: int) -> None:
    """An offset the data hardly see (sd 6 assumed sd) takes up any small misfit 1 / variance times over: on
    planned sessions the shoulder marker's offset along the upper arm came out 20-100 assumed sd from zero with
    the markers on their centres. Judged along every direction, that read as markers 2 cm off."""
    offsets, covariance = _drawn_offsets(seed, 1.0, weak_sd=6.0, weak_bias=-50.0)
    judged = scale_from_offsets(offsets, covariance, np.ones(8, dtype=bool))
    assert judged is not None
    assert judged[0] < 1.3, judged
    # Judged along every direction (as the check did), the same offsets call for the widest scale.
    everything = np.linalg.eigh(covariance)[1]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(placement_scale_module, "seen_directions", lambda _: everything)
        wide = scale_from_offsets(offsets, covariance, np.ones(8, dtype=bool))
    assert wide is not None and wide[0] > 3.0, wide


@pytest.mark.parametrize("seed", range(4))
def test_offsets_3_times_the_assumed_placement_are_still_read_along_the_seen_directions(seed: int) -> None:
    offsets, covariance = _drawn_offsets(seed, 3.0, weak_sd=6.0, weak_bias=-50.0)
    judged = scale_from_offsets(offsets, covariance, np.ones(8, dtype=bool))
    assert judged is not None
    most_likely = float(placement_scale_module._GRID[judged[2]])
    assert judged[0] > 1.4 and 1.5 < most_likely < 5.0, (judged, most_likely)
