"""A MuJoCo cell run as a recorded session: sensor and marker noise, a rosbag2 MCAP bag and its truth.json."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from mujoco_cell import (
    FRICTION_SOLIMP,
    FRICTION_SOLREF,
    WELD_SOLIMP,
    WELD_SOLREF,
    ArmParams,
    CellOptions,
    EngineRun,
    angle_deg,
    degrees_range,
    inertial_ratio,
    peak_speed,
    run_engine,
    wrench_world_from_sensor_angle,
)
from scipy.spatial.transform import Rotation

from bsp_ros.bag.writer import write_session_bag
from bsp_ros.core.simulation import GRAVITY_M_S2, PassiveTruth, SessionTruth, SubjectTruth, rotation_from_rpy_deg
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries, joints_for, markers_for, segments_for
from msg_adapters import TransformSample

_CURVE_POINTS = 21


@dataclass
class CellSession:
    """A recorded MuJoCo session.

    Attributes
    ----------
    session : the streams a bag carries (wrench in the sensor frame, markers in world).
    tf_samples : per wrench sample ``world -> sensor`` (turning sensor), else empty.
    truth : the ``bsp_ros/truth/1`` dict.
    run : the engine's noise-free record.
    """

    session: Session
    tf_samples: list[TransformSample]
    truth: dict[str, Any]
    run: EngineRun


def _stamps_ns(options: CellOptions, t_s: np.ndarray) -> np.ndarray:
    return np.int64(options.start_ns) + np.round(t_s * 1e9).astype(np.int64)


def record(arm: ArmParams, options: CellOptions, run: EngineRun | None = None) -> CellSession:
    """Run the engine (unless ``run`` is given) and sample the sensor and markers with seeded noise.

    The wrench is the engine's sensor reading at the wrench rate: in the turning sensor's axes as MuJoCo reports
    it at the flange-mounted site, or, for a fixed sensor, rotated by the engine's site orientation into world and
    then into the fixed mount. Noise is white Gaussian per sensor axis; markers are the engine's marker sites at
    the marker rate (offset by ``marker_phase_s``) plus white Gaussian noise per world axis. The turning sensor's
    orientation on ``/tf`` is the one the robot commands (handle pitch then mount), not the engine's.
    """
    run = run if run is not None else run_engine(arm, options)
    dt = options.timestep_s
    rng_wrench, rng_markers = (np.random.default_rng(s) for s in np.random.SeedSequence([options.seed, 23]).spawn(2))
    mount = rotation_from_rpy_deg(*options.mount_rpy_deg)

    rows_w = np.arange(0, run.t_s.size, round(1.0 / (options.wrench_hz * dt)))
    t_w = _stamps_ns(options, run.t_s[rows_w])
    force, torque = run.force_site_n[rows_w], run.torque_site_nm[rows_w]
    tf_samples: list[TransformSample] = []
    if options.sensor == "fixed":
        to_sensor = np.einsum("ji,njk->nik", mount, run.rotation_world_from_site[rows_w])  # R_mount^T R_site
        force = np.einsum("nij,nj->ni", to_sensor, force)
        torque = np.einsum("nij,nj->ni", to_sensor, torque)
        rotation = mount
    else:
        known = wrench_world_from_sensor_angle(run, mount)[rows_w]
        quats = Rotation.from_matrix(known).as_quat()
        quats[quats[:, 3] < 0] *= -1.0
        handle = run.markers_m[rows_w, -1]  # the contact-point marker
        tf_samples = [
            TransformSample(int(t), "world", options.frame_id, handle[i], quats[i]) for i, t in enumerate(t_w)
        ]
        rotation = known[0]
    noise = rng_wrench.standard_normal((rows_w.size, 6))
    wrench = WrenchSeries(
        t_ns=t_w,
        force_n=force + options.force_noise_n * noise[:, :3],
        torque_nm=torque + options.torque_noise_nm * noise[:, 3:],
        frame_id=options.frame_id,
    )

    first = round(options.marker_phase_s / dt)
    rows_m = np.arange(first, run.t_s.size, round(1.0 / (options.marker_hz * dt)))
    t_m = _stamps_ns(options, run.t_s[rows_m])
    markers = {
        name: MarkerSeries(
            t_ns=t_m,
            position_m=run.markers_m[rows_m, k]
            + options.marker_noise_m * rng_markers.standard_normal((rows_m.size, 3)),
        )
        for k, name in enumerate(markers_for(arm.n_segments))
    }
    session = Session(wrench=wrench, markers=markers, rotation_world_from_sensor=np.array(rotation))
    return CellSession(session, tf_samples, truth_dict(arm, options, run), run)


def truth_dict(arm: ArmParams, options: CellOptions, run: EngineRun) -> dict[str, Any]:
    """The session's truth in the ``bsp_ros/truth/1`` shape (``SessionTruth.to_dict``) plus the shared keys.

    Per segment: ``inertia_com_kgm2``, ``inertia_kgm2`` (about the proximal joint: I_com + m (l^2 + d^2), d the
    COM's offset normal to the axis), ``grouped_inertia_kgm2`` (+ a_j^2 times the distal masses),
    ``perpendicular_moment_kgm`` (m d). Per joint: ``coulomb_nm`` = MuJoCo's frictionloss, ``viscous_nms`` =
    damping, ``stiffness_nm_per_rad`` = k and ``offset_nm`` = -k q_ref with ``neutral_rad`` 0 (the spring's
    generalized force on the arm is -k (q - q_ref), so the driver supplies k q - k q_ref), and ``passive_curve``:
    the elastic part k q - k q_ref over the angles the joint took (friction depends on the direction, not the
    angle). ``simulation`` names the engine and what the run showed (weld drift, inertial/gravity ratio). A
    2-segment arm's truth has its 2 segments and joints (no wrist, no hand).
    """
    n = arm.n_segments
    stiffness = np.asarray(arm.stiffness_nm_per_rad)
    offset = -stiffness * np.asarray(arm.springref_rad)
    truth = SessionTruth(
        SubjectTruth(arm.lengths_m, arm.masses_kg, arm.com_along_m),
        PassiveTruth(
            coulomb_nm=arm.frictionloss_nm,
            viscous_nms=arm.damping_nms,
            stiffness_nm_per_rad=tuple(stiffness),
            neutral_rad=(0.0,) * n,
            offset_nm=tuple(offset),
        ),
        options.trajectory,
        _simulation(arm, options, run),
    ).to_dict()
    masses = np.asarray(arm.masses_kg)
    for j, name in enumerate(segments_for(n)):
        m, l_along, d = masses[j], arm.com_along_m[j], arm.com_normal_m[j]
        about_joint = arm.inertia_com_kgm2[j] + m * (l_along**2 + d**2)
        truth["segments"][name].update(
            inertia_com_kgm2=arm.inertia_com_kgm2[j],
            inertia_kgm2=float(about_joint),
            grouped_inertia_kgm2=float(about_joint + arm.lengths_m[j] ** 2 * masses[j + 1 :].sum()),
            perpendicular_moment_kgm=float(m * d),
        )
    for j, name in enumerate(joints_for(n)):
        angles = np.linspace(run.q_rad[:, j].min(), run.q_rad[:, j].max(), _CURVE_POINTS)
        truth["joints"][name]["passive_curve"] = {
            "angle_deg": np.degrees(angles).tolist(),
            "moment_nm": (stiffness[j] * angles + offset[j]).tolist(),
        }
    return truth


def _simulation(arm: ArmParams, options: CellOptions, run: EngineRun) -> dict[str, Any]:
    turning = options.sensor == "turning"
    known = wrench_world_from_sensor_angle(run, rotation_from_rpy_deg(*options.mount_rpy_deg))
    return {
        "engine": f"mujoco {mujoco.__version__}",
        "seed": options.seed,
        "duration_s": options.duration_s,
        "start_ns": options.start_ns,
        "trunk_tilt_deg": float(np.degrees(options.trunk_tilt_rad)),
        "gravity_m_s2": GRAVITY_M_S2,
        "timestep_s": options.timestep_s,
        "solver": {
            "weld_solref": WELD_SOLREF,
            "weld_solimp": WELD_SOLIMP,
            "friction_solref": FRICTION_SOLREF,
            "friction_solimp": FRICTION_SOLIMP,
        },
        "wrench_hz": options.wrench_hz,
        "sensor": options.sensor,
        "sensor_frame_id": options.frame_id,
        "sensor_roll_pitch_yaw_deg": list(options.mount_rpy_deg),
        "tf_static": not turning,
        "tf_per_sample": turning,
        "force_noise_n": options.force_noise_n,
        "torque_noise_nm": options.torque_noise_nm,
        "marker_hz": options.marker_hz,
        "marker_phase_s": options.marker_phase_s,
        "marker_noise_m": options.marker_noise_m,
        "shoulder_m": list(options.shoulder_m),
        "skin_offset_m": [list(pair) for pair in options.skin_offset_m],
        "com_normal_m": list(arm.com_normal_m),
        "springref_rad": list(arm.springref_rad),
        "peak_speed_rad_s": list(peak_speed(run)),
        "angle_range_deg": degrees_range(run),
        "inertial_to_gravity": inertial_ratio(run),
        "weld_drift_max_m": float(run.weld_drift_m.max()),
        "weld_drift_max_rad": float(run.weld_drift_rad.max()),
        "sensor_angle_error_max_deg": float(angle_deg(known, run.rotation_world_from_site).max()) if turning else 0.0,
        "tracking_error_max_rad": float(np.abs(run.q_rad - run.q_command_rad).max()),
    }


def write_bag(out_dir: str | Path, cell: CellSession) -> Path:
    """Write ``cell`` as a rosbag2 MCAP bag with truth.json (``/tf_static`` for a fixed sensor, ``/tf`` if turning)."""
    return write_session_bag(
        out_dir,
        cell.session,
        cell.truth,
        tf_static=not cell.tf_samples,
        tf_samples=cell.tf_samples,
        seed=int(cell.truth["simulation"]["seed"]),
    )


def result_z(result: Any, truth: dict[str, Any]) -> dict[str, float]:
    """|z| of an ``IdentificationResult``'s static moments and Coulomb amplitudes against a cell's truth.json
    (:func:`truth_dict`), keyed ``quantity/owner``."""
    std = np.sqrt(np.diag(result.covariance))
    z = {}
    for i, (key, owner) in enumerate(result.names):
        group = "segments" if key == "static_moment_kgm" else "joints"
        if key in ("static_moment_kgm", "coulomb_nm"):
            z[f"{key}/{owner}"] = abs(result.values[i] - truth[group][owner][key]) / std[i]
    return z


__all__ = ["CellSession", "record", "result_z", "truth_dict", "write_bag"]
