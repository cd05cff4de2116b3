"""The identification rate: a fast sensor's samples averaged to 100 Hz give the estimate a 100 Hz sensor gives."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.rate import IDENTIFICATION_MAX_RATE_HZ, block_means, block_size
from bsp_ros.core.pipeline import identify_session


def _session(wrench_hz: float):
    spec = sim.human_arm_cell(seed=21, duration_s=60.0)
    spec = dataclasses.replace(spec, sensor=dataclasses.replace(spec.sensor, wrench_hz=wrench_hz))
    return sim.simulate_cell(spec)


@pytest.fixture(scope="module")
def fast_and_slow():
    out = {}
    for rate in (100.0, 1000.0):
        simulated = _session(rate)
        out[rate] = (simulated, identify_session(simulated.session))
    return out


def test_a_1_khz_sensor_is_identified_at_100_hz_and_counts_every_sample(fast_and_slow) -> None:
    simulated, document = fast_and_slow[1000.0]
    assert document["session"]["identification_rate_hz"] == pytest.approx(IDENTIFICATION_MAX_RATE_HZ, rel=0.01)
    assert document["session"]["n_wrench_samples"] == simulated.session.wrench.t_ns.size  # received, not averaged
    assert fast_and_slow[100.0][1]["session"]["identification_rate_hz"] == pytest.approx(100.0, rel=0.01)


def test_the_estimate_does_not_depend_on_the_sensors_rate(fast_and_slow) -> None:
    # Same arm and motion; at 1 kHz the sensor's noise is drawn ten times as often and averaged back to 100 Hz.
    (slow_sim, slow), (_, fast) = fast_and_slow[100.0], fast_and_slow[1000.0]
    truth = slow_sim.truth.to_dict()
    assert slow["quality"]["valid"] and fast["quality"]["valid"]
    for segment, quantities in fast["segments"].items():
        moment, reference = quantities["static_moment_kgm"], slow["segments"][segment]["static_moment_kgm"]
        assert moment["std"] == pytest.approx(reference["std"], rel=0.25)
        assert abs(moment["value"] - truth["segments"][segment]["static_moment_kgm"]) < 3 * moment["std"]
    for joint, quantities in fast["joints"].items():
        coulomb = quantities["coulomb_nm"]
        assert abs(coulomb["value"] - truth["joints"][joint]["coulomb_nm"]) < 3 * coulomb["std"]


def test_slow_streams_and_jittered_clocks_are_left_alone() -> None:
    rng = np.random.default_rng(2)
    jittered = np.cumsum(rng.normal(10_000_000, 300_000, size=500)).astype(np.int64)  # 100 Hz +- 3 % jitter
    assert block_size(jittered, 100.0) == 1
    values = rng.normal(size=(500, 3))
    stamps, means, counts = block_means(jittered, values, 100.0)
    assert stamps is jittered and means is values and (counts == 1).all()
    assert block_size(jittered[:1], 100.0) == 1  # one sample: nothing to average
    assert block_size((np.arange(100) * 2_000_000).astype(np.int64), 100.0) == 5  # 500 Hz in fives
