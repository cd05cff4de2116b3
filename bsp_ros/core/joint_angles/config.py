"""The settings of the marker kinematics and what they produce: angles, lengths, velocities on a grid."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class KinematicsConfig:
    """How marker trajectories become joint angles.

    Attributes
    ----------
    cutoff_hz : zero-phase low-pass cutoff for the angles (the method paper's 5 Hz).
    direction_cutoff_hz : far lower cutoff for the velocity whose sign gives the direction of motion;
        at 0.03 rad/s a 5 Hz-filtered derivative is as noisy as the signal (NOTES.md 1).
    max_gap_s : marker gaps up to this long are bridged by interpolation; longer ones remove samples.
    min_run_s : stretches of valid frames shorter than this are dropped (the filters need a run-in).
    max_length_error_m : a marker frame whose segment length is further than this (and than
        ``outlier_sd`` robust standard deviations) from the session's median length is removed.
    outlier_sd : a marker position further than this many robust standard deviations from the rolling
        median of its neighbours (a jump no arm makes) is removed, as is a joint angle in
        :func:`kinematics_from_angles`.
    dynamics_cutoff_hz : zero-phase low-pass cutoff of the angles whose derivatives give the velocities and
        accelerations of the inertial torques: twice differentiated, marker noise grows with the cutoff to
        the power 2.5, and an arm moved at rehabilitation speeds has no content above ~0.5 Hz.
    """

    cutoff_hz: float = 5.0
    direction_cutoff_hz: float = 0.5
    dynamics_cutoff_hz: float = 1.0
    max_gap_s: float = 0.1
    min_run_s: float = 2.0
    max_length_error_m: float = 0.005
    outlier_sd: float = 8.0

    def __post_init__(self) -> None:
        check_positive("cutoff_hz", self.cutoff_hz, 1000.0)
        check_positive("direction_cutoff_hz", self.direction_cutoff_hz, self.cutoff_hz)
        check_positive("dynamics_cutoff_hz", self.dynamics_cutoff_hz, 1000.0)
        check_finite_scalar("max_gap_s", self.max_gap_s, 0.0, 10.0)
        check_finite_scalar("min_run_s", self.min_run_s, 0.0, 600.0)
        check_positive("max_length_error_m", self.max_length_error_m, 1.0)
        check_positive("outlier_sd", self.outlier_sd, 1000.0)


@dataclass(frozen=True, kw_only=True)
class MarkerKinematics:
    """Joint angles on a uniform marker-rate grid.

    Attributes
    ----------
    t_ns : (M,) int64 grid stamps (ns).
    q_rad : (M, n) low-pass filtered joint angles (rad); NaN where not valid.
    direction_velocity_rad_s : (M, n) heavily smoothed joint velocities (rad/s); NaN where not valid.
    lengths_m : (n,) segment lengths (m), medians over the session of the sagittal marker distances.
    lengths_std_m : (n,) standard errors of those lengths (m).
    n_frames_bridged : frames filled across short gaps, per marker.
    n_frames_invalid : grid frames without valid angles (long gaps, short runs, edges).
    n_frames_rejected : marker (or ``angles``) -> frames removed as inconsistent with the rigid chain.
    direction_velocity_noise_rad_s : (n,) standard deviation of the marker noise in the direction
        velocities (rad/s), propagated from the angle noise through the filter.
    warnings : plain-language notes on data quality.
    velocity_rad_s, acceleration_rad_s2 : (M, n) derivatives of the angles low-passed at
        ``dynamics_cutoff_hz`` (rad/s, rad/s^2), for the inertial torques; None when not computed.
    config : the filter settings used, cutoffs raised to the motion's band; None when not recorded.
    """

    t_ns: np.ndarray
    q_rad: np.ndarray
    direction_velocity_rad_s: np.ndarray
    lengths_m: np.ndarray
    lengths_std_m: np.ndarray
    n_frames_bridged: dict[str, int]
    n_frames_invalid: int
    direction_velocity_noise_rad_s: np.ndarray
    warnings: list[str] = field(default_factory=list)
    n_frames_rejected: dict[str, int] = field(default_factory=dict)
    velocity_rad_s: np.ndarray | None = None
    acceleration_rad_s2: np.ndarray | None = None
    config: KinematicsConfig | None = None

    @property
    def rate_hz(self) -> float:
        """Grid rate (Hz)."""
        return 1e9 / float(self.t_ns[1] - self.t_ns[0])
