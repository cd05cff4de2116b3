"""The arm's excursion out of the sagittal plane, measured from the markers' lateral coordinates."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.planarity import out_of_plane_fraction, planar_error_nm
from bsp_ros.core.model import gravity_regressor
from bsp_ros.core.streams import MarkerSeries


def _markers(lateral_amplitude_m: float, noise_m: float, seed: int) -> dict[str, MarkerSeries]:
    """A 0.3 m segment swinging in the plane whose distal marker also swings laterally by the amplitude."""
    rng = np.random.default_rng(seed)
    t_s = np.arange(6000) / 50.0
    t_ns = (1_000_000_000 + t_s * 1e9).astype(np.int64)
    angle = -0.7 + 0.2 * np.sin(2 * np.pi * t_s / 20.0)
    shoulder = np.zeros((t_s.size, 3))
    elbow = np.column_stack(
        (lateral_amplitude_m * np.sin(2 * np.pi * t_s / 20.0), 0.3 * np.cos(angle), 0.3 * np.sin(angle))
    )
    return {
        "shoulder": MarkerSeries(t_ns, shoulder + noise_m * rng.standard_normal(shoulder.shape)),
        "elbow": MarkerSeries(t_ns, elbow + noise_m * rng.standard_normal(elbow.shape)),
    }


def test_the_lateral_swing_is_measured_net_of_marker_noise() -> None:
    # A sine's peak-to-peak range is twice its amplitude: 2 x 3 mm over 0.3 m is 2 %.
    measured = out_of_plane_fraction(_markers(0.003, 1.5e-4, 1), ["shoulder", "elbow"])
    assert abs(measured[0] - 0.02) < 0.001, measured
    # A planar arm with the same marker noise: the noise alone would read as 0.7 % peak to peak.
    assert out_of_plane_fraction(_markers(0.0, 1.5e-4, 2), ["shoulder", "elbow"])[0] < 0.001
    assert out_of_plane_fraction({}, ["shoulder", "elbow"]).tolist() == [0.0]


def test_the_planar_error_is_each_segment_s_share_of_the_gravity_torque_times_its_fraction() -> None:
    q = np.column_stack((np.linspace(-1.0, -0.5, 50), np.full(50, 0.8)))
    beta = np.array([0.8, 0.3])
    error = planar_error_nm(q, beta, np.array([0.0, 0.02]))
    forearm = np.abs(gravity_regressor(q)[:, :, 1] * beta[1])  # its share at each joint
    np.testing.assert_allclose(error, 0.02 * np.sqrt(np.mean(forearm**2, axis=0)))
