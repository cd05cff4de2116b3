"""bsp_identifier's settings from parameter values, without rclpy: defaults, the wrench delay's one meaning, and
errors that name the parameter."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core.identification.timing import measured_stamps_ns, parameter_timing
from bsp_ros.errors import InputError
from bsp_ros.live.online.identifier_modes import RecursiveMode, WindowedMode, mode_for
from bsp_ros.live.online.identifier_settings import PARAMETERS, IdentifierSettings


def test_defaults_make_the_windowed_mode_with_the_named_passive_model() -> None:
    settings = IdentifierSettings.from_parameters({})
    assert settings.mode == "windowed" and settings.n_segments == 3 and settings.window_s == 30.0
    assert settings.options.passive.label == "coulomb" and not settings.options.elastic_fallback
    assert settings.options.subject.body_mass_kg is None and settings.options.tare is None
    np.testing.assert_allclose(settings.wrench_frame_rotation, np.eye(3))
    assert isinstance(mode_for(settings), WindowedMode)
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.mode = "recursive"  # type: ignore[misc]


def test_values_as_declared_are_taken() -> None:
    values = {p.name: p.default for p in PARAMETERS} | {
        "mode": "recursive",
        "n_segments": 2,
        "passive": "coulomb+viscous",
        "body_mass_kg": 72.0,
        "wrench_delay_s": 0.004,
    }
    settings = IdentifierSettings.from_parameters(values)
    assert settings.n_segments == 2 and settings.options.subject.body_mass_kg == 72.0
    assert settings.options.passive.label == "coulomb+viscous"
    assert isinstance(mode_for(settings), RecursiveMode)


def test_the_wrench_delay_has_one_meaning_live_and_offline() -> None:
    unset = IdentifierSettings.from_parameters({})
    # Unset: offline estimates it (IdentifyOptions.wrench_delay_s None); live cannot per update and applies 0.
    assert unset.wrench_delay_s is None and unset.options.wrench_delay_s is None
    assert unset.live_wrench_delay_s == 0.0 and "unset" in unset.wrench_delay_note
    assert parameter_timing(unset.options.wrench_delay_s)["source"] == "none"
    known = IdentifierSettings.from_parameters({"wrench_delay_s": 0.02})
    assert known.options.wrench_delay_s == known.live_wrench_delay_s == 0.02  # seconds, as `bsp identify` takes it
    assert parameter_timing(known.options.wrench_delay_s) == {
        "wrench_delay_s": 0.02,
        "wrench_delay_std_s": 0.0,
        "source": "parameter",
    }
    # One function shifts a stamp and a session's stamps alike.
    stamps = np.array([1_000_000_000, 1_020_000_000], dtype=np.int64)
    assert measured_stamps_ns(1_020_000_000, 0.02) == 1_000_000_000
    np.testing.assert_array_equal(measured_stamps_ns(stamps, 0.02), stamps - 20_000_000)


@pytest.mark.parametrize(
    ("values", "named"),
    [
        ({"mode": "batch"}, "'mode'"),
        ({"n_segments": 4}, "'n_segments'"),
        ({"n_segments": 2.0}, "'n_segments'"),
        ({"window_s": float("nan")}, "'window_s'"),
        ({"update_hz": 0.0}, "'update_hz'"),
        ({"wrench_delay_s": 11.0}, "'wrench_delay_s'"),
        ({"wrench_delay_s": "0.01"}, "'wrench_delay_s'"),
        ({"stale_s": True}, "'stale_s'"),
        ({"sex": "other"}, "'sex'"),
        ({"world_frame": None}, "'world_frame'"),
        ({"passive": "coulomb+nonsense"}, "parameter passive"),
        ({"wrench_frame_rotation_xyzw": [0.0, 0.0, 0.0, 2.0]}, "parameter wrench_frame_rotation_xyzw"),
        ({"tare_file": "/nonexistent/tare.yaml"}, "parameter tare_file /nonexistent/tare.yaml"),
        ({"window": 30.0}, "window"),
    ],
)
def test_a_value_not_taken_is_refused_naming_its_parameter(values: dict, named: str) -> None:
    with pytest.raises(InputError, match=f"bsp_identifier: .*{named}"):
        IdentifierSettings.from_parameters(values)


def test_the_frame_source_tf_without_tf2_msgs_is_refused_naming_it() -> None:
    settings = IdentifierSettings.from_parameters({"wrench_frame_source": "tf"})
    assert settings.frame_source(True).tf
    with pytest.raises(InputError, match="wrench_frame_source"):
        settings.frame_source(False)
