"""The truth file of a simulated session: round trip, every nuisance recorded, foreign or old files."""

from __future__ import annotations

import json

import pytest

from bsp_ros.core.simulation import (
    MarkerSpec,
    PassiveTruth,
    SensorSpec,
    SessionTruth,
    human_arm_cell,
    paper_mechanical_arm_cell,
    simulate_cell,
)
from bsp_ros.errors import InputError


def _rich_passive_human():
    return human_arm_cell(
        passive=PassiveTruth(
            coulomb_nm=(0.5, 0.28, 0.06),
            viscous_nms=(0.8, 0.3, 0.1),
            stiffness_nm_per_rad=(0.2, 1.2, 0.05),
            neutral_rad=(-0.5, 1.87, 0.0),
            offset_nm=(0.1, -0.2, 0.03),
        )
    )


def test_truth_round_trips_through_json() -> None:
    truth = simulate_cell(_rich_passive_human()).truth
    text = json.dumps(truth.to_dict())
    back = SessionTruth.from_dict(json.loads(text))
    assert back == truth
    d = json.loads(text)
    assert d["schema"] == "bsp_ros/truth/1"
    assert set(d["joints"]["elbow"]) == {
        "coulomb_nm",
        "viscous_nms",
        "stiffness_nm_per_rad",
        "neutral_rad",
        "offset_nm",
        "stiffening_nm",
    }
    assert d["simulation"]["wrench_hz"] == 100.0 and d["simulation"]["marker_hz"] == 50.0
    assert d["simulation"]["seed"] == 0 and d["simulation"]["force_noise_n"] == 0.05


def test_truth_from_dict_rejects_a_foreign_schema_and_missing_keys() -> None:
    d = simulate_cell(paper_mechanical_arm_cell(duration_s=1.0)).truth.to_dict()
    with pytest.raises(InputError, match="bsp_ros/core/estimate/1"):
        SessionTruth.from_dict({**d, "schema": "bsp_ros/core/estimate/1"})
    del d["segments"]["forearm"]["mass_kg"]
    with pytest.raises(InputError, match="mass_kg"):
        SessionTruth.from_dict(d)


def test_truth_records_every_nuisance_and_reads_back() -> None:
    spec = human_arm_cell(
        passive=PassiveTruth(
            coulomb_nm=(0.5, 0.28, 0.06),
            offset_nm=(0.05, -0.2, 0.0),
            friction_transition_rad_s=0.002,
            stribeck_ratio=1.3,
            stribeck_speed_rad_s=0.02,
        ),
        sensor=SensorSpec(force_drift_n_per_s=(0.0, 0.001, 0.0), handle_mass_kg=0.3, handle_com_m=(0.0, 0.0, 0.04)),
        markers=MarkerSpec(skin_offset_m=((0.0, 0.01),) * 4),
        duration_s=5.0,
    )
    data = json.loads(json.dumps(simulate_cell(spec).truth.to_dict()))
    assert data["friction"] == {"transition_rad_s": 0.002, "stribeck_ratio": 1.3, "stribeck_speed_rad_s": 0.02}
    assert data["joints"]["elbow"]["offset_nm"] == -0.2
    sim = data["simulation"]
    assert (sim["handle_mass_kg"], sim["handle_com_m"]) == (0.3, [0.0, 0.0, 0.04])
    assert sim["force_drift_n_per_s"] == [0.0, 0.001, 0.0]
    assert sim["skin_offset_m"] == [[0.0, 0.01]] * 4
    back = SessionTruth.from_dict(data)
    assert back.passive == spec.passive


def test_truth_without_a_friction_block_reads_as_plain_coulomb() -> None:
    data = simulate_cell(human_arm_cell(duration_s=2.0)).truth.to_dict()
    del data["friction"]
    passive = SessionTruth.from_dict(data).passive
    assert (passive.friction_transition_rad_s, passive.stribeck_ratio) == (0.0, 1.0)
