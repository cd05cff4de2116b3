"""Tremor: a 3-12 Hz oscillation found in series with a known one, taken out, and reported on a simulated arm."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.tremor import band_stopped, tremor_in

RATE_HZ = 200.0
EXACT = JointConfig(marker_placement_sd_m=0.0)


def _series(seconds: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Times (N,) s and a slow motion's torque with white noise (N, 2): no tremor in it."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    slow = np.column_stack((3.0 * np.sin(2 * np.pi * 0.02 * t), 1.0 * np.sin(2 * np.pi * 0.05 * t + 1.0)))
    return t, slow + rng.normal(0.0, 0.01, slow.shape)


def test_a_slow_motion_with_noise_has_no_tremor() -> None:
    _, values = _series(60.0, seed=1)
    assert not tremor_in(values, RATE_HZ).present.any()


def test_a_tremor_is_found_at_its_frequency_with_its_size() -> None:
    t, values = _series(60.0, seed=2)
    values[:, 1] += 0.08 * np.sin(2 * np.pi * 5.2 * t)  # 0.057 Nm RMS at 5.2 Hz
    found = tremor_in(values, RATE_HZ)
    assert list(found.present) == [False, True]
    assert found.frequency_hz == pytest.approx(5.2, abs=0.25)
    assert found.rms[1] == pytest.approx(0.08 / np.sqrt(2), rel=0.1)


def test_the_band_stop_takes_the_tremor_out_and_keeps_the_motion() -> None:
    t, values = _series(60.0, seed=3)
    tremor = 0.2 * np.sin(2 * np.pi * 4.5 * t)
    calmed = band_stopped(values + np.column_stack((tremor, tremor)), RATE_HZ, np.array([True, False]))
    assert np.sqrt(np.mean((calmed[:, 0] - values[:, 0]) ** 2)) < 0.01  # the noise's own band, not the tremor
    assert np.allclose(calmed[:, 1], values[:, 1] + tremor)


@pytest.fixture(scope="module")
def session() -> sim.SimulatedSession:
    subject = sim.SubjectTruth.from_anthropometry("female", 62.0, 1.66, 3, rng=np.random.default_rng(21))
    return sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=21, duration_s=60.0))


@pytest.fixture(scope="module")
def data(session: sim.SimulatedSession) -> IdentificationData:
    return identification_data_from_session(session.session)


def test_a_tremor_in_the_joints_is_reported_and_leaves_the_estimate_right(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    shaking = np.outer(np.sin(2 * np.pi * 5.0 * t_s), [0.3, 0.3, 0.1])  # Elble 2013: 0.1-1 Nm at the wrist
    result = identify_joint(dataclasses.replace(data, tau_nm=data.tau_nm + shaking), EXACT)
    assert result.valid
    (tremor,) = [f for f in result.findings if f.code is FindingCode.TREMOR]
    assert tremor.values["frequency_hz"] == pytest.approx(5.0, abs=0.25)
    assert tremor.values["torque_nm"] == pytest.approx(0.3 / np.sqrt(2), rel=0.15)
    spikes = [f.values["n"] for f in result.findings if f.code is FindingCode.WRENCH_SPIKES_REMOVED]
    assert sum(spikes) < 0.01 * data.t_ns.size  # its swings are not taken for wrench spikes
    _, beta, covariance = result.block("static_moment_kgm")
    z = (beta - np.asarray(session.truth.static_moments_kgm)) / np.sqrt(np.diag(covariance))
    assert np.abs(z).max() < 2.5, z
    plain = identify_joint(data, EXACT)
    assert FindingCode.TREMOR not in [f.code for f in plain.findings]


def test_a_joint_the_tremor_shakes_has_its_friction_called_the_sessions(data: IdentificationData) -> None:
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    shaken = data.q_rad.copy()
    shaken[:, 1] += np.radians(0.3) * np.sin(2 * np.pi * 5.0 * t_s)  # the elbow shaken by 0.3 deg
    torque = data.tau_nm + np.outer(np.sin(2 * np.pi * 5.0 * t_s), [0.0, 0.2, 0.0])
    result = identify_joint(dataclasses.replace(data, q_rad=shaken, tau_nm=torque), EXACT)
    codes = [(f.code, f.where) for f in result.findings]
    assert (FindingCode.TREMOR_FRICTION, "elbow") in codes and result.weak
    assert [where for code, where in codes if code is FindingCode.TREMOR_FRICTION] == ["elbow"]
    # Its Coulomb amplitude's std now covers the friction the shaking may have hidden.
    plain = identify_joint(data, EXACT)
    column = result.names.index(("coulomb_nm", "elbow"))
    assert result.covariance[column, column] > 4 * plain.covariance[column, column]


def test_the_share_of_friction_a_dither_leaves_follows_the_arcsine_law() -> None:
    from bsp_ros.core.identification.joint.tremor_step import dithered_share

    assert dithered_share(np.array([0.02, -0.03]), 0.0) == 1.0
    assert dithered_share(np.array([0.2, -0.3]), 0.01) == 1.0  # the motion always faster than the dither's peak
    peak = np.sqrt(2.0) * 0.01
    assert dithered_share(np.array([0.5 * peak]), 0.01) == pytest.approx(2.0 / np.pi * np.arcsin(0.5))
