"""The simulated force/torque sensor: its stream, nuisances, mounting (fixed or turning) and filter timing."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.checks import GRAVITY_M_S2, check_bool, float_tuple, rotation_from_rpy_deg
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar

FILTER_KINDS = ("first_order", "moving_average")
# Quadrature nodes of the sensor's filter kernel: enough that the filtered slow physics is exact to far
# below the sensor noise, few enough that a session stays a vectorised evaluation.
_BOX_NODES = 8
_EXPONENTIAL_NODES = 16
_EXPONENTIAL_SPAN = 8.0  # bins cover 8 time constants; the tail beyond is one more node at its mean


@normalising
@dataclass(frozen=True, kw_only=True)
class SensorSpec:
    """The force/torque sensor stream.

    Attributes
    ----------
    wrench_hz : sample rate, Hz (1-5000).
    phase_s : first nominal stamp after the session start, s (0 <= phase < 1 s).
    stamp_jitter_s : one standard deviation of the stamp jitter, s (clipped to +-0.4 sample period
        so stamps stay strictly increasing). The wrench is exact at its (jittered) stamp.
    roll_pitch_yaw_deg : (3,) fixed-axis RPY of the sensor frame in ``world``, deg.
    frame_id : ``header.frame_id`` of the wrench.
    force_noise_n : white Gaussian noise per force axis (sensor frame), N (1 sd).
    torque_noise_nm : white Gaussian noise per moment axis (sensor frame), Nm (1 sd).
    force_bias_n : (3,) force offset in the sensor frame at the session start, N.
    torque_bias_nm : (3,) moment offset in the sensor frame at the session start, Nm.
    force_drift_n_per_s : (3,) linear drift of the force offset, sensor frame, N/s (the offset at
        time t s after the session start is ``force_bias_n + t * force_drift_n_per_s``).
    torque_drift_nm_per_s : (3,) linear drift of the moment offset, sensor frame, Nm/s.
    handle_mass_kg : mass of the handle between the sensor and the hand, kg (0-20). Its weight loads
        the sensor: ``R^T m g`` (g = (0, 0, -9.81) m/s^2 in ``world``), rotating with the sensor.
    handle_com_m : (3,) the handle's centre of mass in the sensor frame, relative to the wrench's
        reference point (the contact point), m: its weight adds the moment ``c x R^T m g``.
    tf_static : whether the bag records ``/tf_static`` (False: the world -> sensor transform is lost, as
        in a bag recorded without it; a reader then takes the wrench as given in ``world``).
    spike_fraction : probability that a wrench sample is a spike (a knock, a glitch), in [0, 0.5]: its
        force gains ``+-spike_n`` along one sensor axis (axis and sign drawn per spike).
    spike_n : spike amplitude, N (0-1e30: absurd values included on purpose).
    turns_with_handle : False: the sensor is fixed at ``roll_pitch_yaw_deg``. True: it sits on the robot
        flange and turns with the handle: its orientation is ``Rx(pitch(t)) @ R_mount``, where ``pitch``
        is the last segment's absolute angle minus its session mean (a rotation about world x) and
        ``R_mount`` the mounting rotation above (the orientation at the mean pitch). The wrench is given
        in the turning frame; a bag carries the orientation on ``/tf``.
    filter_delay_s : low-frequency group delay of the sensor's causal low-pass, s (0: no filter, <= 1):
        the time constant of a ``first_order`` filter, or half the window of a ``moving_average``.
    filter_kind : ``"first_order"`` or ``"moving_average"``.
    average_over_period : True: each sample is the mean of the (filtered) wrench over the sample period
        ending at its stamp, like an integrating converter (a further delay of half a period).
    clock_offset_s : the wrench clock reads this much later than the marker (and robot) clock, s
        (within +-1 s): a sample measured at true time t is stamped ``t + clock_offset_s``.

    Filter and averaging act on the sensor's noise-free reading (the arm's wrench and the handle's
    weight, in the sensor's axes); offsets, noise and spikes are added at the stamp (the noise level is
    what the stream shows, after the filter).
    """

    wrench_hz: float = 100.0
    phase_s: float = 0.0013
    stamp_jitter_s: float = 1e-4
    roll_pitch_yaw_deg: tuple[float, float, float] = (180.0, 0.0, 30.0)
    frame_id: str = "ft_sensor"
    force_noise_n: float = 0.05
    torque_noise_nm: float = 0.005
    force_bias_n: tuple[float, float, float] = (0.0, 0.0, 0.0)
    torque_bias_nm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    force_drift_n_per_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    torque_drift_nm_per_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    handle_mass_kg: float = 0.0
    handle_com_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tf_static: bool = True
    spike_fraction: float = 0.0
    spike_n: float = 1000.0
    turns_with_handle: bool = False
    filter_delay_s: float = 0.0
    filter_kind: str = "first_order"
    average_over_period: bool = False
    clock_offset_s: float = 0.0

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the numbers as floats, the vectors as tuples of floats."""
        out: dict[str, Any] = {"wrench_hz": check_finite_scalar("wrench_hz", given.wrench_hz, 1.0, 5000.0)}
        out["phase_s"] = check_finite_scalar("wrench phase_s", given.phase_s, 0.0, 1.0)
        if out["phase_s"] >= 1.0:
            raise InputError(f"wrench phase_s must be below 1 s, got {out['phase_s']!r}")
        out["stamp_jitter_s"] = check_finite_scalar("wrench stamp_jitter_s", given.stamp_jitter_s, 0.0, 0.1)
        out["roll_pitch_yaw_deg"] = float_tuple("roll_pitch_yaw_deg", given.roll_pitch_yaw_deg, 3, -360.0, 360.0)
        frame_id = given.frame_id
        if not isinstance(frame_id, str) or not frame_id.strip() or frame_id != frame_id.strip():
            raise InputError(f"frame_id must be a non-empty name without surrounding spaces, got {frame_id!r}")
        out["force_noise_n"] = check_finite_scalar("force_noise_n", given.force_noise_n, 0.0, 100.0)
        out["torque_noise_nm"] = check_finite_scalar("torque_noise_nm", given.torque_noise_nm, 0.0, 10.0)
        out["force_bias_n"] = float_tuple("force_bias_n", given.force_bias_n, 3, -1e3, 1e3)
        out["torque_bias_nm"] = float_tuple("torque_bias_nm", given.torque_bias_nm, 3, -1e2, 1e2)
        out["force_drift_n_per_s"] = float_tuple("force_drift_n_per_s", given.force_drift_n_per_s, 3, -1.0, 1.0)
        out["torque_drift_nm_per_s"] = float_tuple("torque_drift_nm_per_s", given.torque_drift_nm_per_s, 3, -0.1, 0.1)
        out["handle_mass_kg"] = check_finite_scalar("handle_mass_kg", given.handle_mass_kg, 0.0, 20.0)
        out["handle_com_m"] = float_tuple("handle_com_m", given.handle_com_m, 3, -1.0, 1.0)
        check_bool("tf_static", given.tf_static)
        out["spike_fraction"] = check_finite_scalar("spike_fraction", given.spike_fraction, 0.0, 0.5)
        out["spike_n"] = check_finite_scalar("spike_n", given.spike_n, 0.0, 1e30)
        check_bool("turns_with_handle", given.turns_with_handle)
        out["filter_delay_s"] = check_finite_scalar("wrench filter_delay_s", given.filter_delay_s, 0.0, 1.0)
        if given.filter_kind not in FILTER_KINDS:
            raise InputError(f"wrench filter_kind must be one of {FILTER_KINDS}, got {given.filter_kind!r}")
        check_bool("average_over_period", given.average_over_period)
        out["clock_offset_s"] = check_finite_scalar("wrench clock_offset_s", given.clock_offset_s, -1.0, 1.0)
        return out

    def offset_at(self, t_s: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Force (N) and moment (Nm) offsets in the sensor frame at ``t_s`` s: (N,) -> (N, 3), (N, 3)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        force = np.asarray(self.force_bias_n) + t * np.asarray(self.force_drift_n_per_s)
        torque = np.asarray(self.torque_bias_nm) + t * np.asarray(self.torque_drift_nm_per_s)
        return force, torque

    def payload_wrench(self, rotation_world_from_sensor: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The handle's gravity load in the sensor frame.

        Parameters
        ----------
        rotation_world_from_sensor : (3, 3) or (N, 3, 3) rotation(s) of the sensor in ``world``.

        Returns
        -------
        force (..., 3) N and moment (..., 3) Nm at the reference point: ``R^T m g`` and ``c x R^T m g``.
        """
        rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
        weight_world = np.array([0.0, 0.0, -GRAVITY_M_S2 * self.handle_mass_kg])
        force = weight_world @ rotation  # row form of R^T w
        torque = np.cross(np.asarray(self.handle_com_m), force)
        return force, torque

    @property
    def rotation_world_from_sensor(self) -> np.ndarray:
        """(3, 3) rotation taking sensor-frame vectors into ``world``."""
        return rotation_from_rpy_deg(*self.roll_pitch_yaw_deg)

    @property
    def delay_s(self) -> float:
        """Apparent delay of the wrench behind the markers at low frequency, s: the filter's group delay,
        half a sample period if averaged, and the clock offset."""
        return self.filter_delay_s + (0.5 / self.wrench_hz if self.average_over_period else 0.0) + self.clock_offset_s

    def filter_kernel(self) -> tuple[np.ndarray, np.ndarray]:
        """Quadrature of the sensor's causal filter (and averaging) kernel.

        Returns
        -------
        lags_s : (K,) float, how long before the measurement each node lies, s (>= 0).
        weights : (K,) float, summing to 1; ``sum(weights * lags_s)`` is the kernel's mean, i.e. the
            group delay ``filter_delay_s`` (+ half a period if averaged), exactly. No filter: ``[0], [1]``.
        """
        lags, weights = np.zeros(1), np.ones(1)
        parts = []
        if self.filter_delay_s > 0.0:
            if self.filter_kind == "moving_average":
                parts.append(_box(2.0 * self.filter_delay_s))
            else:
                parts.append(_exponential(self.filter_delay_s))
        if self.average_over_period:
            parts.append(_box(1.0 / self.wrench_hz))
        for part_lags, part_weights in parts:  # the kernels convolve: every pair of nodes adds its lags
            lags = (lags[:, None] + part_lags[None, :]).ravel()
            weights = (weights[:, None] * part_weights[None, :]).ravel()
        return lags, weights


def _box(width_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint nodes of a box kernel over [0, width]: mean width / 2, exactly."""
    return (np.arange(_BOX_NODES) + 0.5) * width_s / _BOX_NODES, np.full(_BOX_NODES, 1.0 / _BOX_NODES)


def _exponential(tau_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of ``exp(-s / tau) / tau`` on s >= 0: each bin's mass at its conditional mean (mass and mean
    exact), the tail beyond the last bin one node at ``edge + tau``."""
    edges = np.linspace(0.0, _EXPONENTIAL_SPAN, _EXPONENTIAL_NODES + 1)  # in units of tau
    lo, hi = edges[:-1], edges[1:]
    mass = np.exp(-lo) - np.exp(-hi)
    # Conditional mean of a unit exponential on [lo, hi]: (lo + 1) e^-lo - (hi + 1) e^-hi over the mass.
    mean = ((lo + 1.0) * np.exp(-lo) - (hi + 1.0) * np.exp(-hi)) / mass
    tail = math.exp(-_EXPONENTIAL_SPAN)
    lags = np.append(mean, _EXPONENTIAL_SPAN + 1.0) * tau_s
    return lags, np.append(mass, tail)
