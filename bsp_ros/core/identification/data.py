"""Identification input: joint angles, direction velocities and contact torques on common stamps."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsp_ros.core.contact_point import chain_markers
from bsp_ros.core.identification.planarity import out_of_plane_fraction
from bsp_ros.core.identification.rate import IDENTIFICATION_MAX_RATE_HZ, block_means
from bsp_ros.core.joint_angles import (
    KinematicsConfig,
    MarkerKinematics,
    kinematics_from_markers,
    resample_with_motion,
)
from bsp_ros.core.model import contact_torques_nm
from bsp_ros.core.streams import EmgSeries, Session, WrenchSeries, markers_for
from bsp_ros.errors import DataError, InputError


@dataclass(frozen=True, kw_only=True)
class IdentificationData:
    """Samples ready for identification, one row per usable wrench sample.

    Attributes
    ----------
    t_ns : (N,) int64 stamps (ns).
    q_rad : (N, n) joint angles (rad).
    velocity_rad_s : (N, n) direction-of-motion velocities (rad/s).
    tau_nm : (N, n) measured joint torques ``-J^T F_end`` (Nm).
    lengths_m, lengths_std_m : (n,) segment lengths and their standard errors (m).
    velocity_noise_rad_s : (n,) noise of the direction velocities (rad/s), NaN if unknown.
    n_wrench_samples : wrench samples received, before any was removed.
    warnings : what was removed and why.
    removed_samples : implausible samples removed before identification: ``wrench_absurd``,
        ``wrench_non_finite`` and ``marker_<name>`` (frames inconsistent with the rigid chain) -> count.
    qd_rad_s, qdd_rad_s2 : (N, n) smooth joint velocities (rad/s) and accelerations (rad/s^2) for the inertial
        torques; None when the source gives none (then the arm is taken as quasi-static, and the inertial
        terms' prior uncertainty cannot be propagated).
    contact_from_robot : True where the contact point came from the robot's handle pose, not a skin marker (its
        placement uncertainty is then the robot's registration to ``world``, not a marker's).
    trunk_rad : (N,) the trunk's tilt in ``world`` per sample (rad, in the sense of ``q_1``), None: upright. A
        recording with the trunk tilted turns gravity relative to the arm while the passive moments follow the
        joint angles: the shoulder's passive angle is ``q_1 - trunk`` (:attr:`passive_q_rad`), gravity and
        the geometry keep ``q_rad``.
    recording_index : (N,) which recording each sample came from (0, 1, ...), None: one recording.
    out_of_plane : (n,) each segment's lateral excursion as a fraction of its length (the planar model's error
        of its gravity torque), None where the markers' lateral coordinates are not known (live).
    markers_moved : the recordings' segment lengths differ beyond their noise: a marker was re-attached between
        them, so each recording has its own placement (``recording_index``), not one shared by all.
    emg : the muscles' EMG envelopes over the session (on their own stamps), None where none were recorded.
    """

    t_ns: np.ndarray
    q_rad: np.ndarray
    velocity_rad_s: np.ndarray
    tau_nm: np.ndarray
    lengths_m: np.ndarray
    lengths_std_m: np.ndarray
    velocity_noise_rad_s: np.ndarray
    n_wrench_samples: int = 0
    warnings: list[str] = field(default_factory=list)
    removed_samples: dict[str, int] = field(default_factory=dict)
    qd_rad_s: np.ndarray | None = None
    qdd_rad_s2: np.ndarray | None = None
    contact_from_robot: bool = False
    trunk_rad: np.ndarray | None = None
    recording_index: np.ndarray | None = None
    out_of_plane: np.ndarray | None = None
    markers_moved: bool = False
    emg: EmgSeries | None = None

    @property
    def n_joints(self) -> int:
        """Number of joints (= segments)."""
        return int(self.q_rad.shape[1])

    @property
    def passive_q_rad(self) -> np.ndarray:
        """(N, n) the angles the passive moments follow: the shoulder's relative to the trunk, the others as
        ``q_rad``."""
        if self.trunk_rad is None:
            return self.q_rad
        q = self.q_rad.copy()
        q[:, 0] -= self.trunk_rad
        return q

    def window(self, start: int, stop: int) -> IdentificationData:
        """Rows ``start:stop`` (a sliding window for online use)."""
        return IdentificationData(
            t_ns=self.t_ns[start:stop],
            q_rad=self.q_rad[start:stop],
            velocity_rad_s=self.velocity_rad_s[start:stop],
            tau_nm=self.tau_nm[start:stop],
            lengths_m=self.lengths_m,
            lengths_std_m=self.lengths_std_m,
            velocity_noise_rad_s=self.velocity_noise_rad_s,
            n_wrench_samples=stop - start,
            warnings=list(self.warnings),
            removed_samples=dict(self.removed_samples),
            qd_rad_s=None if self.qd_rad_s is None else self.qd_rad_s[start:stop],
            qdd_rad_s2=None if self.qdd_rad_s2 is None else self.qdd_rad_s2[start:stop],
            contact_from_robot=self.contact_from_robot,
            trunk_rad=None if self.trunk_rad is None else self.trunk_rad[start:stop],
            recording_index=None if self.recording_index is None else self.recording_index[start:stop],
            out_of_plane=self.out_of_plane,
            markers_moved=self.markers_moved,
            emg=self.emg,
        )


# A step back in stamps larger than this is a clock jump, not jitter or reordering in transport.
CLOCK_JUMP_NS = 1_000_000_000

# No arm on a rehab cell's force sensor exerts this: such a sample is damage or a sensor fault.
MAX_FORCE_N = 5000.0
MAX_TORQUE_NM = 500.0


def wrench_world_yzx(wrench: WrenchSeries, rotation_world_from_sensor: np.ndarray) -> np.ndarray:
    """``[F_y, F_z, M_x]`` in ``world`` from a sensor-frame wrench.

    Parameters
    ----------
    wrench : force (N) and moment (Nm) in the sensor frame, referenced at the contact point.
    rotation_world_from_sensor : (3, 3), or (N, 3, 3) one per sample.

    Returns
    -------
    (N, 3) ``[F_y (N), F_z (N), M_x (Nm)]``; the translation of the frame does not matter because the
    wrench is already referenced at the contact point.
    """
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    if rotation.shape == (3, 3):
        force = wrench.force_n @ rotation.T
        torque = wrench.torque_nm @ rotation.T
    elif rotation.shape == (wrench.t_ns.size, 3, 3):
        force = np.einsum("nij,nj->ni", rotation, wrench.force_n)
        torque = np.einsum("nij,nj->ni", rotation, wrench.torque_nm)
    else:
        raise InputError(f"rotation_world_from_sensor must be (3, 3) or (N, 3, 3), got {rotation.shape}")
    return np.column_stack((force[:, 1], force[:, 2], torque[:, 0]))


def _clean_wrench(wrench: WrenchSeries) -> tuple[np.ndarray, list[str], dict[str, int]]:
    """Indices of usable wrench samples in time order: finite, unique stamps; say what was removed."""
    t_ns = np.asarray(wrench.t_ns, dtype=np.int64)
    values = np.column_stack((wrench.force_n, wrench.torque_nm))
    notes = []
    finite = np.isfinite(values).all(axis=1)
    if not finite.all():
        notes.append(f"wrench: {int((~finite).sum())} samples with NaN/Inf removed")
    with np.errstate(invalid="ignore", over="ignore"):
        absurd = finite & (
            (np.linalg.norm(values[:, :3], axis=1) > MAX_FORCE_N)
            | (np.linalg.norm(values[:, 3:], axis=1) > MAX_TORQUE_NM)
        )
    if absurd.any():
        notes.append(
            f"wrench: removed {int(absurd.sum())} samples with an absurd magnitude (|F| > {MAX_FORCE_N:g} N or "
            f"|M| > {MAX_TORQUE_NM:g} Nm)"
        )
        finite &= ~absurd
    positive = t_ns > 0
    if not positive.all():
        notes.append(f"wrench: {int((~positive).sum())} samples with stamp <= 0 removed")
    steps = np.diff(t_ns)
    if steps.size and steps.min() < -CLOCK_JUMP_NS:
        at = int(np.argmin(steps)) + 1
        raise DataError(
            f"wrench stamps jump back by {-steps.min() / 1e9:.3f} s at sample {at} (a looped replay or a reset "
            "clock): the parts cannot be told apart; split the recording"
        )
    if (steps < 0).any():
        notes.append(f"wrench: {int((steps < 0).sum())} stamps go backwards; samples re-ordered by stamp")
    order = np.argsort(t_ns, kind="stable")
    duplicate = np.concatenate(([False], np.diff(t_ns[order]) == 0))
    if duplicate.any():
        notes.append(f"wrench: {int(duplicate.sum())} duplicate stamps removed (first kept)")
    keep = (finite & positive)[order] & ~duplicate
    removed = {"wrench_absurd": int(absurd.sum()), "wrench_non_finite": int((~np.isfinite(values).all(axis=1)).sum())}
    return order[keep], notes, {k: v for k, v in removed.items() if v}


def identification_data_from_session(
    session: Session, kinematics_config: KinematicsConfig | None = None, kinematics: MarkerKinematics | None = None
) -> IdentificationData:
    """Angles from the markers, resampled onto the wrench stamps, with the contact torques.

    ``kinematics``: the session markers' angles, when already computed (the wrench-delay search needs them too).

    Raises
    ------
    DataError
        No wrench sample coincides with valid marker angles.
    """
    n_wrench = int(np.asarray(session.wrench.t_ns).size)
    if n_wrench == 0:
        raise DataError("the session holds no wrench samples")
    chain = chain_markers(session)
    if kinematics is None:
        kinematics = kinematics_from_markers(chain, session.n_segments, kinematics_config)
    rotation = np.asarray(session.rotation_world_from_sensor, dtype=np.float64)
    keep, notes, removed = _clean_wrench(session.wrench)
    removed.update({f"marker_{name}": count for name, count in kinematics.n_frames_rejected.items()})
    if rotation.ndim == 3:
        rotation = rotation[keep]
    wrench = WrenchSeries(
        session.wrench.t_ns[keep],
        session.wrench.force_n[keep],
        session.wrench.torque_nm[keep],
        session.wrench.frame_id,
    )
    # A fast sensor's samples are averaged to the identification rate in world (a turning sensor included).
    t_ns, wrench_yzx, counts = block_means(wrench.t_ns, wrench_world_yzx(wrench, rotation), IDENTIFICATION_MAX_RATE_HZ)
    q_rad, velocity, qd_all, qdd_all, valid = resample_with_motion(kinematics, t_ns)
    if not valid.any():
        raise DataError("no wrench sample falls where the markers give joint angles (streams do not overlap)")
    # Samples before the first and after the last angle are the session's edges (filter run-in): expected,
    # not worth a warning. Those lost inside the session are.
    inside = slice(np.flatnonzero(valid)[0], np.flatnonzero(valid)[-1] + 1)
    dropped = int(counts[inside][~valid[inside]].sum())
    if dropped:
        notes.append(f"{dropped} of {keep.size} wrench samples inside the session have no joint angles (marker gaps)")
    tau = contact_torques_nm(q_rad[valid], kinematics.lengths_m, wrench_yzx[valid])
    qd, qdd = qd_all[valid], qdd_all[valid]
    return IdentificationData(
        t_ns=t_ns[valid],
        q_rad=q_rad[valid],
        velocity_rad_s=velocity[valid],
        tau_nm=tau,
        lengths_m=kinematics.lengths_m,
        lengths_std_m=kinematics.lengths_std_m,
        velocity_noise_rad_s=kinematics.direction_velocity_noise_rad_s,
        n_wrench_samples=n_wrench,
        warnings=kinematics.warnings + notes,
        removed_samples=removed,
        qd_rad_s=qd,
        qdd_rad_s2=qdd,
        contact_from_robot=session.handle_pose is not None,
        out_of_plane=out_of_plane_fraction(chain, markers_for(session.n_segments)),
        emg=session.emg,
    )
