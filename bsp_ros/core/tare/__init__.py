"""Tare of the F/T sensor: its offset and the handle's load, from a recording with the handle free."""

from bsp_ros.core.tare.apply import (
    MAX_CONSTANT_LOAD_TILT_DEG,
    MAX_TARE_SESSION_TILT_DEG,
    corrected_session,
    recording_warnings,
    tare_warnings,
    tare_wrench,
)
from bsp_ros.core.tare.estimate import estimate_tare
from bsp_ros.core.tare.files import read_tare_file, write_tare_file
from bsp_ros.core.tare.model import (
    LOADS,
    MAX_UNSTEADINESS,
    MIN_SWING_DEG,
    MIN_TARE_DURATION_S,
    TARE_SCHEMA,
    Tare,
)

__all__ = [
    "LOADS",
    "MAX_CONSTANT_LOAD_TILT_DEG",
    "MAX_TARE_SESSION_TILT_DEG",
    "MAX_UNSTEADINESS",
    "MIN_SWING_DEG",
    "MIN_TARE_DURATION_S",
    "TARE_SCHEMA",
    "Tare",
    "corrected_session",
    "estimate_tare",
    "read_tare_file",
    "recording_warnings",
    "tare_warnings",
    "tare_wrench",
    "write_tare_file",
]
