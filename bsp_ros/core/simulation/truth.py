"""The truth of a simulated session (schema ``bsp_ros/truth/1``): what an estimate is scored against."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from bsp_ros.core.simulation.cell import CellSpec
from bsp_ros.core.simulation.checks import GRAVITY_M_S2, TRUTH_SCHEMA, check_n_segments
from bsp_ros.core.simulation.subject import PassiveTruth, SubjectTruth
from bsp_ros.core.simulation.trajectory import JointTrajectory, TrajectorySpec
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError


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
        """(n,) grouped static moments beta_j (docs/contract.md), kg m."""
        return self.subject.static_moments_kgm

    @property
    def inertia_com_kgm2(self) -> tuple[float, ...]:
        """(n,) inertias about the COMs (sagittal-plane rotation), kg m^2."""
        return self.subject.inertia_com_kgm2

    @property
    def inertia_kgm2(self) -> tuple[float, ...]:
        """(n,) inertias about the proximal joints, kg m^2."""
        return self.subject.inertia_kgm2

    @property
    def grouped_inertia_kgm2(self) -> tuple[float, ...]:
        """(n,) identifiable inertia groups, kg m^2."""
        return self.subject.grouped_inertia_kgm2

    @property
    def perpendicular_moments_kgm(self) -> tuple[float, ...]:
        """(n,) ``m_j d_j``, kg m."""
        return self.subject.perpendicular_moments_kgm

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (schema ``bsp_ros/truth/1``), shaped like the estimate but with plain floats.

        Returns
        -------
        dict
            ``{"schema", "segments": {name: {length_m, static_moment_kgm, mass_kg, com_m,
            first_moment_kgm, inertia_com_kgm2, inertia_kgm2, grouped_inertia_kgm2,
            perpendicular_moment_kgm, com_perpendicular_m}}, "joints": {name: {coulomb_nm, viscous_nms,
            stiffness_nm_per_rad, neutral_rad, offset_nm, stiffening_nm}}, "friction": {transition_rad_s,
            stribeck_ratio, stribeck_speed_rad_s}, "elastic": {biarticular_nm, biarticular_neutral_rad,
            stiffening_width_rad}, "trajectory": {joint: {center_deg, amplitude_deg, period_s,
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
                "inertia_com_kgm2": s.inertia_com_kgm2[j],
                "inertia_kgm2": s.inertia_kgm2[j],
                "grouped_inertia_kgm2": s.grouped_inertia_kgm2[j],
                "perpendicular_moment_kgm": s.perpendicular_moments_kgm[j],
                "com_perpendicular_m": s.com_perpendicular_m[j],
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
                "stiffening_nm": p.stiffening_nm[j],
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
            "elastic": {
                "biarticular_nm": p.biarticular_nm,
                "biarticular_neutral_rad": p.biarticular_neutral_rad,
                "stiffening_width_rad": p.stiffening_width_rad,
            },
            "trajectory": trajectory,
            "simulation": dict(self.simulation),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SessionTruth:
        """Read back what ``to_dict`` wrote.

        Parameters
        ----------
        data : a ``bsp_ros/truth/1`` dict. Files written before inertias were simulated lack the
            segments' inertia keys: their inertias take ``SubjectTruth``'s default and their COMs lie
            on the axes.

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
        n = check_n_segments(len(segments), "truth dict: the number of segments")
        seg = [_require(segments, name, "segments.") for name in segments_for(n)]
        subject = SubjectTruth(
            lengths_m=tuple(_require(x, "length_m", "segment ") for x in seg),
            masses_kg=tuple(_require(x, "mass_kg", "segment ") for x in seg),
            com_m=tuple(_require(x, "com_m", "segment ") for x in seg),
            inertia_com_kgm2=_inertias(seg),
            com_perpendicular_m=tuple(x.get("com_perpendicular_m", 0.0) for x in seg),
        )
        joints = _require(data, "joints", "")
        jnt = [_require(joints, name, "joints.") for name in joints_for(n)]
        passive = PassiveTruth(
            coulomb_nm=tuple(_require(x, "coulomb_nm", "joint ") for x in jnt),
            viscous_nms=tuple(x.get("viscous_nms", 0.0) for x in jnt),
            stiffness_nm_per_rad=tuple(x.get("stiffness_nm_per_rad", 0.0) for x in jnt),
            neutral_rad=tuple(x.get("neutral_rad", 0.0) for x in jnt),
            offset_nm=tuple(x.get("offset_nm", 0.0) for x in jnt),
            stiffening_nm=tuple(x.get("stiffening_nm", 0.0) for x in jnt),
            **_friction_fields(data.get("friction", {})),
            **_elastic_fields(data.get("elastic", {})),
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


def _elastic_fields(elastic: Any) -> dict[str, Any]:
    """PassiveTruth two-joint and stiffening keywords from a truth dict's ``elastic`` block (absent: none)."""
    if not isinstance(elastic, Mapping):
        raise InputError(f"truth dict: elastic must be a mapping, got {elastic!r}")
    keys = ("biarticular_nm", "biarticular_neutral_rad", "stiffening_width_rad")
    return {key: elastic[key] for key in keys if key in elastic}


def _inertias(segments: list[Any]) -> tuple[float, ...]:
    """Per-segment ``inertia_com_kgm2`` of a truth dict, or ``()`` (the default) if any segment lacks it."""
    if all(isinstance(x, Mapping) and "inertia_com_kgm2" in x for x in segments):
        return tuple(x["inertia_com_kgm2"] for x in segments)
    return ()


def simulation_settings(
    spec: CellSpec, skin_offset_m: tuple[tuple[float, float], ...], pitch_reference_rad: float
) -> dict[str, Any]:
    """JSON-ready settings of a session for the truth's ``simulation`` block.

    Parameters
    ----------
    spec : the cell.
    skin_offset_m : the session's skin marker offsets (given plus drawn), ``(along, normal)`` per marker, m.
    pitch_reference_rad : the handle pitch at which a turning sensor sits at its mounting orientation, rad.
    """
    s, m = spec.sensor, spec.markers
    return {
        "seed": spec.seed,
        "duration_s": spec.duration_s,
        "start_ns": spec.start_ns,
        "gravity_m_s2": GRAVITY_M_S2,
        "inertia": spec.inertia,
        "robot_handle_pose": spec.robot_handle_pose,
        "trunk_tilt_deg": math.degrees(spec.trunk_tilt_rad),
        "wrench_hz": s.wrench_hz,
        "wrench_phase_s": s.phase_s,
        "wrench_stamp_jitter_s": s.stamp_jitter_s,
        "sensor_frame_id": s.frame_id,
        "sensor_roll_pitch_yaw_deg": list(s.roll_pitch_yaw_deg),
        "sensor_turns_with_handle": s.turns_with_handle,
        "handle_pitch_reference_rad": pitch_reference_rad,
        "wrench_filter_kind": s.filter_kind,
        "wrench_filter_delay_s": s.filter_delay_s,
        "wrench_average_over_period": s.average_over_period,
        "wrench_clock_offset_s": s.clock_offset_s,
        "wrench_delay_s": s.delay_s,
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
        "skin_offset_m": [list(pair) for pair in skin_offset_m],
        "skin_offset_bound_m": m.skin_offset_bound_m,
    }
