"""Effects the model lacks (a drifting sensor, Stribeck-like friction) make the estimate invalid, named."""

from __future__ import annotations

import dataclasses

import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import identify_joint
from bsp_ros.core.identification.result import IdentificationResult


def identified(seed: int, **changes: object) -> IdentificationResult:
    """60 s of the human arm with sensor or passive changes (``sensor__name`` / ``passive__name``)."""
    spec = sim.human_arm_cell(seed=seed, duration_s=60.0)
    sensor = {k.removeprefix("sensor__"): v for k, v in changes.items() if k.startswith("sensor__")}
    passive = {k.removeprefix("passive__"): v for k, v in changes.items() if k.startswith("passive__")}
    spec = dataclasses.replace(
        spec,
        sensor=dataclasses.replace(spec.sensor, **sensor),  # type: ignore[arg-type]
        passive=dataclasses.replace(spec.passive, **passive),  # type: ignore[arg-type]
    )
    return identify_joint(identification_data_from_session(sim.simulate_cell(spec).session))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_clean_session_shows_neither_drift_nor_speed_dependent_friction(seed: int) -> None:
    result = identified(seed)
    assert result.valid, result.message
    assert not any("drifts" in w or "Stribeck" in w for w in result.warnings)


def test_a_drifting_force_sensor_makes_the_estimate_invalid_and_is_named() -> None:
    """10 mN/s along world y and z: 0.6 N over the minute, which biases the static moments."""
    result = identified(2, sensor__force_drift_n_per_s=(0.0, 0.007, 0.007))
    assert not result.valid
    assert any("the wrench drifts during the session" in w for w in result.warnings)


def test_stribeck_like_friction_makes_the_estimate_invalid_and_names_the_joint() -> None:
    """Friction 1.5 times larger below 10 mrad/s: a sign step's amplitude is then a speed-dependent average."""
    result = identified(3, passive__stribeck_ratio=1.5, passive__stribeck_speed_rad_s=0.01)
    assert not result.valid
    assert any("friction at the elbow depends on speed (Stribeck-like" in w for w in result.warnings)
