"""A simulated rehab cell: a planar arm held quasi-statically by a robot, with noisy wrench and markers."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from bsp_ros.core.anthropometry import (
    check_body_mass_kg,
    check_height_m,
    check_sex,
    length_from_height_m,
    segment_norm,
)
from bsp_ros.core.streams import (
    MarkerSeries,
    Session,
    WrenchSeries,
    joints_for,
    markers_for,
    segments_for,
)
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive, check_stamps_ns

__all__ = [
    "DEFAULT_START_NS",
    "GRAVITY_M_S2",
    "TRUTH_SCHEMA",
    "CellSimulator",
    "CellSpec",
    "JointTrajectory",
    "MarkerSpec",
    "PassiveTruth",
    "SensorSpec",
    "SessionTruth",
    "SimulatedSession",
    "SimulatedTare",
    "SubjectTruth",
    "TareSpec",
    "TrajectorySpec",
    "human_arm_cell",
    "paper_mechanical_arm_cell",
    "rotation_from_rpy_deg",
    "simulate_cell",
    "simulate_tare",
    "tare_rotations",
]

GRAVITY_M_S2 = 9.81
TRUTH_SCHEMA = "bsp_ros/truth/1"
# 2023-11-14T22:13:20Z: a realistic ROS time (a stamp of 0 is an error on the wire).
DEFAULT_START_NS = 1_700_000_000_000_000_000

# Plausibility bounds of a spec (anything outside is a typo, not a subject).
_MAX_LENGTH_M = 1.0
_MIN_LENGTH_M = 0.01
_MAX_MASS_KG = 30.0
_MAX_COM_FRACTION = 1.5  # COM up to 1.5 segment lengths from the proximal joint (hand past the contact point)
_MAX_COULOMB_NM = 20.0
_MAX_VISCOUS_NMS = 100.0
_MAX_STIFFNESS_NM_PER_RAD = 100.0
_MAX_OFFSET_NM = 20.0
_MAX_DURATION_S = 86_400.0
_MIN_ELBOW_SIN = math.sin(math.radians(5.0))  # keep the elbow 5 deg away from a straight/folded arm
_JITTER_CLIP_PERIODS = 0.4  # |jitter| <= 0.4 period keeps stamps strictly increasing


# --------------------------------------------------------------------------------------------------------
# validation helpers
# --------------------------------------------------------------------------------------------------------


def _float_tuple(
    name: str,
    values: Any,
    n: int | None = None,
    lo: float = -math.inf,
    hi: float = math.inf,
    positive: bool = False,
) -> tuple[float, ...]:
    """Return ``values`` as a tuple of floats, each finite and in range; raise InputError naming the value."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise InputError(f"{name} must be a sequence of numbers, got {values!r}")
    items = list(values)
    if n is not None and len(items) != n:
        raise InputError(f"{name} must have {n} entries, got {len(items)}: {tuple(values)!r}")
    out: list[float] = []
    for i, item in enumerate(items):
        label = f"{name}[{i}]"
        out.append(check_positive(label, item, hi) if positive else check_finite_scalar(label, item, lo, hi))
    return tuple(out)


def _check_int(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    """Return ``value`` as an int if it is an integer (not bool) within ``[lo, hi]``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InputError(f"{name} must be an integer, got {value!r}")
    number = int(value)
    if number < lo or (hi is not None and number > hi):
        raise InputError(f"{name} must be within [{lo}, {hi if hi is not None else 'inf'}], got {value!r}")
    return number


def _check_n_segments(n_segments: Any, what: str = "n_segments") -> int:
    if isinstance(n_segments, bool) or n_segments not in (2, 3):
        raise InputError(f"{what} must be 2 or 3, got {n_segments!r}")
    return int(n_segments)


def rotation_from_rpy_deg(roll_deg: float, pitch_deg: float, yaw_deg: float) -> np.ndarray:
    """Rotation matrix of fixed-axis roll, pitch, yaw (ROS/tf2 ``setRPY`` convention).

    Parameters
    ----------
    roll_deg, pitch_deg, yaw_deg : float
        Rotations about the fixed x, then y, then z axes, in degrees.

    Returns
    -------
    (3, 3) float64 ndarray
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
    """
    r, p, y = (
        math.radians(check_finite_scalar(n, v))
        for n, v in zip(("roll", "pitch", "yaw"), (roll_deg, pitch_deg, yaw_deg), strict=True)
    )
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


# --------------------------------------------------------------------------------------------------------
# specs
# --------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SubjectTruth:
    """True segment geometry and mass of a simulated arm (2 or 3 segments, proximal to distal).

    Attributes
    ----------
    lengths_m : (n,) tuple of float
        Segment lengths a_j in m: shoulder->elbow, elbow->wrist, wrist->contact point (a 2-segment
        chain: shoulder->elbow, elbow->contact point).
    masses_kg : (n,) tuple of float
        Segment masses m_j in kg.
    com_m : (n,) tuple of float
        COM distance l_j from the proximal joint along the segment axis, in m.

    Raises
    ------
    InputError
        If n is not 2 or 3, the tuples differ in length, or a value is non-finite or implausible
        (length outside [0.01, 1] m, mass outside (0, 30] kg, COM outside (0, 1.5 a_j]).
    """

    lengths_m: tuple[float, ...]
    masses_kg: tuple[float, ...]
    com_m: tuple[float, ...]

    def __post_init__(self) -> None:
        lengths = _float_tuple("lengths_m", self.lengths_m, None, _MIN_LENGTH_M, _MAX_LENGTH_M)
        n = _check_n_segments(len(lengths), "the number of segments (entries of lengths_m)")
        masses = _float_tuple("masses_kg", self.masses_kg, n, positive=True, hi=_MAX_MASS_KG)
        coms = _float_tuple("com_m", self.com_m, n, positive=True)
        for j, (com, length) in enumerate(zip(coms, lengths, strict=True)):
            if com > _MAX_COM_FRACTION * length:
                raise InputError(
                    f"com_m[{j}] = {com!r} m is implausible for a segment of length {length!r} m "
                    f"(at most {_MAX_COM_FRACTION} lengths)"
                )
        object.__setattr__(self, "lengths_m", lengths)
        object.__setattr__(self, "masses_kg", masses)
        object.__setattr__(self, "com_m", coms)

    @property
    def n_segments(self) -> int:
        """Number of segments (2 or 3)."""
        return len(self.lengths_m)

    @property
    def segment_names(self) -> tuple[str, ...]:
        """``upper_arm``, ``forearm`` (, ``hand``)."""
        return segments_for(self.n_segments)

    @property
    def first_moments_kgm(self) -> tuple[float, ...]:
        """(n,) ``m_j l_j`` per segment, kg m."""
        return tuple(m * c for m, c in zip(self.masses_kg, self.com_m, strict=True))

    @property
    def static_moments_kgm(self) -> tuple[float, ...]:
        """(n,) grouped static moments ``beta_j = m_j l_j + a_j * sum_{k>j} m_k`` (CONTRACT.md), kg m."""
        out = []
        for j in range(self.n_segments):
            distal_mass = sum(self.masses_kg[j + 1 :])
            out.append(self.masses_kg[j] * self.com_m[j] + self.lengths_m[j] * distal_mass)
        return tuple(out)

    @classmethod
    def from_anthropometry(
        cls,
        sex: str = "male",
        body_mass_kg: float = 75.0,
        height_m: float = 1.78,
        n_segments: int = 3,
        rng: np.random.Generator | None = None,
    ) -> SubjectTruth:
        """A subject from the de Leva table (``bsp_ros.core.anthropometry``).

        Lengths are the table lengths scaled with height (the hand: wrist -> 3rd metacarpale, taken as
        wrist -> contact point). Masses are ``mass_fraction * body_mass_kg`` and COM distances
        ``com_fraction * length``, at the table means if ``rng`` is None, else drawn from the table's
        Gaussian prior (fractions clipped to [0.3, 1.7] x mean for mass, [0.2, 0.9] for COM).

        Parameters
        ----------
        sex : ``"male"`` or ``"female"``.
        body_mass_kg : body mass, kg (20-300).
        height_m : stature, m (1.0-2.5).
        n_segments : 2 (upper arm, forearm) or 3 (plus hand).
        rng : generator for a draw from the prior; None for the table means.

        Returns
        -------
        SubjectTruth
        """
        sex = check_sex(sex)
        body_mass = check_body_mass_kg(body_mass_kg)
        height = check_height_m(height_m)
        n = _check_n_segments(n_segments)
        lengths, masses, coms = [], [], []
        for name in segments_for(n):
            norm = segment_norm(sex, name)
            length = length_from_height_m(sex, name, height)
            mass_fraction, com_fraction = norm.mass_fraction, norm.com_fraction
            if rng is not None:
                mass_fraction = float(
                    np.clip(
                        rng.normal(norm.mass_fraction, norm.mass_fraction_sd),
                        0.3 * norm.mass_fraction,
                        1.7 * norm.mass_fraction,
                    )
                )
                com_fraction = float(np.clip(rng.normal(norm.com_fraction, norm.com_fraction_sd), 0.2, 0.9))
            lengths.append(length)
            masses.append(mass_fraction * body_mass)
            coms.append(com_fraction * length)
        return cls(tuple(lengths), tuple(masses), tuple(coms))

    @classmethod
    def paper_mechanical_arm(cls) -> SubjectTruth:
        """The method paper's 2-segment mechanical arm (Table 1 CAD values).

        From Table 1: ``m2 l2 = 0.130`` kg m, ``m2 = 1.160`` kg, ``m1 l1 = 0.260`` kg m, so
        ``l2 = 0.130 / 1.160 = 0.1121`` m (the table prints 0.115). **Assumed** (the paper gives no
        values): ``a1 = a2 = 0.30`` m and ``m1 = 1.5`` kg, hence ``l1 = 0.260 / 1.5 = 0.1733`` m.

        Returns
        -------
        SubjectTruth
        """
        m1, m2 = 1.5, 1.160
        return cls(lengths_m=(0.30, 0.30), masses_kg=(m1, m2), com_m=(0.260 / m1, 0.130 / m2))


@dataclass(frozen=True)
class PassiveTruth:
    """True passive joint moment, per joint (shoulder, elbow, wrist), the torque the driver must supply.

    ``tau_p,j = c_j s(qdot_j) h(qdot_j) + b_j qdot_j + k_j (q_j - q0_j) + offset_j`` (Nm), where the
    direction shape ``s(v) = sign(v)`` (``sign(0) = 0``) if ``friction_transition_rad_s`` is 0, else
    ``tanh(v / friction_transition_rad_s)`` (a smooth transition), and the Stribeck-like level
    ``h(v) = 1 + (stribeck_ratio - 1) exp(-(v / stribeck_speed_rad_s)^2)`` (1 for the default ratio 1:
    plain Coulomb; > 1 sticks more at low speed). ``c_j`` is the level at speeds far above both widths.
    An empty tuple (the default for all but ``coulomb_nm``) means zeros for every joint.

    Attributes
    ----------
    coulomb_nm : (n,) Coulomb amplitudes c_j >= 0, Nm.
    viscous_nms : (n,) viscous coefficients b_j >= 0, Nm s/rad.
    stiffness_nm_per_rad : (n,) stiffnesses k_j >= 0, Nm/rad.
    neutral_rad : (n,) neutral angles q0_j of the elastic term, rad (relative joint angles).
    offset_nm : (n,) constant offsets, Nm.
    friction_transition_rad_s : width of the tanh direction transition, rad/s (0: a sign step).
    stribeck_ratio : friction level at zero speed over ``c_j`` (>= 0; 1: no Stribeck effect).
    stribeck_speed_rad_s : speed scale of the Stribeck decay, rad/s (> 0).
    """

    coulomb_nm: tuple[float, ...]
    viscous_nms: tuple[float, ...] = ()
    stiffness_nm_per_rad: tuple[float, ...] = ()
    neutral_rad: tuple[float, ...] = ()
    offset_nm: tuple[float, ...] = ()
    friction_transition_rad_s: float = 0.0
    stribeck_ratio: float = 1.0
    stribeck_speed_rad_s: float = 0.01

    def __post_init__(self) -> None:
        coulomb = _float_tuple("coulomb_nm", self.coulomb_nm, None, 0.0, _MAX_COULOMB_NM)
        n = _check_n_segments(len(coulomb), "the number of joints (entries of coulomb_nm)")
        bounds = {
            "viscous_nms": (0.0, _MAX_VISCOUS_NMS),
            "stiffness_nm_per_rad": (0.0, _MAX_STIFFNESS_NM_PER_RAD),
            "neutral_rad": (-2.0 * math.pi, 2.0 * math.pi),
            "offset_nm": (-_MAX_OFFSET_NM, _MAX_OFFSET_NM),
        }
        object.__setattr__(self, "coulomb_nm", coulomb)
        for name, (lo, hi) in bounds.items():
            value = getattr(self, name)
            if isinstance(value, Sequence | np.ndarray) and len(value) == 0:
                value = (0.0,) * n
            object.__setattr__(self, name, _float_tuple(name, value, n, lo, hi))
        object.__setattr__(
            self,
            "friction_transition_rad_s",
            check_finite_scalar("friction_transition_rad_s", self.friction_transition_rad_s, 0.0, 10.0),
        )
        object.__setattr__(
            self, "stribeck_ratio", check_finite_scalar("stribeck_ratio", self.stribeck_ratio, 0.0, 10.0)
        )
        object.__setattr__(
            self, "stribeck_speed_rad_s", check_positive("stribeck_speed_rad_s", self.stribeck_speed_rad_s, 10.0)
        )

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.coulomb_nm)

    def friction_nm(self, qdot_rad_s: npt.ArrayLike) -> np.ndarray:
        """Friction part ``c_j s(qdot_j) h(qdot_j)`` of the passive moment: (N, n) rad/s -> (N, n) Nm."""
        v = np.asarray(qdot_rad_s, dtype=np.float64)
        width = self.friction_transition_rad_s
        shape = np.sign(v) if width == 0.0 else np.tanh(v / width)
        level = 1.0 + (self.stribeck_ratio - 1.0) * np.exp(-((v / self.stribeck_speed_rad_s) ** 2))
        return np.asarray(self.coulomb_nm) * shape * level


@dataclass(frozen=True)
class TrajectorySpec:
    """Slow sinusoidal joint motion ``q_j(t) = center_j + amp_j sin(2 pi t / period_j + phase_j)``.

    Attributes
    ----------
    center_deg : (n,) operating point, deg (q1 absolute from +y, q2 and q3 relative).
    amplitude_deg : (n,) amplitude >= 0, deg (0 holds the joint still: qdot = 0 exactly).
    period_s : (n,) period > 0, s.
    phase_rad : (n,) phase at t = 0 (the session start), rad.
    """

    center_deg: tuple[float, ...]
    amplitude_deg: tuple[float, ...]
    period_s: tuple[float, ...]
    phase_rad: tuple[float, ...]

    def __post_init__(self) -> None:
        centre = _float_tuple("center_deg", self.center_deg, None, -180.0, 180.0)
        n = _check_n_segments(len(centre), "the number of joints (entries of center_deg)")
        object.__setattr__(self, "center_deg", centre)
        object.__setattr__(self, "amplitude_deg", _float_tuple("amplitude_deg", self.amplitude_deg, n, 0.0, 90.0))
        object.__setattr__(self, "period_s", _float_tuple("period_s", self.period_s, n, positive=True, hi=1e5))
        object.__setattr__(self, "phase_rad", _float_tuple("phase_rad", self.phase_rad, n, -100.0, 100.0))

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.center_deg)

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) peak joint speeds ``amp * 2 pi / period``, rad/s."""
        return tuple(
            math.radians(a) * 2.0 * math.pi / p for a, p in zip(self.amplitude_deg, self.period_s, strict=True)
        )

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        centre, amp, omega, phase = self._arrays()
        return centre + amp * np.sin(omega * t + phase)

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Analytic joint velocities at ``t_s``: (N,) -> (N, n) rad/s (exactly 0 where the amplitude is 0)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        _, amp, omega, phase = self._arrays()
        return amp * omega * np.cos(omega * t + phase)

    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return (
            np.radians(np.asarray(self.center_deg)),
            np.radians(np.asarray(self.amplitude_deg)),
            2.0 * np.pi / np.asarray(self.period_s),
            np.asarray(self.phase_rad),
        )


@runtime_checkable
class JointTrajectory(Protocol):
    """Any joint motion the simulator can follow: ``TrajectorySpec`` or ``bsp_ros.core.planning.PlannedTrajectory``."""

    @property
    def n_joints(self) -> int: ...

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]: ...

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray: ...

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray: ...


@dataclass(frozen=True)
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

    def __post_init__(self) -> None:
        object.__setattr__(self, "wrench_hz", check_finite_scalar("wrench_hz", self.wrench_hz, 1.0, 5000.0))
        object.__setattr__(self, "phase_s", check_finite_scalar("wrench phase_s", self.phase_s, 0.0, 1.0))
        if self.phase_s >= 1.0:
            raise InputError(f"wrench phase_s must be below 1 s, got {self.phase_s!r}")
        object.__setattr__(
            self,
            "stamp_jitter_s",
            check_finite_scalar("wrench stamp_jitter_s", self.stamp_jitter_s, 0.0, 0.1),
        )
        rpy = _float_tuple("roll_pitch_yaw_deg", self.roll_pitch_yaw_deg, 3, -360.0, 360.0)
        object.__setattr__(self, "roll_pitch_yaw_deg", rpy)
        if not isinstance(self.frame_id, str) or not self.frame_id.strip() or self.frame_id != self.frame_id.strip():
            raise InputError(f"frame_id must be a non-empty name without surrounding spaces, got {self.frame_id!r}")
        object.__setattr__(self, "force_noise_n", check_finite_scalar("force_noise_n", self.force_noise_n, 0.0, 100.0))
        object.__setattr__(
            self, "torque_noise_nm", check_finite_scalar("torque_noise_nm", self.torque_noise_nm, 0.0, 10.0)
        )
        object.__setattr__(self, "force_bias_n", _float_tuple("force_bias_n", self.force_bias_n, 3, -1e3, 1e3))
        object.__setattr__(self, "torque_bias_nm", _float_tuple("torque_bias_nm", self.torque_bias_nm, 3, -1e2, 1e2))
        object.__setattr__(
            self, "force_drift_n_per_s", _float_tuple("force_drift_n_per_s", self.force_drift_n_per_s, 3, -1.0, 1.0)
        )
        object.__setattr__(
            self,
            "torque_drift_nm_per_s",
            _float_tuple("torque_drift_nm_per_s", self.torque_drift_nm_per_s, 3, -0.1, 0.1),
        )
        object.__setattr__(
            self, "handle_mass_kg", check_finite_scalar("handle_mass_kg", self.handle_mass_kg, 0.0, 20.0)
        )
        object.__setattr__(self, "handle_com_m", _float_tuple("handle_com_m", self.handle_com_m, 3, -1.0, 1.0))
        if not isinstance(self.tf_static, bool):
            raise InputError(f"tf_static must be True or False, got {self.tf_static!r}")
        object.__setattr__(self, "spike_fraction", check_finite_scalar("spike_fraction", self.spike_fraction, 0.0, 0.5))
        object.__setattr__(self, "spike_n", check_finite_scalar("spike_n", self.spike_n, 0.0, 1e30))

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


@dataclass(frozen=True)
class MarkerSpec:
    """The motion-capture streams (one marker per joint centre, ``hand`` at the contact point).

    Attributes
    ----------
    marker_hz : frame rate, Hz (> 0, at most 5000).
    phase_s : first nominal frame after the session start, s (0 <= phase < 1 s).
    stamp_jitter_s : one standard deviation of the frame stamp jitter, s (clipped like the wrench's).
    shoulder_m : (3,) fixed shoulder position in ``world``, m; the arm moves in the plane x = shoulder x.
    noise_m : white Gaussian position noise per axis (x included), m (1 sd).
    dropout_fraction : long-run fraction of frames lost, per marker independently, in [0, 0.9].
    dropout_mean_frames : mean length of a gap of lost frames (>= 1), frames.
    skin_offset_m : per marker (proximal to distal: shoulder, elbow, (wrist,) hand), the skin marker's
        offset from the joint centre ``(along, normal)`` in m, fixed in the segment that starts at that
        joint (the hand marker: in the hand, the last segment); ``along`` points distally along the
        segment axis, ``normal`` 90 deg counter-clockwise from it in the y-z plane. Empty: on the centres.
    """

    marker_hz: float = 50.0
    phase_s: float = 0.0071
    stamp_jitter_s: float = 0.0
    shoulder_m: tuple[float, float, float] = (0.20, 0.0, 1.20)
    noise_m: float = 1e-4
    dropout_fraction: float = 0.0
    dropout_mean_frames: float = 10.0
    skin_offset_m: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "marker_hz", check_positive("marker_hz", self.marker_hz, 5000.0))
        object.__setattr__(self, "phase_s", check_finite_scalar("marker phase_s", self.phase_s, 0.0, 1.0))
        if self.phase_s >= 1.0:
            raise InputError(f"marker phase_s must be below 1 s, got {self.phase_s!r}")
        object.__setattr__(
            self,
            "stamp_jitter_s",
            check_finite_scalar("marker stamp_jitter_s", self.stamp_jitter_s, 0.0, 0.1),
        )
        object.__setattr__(self, "shoulder_m", _float_tuple("shoulder_m", self.shoulder_m, 3, -100.0, 100.0))
        object.__setattr__(self, "noise_m", check_finite_scalar("marker noise_m", self.noise_m, 0.0, 0.1))
        object.__setattr__(
            self, "dropout_fraction", check_finite_scalar("dropout_fraction", self.dropout_fraction, 0.0, 0.9)
        )
        object.__setattr__(
            self,
            "dropout_mean_frames",
            check_finite_scalar("dropout_mean_frames", self.dropout_mean_frames, 1.0, 1e6),
        )
        offsets = self.skin_offset_m
        if isinstance(offsets, str | bytes) or not isinstance(offsets, Sequence | np.ndarray):
            raise InputError(f"skin_offset_m must be a sequence of (along, normal) pairs, got {offsets!r}")
        pairs = tuple(_float_tuple(f"skin_offset_m[{k}]", pair, 2, -0.1, 0.1) for k, pair in enumerate(offsets))
        if pairs and len(pairs) not in (3, 4):
            raise InputError(f"skin_offset_m needs one (along, normal) pair per marker (3 or 4), got {len(pairs)}")
        object.__setattr__(self, "skin_offset_m", pairs)


@dataclass(frozen=True)
class CellSpec:
    """Everything that defines one simulated session.

    Attributes
    ----------
    subject : segment geometry and masses.
    passive : passive joint moments (one entry per joint).
    trajectory : joint motion (one entry per joint): a ``TrajectorySpec`` or any ``JointTrajectory``
        (e.g. a planned one from ``bsp_ros.core.planning``).
    sensor : the wrench stream.
    markers : the marker streams.
    duration_s : session length, s (0 < d <= 86400).
    start_ns : ROS time of the session start (trajectory t = 0), int ns > 0.
    seed : seed of every random draw (stamps jitter, noise, dropouts), int >= 0.

    Raises
    ------
    InputError
        On a bad value, mismatched joint counts, or an elbow range within 5 deg of a straight or
        folded arm (the contact-point Jacobian is singular there).
    """

    subject: SubjectTruth
    passive: PassiveTruth
    trajectory: TrajectorySpec | JointTrajectory
    sensor: SensorSpec = field(default_factory=SensorSpec)
    markers: MarkerSpec = field(default_factory=MarkerSpec)
    duration_s: float = 120.0
    start_ns: int = DEFAULT_START_NS
    seed: int = 0

    def __post_init__(self) -> None:
        for name, kind in (
            ("subject", SubjectTruth),
            ("passive", PassiveTruth),
            ("trajectory", JointTrajectory),
            ("sensor", SensorSpec),
            ("markers", MarkerSpec),
        ):
            if not isinstance(getattr(self, name), kind):
                raise InputError(f"{name} must be a {kind.__name__}, got {getattr(self, name)!r}")
        n = self.subject.n_segments
        if self.passive.n_joints != n:
            raise InputError(f"passive has {self.passive.n_joints} joints, the subject has {n} segments")
        if self.trajectory.n_joints != n:
            raise InputError(f"trajectory has {self.trajectory.n_joints} joints, the subject has {n} segments")
        if self.markers.skin_offset_m and len(self.markers.skin_offset_m) != n + 1:
            raise InputError(
                f"markers.skin_offset_m has {len(self.markers.skin_offset_m)} pairs, the chain has {n + 1} markers"
            )
        object.__setattr__(self, "duration_s", check_positive("duration_s", self.duration_s, _MAX_DURATION_S))
        object.__setattr__(self, "start_ns", _check_int("start_ns", self.start_ns, 1, 2**62))
        object.__setattr__(self, "seed", _check_int("seed", self.seed, 0))
        if isinstance(self.trajectory, TrajectorySpec):
            centre, amp = self.trajectory.center_deg[1], self.trajectory.amplitude_deg[1]
            elbow = np.radians(np.linspace(centre - amp, centre + amp, 721))
        else:  # any other motion: the elbow angles it takes over the session
            elbow = self.trajectory.angles_rad(np.linspace(0.0, self.duration_s, 7201))[:, 1]
            centre, amp = float(np.degrees(elbow.mean())), float(np.degrees(np.ptp(elbow)) / 2)
        worst = float(np.abs(np.sin(elbow)).min())
        if worst < _MIN_ELBOW_SIN:
            raise InputError(
                f"elbow range {centre!r} +- {amp!r} deg comes within 5 deg of a straight or folded arm "
                f"(|sin q2| = {worst:.3g}): the wrench cannot be resolved there"
            )

    @property
    def n_segments(self) -> int:
        """Number of segments (2 or 3)."""
        return self.subject.n_segments


def _apply_overrides(spec: CellSpec, overrides: Mapping[str, Any]) -> CellSpec:
    known = {f.name for f in dataclasses.fields(CellSpec)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise InputError(f"unknown CellSpec field(s) {unknown}; known: {sorted(known)}")
    return dataclasses.replace(spec, **overrides)


def human_arm_cell(
    *,
    sex: str = "male",
    body_mass_kg: float = 75.0,
    height_m: float = 1.78,
    **overrides: Any,
) -> CellSpec:
    """A 3-segment human arm cell like the paper's human experiment (Fig. 4 right).

    Subject: de Leva table means for ``sex``, ``body_mass_kg``, ``height_m`` (override with
    ``subject=``). Passive: Coulomb (0.5, 0.28, 0.06) Nm at shoulder/elbow/wrist (the order of the
    paper's human results), no viscosity, stiffness or offset. Trajectory: centres (-43.3, 29.5, 0.2)
    deg, amplitudes (6, 1.7, 0.9) deg, periods (22, 19, 17) s and phases (0, pi/3, 2 pi/3) rad: the
    shoulder peaks at 0.030 rad/s (the paper's ~0.03 rad/s), and the unequal periods/phases keep the
    joints' motions from being collinear over a session.

    Parameters
    ----------
    sex, body_mass_kg, height_m : the anthropometric subject (ignored if ``subject`` is overridden).
    **overrides : any ``CellSpec`` field (``subject``, ``passive``, ``trajectory``, ``sensor``,
        ``markers``, ``duration_s``, ``start_ns``, ``seed``).

    Returns
    -------
    CellSpec
    """
    if "subject" in overrides:
        subject = overrides["subject"]
    else:
        subject = SubjectTruth.from_anthropometry(sex, body_mass_kg, height_m, n_segments=3)
    spec = CellSpec(
        subject=subject,
        passive=PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06)),
        trajectory=TrajectorySpec(
            center_deg=(-43.3, 29.5, 0.2),
            amplitude_deg=(6.0, 1.7, 0.9),
            period_s=(22.0, 19.0, 17.0),
            phase_rad=(0.0, math.pi / 3.0, 2.0 * math.pi / 3.0),
        ),
    )
    return _apply_overrides(spec, overrides)


def paper_mechanical_arm_cell(**overrides: Any) -> CellSpec:
    """The paper's 2-segment mechanical arm cell (Table 1, Fig. 4 left).

    Subject: ``SubjectTruth.paper_mechanical_arm()`` (assumed a1 = a2 = 0.30 m, m1 = 1.5 kg).
    Passive: Coulomb 0.139 Nm (shoulder), 0.161 Nm (elbow), the CAD/load-cell reference values.
    Trajectory: centres (-36.6, 35.8) deg, amplitudes (5.7, 5.7) deg, periods (21, 23) s, phases
    (0, pi/2) rad: peak speeds 0.030 and 0.027 rad/s, not in step.

    Parameters
    ----------
    **overrides : any ``CellSpec`` field.

    Returns
    -------
    CellSpec
    """
    spec = CellSpec(
        subject=SubjectTruth.paper_mechanical_arm(),
        passive=PassiveTruth(coulomb_nm=(0.139, 0.161)),
        trajectory=TrajectorySpec(
            center_deg=(-36.6, 35.8),
            amplitude_deg=(5.7, 5.7),
            period_s=(21.0, 23.0),
            phase_rad=(0.0, math.pi / 2.0),
        ),
    )
    return _apply_overrides(spec, overrides)


# --------------------------------------------------------------------------------------------------------
# truth
# --------------------------------------------------------------------------------------------------------


def _require(mapping: Any, key: str, where: str) -> Any:
    if not isinstance(mapping, Mapping) or key not in mapping:
        raise InputError(f"truth dict: missing {where}{key!r}")
    return mapping[key]


@dataclass(frozen=True)
class SessionTruth:
    """What a simulated session really was: the reference an estimate is scored against.

    Attributes
    ----------
    subject : segment lengths, masses and COM distances.
    passive : passive joint moment parameters.
    trajectory : the joint motion.
    simulation : JSON-ready settings of the session (seed, duration, rates, noise, ...).
    """

    subject: SubjectTruth
    passive: PassiveTruth
    trajectory: TrajectorySpec | JointTrajectory
    simulation: Mapping[str, Any] = field(default_factory=dict)

    @property
    def n_segments(self) -> int:
        """Number of segments (2 or 3)."""
        return self.subject.n_segments

    @property
    def segment_names(self) -> tuple[str, ...]:
        """``upper_arm``, ``forearm`` (, ``hand``)."""
        return segments_for(self.n_segments)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """``shoulder``, ``elbow`` (, ``wrist``)."""
        return joints_for(self.n_segments)

    @property
    def lengths_m(self) -> tuple[float, ...]:
        """(n,) segment lengths a_j, m."""
        return self.subject.lengths_m

    @property
    def masses_kg(self) -> tuple[float, ...]:
        """(n,) segment masses m_j, kg."""
        return self.subject.masses_kg

    @property
    def com_m(self) -> tuple[float, ...]:
        """(n,) COM distances l_j from the proximal joint, m."""
        return self.subject.com_m

    @property
    def first_moments_kgm(self) -> tuple[float, ...]:
        """(n,) ``m_j l_j``, kg m."""
        return self.subject.first_moments_kgm

    @property
    def static_moments_kgm(self) -> tuple[float, ...]:
        """(n,) grouped static moments beta_j (CONTRACT.md), kg m."""
        return self.subject.static_moments_kgm

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (schema ``bsp_ros/truth/1``), shaped like the estimate but with plain floats.

        Returns
        -------
        dict
            ``{"schema", "segments": {name: {length_m, static_moment_kgm, mass_kg, com_m,
            first_moment_kgm}}, "joints": {name: {coulomb_nm, viscous_nms, stiffness_nm_per_rad,
            neutral_rad, offset_nm}}, "friction": {transition_rad_s, stribeck_ratio,
            stribeck_speed_rad_s}, "trajectory": {joint: {center_deg, amplitude_deg, period_s,
            phase_rad}}, "simulation": {...}}``; ``simulation`` holds every sensor and marker nuisance
            (offsets and drift, handle payload, ``tf_static``, skin marker offsets).
        """
        s, p, t = self.subject, self.passive, self.trajectory
        segments = {
            name: {
                "length_m": s.lengths_m[j],
                "static_moment_kgm": s.static_moments_kgm[j],
                "mass_kg": s.masses_kg[j],
                "com_m": s.com_m[j],
                "first_moment_kgm": s.first_moments_kgm[j],
            }
            for j, name in enumerate(self.segment_names)
        }
        joints = {
            name: {
                "coulomb_nm": p.coulomb_nm[j],
                "viscous_nms": p.viscous_nms[j],
                "stiffness_nm_per_rad": p.stiffness_nm_per_rad[j],
                "neutral_rad": p.neutral_rad[j],
                "offset_nm": p.offset_nm[j],
            }
            for j, name in enumerate(self.joint_names)
        }
        if not isinstance(t, TrajectorySpec):  # a planned trajectory: its knots (bsp_ros.core.planning)
            trajectory: dict[str, Any] = {"planned": t.to_dict() if hasattr(t, "to_dict") else repr(t)}
        else:
            trajectory = {
                name: {
                    "center_deg": t.center_deg[j],
                    "amplitude_deg": t.amplitude_deg[j],
                    "period_s": t.period_s[j],
                    "phase_rad": t.phase_rad[j],
                }
                for j, name in enumerate(self.joint_names)
            }
        friction = {
            "transition_rad_s": p.friction_transition_rad_s,
            "stribeck_ratio": p.stribeck_ratio,
            "stribeck_speed_rad_s": p.stribeck_speed_rad_s,
        }
        return {
            "schema": TRUTH_SCHEMA,
            "segments": segments,
            "joints": joints,
            "friction": friction,
            "trajectory": trajectory,
            "simulation": dict(self.simulation),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SessionTruth:
        """Read back what ``to_dict`` wrote.

        Parameters
        ----------
        data : a ``bsp_ros/truth/1`` dict.

        Returns
        -------
        SessionTruth

        Raises
        ------
        InputError
            On a foreign schema, a missing key or a bad value.
        """
        schema = _require(data, "schema", "")
        if schema != TRUTH_SCHEMA:
            raise InputError(f"truth dict: schema must be {TRUTH_SCHEMA!r}, got {schema!r}")
        segments = _require(data, "segments", "")
        if not isinstance(segments, Mapping):
            raise InputError(f"truth dict: segments must be a mapping, got {segments!r}")
        n = _check_n_segments(len(segments), "truth dict: the number of segments")
        seg = [_require(segments, name, "segments.") for name in segments_for(n)]
        subject = SubjectTruth(
            lengths_m=tuple(_require(x, "length_m", "segment ") for x in seg),
            masses_kg=tuple(_require(x, "mass_kg", "segment ") for x in seg),
            com_m=tuple(_require(x, "com_m", "segment ") for x in seg),
        )
        joints = _require(data, "joints", "")
        jnt = [_require(joints, name, "joints.") for name in joints_for(n)]
        passive = PassiveTruth(
            coulomb_nm=tuple(_require(x, "coulomb_nm", "joint ") for x in jnt),
            viscous_nms=tuple(x.get("viscous_nms", 0.0) for x in jnt),
            stiffness_nm_per_rad=tuple(x.get("stiffness_nm_per_rad", 0.0) for x in jnt),
            neutral_rad=tuple(x.get("neutral_rad", 0.0) for x in jnt),
            offset_nm=tuple(x.get("offset_nm", 0.0) for x in jnt),
            **_friction_fields(data.get("friction", {})),
        )
        traj = _require(data, "trajectory", "")
        if isinstance(traj, Mapping) and "planned" in traj:
            from bsp_ros.core.planning.trajectory import PlannedTrajectory

            planned = PlannedTrajectory.from_dict(traj["planned"])
            return cls(subject, passive, planned, dict(data.get("simulation", {})))
        trj = [_require(traj, name, "trajectory.") for name in joints_for(n)]
        trajectory = TrajectorySpec(
            center_deg=tuple(_require(x, "center_deg", "trajectory ") for x in trj),
            amplitude_deg=tuple(_require(x, "amplitude_deg", "trajectory ") for x in trj),
            period_s=tuple(_require(x, "period_s", "trajectory ") for x in trj),
            phase_rad=tuple(_require(x, "phase_rad", "trajectory ") for x in trj),
        )
        simulation = data.get("simulation", {})
        if not isinstance(simulation, Mapping):
            raise InputError(f"truth dict: simulation must be a mapping, got {simulation!r}")
        return cls(subject, passive, trajectory, dict(simulation))


def _friction_fields(friction: Any) -> dict[str, Any]:
    """PassiveTruth friction-shape keywords from a truth dict's ``friction`` block (absent: plain Coulomb)."""
    if not isinstance(friction, Mapping):
        raise InputError(f"truth dict: friction must be a mapping, got {friction!r}")
    keys = {
        "transition_rad_s": "friction_transition_rad_s",
        "stribeck_ratio": "stribeck_ratio",
        "stribeck_speed_rad_s": "stribeck_speed_rad_s",
    }
    return {name: friction[key] for key, name in keys.items() if key in friction}


def _simulation_settings(spec: CellSpec) -> dict[str, Any]:
    s, m = spec.sensor, spec.markers
    return {
        "seed": spec.seed,
        "duration_s": spec.duration_s,
        "start_ns": spec.start_ns,
        "gravity_m_s2": GRAVITY_M_S2,
        "wrench_hz": s.wrench_hz,
        "wrench_phase_s": s.phase_s,
        "wrench_stamp_jitter_s": s.stamp_jitter_s,
        "sensor_frame_id": s.frame_id,
        "sensor_roll_pitch_yaw_deg": list(s.roll_pitch_yaw_deg),
        "force_noise_n": s.force_noise_n,
        "torque_noise_nm": s.torque_noise_nm,
        "force_bias_n": list(s.force_bias_n),
        "torque_bias_nm": list(s.torque_bias_nm),
        "force_drift_n_per_s": list(s.force_drift_n_per_s),
        "torque_drift_nm_per_s": list(s.torque_drift_nm_per_s),
        "handle_mass_kg": s.handle_mass_kg,
        "handle_com_m": list(s.handle_com_m),
        "tf_static": s.tf_static,
        "spike_fraction": s.spike_fraction,
        "spike_n": s.spike_n,
        "marker_hz": m.marker_hz,
        "marker_phase_s": m.phase_s,
        "marker_stamp_jitter_s": m.stamp_jitter_s,
        "marker_noise_m": m.noise_m,
        "shoulder_m": list(m.shoulder_m),
        "dropout_fraction": m.dropout_fraction,
        "dropout_mean_frames": m.dropout_mean_frames,
        "skin_offset_m": [list(pair) for pair in m.skin_offset_m],
    }


# --------------------------------------------------------------------------------------------------------
# simulator
# --------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SimulatedSession:
    """A simulated session and its truth.

    Attributes
    ----------
    session : the recorded streams (markers keyed ``shoulder``/``elbow``/(``wrist``)/``hand``).
    truth : what the session really was.
    """

    session: Session
    truth: SessionTruth


class CellSimulator:
    """The simulated cell, usable sample by sample (a real-time publisher) or for a whole session.

    Physics (CONTRACT.md): a planar chain in the world y-z plane, held quasi-statically (inertial and
    Coriolis terms omitted: at ~0.03 rad/s they are ~1e-4 of gravity) so that
    ``tau_G(q) + tau_p = -J(q)^T F_end``. ``tau_G`` is computed from each segment's mass and COM
    position (not from the grouped static moments); ``F_end = [Fy, Fz, Mx]`` is the wrench the hand
    exerts on the sensor at the contact point, in ``world``. A 2-segment chain holds a bearing: Mx = 0.
    Fx = My = Mz = 0 in ``world``. The sensor reads that wrench in its own axes plus the cell's nuisances
    (``SensorSpec``: offset and drift, the handle's weight, spikes; ``MarkerSpec.skin_offset_m``;
    ``PassiveTruth`` friction shape and elastic terms); :meth:`sample_tare_wrench` gives the handle-free
    readings of a tare.

    Random draws: one seeded ``np.random.Generator`` per stream (wrench stamps, wrench noise, marker
    stamps, and noise and dropouts per marker, wrench spikes), all seeded by ``spec.seed``, so a stream's values do
    not depend on how calls to the other streams interleave, and sampling in chunks gives the same
    values as sampling all at once.

    Parameters
    ----------
    spec : CellSpec
    """

    def __init__(self, spec: CellSpec) -> None:
        if not isinstance(spec, CellSpec):
            raise InputError(f"spec must be a CellSpec, got {spec!r}")
        self._spec = spec
        n = spec.n_segments
        self._marker_names = markers_for(n)
        self._lengths = np.asarray(spec.subject.lengths_m)
        self._masses = np.asarray(spec.subject.masses_kg)
        self._coms = np.asarray(spec.subject.com_m)
        self._rotation = spec.sensor.rotation_world_from_sensor
        self._rotation.setflags(write=False)
        self._shoulder = np.asarray(spec.markers.shoulder_m)
        children = np.random.SeedSequence(spec.seed).spawn(3 + 2 * len(self._marker_names))
        rngs = [np.random.default_rng(child) for child in children]
        self._rng_wrench_stamps, self._rng_wrench_noise, self._rng_marker_stamps = rngs[:3]
        k = len(self._marker_names)
        self._rng_marker_noise = dict(zip(self._marker_names, rngs[3 : 3 + k], strict=True))
        self._rng_dropout = dict(zip(self._marker_names, rngs[3 + k :], strict=True))
        self._lost: dict[str, bool | None] = dict.fromkeys(self._marker_names)
        # Its own stream (not one of the spawned children above), so spikes leave every other draw unchanged.
        self._rng_spikes = np.random.default_rng(np.random.SeedSequence([spec.seed, 13]))
        self._truth = SessionTruth(spec.subject, spec.passive, spec.trajectory, _simulation_settings(spec))

    # ---- properties -------------------------------------------------------------------------------

    @property
    def spec(self) -> CellSpec:
        """The cell's spec."""
        return self._spec

    @property
    def truth(self) -> SessionTruth:
        """The true parameters of the simulated cell."""
        return self._truth

    @property
    def n_segments(self) -> int:
        """Number of segments (2 or 3)."""
        return self._spec.n_segments

    @property
    def marker_names(self) -> tuple[str, ...]:
        """Marker names, proximal to distal."""
        return self._marker_names

    @property
    def rotation_world_from_sensor(self) -> np.ndarray:
        """(3, 3) rotation taking sensor-frame vectors into ``world`` (read-only)."""
        return self._rotation

    # ---- noise-free physics ------------------------------------------------------------------------

    def seconds_since_start(self, t_ns: npt.ArrayLike) -> np.ndarray:
        """(N,) int ns stamps -> (N,) float s since ``spec.start_ns`` (the trajectory's t = 0)."""
        stamps = np.atleast_1d(np.asarray(t_ns, dtype=np.int64))
        return (stamps - np.int64(self._spec.start_ns)).astype(np.float64) * 1e-9

    def joint_angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """True joint angles: (N,) s -> (N, n) rad (q1 absolute from +y, q2, q3 relative)."""
        return self._spec.trajectory.angles_rad(t_s)

    def joint_velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """True (analytic) joint velocities: (N,) s -> (N, n) rad/s."""
        return self._spec.trajectory.velocities_rad_s(t_s)

    def _joint_points_yz(self, q: np.ndarray) -> np.ndarray:
        """(N, n) angles -> (N, n + 1, 2) y-z positions of the joints and the contact point."""
        phi = np.cumsum(q, axis=1)  # absolute segment angles
        steps = self._lengths[:, None] * np.stack([np.cos(phi), np.sin(phi)], axis=-1)  # (N, n, 2)
        origin = np.broadcast_to(self._shoulder[1:], (q.shape[0], 1, 2))
        return np.concatenate([origin, origin + np.cumsum(steps, axis=1)], axis=1)

    def marker_positions_m(self, t_s: npt.ArrayLike) -> dict[str, np.ndarray]:
        """Noise-free marker positions in ``world`` (skin offsets included): (N,) s -> name -> (N, 3) m."""
        q = self.joint_angles_rad(t_s)
        points = self._joint_points_yz(q)
        phi = np.cumsum(q, axis=1)
        offsets = self._spec.markers.skin_offset_m
        out = {}
        for i, name in enumerate(self._marker_names):
            xyz = np.empty((q.shape[0], 3))
            xyz[:, 0] = self._shoulder[0]
            xyz[:, 1:] = points[:, i, :]
            if offsets:
                # Fixed in the segment starting at this joint (the hand marker: in the last segment).
                angle = phi[:, min(i, q.shape[1] - 1)]
                along, normal = offsets[i]
                xyz[:, 1] += along * np.cos(angle) - normal * np.sin(angle)
                xyz[:, 2] += along * np.sin(angle) + normal * np.cos(angle)
            out[name] = xyz
        return out

    def gravity_torque_nm(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Torque needed at each joint to hold the arm against gravity: (N,) s -> (N, n) Nm.

        ``tau_G,i = g * sum_{j >= i} m_j (y_com_j - y_joint_i)``: each segment's weight times the
        horizontal lever arm of its COM about joint i (positive: the COM is anterior of the joint).
        """
        q = self.joint_angles_rad(t_s)
        points = self._joint_points_yz(q)
        phi = np.cumsum(q, axis=1)
        com_y = points[:, :-1, 0] + self._coms * np.cos(phi)  # (N, n)
        n = self.n_segments
        tau = np.zeros_like(q)
        for i in range(n):
            for j in range(i, n):
                tau[:, i] += self._masses[j] * GRAVITY_M_S2 * (com_y[:, j] - points[:, i, 0])
        return tau

    def passive_torque_nm(self, t_s: npt.ArrayLike) -> np.ndarray:
        """True passive moments (the torque the driver must supply): (N,) s -> (N, n) Nm."""
        q = self.joint_angles_rad(t_s)
        qdot = self.joint_velocities_rad_s(t_s)
        p = self._spec.passive
        return (
            p.friction_nm(qdot)
            + np.asarray(p.viscous_nms) * qdot
            + np.asarray(p.stiffness_nm_per_rad) * (q - np.asarray(p.neutral_rad))
            + np.asarray(p.offset_nm)
        )

    def contact_jacobian(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Planar Jacobian of the contact point: (N,) s -> (N, 3, n), rows y, z, phi = q1 + ... + qn."""
        q = self.joint_angles_rad(t_s)
        points = self._joint_points_yz(q)
        lever = points[:, -1:, :] - points[:, :-1, :]  # contact point relative to each joint, (N, n, 2)
        jac = np.empty((q.shape[0], 3, q.shape[1]))
        jac[:, 0, :] = -lever[:, :, 1]
        jac[:, 1, :] = lever[:, :, 0]
        jac[:, 2, :] = 1.0
        return jac

    def wrench_world(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Noise-free wrench the hand exerts on the sensor, in ``world`` at the contact point.

        Parameters
        ----------
        t_s : (N,) float, s since the session start.

        Returns
        -------
        (N, 3) float64 ndarray
            ``[Fy (N), Fz (N), Mx (Nm)]`` solving ``-J^T F = tau_G + tau_p`` (Mx = 0 for 2 segments).
        """
        tau = self.gravity_torque_nm(t_s) + self.passive_torque_nm(t_s)
        jac = self.contact_jacobian(t_s)
        out = np.zeros((tau.shape[0], 3))
        if self.n_segments == 3:
            out[:] = np.linalg.solve(-jac.transpose(0, 2, 1), tau[..., None])[..., 0]
        else:
            out[:, :2] = np.linalg.solve(-jac[:, :2, :].transpose(0, 2, 1), tau[..., None])[..., 0]
        return out

    # ---- stamps --------------------------------------------------------------------------------------

    def _stamps(self, rate_hz: float, phase_s: float, jitter_s: float, rng: np.random.Generator) -> np.ndarray:
        count = max(math.ceil((self._spec.duration_s - phase_s) * rate_hz), 1)
        nominal = phase_s + np.arange(count, dtype=np.float64) / rate_hz
        offsets = np.round(nominal * 1e9)
        if jitter_s > 0.0:
            clip = _JITTER_CLIP_PERIODS * 1e9 / rate_hz
            offsets += np.round(np.clip(rng.normal(0.0, jitter_s * 1e9, count), -clip, clip))
        stamps = np.int64(self._spec.start_ns) + offsets.astype(np.int64)
        return check_stamps_ns("simulated stamps", stamps)

    def wrench_stamps_ns(self) -> np.ndarray:
        """(N,) int64 stamps of the whole session's wrench stream (nominal grid + jitter).

        The grid is ``start_ns + phase_s + k / wrench_hz`` for ``k`` with the nominal time below
        ``duration_s``. Each call draws fresh jitter from the stream's generator.
        """
        s = self._spec.sensor
        return self._stamps(s.wrench_hz, s.phase_s, s.stamp_jitter_s, self._rng_wrench_stamps)

    def marker_stamps_ns(self) -> np.ndarray:
        """(M,) int64 frame stamps of the whole session's marker streams (one mocap clock)."""
        m = self._spec.markers
        return self._stamps(m.marker_hz, m.phase_s, m.stamp_jitter_s, self._rng_marker_stamps)

    # ---- noisy samples -------------------------------------------------------------------------------

    def sample_wrench(self, t_ns: npt.ArrayLike) -> WrenchSeries:
        """Noisy wrench in the sensor frame at the given stamps.

        Parameters
        ----------
        t_ns : (N,) int64, strictly increasing stamps, ns (the wrench is exact at each stamp).

        Returns
        -------
        WrenchSeries
            Force (N, 3) N and moment (N, 3) Nm in ``sensor.frame_id`` axes, referenced at the contact
            point: ``R^T F_world + offset(t) + payload + noise`` (offset with its drift, the handle's
            gravity load ``R^T m g`` and its moment ``c x R^T m g``; spikes if ``spike_fraction`` > 0).
        """
        stamps = check_stamps_ns("t_ns", t_ns)
        world = self.wrench_world(self.seconds_since_start(stamps))
        force_w = np.zeros((stamps.size, 3))
        torque_w = np.zeros((stamps.size, 3))
        force_w[:, 1:] = world[:, :2]
        torque_w[:, 0] = world[:, 2]
        s = self._spec.sensor
        noise = self._rng_wrench_noise.standard_normal((stamps.size, 6))
        # Row vectors: v_sensor = R^T v_world  <=>  v_sensor_row = v_world_row @ R.
        offset_f, offset_m = s.offset_at(self.seconds_since_start(stamps))
        load_f, load_m = s.payload_wrench(self._rotation)
        force = force_w @ self._rotation + offset_f + load_f + s.force_noise_n * noise[:, :3]
        if s.spike_fraction > 0.0:
            draws = self._rng_spikes.random((stamps.size, 3))
            hit = draws[:, 0] < s.spike_fraction
            axis = (draws[hit, 1] * 3).astype(int)
            force[np.flatnonzero(hit), axis] += np.where(draws[hit, 2] < 0.5, -s.spike_n, s.spike_n)
        torque = torque_w @ self._rotation + offset_m + load_m + s.torque_noise_nm * noise[:, 3:]
        return WrenchSeries(t_ns=stamps, force_n=force, torque_nm=torque, frame_id=s.frame_id)

    def sample_tare_wrench(self, t_ns: npt.ArrayLike, tare: TareSpec) -> tuple[WrenchSeries, np.ndarray]:
        """Noisy wrench of the cell in tare mode (handle free, no arm) at the given stamps, for a live publisher.

        Parameters
        ----------
        t_ns : (N,) int64, strictly increasing stamps, ns.
        tare : the tare recording; it starts ``tare.start_offset_s`` after ``spec.start_ns`` (use 0 for a
            publisher that starts in tare mode).

        Returns
        -------
        wrench : offset (with drift) + handle load + noise in the sensor frame (see :func:`simulate_tare`).
        rotations : (N, 3, 3) the sensor's orientation at each stamp (publish it on ``/tf`` if it swings).
        """
        if not isinstance(tare, TareSpec):
            raise InputError(f"tare must be a TareSpec, got {tare!r}")
        stamps = check_stamps_ns("t_ns", t_ns)
        return _tare_wrench(self._spec, tare, stamps, self._rng_wrench_noise.standard_normal((stamps.size, 6)))

    def _dropout_mask(self, name: str, count: int) -> np.ndarray:
        """(count,) bool, True where the frame is lost: a two-state Markov chain carried across calls."""
        m = self._spec.markers
        lost = np.zeros(count, dtype=bool)
        if m.dropout_fraction <= 0.0 or count == 0:
            return lost
        p_recover = 1.0 / m.dropout_mean_frames
        p_lose = m.dropout_fraction * p_recover / (1.0 - m.dropout_fraction)
        draws = self._rng_dropout[name].random(count)
        state = self._lost[name]
        if state is None:  # the first frame: drawn from the stationary distribution
            state = bool(draws[0] < m.dropout_fraction)
            lost[0] = state
            start = 1
        else:
            start = 0
        for k in range(start, count):
            state = bool(draws[k] >= p_recover) if state else bool(draws[k] < p_lose)
            lost[k] = state
        self._lost[name] = state
        return lost

    def sample_markers(self, t_ns: npt.ArrayLike) -> dict[str, MarkerSeries]:
        """Noisy marker positions at the given frame stamps, with occluded frames left out.

        Parameters
        ----------
        t_ns : (M,) int64, strictly increasing frame stamps, ns.

        Returns
        -------
        dict
            Marker name -> ``MarkerSeries`` with the frames that marker was visible in ((M_k, 3), m,
            ``world``). Dropouts follow a per-marker Markov chain whose state persists across calls.
        """
        stamps = check_stamps_ns("t_ns", t_ns)
        clean = self.marker_positions_m(self.seconds_since_start(stamps)) if stamps.size else {}
        out = {}
        for name in self._marker_names:
            noise = self._rng_marker_noise[name].standard_normal((stamps.size, 3)) * self._spec.markers.noise_m
            keep = ~self._dropout_mask(name, stamps.size)
            position = clean[name] + noise if stamps.size else np.zeros((0, 3))
            out[name] = MarkerSeries(t_ns=stamps[keep], position_m=position[keep])
        return out


def simulate_cell(spec: CellSpec) -> SimulatedSession:
    """Simulate a whole session.

    Parameters
    ----------
    spec : CellSpec

    Returns
    -------
    SimulatedSession
        ``.session`` (wrench in the sensor frame, markers in ``world``, ``rotation_world_from_sensor``
        set; the identity if ``spec.sensor.tf_static`` is False, as a reader of a bag without
        ``/tf_static`` takes it) and ``.truth``.
    """
    sim = CellSimulator(spec)
    wrench = sim.sample_wrench(sim.wrench_stamps_ns())
    markers = sim.sample_markers(sim.marker_stamps_ns())
    rotation = np.array(sim.rotation_world_from_sensor) if spec.sensor.tf_static else np.eye(3)
    session = Session(wrench=wrench, markers=markers, rotation_world_from_sensor=rotation)
    return SimulatedSession(session=session, truth=sim.truth)


# --------------------------------------------------------------------------------------------------------
# tare recording (handle free)
# --------------------------------------------------------------------------------------------------------

_SWING_PHASES_RAD = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)


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

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration_s", check_positive("tare duration_s", self.duration_s, 3600.0))
        object.__setattr__(
            self, "start_offset_s", check_finite_scalar("tare start_offset_s", self.start_offset_s, -1e5, 1e5)
        )
        object.__setattr__(self, "swing_rpy_deg", _float_tuple("swing_rpy_deg", self.swing_rpy_deg, 3, 0.0, 90.0))
        object.__setattr__(self, "swing_period_s", check_positive("swing_period_s", self.swing_period_s, 1e4))
        object.__setattr__(self, "tf_hz", check_positive("tf_hz", self.tf_hz, 1000.0))

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


def _tare_wrench(
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
        clip = _JITTER_CLIP_PERIODS * 1e9 / s.wrench_hz
        offsets_ns += np.round(np.clip(rng_stamps.normal(0.0, s.stamp_jitter_s * 1e9, count), -clip, clip))
    stamps = check_stamps_ns("tare stamps", np.int64(start_ns) + offsets_ns.astype(np.int64))
    wrench, _ = _tare_wrench(spec, tare, stamps, rng_noise.standard_normal((count, 6)))
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
