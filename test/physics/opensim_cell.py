"""An independent test cell: OpenSim's arm26 (six relaxed muscles, two of them two-joint) held at the hand.

Test support (not part of the installed package): ``test/physics/test_opensim_cell.py`` and
``bench/musculoskeletal.py`` import it. The masses, inertias, joint axes and muscle paths live only in
``test/data/arm26.osim`` (see ``test/data/arm26.README.md``); gravity, inertial and muscle torques come from
OpenSim's inverse dynamics, never from ``bsp_ros``'s model.

The arm is docs/contract.md's 2-segment chain: ``upper_arm`` = ``r_humerus`` (shoulder centre -> elbow centre),
``forearm`` = ``r_ulna_radius_hand`` (elbow centre -> contact point). The contact point is the centre of the
handle bearing in the fist, :data:`CONTACT_IN_FOREARM_M` in the forearm body's frame: on the forearm's long
axis (which passes through the forearm-and-hand COM), 0.31 m from the elbow centre, about 7.5 cm distal of the
radial styloid's level (mid-palm). A bearing transmits no moment: the robot pushes in the y-z plane (F_x = 0,
M = 0) with the force that, with OpenSim's joint torques ``tau``, satisfies ``-J^T F_end = tau``.

Frames: OpenSim's ground has x anterior, y up, z lateral (right arm): its sagittal plane x-y is docs/contract.md's
y-z plane, so ``world`` = (ground z, ground x, ground y), shifted so that the shoulder centre sits at
``SessionOptions.shoulder_m``. A rotation about +z (ground) from anterior toward up is docs/contract.md's positive
rotation about +x from +y toward +z, so docs/contract.md's angles are ``q1 = r_shoulder_elev + offset_1`` (the upper arm
hangs at elevation 0: ``q1 ~ -88.8 deg``) and ``q2 = r_elbow_flex + offset_2``, the offsets measured once in the
y-z plane at coordinates 0 (:attr:`Arm26.offsets_rad`). arm26's joint axes are 3.4 deg (shoulder) and 3.5 deg
(elbow, at elevation 0) oblique to world x, tilted opposite ways: the arm is not planar, and the contact point
leaves the y-z plane by centimetres. ``planar=True`` makes both axes exactly lateral (checked against the planar
model to 1e-9).

Muscles: Thelen 2003, held at their minimum activation (0.01) and in fibre-tendon equilibrium at every
instant (quasi-static: their passive force-length curves plus 1 % of their active force). Their maximum
isometric forces are scaled by ``force_scale`` (:func:`force_scale_for_share`: arm26's relaxed passive moments
are ~0.8 of gravity on the paper's protocol, likely several times a real relaxed arm's).

Known defects of OpenSim 4.6 handled here (NOTES.md 7): BIClong wraps the wrong way over its humeral-head
ellipsoid between 29.6 and 29.7 deg elevation (an 87 mm length jump, NaN moment arms): a trajectory entering
:data:`WRONG_WRAP_ELEVATION_DEG` is refused. BIClong (31.3 deg) and TRIlong (41.7, 70.9 deg) switch wraps with
1.7-2.7 mm length jumps (steps of ~0.1-0.7 Nm in the passive moments at force scale 1): the paper's
protocol and :data:`PLANNED_LIMITS_DEG` stay between 41.7 and 70.9 deg.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicSpline

from bsp_ros.bag.writer import write_session_bag
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol, trajectory_from_points
from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.core.simulation import (
    DEFAULT_START_NS,
    GRAVITY_M_S2,
    JointTrajectory,
    PassiveTruth,
    SessionTruth,
    SubjectTruth,
    TrunkTiltedTrajectory,
    paper_mechanical_arm_cell,
    rotation_from_rpy_deg,
)
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries


def import_opensim() -> Any:
    """``import opensim``, keeping LD_LIBRARY_PATH: opensim 4.6's __init__ overwrites it with its own folder and
    PATH, and every process started afterwards (the ROS 2 nodes of other tests) then cannot load rclpy's libraries."""
    saved = os.environ.get("LD_LIBRARY_PATH")
    try:
        import opensim
    finally:
        if saved is None:
            os.environ.pop("LD_LIBRARY_PATH", None)
        else:
            os.environ["LD_LIBRARY_PATH"] = saved
    return opensim


osim = import_opensim()

ARM26_OSIM = Path(__file__).resolve().parents[1] / "data" / "arm26.osim"
SEGMENTS = ("upper_arm", "forearm")
JOINTS = ("shoulder", "elbow")
BODIES = ("r_humerus", "r_ulna_radius_hand")
OSIM_JOINTS = ("r_shoulder", "r_elbow")
COORDINATES = ("r_shoulder_elev", "r_elbow_flex")
CONTACT_IN_FOREARM_M = (0.0, -0.31, 0.0)
WRONG_WRAP_ELEVATION_DEG = (29.0, 31.6)
#: The paper's 2-segment sine protocol (bsp_ros.core.simulation.paper_mechanical_arm_cell).
PAPER_PROTOCOL = paper_mechanical_arm_cell().trajectory
#: Planned-protocol ranges (docs/contract.md angles, deg): elevation 43-67 deg, between TRIlong's wrap switches.
PLANNED_LIMITS_DEG = ((-46.0, -22.0), (20.0, 80.0))
PASSIVE_CURVE_POINTS = 25
_FD_STEP_RAD = 1e-6  # central differences of the contact point: error ~1e-10 m/rad


def _vec(v: Any) -> np.ndarray:
    return np.array([v.get(0), v.get(1), v.get(2)])


@dataclass(frozen=True)
class CellOptions:
    """How arm26 is set up.

    Attributes
    ----------
    force_scale : factor on every muscle's maximum isometric force (> 0).
    muscles : False leaves the muscles out (rigid arm: gravity and inertia only).
    planar : True makes both joint axes exactly lateral (a planar arm); False keeps arm26's oblique axes.
    inertia : False holds the arm quasi-statically (speeds and accelerations 0 in the inverse dynamics).
    gravity_m_s2 : gravity (docs/contract.md's 9.81; arm26 ships 9.8066).
    trunk_tilt_rad : the trunk (arm26's ground, which carries the shoulder and the muscles' origins) turned about
        world x by this much: gravity turns in ground, ``world`` keeps z up, and the docs/contract.md angles ``q_rad``
        stay world angles (the shoulder's is the angle to the trunk plus the tilt).
    """

    force_scale: float = 1.0
    muscles: bool = True
    planar: bool = False
    inertia: bool = True
    gravity_m_s2: float = GRAVITY_M_S2
    trunk_tilt_rad: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.force_scale) and self.force_scale > 0):
            raise ValueError(f"force_scale must be a positive number, got {self.force_scale!r}")


class Arm26:
    """arm26 in docs/contract.md's frames and angles: kinematics, inverse dynamics, passive muscle moments.

    Angles ``q_rad`` are (N, 2) docs/contract.md angles (q1 absolute from +y, q2 relative), rad.

    Parameters
    ----------
    options : the set-up.
    path : the ``.osim`` file.
    """

    def __init__(self, options: CellOptions | None = None, path: Path = ARM26_OSIM) -> None:
        osim.Logger.setLevelString("error")  # arm26's meshes are absent: drawing only
        self.options = options or CellOptions()
        model = osim.Model(str(path))
        #: (3, 3) rows: world x, y, z in ground axes (sagittal plane x-y is docs/contract.md's y-z plane, turned
        #: by the trunk's tilt about world x); world = R (ground - shoulder) + shoulder_m.
        c, s = math.cos(self.options.trunk_tilt_rad), math.sin(self.options.trunk_tilt_rad)
        tilt = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        self.rotation_world_from_ground = tilt @ np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
        gravity_ground = self.rotation_world_from_ground.T @ np.array([0.0, 0.0, -self.options.gravity_m_s2])
        model.setGravity(osim.Vec3(*(float(g) for g in gravity_ground)))
        if self.options.planar:
            for name in OSIM_JOINTS:
                transform = osim.CustomJoint.safeDownCast(model.getJointSet().get(name)).upd_SpatialTransform()
                transform.updTransformAxis(0).setAxis(osim.Vec3(0.0, 0.0, 1.0))
                transform.updTransformAxis(2).setAxis(osim.Vec3(1.0, 0.0, 0.0))
        muscles = model.getMuscles()
        for i in range(muscles.getSize()):
            muscle = muscles.get(i)
            muscle.setMaxIsometricForce(muscle.getMaxIsometricForce() * self.options.force_scale)
        model.finalizeConnections()
        self._model = model
        self._state = model.initSystem()
        self._solver = osim.InverseDynamicsSolver(model)
        self._coords = [model.getCoordinateSet().get(name) for name in COORDINATES]
        self._muscles = [osim.Thelen2003Muscle.safeDownCast(muscles.get(i)) for i in range(muscles.getSize())]
        self.muscle_names = tuple(m.getName() for m in self._muscles)
        self._joints = [model.getJointSet().get(name) for name in OSIM_JOINTS]
        self._bodies = [model.getBodySet().get(name) for name in BODIES]
        self._contact = osim.Vec3(*CONTACT_IN_FOREARM_M)
        self._set_coordinates(np.zeros(2))
        self.shoulder_ground_m = self._points_ground()[0]
        points = self._points_world(np.zeros(3))
        phi1 = math.atan2(*(points[1] - points[0])[[2, 1]])
        phi2 = math.atan2(*(points[2] - points[1])[[2, 1]])
        #: (2,) CONTRACT angle minus OpenSim coordinate, rad, measured at coordinates 0.
        self.offsets_rad = np.array([phi1, phi2 - phi1])
        axes = [
            _vec(self._joints[k].getParentFrame().expressVectorInGround(self._state, self._axis(k))) for k in (0, 1)
        ]
        #: Angles of the shoulder and elbow axes from world x at coordinates 0, deg (0 and 0 for a planar arm).
        self.axis_tilt_deg = tuple(
            math.degrees(math.acos(min(1.0, abs(self.rotation_world_from_ground[0] @ a) / np.linalg.norm(a))))
            for a in axes
        )

    # ---- set-up ------------------------------------------------------------------------------------------

    def _axis(self, joint: int) -> Any:
        transform = osim.CustomJoint.safeDownCast(self._joints[joint]).get_SpatialTransform()
        return transform.getTransformAxis(0).getAxis()

    def _set_coordinates(self, coords_rad: np.ndarray, speeds_rad_s: np.ndarray | None = None) -> None:
        for k, coordinate in enumerate(self._coords):
            coordinate.setValue(self._state, float(coords_rad[k]), False)
            coordinate.setSpeedValue(self._state, 0.0 if speeds_rad_s is None else float(speeds_rad_s[k]))
        self._model.realizePosition(self._state)

    def coordinates_rad(self, q_rad: npt.ArrayLike) -> np.ndarray:
        """(N, 2) OpenSim coordinates (elevation, flexion) of docs/contract.md angles; refuses the wrong-wrap band."""
        coords = np.atleast_2d(np.asarray(q_rad, dtype=np.float64)) - self.offsets_rad
        elevation_deg = np.degrees(coords[:, 0])
        bad = (elevation_deg >= WRONG_WRAP_ELEVATION_DEG[0]) & (elevation_deg <= WRONG_WRAP_ELEVATION_DEG[1])
        if bad.any():
            raise ValueError(
                f"shoulder elevation {elevation_deg[bad][0]:.2f} deg is within {WRONG_WRAP_ELEVATION_DEG} deg, "
                "where OpenSim 4.6 wraps arm26's BIClong the wrong way: keep the path out of it"
            )
        for k, coordinate in enumerate(self._coords):
            lo, hi = coordinate.getRangeMin(), coordinate.getRangeMax()
            if (coords[:, k] < lo - 1e-9).any() or (coords[:, k] > hi + 1e-9).any():
                raise ValueError(f"{COORDINATES[k]} leaves its range [{lo:.3f}, {hi:.3f}] rad")
        return coords

    # ---- kinematics --------------------------------------------------------------------------------------

    def _points_ground(self) -> np.ndarray:
        """(3, 3) shoulder centre, elbow centre, contact point in ground at the current state, m."""
        shoulder = _vec(self._joints[0].getParentFrame().getPositionInGround(self._state))
        elbow = _vec(self._joints[1].getParentFrame().getPositionInGround(self._state))
        contact = _vec(self._bodies[1].findStationLocationInGround(self._state, self._contact))
        return np.vstack((shoulder, elbow, contact))

    def _points_world(self, shoulder_m: np.ndarray) -> np.ndarray:
        ground = self._points_ground()
        return (ground - ground[0]) @ self.rotation_world_from_ground.T + shoulder_m

    def points_world_m(self, q_rad: npt.ArrayLike, shoulder_m: npt.ArrayLike = (0.0, 0.0, 0.0)) -> np.ndarray:
        """(N, 3, 3) shoulder centre, elbow centre and contact point in ``world`` (shoulder at ``shoulder_m``), m."""
        coords = self.coordinates_rad(q_rad)
        out = np.empty((coords.shape[0], 3, 3))
        for i, c in enumerate(coords):
            self._set_coordinates(c)
            out[i] = self._points_world(np.asarray(shoulder_m, dtype=np.float64))
        return out

    def _contact_jacobian(self, coords: np.ndarray) -> np.ndarray:
        """(3, 2) d(contact point in world)/d(coordinates) by central differences (independent of axis data)."""
        jac = np.empty((3, 2))
        for k in range(2):
            step = np.zeros(2)
            step[k] = _FD_STEP_RAD
            self._set_coordinates(coords + step)
            plus = self._points_world(np.zeros(3))[2]
            self._set_coordinates(coords - step)
            minus = self._points_world(np.zeros(3))[2]
            jac[:, k] = (plus - minus) / (2.0 * _FD_STEP_RAD)
        return jac

    # ---- dynamics ----------------------------------------------------------------------------------------

    def _torques(self, coords: np.ndarray, speeds: np.ndarray, accelerations: np.ndarray) -> tuple[np.ndarray, ...]:
        """Joint torques the driver supplies with and without the muscles at one state, Nm."""
        self._set_coordinates(coords, speeds)
        udot = osim.Vector(2, 0.0)
        for k in range(2):
            udot.set(k, float(accelerations[k]))
        for muscle in self._muscles:
            muscle.setAppliesForce(self._state, True)
            muscle.setActivation(self._state, muscle.getMinimumActivation())
        self._model.realizeVelocity(self._state)
        self._model.equilibrateMuscles(self._state)
        with_muscles = self._solver.solve(self._state, udot)
        on = np.array([with_muscles.get(0), with_muscles.get(1)])
        for muscle in self._muscles:
            muscle.setAppliesForce(self._state, False)
        without = self._solver.solve(self._state, udot)
        off = np.array([without.get(0), without.get(1)])
        return on, off

    def dynamics(
        self, q_rad: npt.ArrayLike, qdot_rad_s: npt.ArrayLike, qddot_rad_s2: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What holds the arm on a path: torques and the contact Jacobian.

        Parameters
        ----------
        q_rad, qdot_rad_s, qddot_rad_s2 : (N, 2) angles, speeds, accelerations (CONTRACT = OpenSim's up to offsets).

        Returns
        -------
        torque_nm : (N, 2) the driver's torques ``M q'' + C q' + tau_G + tau_p`` (OpenSim inverse dynamics,
            muscles included unless ``options.muscles`` is False; speeds/accelerations 0 if ``options.inertia``
            is False).
        passive_nm : (N, 2) the muscles' share ``tau_p`` (inverse dynamics with minus without them).
        jacobian : (N, 3, 2) d(contact point in world)/dq, m/rad.
        """
        coords = self.coordinates_rad(q_rad)
        speeds = np.atleast_2d(np.asarray(qdot_rad_s, dtype=np.float64))
        accelerations = np.atleast_2d(np.asarray(qddot_rad_s2, dtype=np.float64))
        if not self.options.inertia:
            speeds, accelerations = np.zeros_like(coords), np.zeros_like(coords)
        torque = np.empty_like(coords)
        passive = np.zeros_like(coords)
        jac = np.empty((coords.shape[0], 3, 2))
        for i in range(coords.shape[0]):
            on, off = self._torques(coords[i], speeds[i], accelerations[i])
            torque[i] = on if self.options.muscles else off
            if self.options.muscles:
                passive[i] = on - off
            jac[i] = self._contact_jacobian(coords[i])
        return torque, passive, jac

    def passive_moment_nm(self, q_rad: npt.ArrayLike) -> np.ndarray:
        """(N, 2) the relaxed muscles' moments at rest (what the driver supplies beside gravity), Nm; 0 without them."""
        q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
        zeros = np.zeros_like(q)
        if not self.options.muscles:  # the rigid arm has no passive moment: its truth curve is 0, not the muscles'
            return zeros
        return np.array([np.subtract(*self._torques(c, zeros[0], zeros[0])) for c in self.coordinates_rad(q)])

    def gravity_torque_nm(self, q_rad: npt.ArrayLike) -> np.ndarray:
        """(N, 2) the torques that hold the rigid arm still against gravity (OpenSim), Nm."""
        q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
        zeros = np.zeros(2)
        return np.array([self._torques(c, zeros, zeros)[1] for c in self.coordinates_rad(q)])

    # ---- mass properties ---------------------------------------------------------------------------------

    def segment_properties(self, q_rad: npt.ArrayLike) -> list[dict[str, float]]:
        """Per segment at one posture, projected on the world y-z plane.

        Returns
        -------
        list of dicts (upper_arm, forearm): ``length_m`` (in-plane joint-centre distance), ``mass_kg``, ``com_m``
        (COM along the in-plane segment axis from the proximal joint), ``normal_m`` (COM offset 90 deg
        counter-clockwise of the axis), ``inertia_com_kgm2`` (about world x through the COM).
        """
        coords = self.coordinates_rad(q_rad)[0]
        self._set_coordinates(coords)
        points = self._points_world(np.zeros(3))
        rotation = self.rotation_world_from_ground
        out = []
        for j, body in enumerate(self._bodies):
            axis = (points[j + 1] - points[j])[1:]
            length = float(np.hypot(*axis))
            along = axis / length
            normal = np.array([-along[1], along[0]])
            com_ground = _vec(body.findStationLocationInGround(self._state, body.getMassCenter()))
            offset = ((com_ground - self.shoulder_ground_m) @ rotation.T - points[j])[1:]
            # The planar motion's rotation axis (world x) in the body's axes; arm26's inertia is about the COM.
            body_rotation = body.getTransformInGround(self._state).R()
            ground_from_body = np.array([[body_rotation.get(a, b) for b in range(3)] for a in range(3)])
            x_in_body = ground_from_body.T @ rotation[0]
            moments, products = _vec(body.getInertia().getMoments()), _vec(body.getInertia().getProducts())
            tensor = np.diag(moments)
            tensor[0, 1] = tensor[1, 0] = products[0]
            tensor[0, 2] = tensor[2, 0] = products[1]
            tensor[1, 2] = tensor[2, 1] = products[2]
            out.append(
                {
                    "length_m": length,
                    "mass_kg": float(body.getMass()),
                    "com_m": float(offset @ along),
                    "normal_m": float(offset @ normal),
                    "inertia_com_kgm2": float(x_in_body @ tensor @ x_in_body),
                }
            )
        return out


# ---- scaling ---------------------------------------------------------------------------------------------


def _rms(values: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(values**2, axis=0))


def passive_share(arm: Arm26, duration_s: float = 120.0) -> float:
    """Largest per-joint RMS passive moment over RMS gravity torque on the paper's protocol (2 Hz grid)."""
    q = PAPER_PROTOCOL.angles_rad(np.arange(0.0, duration_s, 0.5))
    return float(np.max(_rms(arm.passive_moment_nm(q)) / _rms(arm.gravity_torque_nm(q))))


@lru_cache(maxsize=4)
def _unit_share(planar: bool) -> float:
    return passive_share(Arm26(CellOptions(planar=planar)))


def force_scale_for_share(share: float, planar: bool = False) -> float:
    """The ``force_scale`` that makes :func:`passive_share` equal ``share`` (muscle forces scale with it)."""
    return share / _unit_share(planar)


# ---- protocols -------------------------------------------------------------------------------------------


def planned_protocol(arm: Arm26, duration_s: float = 120.0, optimise: bool = True) -> PlannedTrajectory:
    """A protocol of ``bsp_ros.core.planning`` within :data:`PLANNED_LIMITS_DEG` at 0.03 rad/s.

    ``optimise`` runs the planner (``plan_protocol``: a few seconds); False visits two fixed operating points
    (``trajectory_from_points``, instantaneous) for fast tests.
    """
    limits = JointLimits(PLANNED_LIMITS_DEG, max_speed_rad_s=0.03)
    if not optimise:
        centres = np.radians([[-40.0, 35.0], [-28.0, 60.0]])
        return trajectory_from_points(centres, np.radians([4.0, 5.0]), duration_s, limits.max_speed_rad_s)
    lengths = [p["length_m"] for p in arm.segment_properties(np.radians([[-34.0, 50.0]]))]
    request = PlanRequest(
        nominal=NominalArm.from_anthropometry(lengths), shoulder_yz_m=(0.0, 1.2), limits=limits, duration_s=duration_s
    )
    return plan_protocol(request).trajectory


#: ``trajectory`` recorded with the trunk tilted: the same angles relative to the trunk (the simulator's own).
TrunkTilted = TrunkTiltedTrajectory


def accelerations_rad_s2(trajectory: JointTrajectory, t_s: np.ndarray, step_s: float = 1e-3) -> np.ndarray:
    """(N, n) joint accelerations by central differences of the trajectory's analytic velocities, rad/s^2."""
    return (trajectory.velocities_rad_s(t_s + step_s) - trajectory.velocities_rad_s(t_s - step_s)) / (2.0 * step_s)


# ---- a recorded session ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class SessionOptions:
    """The recording: rates, noise (seeded), sensor mounting and where the shoulder is.

    Attributes
    ----------
    duration_s : session length, s.
    seed : seed of every draw (stamp jitter, wrench noise, marker noise).
    wrench_hz, marker_hz : stream rates, Hz.
    physics_hz : rate of the OpenSim evaluations; the wrench is a cubic spline through them (at 0.03 rad/s
        the spline's error is far below the sensor noise: checked by the tests).
    force_noise_n, torque_noise_nm : white noise per sensor axis (1 sd).
    marker_noise_m : white noise per marker axis (1 sd), m.
    wrench_jitter_s : wrench stamp jitter (1 sd, clipped to +-0.4 period), s.
    sensor_rpy_deg : the sensor frame's fixed-axis roll, pitch, yaw in ``world``, deg.
    frame_id : the wrench's frame id.
    shoulder_m : shoulder centre in ``world``, m.
    start_ns : ROS time of t = 0.
    """

    duration_s: float = 120.0
    seed: int = 0
    wrench_hz: float = 100.0
    marker_hz: float = 50.0
    physics_hz: float = 20.0
    force_noise_n: float = 0.05
    torque_noise_nm: float = 0.005
    marker_noise_m: float = 1e-4
    wrench_jitter_s: float = 1e-4
    sensor_rpy_deg: tuple[float, float, float] = (180.0, 0.0, 30.0)
    frame_id: str = "ft_sensor"
    shoulder_m: tuple[float, float, float] = (0.20, 0.0, 1.20)
    start_ns: int = DEFAULT_START_NS


@dataclass(frozen=True)
class CellRun:
    """One simulated session: the streams, the truth, and the noise-free physics on the physics grid.

    Attributes
    ----------
    session : wrench (sensor frame) and markers (``world``), as a bag holds them.
    truth : ``bsp_ros/truth/1`` dict (see :func:`truth_dict`).
    t_s : (K,) physics grid, s since the start.
    q_rad : (K, 2) prescribed docs/contract.md angles.
    torque_nm : (K, 2) the driver's torques (OpenSim inverse dynamics).
    passive_nm : (K, 2) the muscles' share of them.
    wrench_world : (K, 3) ``[F_y, F_z, M_x]`` the hand exerts on the sensor, ``world``, noise-free.
    points_m : (K, 3, 3) shoulder, elbow, contact point in ``world``, noise-free.
    """

    session: Session
    truth: dict[str, Any]
    t_s: np.ndarray
    q_rad: np.ndarray
    torque_nm: np.ndarray
    passive_nm: np.ndarray
    wrench_world: np.ndarray
    points_m: np.ndarray


def wrench_from_torques(torque_nm: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
    """(N, 3) ``[F_y, F_z, M_x = 0]`` with ``-J^T F = tau``: the in-plane force of a bearing (F_x = 0)."""
    jac_yz = jacobian[:, 1:, :]  # rows world y, z
    force = np.linalg.solve(-jac_yz.transpose(0, 2, 1), torque_nm[..., None])[..., 0]
    return np.column_stack((force, np.zeros(len(force))))


def _stamps_ns(options: SessionOptions, rate_hz: float, phase_s: float, jitter_s: float, rng: Any) -> np.ndarray:
    count = math.ceil((options.duration_s - phase_s) * rate_hz)
    offsets_s = phase_s + np.arange(count) / rate_hz
    if jitter_s > 0:
        clip = 0.4 / rate_hz
        offsets_s = offsets_s + np.clip(rng.normal(0.0, jitter_s, count), -clip, clip)
    return options.start_ns + np.round(offsets_s * 1e9).astype(np.int64)


def run_cell(arm: Arm26, trajectory: JointTrajectory, options: SessionOptions | None = None) -> CellRun:
    """Move arm26 along ``trajectory`` and record what the cell's sensor and markers see.

    Parameters
    ----------
    arm : the OpenSim arm.
    trajectory : the prescribed docs/contract.md angles (a ``TrajectorySpec`` or a ``PlannedTrajectory``).
    options : the recording.

    Returns
    -------
    CellRun
    """
    options = options or SessionOptions()
    rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(options.seed).spawn(3)]
    t = np.arange(0.0, options.duration_s + 1.0 / options.physics_hz, 1.0 / options.physics_hz)
    q = trajectory.angles_rad(t)
    torque, passive, jac = arm.dynamics(q, trajectory.velocities_rad_s(t), accelerations_rad_s2(trajectory, t))
    world = wrench_from_torques(torque, jac)
    shoulder = np.asarray(options.shoulder_m, dtype=np.float64)
    points = arm.points_world_m(q, shoulder)

    t_w = _stamps_ns(options, options.wrench_hz, 0.0013, options.wrench_jitter_s, rngs[0])
    wrench = CubicSpline(t, world)((t_w - options.start_ns) * 1e-9)
    rotation = rotation_from_rpy_deg(*options.sensor_rpy_deg)
    force_w = np.column_stack((np.zeros(len(t_w)), wrench[:, 0], wrench[:, 1]))
    torque_w = np.column_stack((wrench[:, 2], np.zeros((len(t_w), 2))))
    noise = rngs[1].standard_normal((len(t_w), 6))
    series = WrenchSeries(
        t_ns=t_w,
        force_n=force_w @ rotation + options.force_noise_n * noise[:, :3],  # rows: R^T v
        torque_nm=torque_w @ rotation + options.torque_noise_nm * noise[:, 3:],
        frame_id=options.frame_id,
    )
    t_m = _stamps_ns(options, options.marker_hz, 0.0071, 0.0, None)
    clean = arm.points_world_m(trajectory.angles_rad((t_m - options.start_ns) * 1e-9), shoulder)
    clean = clean + options.marker_noise_m * rngs[2].standard_normal(clean.shape)
    markers = {
        name: MarkerSeries(t_ns=t_m, position_m=clean[:, k]) for k, name in enumerate(("shoulder", "elbow", "hand"))
    }
    session = Session(wrench=series, markers=markers, rotation_world_from_sensor=rotation)
    truth = truth_dict(arm, trajectory, options, t, points)
    return CellRun(session, truth, t, q, torque, passive, world, points)


def write_bag(out_dir: str | Path, run: CellRun, seed: int = 0) -> Path:
    """Write ``run`` as a rosbag2 MCAP bag with its truth.json (``bsp_ros.bag.writer``)."""
    return write_session_bag(out_dir, run.session, run.truth, seed=seed)


# ---- truth -----------------------------------------------------------------------------------------------


def _passive_truth(arm: Arm26, q: np.ndarray) -> dict[str, dict[str, Any]]:
    """Per joint: the passive curve over the path's range (the other joint at its mean) and its coupling; the
    shoulder's angles relative to the trunk (CONTRACT world angle minus the trunk's tilt), as the estimate's."""
    mean, low, high = q.mean(axis=0), q.min(axis=0), q.max(axis=0)
    relative = np.array([arm.options.trunk_tilt_rad, 0.0])
    out = {}
    for j, name in enumerate(JOINTS):
        other = 1 - j
        grid = np.linspace(low[j], high[j], PASSIVE_CURVE_POINTS)
        curves = []
        for level in (low[other], mean[other], high[other]):
            points = np.empty((grid.size, 2))
            points[:, j], points[:, other] = grid, level
            curves.append(arm.passive_moment_nm(points)[:, j])
        step = math.radians(0.5)
        around = np.array([mean, mean])
        around[0, other] -= step
        around[1, other] += step
        slope = np.diff(arm.passive_moment_nm(around)[:, j])[0] / (2.0 * step)
        out[name] = {
            "passive_curve": {"angle_deg": np.degrees(grid - relative[j]).tolist(), "moment_nm": curves[1].tolist()},
            "passive_coupling": {
                "other_joint": JOINTS[other],
                "other_angle_deg": np.degrees(
                    np.array([low[other], mean[other], high[other]]) - relative[other]
                ).tolist(),
                "moment_nm": [c.tolist() for c in curves],
                "slope_nm_per_rad_of_other": float(slope),
            },
        }
    return out


def truth_dict(
    arm: Arm26, trajectory: JointTrajectory, options: SessionOptions, t_s: np.ndarray, points_m: np.ndarray
) -> dict[str, Any]:
    """The session's ``bsp_ros/truth/1`` truth.

    Segments: OpenSim's masses, COMs and inertias projected on the ``world`` y-z plane at the session's mean
    posture (``segment_properties``); ``static_moment_kgm`` is docs/contract.md's grouped ``m_j l_j + a_j sum m_k``,
    plus ``perpendicular_moment_kgm``, the inertia keys and ``length_range_m`` (the in-plane length over the
    session: it varies on the oblique arm). Joints: ``coulomb_nm`` 0 (arm26 has no dry friction), no elastic
    parameters (the muscles are not a linear spring), and ``passive_curve`` / ``passive_coupling``
    (:func:`_passive_truth`). ``opensim`` records the model set-up.
    """
    q = trajectory.angles_rad(t_s)
    props = arm.segment_properties(q.mean(axis=0)[None, :])
    subject = SubjectTruth(
        lengths_m=tuple(p["length_m"] for p in props),
        masses_kg=tuple(p["mass_kg"] for p in props),
        com_m=tuple(p["com_m"] for p in props),
    )
    simulation = {
        "cell": "opensim arm26 (test/physics/opensim_cell.py)",
        "gravity_m_s2": arm.options.gravity_m_s2,
        "trunk_tilt_deg": math.degrees(arm.options.trunk_tilt_rad),
        **{k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(options).items()},
    }
    truth = SessionTruth(subject, PassiveTruth(coulomb_nm=(0.0, 0.0)), trajectory, simulation).to_dict()
    lengths = np.linalg.norm(np.diff(points_m[:, :, 1:], axis=1), axis=2)  # (K, 2) in-plane
    for j, name in enumerate(SEGMENTS):
        p = props[j]
        segment = truth["segments"][name]
        inertia = p["inertia_com_kgm2"] + p["mass_kg"] * (p["com_m"] ** 2 + p["normal_m"] ** 2)
        distal_mass = sum(x["mass_kg"] for x in props[j + 1 :])
        segment.update(
            perpendicular_moment_kgm=p["mass_kg"] * p["normal_m"],
            inertia_com_kgm2=p["inertia_com_kgm2"],
            inertia_kgm2=inertia,
            grouped_inertia_kgm2=inertia + p["length_m"] ** 2 * distal_mass,
            length_range_m=[float(lengths[:, j].min()), float(lengths[:, j].max())],
        )
    passive = _passive_truth(arm, q)
    for name in JOINTS:
        joint = truth["joints"][name]
        for key in ("stiffness_nm_per_rad", "neutral_rad", "offset_nm", "viscous_nms"):
            joint.pop(key, None)
        joint.update(passive[name])
    truth["opensim"] = {
        "model": "arm26 (test/data/arm26.osim, CC BY 3.0)",
        "version": osim.__version__,
        "force_scale": arm.options.force_scale,
        "muscles": list(arm.muscle_names) if arm.options.muscles else [],
        "planar": arm.options.planar,
        "inertia": arm.options.inertia,
        "axis_tilt_deg": list(arm.axis_tilt_deg),
        "angle_offsets_deg": np.degrees(arm.offsets_rad).tolist(),
        "contact_in_forearm_m": list(CONTACT_IN_FOREARM_M),
    }
    return truth
