"""Passive-moment curves: kept whole, sampled at fixed angles (compared across sessions like any parameter)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsp_ros.cli.session_actions import record_to_json
from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.curves import angle_key, sample_curve
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate
from bsp_ros.errors import StoreError


def _with_curve(seed: int, stiffness: float, day: int = 0) -> dict:
    estimate = sample_estimate(seed, start_time_ns=SAMPLE_START_NS + day * 86_400 * 10**9)
    angle = np.linspace(23.3, 41.9, 40)
    moment = stiffness * np.radians(angle - 30.0) + 0.1  # a linear spring: known at every angle
    estimate["joints"]["elbow"]["passive_curve"] = {
        "angle_deg": angle.tolist(),
        "moment_nm": moment.tolist(),
        "std_nm": [0.01] * angle.size,
    }
    return estimate


def test_curve_round_trips_and_is_sampled_at_multiples_of_five_degrees(tmp_path: Path) -> None:
    with open_store(tmp_path / "s.sqlite") as store:
        stored = store.add_estimate(_with_curve(1, 1.5), "C1")
        store.add_estimate(sample_estimate(2, start_time_ns=SAMPLE_START_NS + 10**12), "C1")  # no curve: fine
        first, second = store.sessions("C1")
    assert first.passive_curves["elbow"]["angle_deg"][0] == pytest.approx(23.3)
    at = {a: first.parameters[("joints", "elbow", angle_key(a))] for a in (25, 30, 35, 40)}
    assert set(k[2] for k in first.parameters if k[2].startswith("passive_moment_at")) == {angle_key(a) for a in at}
    for angle, q in at.items():
        assert q.value == pytest.approx(1.5 * np.radians(angle - 30.0) + 0.1, abs=1e-9) and q.std == pytest.approx(0.01)
    assert not second.passive_curves and stored.number == 1
    shown = record_to_json(first)
    assert "passive_curve" in shown["joints"]["elbow"] and angle_key(30) not in shown["joints"]["elbow"]


def test_a_malformed_curve_is_refused(tmp_path: Path) -> None:
    estimate = _with_curve(1, 1.5)
    estimate["joints"]["elbow"]["passive_curve"]["moment_nm"].pop()
    with open_store(tmp_path / "s.sqlite") as store, pytest.raises(StoreError, match="differ in length"):
        store.add_estimate(estimate, "C1")


def test_sampling_does_not_extrapolate() -> None:
    assert sample_curve({"angle_deg": [31.0, 34.0], "moment_nm": [1.0, 2.0], "std_nm": [0.1, 0.1]}) == {}
