"""Simulated tare recordings: the cell's sensor with the handle free (no arm), at rest or swinging."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.cell import CellSpec
from bsp_ros.core.simulation.checks import GRAVITY_M_S2, JITTER_CLIP_PERIODS, float_tuple, rotation_from_rpy_deg
from bsp_ros.core.streams import WrenchSeries
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive, check_stamps_ns

_SWING_PHASES_RAD = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)


@normalising
@dataclass(frozen=True)
class TareSpec:
    """A tare recording of a cell: the handle free (no arm), the robot at rest or swinging the sensor.

    The sensor's orientation is ``R_mount @ Rpy(swing_rpy_deg * sin(2 pi t / swing_period_s + phase))``
    with phases (0, 2 pi / 3, 4 pi / 3) rad for roll, pitch, yaw, ``R_mount`` from the cell's
    ``SensorSpec.roll_pitch_yaw_deg``; zero swing holds it at rest.

    Attributes
    ----------
    duration_s : length of the recording, s (0 < d <= 3600).
    start_offset_s : its start relative to the session start, s (negative: before the session); the
        offset drift of ``SensorSpec`` continues through it.
    swing_rpy_deg : (3,) swing amplitudes about the fixed x, y, z axes, deg (0-90).
    swing_period_s : period of the swing, s (> 0).
    tf_hz : rate of the ``/tf`` orientation samples of a swinging sensor, Hz.
    """

    duration_s: float = 20.0
    start_offset_s: float = -60.0
    swing_rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    swing_period_s: float = 10.0
    tf_hz: float = 50.0

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the numbers as floats, the swing as a tuple of floats."""
        return {
            "duration_s": check_positive("tare duration_s", given.duration_s, 3600.0),
            "start_offset_s": check_finite_scalar("tare start_offset_s", given.start_offset_s, -1e5, 1e5),
            "swing_rpy_deg": float_tuple("swing_rpy_deg", given.swing_rpy_deg, 3, 0.0, 90.0),
            "swing_period_s": check_positive("swing_period_s", given.swing_period_s, 1e4),
            "tf_hz": check_positive("tf_hz", given.tf_hz, 1000.0),
        }

    @property
    def swinging(self) -> bool:
        """True if the sensor's orientation varies during the recording."""
        return any(a > 0.0 for a in self.swing_rpy_deg)


@dataclass(frozen=True)
class SimulatedTare:
    """A simulated tare recording and its truth.

    Attributes
    ----------
    wrench : the wrench stream (sensor frame): offset (with drift) + handle load + noise.
    tf_t_ns : (K,) int64 stamps of the orientation samples (empty if the sensor was at rest).
    rotations_world_from_sensor : (K, 3, 3) sensor orientations at ``tf_t_ns``.
    rotation_world_from_sensor : (3, 3) the mounting orientation (the sensor at rest).
    truth : JSON-ready truth: the offsets at the recording's middle and the handle's mass and COM.
    """

    wrench: WrenchSeries
    tf_t_ns: np.ndarray
    rotations_world_from_sensor: np.ndarray
    rotation_world_from_sensor: np.ndarray
    truth: dict[str, Any]


def tare_rotations(spec: CellSpec, tare: TareSpec, t_s: npt.ArrayLike) -> np.ndarray:
    """Sensor orientations of a tare recording: (N,) s since the tare's start -> (N, 3, 3)."""
    t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
    mount = spec.sensor.rotation_world_from_sensor
    angles = np.asarray(tare.swing_rpy_deg) * np.sin(
        2.0 * np.pi * t[:, None] / tare.swing_period_s + np.asarray(_SWING_PHASES_RAD)
    )
    return np.stack([mount @ rotation_from_rpy_deg(*row) for row in angles]) if t.size else np.zeros((0, 3, 3))


def tare_wrench(
    spec: CellSpec, tare: TareSpec, stamps: np.ndarray, noise: np.ndarray
) -> tuple[WrenchSeries, np.ndarray]:
    """Handle-free wrench at ``stamps`` given (N, 6) standard normal draws; and the (N, 3, 3) orientations."""
    s = spec.sensor
    start_ns = spec.start_ns + round(tare.start_offset_s * 1e9)
    t_tare = (stamps - np.int64(start_ns)).astype(np.float64) * 1e-9
    rotations = tare_rotations(spec, tare, t_tare)
    offset_f, offset_m = s.offset_at(t_tare + tare.start_offset_s)
    load_f = np.einsum("k,nkj->nj", np.array([0.0, 0.0, -GRAVITY_M_S2 * s.handle_mass_kg]), rotations)
    load_m = np.cross(np.asarray(s.handle_com_m), load_f)
    wrench = WrenchSeries(
        t_ns=stamps,
        force_n=offset_f + load_f + s.force_noise_n * noise[:, :3],
        torque_nm=offset_m + load_m + s.torque_noise_nm * noise[:, 3:],
        frame_id=s.frame_id,
    )
    return wrench, rotations


def simulate_tare(spec: CellSpec, tare: TareSpec | None = None) -> SimulatedTare:
    """Simulate the tare recording of a cell (the handle free: no arm, markers not recorded).

    The wrench is ``offset(t) + R(t)^T m g`` (force) and ``offset_M(t) + c x R(t)^T m g`` (moment) plus
    the sensor's white noise, with the offsets, drift, handle mass ``m`` and COM ``c`` of
    ``spec.sensor``; draws come from a generator seeded by ``spec.seed`` but independent of the
    session's streams.

    Parameters
    ----------
    spec : the cell (sensor, seed, session start).
    tare : the recording (default ``TareSpec()``: 20 s at rest, a minute before the session).

    Returns
    -------
    SimulatedTare
    """
    tare = tare if tare is not None else TareSpec()
    if not isinstance(tare, TareSpec):
        raise InputError(f"tare must be a TareSpec, got {tare!r}")
    s = spec.sensor
    start_ns = spec.start_ns + round(tare.start_offset_s * 1e9)
    if start_ns <= 0:
        raise InputError(f"the tare would start at ROS time {start_ns} ns (<= 0): start_offset_s is too early")
    rng_stamps, rng_noise = (np.random.default_rng(c) for c in np.random.SeedSequence([spec.seed, 7]).spawn(2))
    count = max(math.ceil((tare.duration_s - s.phase_s) * s.wrench_hz), 1)
    nominal = s.phase_s + np.arange(count, dtype=np.float64) / s.wrench_hz
    offsets_ns = np.round(nominal * 1e9)
    if s.stamp_jitter_s > 0.0:
        clip = JITTER_CLIP_PERIODS * 1e9 / s.wrench_hz
        offsets_ns += np.round(np.clip(rng_stamps.normal(0.0, s.stamp_jitter_s * 1e9, count), -clip, clip))
    stamps = check_stamps_ns("tare stamps", np.int64(start_ns) + offsets_ns.astype(np.int64))
    wrench, _ = tare_wrench(spec, tare, stamps, rng_noise.standard_normal((count, 6)))
    if tare.swinging:
        n_tf = max(math.ceil(tare.duration_s * tare.tf_hz), 2)
        tf_s = np.arange(n_tf, dtype=np.float64) / tare.tf_hz
        tf_t_ns = np.int64(start_ns) + np.round(tf_s * 1e9).astype(np.int64)
        tf_rotations = tare_rotations(spec, tare, tf_s)
    else:
        tf_t_ns, tf_rotations = np.zeros(0, dtype=np.int64), np.zeros((0, 3, 3))
    middle_f, middle_m = s.offset_at([tare.start_offset_s + 0.5 * tare.duration_s])
    truth = {
        "schema": "bsp_ros/tare_truth/1",
        "frame_id": s.frame_id,
        "force_offset_n": middle_f[0].tolist(),
        "torque_offset_nm": middle_m[0].tolist(),
        "force_drift_n_per_s": list(s.force_drift_n_per_s),
        "torque_drift_nm_per_s": list(s.torque_drift_nm_per_s),
        "handle_mass_kg": s.handle_mass_kg,
        "handle_com_m": list(s.handle_com_m),
        "duration_s": tare.duration_s,
        "start_offset_s": tare.start_offset_s,
        "swing_rpy_deg": list(tare.swing_rpy_deg),
        "swing_period_s": tare.swing_period_s,
        "sensor_roll_pitch_yaw_deg": list(s.roll_pitch_yaw_deg),
        "force_noise_n": s.force_noise_n,
        "torque_noise_nm": s.torque_noise_nm,
        "wrench_hz": s.wrench_hz,
        "seed": spec.seed,
        "start_ns": int(start_ns),
    }
    return SimulatedTare(
        wrench=wrench,
        tf_t_ns=tf_t_ns,
        rotations_world_from_sensor=tf_rotations,
        rotation_world_from_sensor=np.array(s.rotation_world_from_sensor),
        truth=truth,
    )
