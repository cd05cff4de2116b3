"""Simulated patient histories: sessions on different days with the day-to-day error of a real clinic.

Between any two sessions (days apart, or a same-day retest) the markers are re-placed and the force sensor is
re-zeroed (a fresh offset of ``bias_n`` N per axis, 1 SD), and the recording noise is drawn anew. The
re-placement is either every marker, shoulder to contact point, off its joint centre by a Gaussian draw of
``placement_sd_mm`` per in-plane axis (:data:`PLACEMENT_SD_MM`: the sd `bsp identify` assumes,
``--marker-placement-sd-mm``), or, with ``placement_sd_mm`` 0 (the default), the shoulder and elbow markers
within +-``skin_mm`` and the wrist and hand markers within +-``distal_skin_mm`` (uniform draws, as
``bsp simulate --skin-offset-mm``). The estimate comes from :func:`bsp_ros.core.pipeline.identify_session`, as
for a recorded bag.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.simulation import MarkerSpec, PassiveTruth, SensorSpec, human_arm_cell, simulate_cell
from bsp_ros.core.tare import Tare

DAY_NS = 86_400 * 10**9
HISTORY_START_NS = 1_717_225_200 * 10**9  # 2024-06-01T07:00:00Z
RETEST_AFTER_NS = 3_600 * 10**9
"""A retest is recorded an hour after the day's session, the arm taken out and re-attached in between."""
HANDLE_COM_M = (0.0, 0.0, 0.05)
TARE_SD = (0.02, 0.002)
"""A tare's 1 SD per axis (force N, moment Nm): a few seconds of the handle at rest, averaged."""
PLACEMENT_SD_MM = 1e3 * IdentifyOptions().marker_placement_sd_m
"""The marker placement sd `bsp identify` assumes (1 sd per in-plane axis, mm): re-placing every marker by it
draws the day-to-day error its std holds."""
N_MARKERS = 4
"""Shoulder, elbow, wrist and hand (the contact point)."""


@dataclass(frozen=True)
class Patient:
    """The simulated subject: body data and passive moments per joint (shoulder, elbow, wrist)."""

    sex: str = "female"
    body_mass_kg: float = 68.0
    height_m: float = 1.65
    coulomb_nm: tuple[float, float, float] = (0.5, 0.28, 0.06)
    stiffness_nm_per_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    neutral_rad: tuple[float, float, float] = (0.0, 1.87, 0.0)
    passive: str = "coulomb"

    def options(self) -> IdentifyOptions:
        """What `bsp identify` is told: the passive model and the body data."""
        return IdentifyOptions(
            passive=PassiveModel.parse(self.passive),
            subject=SubjectInfo(self.body_mass_kg, self.height_m, self.sex),
        )


def session_estimate(
    patient: Patient,
    day: int,
    seed: int,
    *,
    retest: bool = False,
    skin_mm: float = 3.0,
    distal_skin_mm: float = 0.0,
    placement_sd_mm: float = 0.0,
    bias_n: float = 0.2,
    duration_s: float = 40.0,
    wrench_hz: float = 50.0,
    marker_hz: float = 25.0,
    handle_mass_kg: float = 0.0,
    tared: bool = False,
) -> dict[str, Any]:
    """The estimate document of one simulated session of ``patient`` on ``day`` (0 = 2024-06-01).

    ``seed`` draws the marker re-placement, the sensor offset and the recording noise. ``placement_sd_mm`` > 0
    re-places every marker by a Gaussian draw of that sd per axis (mm) in place of the uniform ``skin_mm`` and
    ``distal_skin_mm`` draws (:func:`skin_offsets_m`). The rates are half
    the simulator's defaults, so a history of a dozen sessions is made in seconds. ``handle_mass_kg`` hangs
    a handle between the sensor and the hand (its centre 5 cm beyond the sensor); ``tared`` subtracts a tare
    of the sensor's offset and the handle's weight (read with the handle free: :func:`session_tare`), as
    ``bsp sessions add --tare`` does; untared, both load the arm's estimate.
    """
    rng = random.Random(seed)
    skin = skin_offsets_m(rng, placement_sd_mm=placement_sd_mm, skin_mm=skin_mm, distal_skin_mm=distal_skin_mm)
    bias = (rng.gauss(0.0, bias_n), rng.gauss(0.0, bias_n), rng.gauss(0.0, bias_n))
    start_ns = HISTORY_START_NS + day * DAY_NS + (RETEST_AFTER_NS if retest else 0)
    spec = human_arm_cell(
        sex=patient.sex,
        body_mass_kg=patient.body_mass_kg,
        height_m=patient.height_m,
        passive=PassiveTruth(
            coulomb_nm=patient.coulomb_nm,
            stiffness_nm_per_rad=patient.stiffness_nm_per_rad,
            neutral_rad=patient.neutral_rad,
        ),
        markers=MarkerSpec(skin_offset_m=skin, marker_hz=marker_hz),
        sensor=SensorSpec(
            force_bias_n=bias, wrench_hz=wrench_hz, handle_mass_kg=handle_mass_kg, handle_com_m=HANDLE_COM_M
        ),
        duration_s=duration_s,
        start_ns=start_ns,
        seed=seed,
    )
    session = simulate_cell(spec).session
    options = patient.options()
    if tared:
        options = replace(options, tare=session_tare(spec.sensor, session.wrench.frame_id))
    document = identify_session(session, options, {"source": f"day{day:03d}_{seed}.mcap"})
    if retest:
        document["session"]["retest"] = True
    return document


def skin_offsets_m(
    rng: random.Random, *, placement_sd_mm: float, skin_mm: float, distal_skin_mm: float
) -> tuple[tuple[float, float], ...]:
    """One session's marker offsets from the joint centres, ``(along, normal)`` per marker (m), shoulder first.

    Parameters
    ----------
    rng : the session's draws; the sensor offset is drawn from it next.
    placement_sd_mm : > 0: every marker re-placed by a Gaussian draw of this sd per axis (mm), as the placement
        prior of `bsp identify` has it; 0: the uniform draws below.
    skin_mm, distal_skin_mm : half-widths (mm) of the uniform draws of the shoulder and elbow markers and of the
        wrist and hand markers.
    """
    if placement_sd_mm > 0.0:
        return tuple(
            (rng.gauss(0.0, placement_sd_mm) / 1e3, rng.gauss(0.0, placement_sd_mm) / 1e3) for _ in range(N_MARKERS)
        )
    return tuple(
        (rng.uniform(-mm, mm) / 1e3, rng.uniform(-mm, mm) / 1e3)
        for mm in (skin_mm, skin_mm, distal_skin_mm, distal_skin_mm)
    )


def session_tare(sensor: SensorSpec, frame_id: str) -> Tare:
    """The tare of a simulated session: the sensor's offset and the handle's weight at its fixed orientation,
    as a tare recording with the handle free reads them (within :data:`TARE_SD`)."""
    force_offset, torque_offset = sensor.offset_at([0.0])
    force, torque = sensor.payload_wrench(sensor.rotation_world_from_sensor)
    values = np.concatenate([force_offset[0] + force, torque_offset[0] + torque])
    covariance = np.diag([TARE_SD[0] ** 2] * 3 + [TARE_SD[1] ** 2] * 3)
    return Tare(
        frame_id=frame_id,
        load="constant",
        values=values,
        covariance=covariance,
        n_samples=1000,
        start_time_ns=0,
        duration_s=20.0,
        source="tare.mcap",
    )
