"""A sensor that turns with the handle: its orientation on /tf, applied per wrench sample by `bsp identify`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from turning_sensor import TurningSession, assert_within_3_std, turning_session

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.findings import FindingCode, findings_of


@pytest.fixture(scope="module")
def turning() -> TurningSession:
    return turning_session(60.0, seed=7, tf_hz=100.0)


@pytest.mark.parametrize("tf_hz", [100.0, 20.0])
def test_a_turning_sensor_on_tf_is_identified_within_3_std(
    tmp_path: Path, turning: TurningSession, tf_hz: float
) -> None:
    # 100 Hz: a /tf sample per wrench sample (on another phase); 20 Hz: five wrench samples per /tf sample.
    samples = turning.tf_samples[:: round(100.0 / tf_hz)]
    bag = write_session_bag(tmp_path / "turning", turning.session, tf_static=False, tf_samples=samples)
    read = read_session(bag)
    rotation = read.session.rotation_world_from_sensor
    assert rotation.shape == (turning.session.wrench.t_ns.size, 3, 3)
    assert read.report.rotation_source == "tf" and not any("/tf" in w for w in read.report.warnings)
    document = identify_bag(bag)
    assert_within_3_std(document, turning)
    assert document["quality"]["rotation"]["source"] == "tf"
    assert document["quality"]["rotation"]["per_sample"] is True
    assert document["quality"]["rotation"]["range_deg"] == pytest.approx(turning.range_deg, abs=0.05)
    assert 9.0 < turning.range_deg < 13.0


def test_the_same_turning_sensor_with_one_fixed_rotation_is_a_fit_failure(
    tmp_path: Path, turning: TurningSession
) -> None:
    # /tf_static only (the mount orientation): nothing says the sensor turns, so the model cannot fit.
    bag = write_session_bag(tmp_path / "fixed", turning.session, tf_static=True)
    document = identify_bag(bag)
    quality = document["quality"]
    assert not quality["valid"] and FindingCode.MODEL_MISFIT in [f.code for f in findings_of(quality)], quality
    assert document["quality"]["rotation"] == {"source": "tf", "per_sample": False, "range_deg": 0.0}


def test_wrench_samples_long_outside_the_tf_track_hold_its_ends_and_are_named(
    tmp_path: Path, turning: TurningSession
) -> None:
    # /tf stops 10 s before the wrench does (a publisher that died): those samples hold the last orientation.
    end = int(turning.session.wrench.t_ns[-1]) - 10_000_000_000
    samples = [s for s in turning.tf_samples if s.t_ns <= end]
    bag = write_session_bag(tmp_path / "short_tf", turning.session, tf_static=False, tf_samples=samples)
    read = read_session(bag)
    held = [w for w in read.report.warnings if "outside its /tf samples" in w]
    assert len(held) == 1 and "nearest orientation is held" in held[0], read.report.warnings
    rotation = read.session.rotation_world_from_sensor
    late = read.session.wrench.t_ns > end
    np.testing.assert_allclose(rotation[late], np.broadcast_to(rotation[late][0], rotation[late].shape), atol=1e-12)
    assert late.sum() > 900
