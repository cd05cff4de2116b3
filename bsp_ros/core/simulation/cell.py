"""One simulated session's definition (CellSpec) and the two standard cells: a human arm and the paper's arm."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.checks import (
    DEFAULT_START_NS,
    MAX_DURATION_S,
    MIN_ELBOW_SIN,
    check_bool,
    check_int,
)
from bsp_ros.core.simulation.markers import MarkerSpec
from bsp_ros.core.simulation.sensor import SensorSpec
from bsp_ros.core.simulation.subject import PassiveTruth, SubjectTruth
from bsp_ros.core.simulation.trajectory import JointTrajectory, TrajectorySpec
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive


@normalising
@dataclass(frozen=True, kw_only=True)
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
    inertia : True: the wrench solves the full rigid-body equation ``M(q) q'' + C(q, q') q' + tau_G(q)
        + tau_p = -J^T F_end`` with the trajectory's velocities and accelerations (the default: a real arm
        has inertia). False: quasi-static, ``tau_G(q) + tau_p = -J^T F_end``, as the method paper models it
        (inertial terms are ~1e-4 of gravity at 0.03 rad/s).
    robot_handle_pose : True: the robot publishes the contact point from its kinematics (``Session.handle_pose``,
        ``/robot/handle_pose``), exact, at each wrench sample's instant on the marker clock.
    trunk_tilt_rad : the patient's trunk tilted in ``world`` by this much (rad, in the sense of ``q_1``; within
        +-pi/2): the shoulder's passive moment follows ``q_1 - trunk_tilt_rad``, gravity the world angles.

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
    inertia: bool = True
    robot_handle_pose: bool = False
    trunk_tilt_rad: float = 0.0

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the duration as a float, the start and the seed as ints."""
        for name, kind in (
            ("subject", SubjectTruth),
            ("passive", PassiveTruth),
            ("trajectory", JointTrajectory),
            ("sensor", SensorSpec),
            ("markers", MarkerSpec),
        ):
            if not isinstance(getattr(given, name), kind):
                raise InputError(f"{name} must be a {kind.__name__}, got {getattr(given, name)!r}")
        n = given.subject.n_segments
        if given.passive.n_joints != n:
            raise InputError(f"passive has {given.passive.n_joints} joints, the subject has {n} segments")
        if given.trajectory.n_joints != n:
            raise InputError(f"trajectory has {given.trajectory.n_joints} joints, the subject has {n} segments")
        if given.markers.skin_offset_m and len(given.markers.skin_offset_m) != n + 1:
            raise InputError(
                f"markers.skin_offset_m has {len(given.markers.skin_offset_m)} pairs, the chain has {n + 1} markers"
            )
        out = {
            "duration_s": check_positive("duration_s", given.duration_s, MAX_DURATION_S),
            "start_ns": check_int("start_ns", given.start_ns, 1, 2**62),
            "seed": check_int("seed", given.seed, 0),
        }
        check_bool("inertia", given.inertia)
        check_finite_scalar("trunk_tilt_rad", given.trunk_tilt_rad, -np.pi / 2, np.pi / 2)
        if isinstance(given.trajectory, TrajectorySpec):
            centre, amp = given.trajectory.center_deg[1], given.trajectory.amplitude_deg[1]
            elbow = np.radians(np.linspace(centre - amp, centre + amp, 721))
        else:  # any other motion: the elbow angles it takes over the session
            elbow = given.trajectory.angles_rad(np.linspace(0.0, out["duration_s"], 7201))[:, 1]
            centre, amp = float(np.degrees(elbow.mean())), float(np.degrees(np.ptp(elbow)) / 2)
        worst = float(np.abs(np.sin(elbow)).min())
        if worst < MIN_ELBOW_SIN:
            raise InputError(
                f"elbow range {centre!r} +- {amp!r} deg comes within 5 deg of a straight or folded arm "
                f"(|sin q2| = {worst:.3g}): the wrench cannot be resolved there"
            )
        return out

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
