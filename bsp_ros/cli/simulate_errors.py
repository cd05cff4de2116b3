"""`bsp simulate`: the simulator's value errors said with the option the user typed (`--coulomb`, not `coulomb_nm`)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager

from bsp_ros.errors import InputError

# The simulator's spec field (as its checks name it) -> the `bsp simulate` option and the unit of its range.
# One table, so the core keeps its own bounds (the range in the message stays the one it enforces).
OPTION_OF_FIELD: dict[str, tuple[str, str]] = {
    "coulomb_nm": ("--coulomb", " Nm"),
    "stiffness_nm_per_rad": ("--stiffness", " Nm/rad"),
    "viscous_nms": ("--viscous", " Nm s/rad"),
    "offset_nm": ("--passive-offset", " Nm"),
    "neutral_rad": ("--neutral", " rad"),
    "friction_transition_rad_s": ("--friction-transition", " rad/s"),
    "stribeck_ratio": ("--stribeck-ratio", ""),
    "stribeck_speed_rad_s": ("--stribeck-speed", " rad/s"),
    "wrench_hz": ("--wrench-hz", " Hz"),
    "marker_hz": ("--marker-hz", " Hz"),
    "force_noise_n": ("--force-noise", " N"),
    "torque_noise_nm": ("--torque-noise", " Nm"),
    "marker noise_m": ("--marker-noise", " m"),
    "dropout_fraction": ("--dropout", ""),
    "force_bias_n": ("--force-offset", " N"),
    "torque_bias_nm": ("--torque-offset", " Nm"),
    "force_drift_n_per_s": ("--force-drift", " N/s"),
    "torque_drift_nm_per_s": ("--torque-drift", " Nm/s"),
    "handle_mass_kg": ("--handle-mass", " kg"),
    "handle_com_m": ("--handle-com", " m"),
    "skin_offset_m": ("--skin-offset", " m"),
    "spike_fraction": ("--spikes", ""),
    "spike_n": ("--spike-size", " N"),
    "wrench filter_delay_s": ("--wrench-filter-delay-s", " s"),
    "wrench clock_offset_s": ("--wrench-clock-offset-s", " s"),
    "duration_s": ("--duration", " s"),
    "tare duration_s": ("--duration", " s"),
    "tare start_offset_s": ("--tare-start", " s"),
    "swing_rpy_deg": ("--tare-swing", " deg"),
    "swing_period_s": ("--tare-period", " s"),
    "body mass (kg)": ("--body-mass", " kg"),
    "height (m)": ("--height", " m"),
}

# "<field>[i][j] must <rule>, got <value>": the checks' message shape (bsp_ros.validation, simulation.checks).
_MESSAGE = re.compile(r"^(?P<field>[a-z_ ()]+?)(?:\[(?P<i>\d+)\])?(?:\[(?P<j>\d+)\])? must (?P<rule>.+)$")
_RANGE = re.compile(r"([\[(][^\]]*\])")


def option_message(message: str) -> str:
    """``message`` with a known spec field replaced by its option (value k counted from 1); else unchanged."""
    match = _MESSAGE.match(message)
    if match is None or match["field"] not in OPTION_OF_FIELD:
        return message
    option, unit = OPTION_OF_FIELD[match["field"]]
    # --skin-offset is typed flat (along, normal per marker); the spec holds it as pairs.
    index = None if match["i"] is None else int(match["i"]) * (2 if match["j"] is not None else 1)
    if match["j"] is not None:
        index = (index or 0) + int(match["j"])
    position = "" if index is None else f" value {index + 1}"
    rule = _RANGE.sub(lambda bracket: bracket[1] + unit, match["rule"], count=1)
    return f"{option}{position} must {rule}"


@contextmanager
def option_names() -> Iterator[None]:
    """Re-raise a simulator InputError with the option's name in place of the spec field's."""
    try:
        yield
    except InputError as error:
        raise InputError(option_message(str(error))) from None
