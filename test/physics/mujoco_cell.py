"""An independent physics cell: a planar 2- or 3-segment arm in MuJoCo, held by a kinematically driven robot handle.

Test support (not part of the installed package): tests and ``bench/physics_engine.py`` import it. The arm's
masses, COMs, inertias and joint friction, springs and damping live only in the MJCF text built here; the
wrench written to a bag is what MuJoCo's own ``force``/``torque`` sensors report at the contact point, never a
value of ``bsp_ros``'s model. ``mujoco_session`` turns a run into a bag (``bsp_ros.bag.writer``) with a
``bsp_ros/truth/1`` truth.json.

Frames (docs/contract.md): world x lateral, y anterior, z up; hinges about world +x; all joint angles zero is the
arm straight along +y, so MuJoCo's hinge angles are docs/contract.md's q1 (absolute), q2, q3 (relative). Each
segment body's frame has its axis along local +y and its origin at the proximal joint. The last segment carries a
massless body ``hand_contact`` at the contact point, held by the mocap body ``robot_handle``; the sensor site sits
on ``hand_contact``, so MuJoCo's ``cfrc_int`` of that body is the wrench the arm exerts on the handle (checked by
the statics tests to 1e-9 Nm). A 3-segment arm (upper arm, forearm, hand) is strapped at the hand: a ``weld``,
which transmits M_x. A 2-segment chain (upper arm, forearm: the method paper's mechanical arm) is coupled through a
bearing, as the paper's arm was ("a screw attached to a bearing"): a ``connect``, which transmits no moment; it
has no wrist and no wrist marker (docs/contract.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from bsp_ros.core.anthropometry import inertia_com_kgm2
from bsp_ros.core.simulation import (
    DEFAULT_START_NS,
    GRAVITY_M_S2,
    JointTrajectory,
    SubjectTruth,
    TrajectorySpec,
    human_arm_cell,
    rotation_from_rpy_deg,
)
from bsp_ros.core.streams import SEGMENTS_3 as SEGMENTS
from bsp_ros.core.streams import joints_for, markers_for

JOINTS = ("shoulder", "elbow", "wrist")
MARKERS = ("shoulder", "elbow", "wrist", "hand")
PAPER_COULOMB_NM = (0.5, 0.28, 0.06)  # human_arm_cell()'s Coulomb levels, the order of the paper's results
SPRING_NM_PER_RAD = (0.30, 0.50, 0.15)  # issue 19's joint springs
# Spring neutral angles (rad): the elbow's relaxed angle ~107 deg (NOTES 3), shoulder and wrist off the
# paper's operating point so that each spring loads its joint there.
SPRING_REF_RAD = (-0.35, 1.87, 0.35)
# NOTES 7: MuJoCo's default friction regularisation makes frictionloss a damper at 0.03 rad/s.
FRICTION_SOLREF = "0.002 1"
FRICTION_SOLIMP = "0.99 0.999 0.001"
WELD_SOLREF = "0.002 1"
WELD_SOLIMP = "0.99 0.999 0.001"


@dataclass(frozen=True)
class ArmParams:
    """The simulated subject: per segment (upper arm, forearm[, hand]) and per joint (shoulder, elbow[, wrist]).

    ``n`` = ``len(lengths_m)``, 2 or 3; every tuple has one value per segment (joint). The defaults are a 3-segment
    arm's: a 2-segment arm gives every field (``mujoco_mechanical.mechanical_arm`` does).

    Attributes
    ----------
    lengths_m : (n,) a_j, m (the last segment: its joint -> contact point).
    masses_kg : (n,) m_j, kg.
    com_along_m : (n,) l_j, COM distance from the proximal joint along the segment axis, m.
    com_normal_m : (n,) COM offset normal to the axis, m (+ toward 90 deg counter-clockwise, i.e. local +z).
    inertia_com_kgm2 : (n,) moment of inertia about the COM for rotation about x, kg m^2.
    frictionloss_nm : (n,) dry friction c_j, Nm (MuJoCo ``frictionloss``).
    damping_nms : (n,) viscous b_j, Nm s/rad (MuJoCo ``damping``).
    stiffness_nm_per_rad : (n,) k_j, Nm/rad (MuJoCo ``stiffness``).
    springref_rad : (n,) q_ref,j, rad (MuJoCo ``springref``): the spring's generalized force is -k (q - q_ref).

    Raises
    ------
    ValueError
        If ``lengths_m`` has neither 2 nor 3 values, or another field has a different count.
    """

    lengths_m: tuple[float, ...]
    masses_kg: tuple[float, ...]
    com_along_m: tuple[float, ...]
    com_normal_m: tuple[float, ...] = (0.0, 0.0, 0.0)
    inertia_com_kgm2: tuple[float, ...] = (0.0, 0.0, 0.0)
    frictionloss_nm: tuple[float, ...] = PAPER_COULOMB_NM
    damping_nms: tuple[float, ...] = (0.0, 0.0, 0.0)
    stiffness_nm_per_rad: tuple[float, ...] = (0.0, 0.0, 0.0)
    springref_rad: tuple[float, ...] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        n = len(self.lengths_m)
        if n not in (2, 3):
            raise ValueError(f"lengths_m needs 2 or 3 segments, got {n}")
        for name in (
            "masses_kg",
            "com_along_m",
            "com_normal_m",
            "inertia_com_kgm2",
            "frictionloss_nm",
            "damping_nms",
            "stiffness_nm_per_rad",
            "springref_rad",
        ):
            count = len(getattr(self, name))
            if count != n:
                raise ValueError(f"{name} has {count} values, lengths_m has {n}: give one per segment")

    @property
    def n_segments(self) -> int:
        """2 (upper arm, forearm) or 3 (with the hand)."""
        return len(self.lengths_m)


def draw_arm(
    seed: int | None,
    *,
    springs: bool = False,
    off_axis: bool = False,
    sex: str = "male",
    body_mass_kg: float = 75.0,
    height_m: float = 1.78,
) -> ArmParams:
    """A subject: de Leva table means (``seed`` None) or a seeded draw of masses, COMs, inertias and friction.

    A draw takes masses and COM fractions from the anthropometric prior, inertias from de Leva's radii of
    gyration times a log-normal factor (15 %), friction from the paper's levels times U(0.7, 1.3), spring
    stiffness from issue 19's (0.30, 0.50, 0.15) Nm/rad times U(0.8, 1.2); ``off_axis`` puts each COM
    up to 1.5 % of the segment length off the axis.
    """
    rng = None if seed is None else np.random.default_rng([seed, 19])
    subject = SubjectTruth.from_anthropometry(sex, body_mass_kg, height_m, 3, rng=rng)
    factor = np.ones(3) if rng is None else np.exp(rng.normal(0.0, 0.15, 3))
    inertia = tuple(
        float(f * inertia_com_kgm2(sex, name, m, a))
        for f, name, m, a in zip(factor, SEGMENTS, subject.masses_kg, subject.lengths_m, strict=True)
    )
    friction = np.asarray(PAPER_COULOMB_NM) * (1.0 if rng is None else rng.uniform(0.7, 1.3, 3))
    stiffness = np.asarray(SPRING_NM_PER_RAD) * (1.0 if rng is None else rng.uniform(0.8, 1.2, 3))
    normal = np.zeros(3)
    if off_axis:
        normal = np.asarray(subject.lengths_m) * (0.01 if rng is None else rng.uniform(-0.015, 0.015, 3))
    return ArmParams(
        lengths_m=_triple(subject.lengths_m),
        masses_kg=_triple(subject.masses_kg),
        com_along_m=_triple(subject.com_m),
        com_normal_m=_triple(normal),
        inertia_com_kgm2=_triple(inertia),
        frictionloss_nm=_triple(friction),
        stiffness_nm_per_rad=_triple(stiffness) if springs else (0.0, 0.0, 0.0),
        springref_rad=SPRING_REF_RAD if springs else (0.0, 0.0, 0.0),
    )


def _triple(values: Any) -> tuple[float, float, float]:
    a, b, c = (float(v) for v in values)
    return (a, b, c)


def paper_sine(peak_speed_rad_s: float = 0.03) -> TrajectorySpec:
    """The paper's sine protocol of ``human_arm_cell()``, periods scaled so the shoulder peaks at ``peak_speed``."""
    base = human_arm_cell().trajectory
    assert isinstance(base, TrajectorySpec)
    scale = base.peak_speed_rad_s[0] / peak_speed_rad_s
    return TrajectorySpec(base.center_deg, base.amplitude_deg, tuple(p * scale for p in base.period_s), base.phase_rad)


@dataclass(frozen=True)
class CellOptions:
    """How the cell runs and what it records.

    Attributes
    ----------
    trajectory : joint angles q(t) the robot imposes (the handle follows their forward kinematics).
    duration_s : recorded length, s (after ``lead_in_s`` of unrecorded motion that lets the weld settle).
    timestep_s : MuJoCo step, s; the wrench and marker rates must divide its inverse.
    wrench_hz, marker_hz : sample rates, Hz (wrench at most 1 kHz).
    sensor : ``"fixed"`` (axes fixed in world at ``mount_rpy_deg``, ``/tf_static``) or ``"turning"`` (on the
        flange: the handle's pitch then ``mount_rpy_deg``, published per wrench sample on ``/tf``).
    force_noise_n, torque_noise_nm : white Gaussian noise per sensor axis (1 sd).
    marker_noise_m : white Gaussian marker noise per world axis (1 sd).
    skin_offset_m : one ``(along, normal)`` marker offset per marker (4 for a 3-segment arm, 3 for a 2-segment
        one: shoulder, elbow, hand) from the joint centres (CONTRACT: fixed in the segment starting at that joint,
        the contact-point marker in the last segment), m; empty: on the centres.
    trunk_tilt_rad : the trunk (the shoulder joint's parent body) turned about world x by this much, rad: the
        shoulder hinge, its spring and ``trajectory`` are relative to the trunk, gravity stays world -z.
    """

    trajectory: JointTrajectory
    duration_s: float = 60.0
    timestep_s: float = 0.001
    wrench_hz: float = 1000.0
    marker_hz: float = 100.0
    marker_phase_s: float = 0.003
    sensor: str = "fixed"
    mount_rpy_deg: tuple[float, float, float] = (180.0, 0.0, 30.0)
    frame_id: str = "ft_sensor"
    force_noise_n: float = 0.05
    torque_noise_nm: float = 0.005
    marker_noise_m: float = 1e-4
    skin_offset_m: tuple[tuple[float, float], ...] = ()
    shoulder_m: tuple[float, float, float] = (0.20, 0.0, 1.20)
    lead_in_s: float = 1.0
    start_ns: int = DEFAULT_START_NS
    seed: int = 0
    trunk_tilt_rad: float = 0.0

    def __post_init__(self) -> None:
        if self.sensor not in ("fixed", "turning"):
            raise ValueError(f"sensor must be 'fixed' or 'turning', got {self.sensor!r}")
        if self.wrench_hz > 1000.0:
            raise ValueError(f"wrench_hz must be at most 1000 Hz, got {self.wrench_hz!r}")
        for name in ("wrench_hz", "marker_hz"):
            _stride(getattr(self, name), self.timestep_s, name)
        if self.skin_offset_m and len(self.skin_offset_m) not in (3, 4):
            count = len(self.skin_offset_m)
            raise ValueError(f"skin_offset_m needs 3 or 4 (along, normal) pairs (one per marker), got {count}")


def _stride(rate_hz: float, timestep_s: float, name: str) -> int:
    steps = 1.0 / (rate_hz * timestep_s)
    if abs(steps - round(steps)) > 1e-9 or round(steps) < 1:
        raise ValueError(f"{name} = {rate_hz!r} Hz is not a whole number of {timestep_s!r} s steps")
    return round(steps)


def _quat_wxyz(rotation: np.ndarray) -> str:
    x, y, z, w = Rotation.from_matrix(rotation).as_quat()
    return f"{w:.17g} {x:.17g} {y:.17g} {z:.17g}"


def mjcf_text(arm: ArmParams, options: CellOptions) -> str:
    """The MJCF of the cell: the arm (2 or 3 hinges about world x), its contact body, the robot's mocap handle.

    Raises
    ------
    ValueError
        If ``options.skin_offset_m`` does not give one pair per marker of ``arm``'s chain.
    """
    n = arm.n_segments
    if options.skin_offset_m and len(options.skin_offset_m) != n + 1:
        count = len(options.skin_offset_m)
        raise ValueError(f"skin_offset_m has {count} (along, normal) pairs, a {n}-segment arm has {n + 1} markers")
    sy, sz = options.shoulder_m[1], options.shoulder_m[2]
    half = options.trunk_tilt_rad / 2.0
    trunk = f"{np.cos(half):.17g} {np.sin(half):.17g} 0 0"  # about world x
    handle_y = sy
    for a in arm.lengths_m:  # in the chain's order, the sum's rounding that of sy + a1 + a2 + a3
        handle_y += a
    return f"""<mujoco model="planar_arm_cell">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{options.timestep_s:.17g}" gravity="0 0 {-GRAVITY_M_S2:.17g}" integrator="Euler"
          tolerance="1e-12" iterations="200">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="trunk" pos="{options.shoulder_m[0]:.17g} {sy:.17g} {sz:.17g}" quat="{trunk}">
{_chain_text(arm, options)}
    </body>
    <body name="robot_handle" mocap="true" pos="{options.shoulder_m[0]:.17g} {handle_y:.17g} {sz:.17g}"/>
  </worldbody>
  <equality>
    {_strap_text(n)}
  </equality>
  <sensor>
    <force name="ft_force" site="ft_site"/>
    <torque name="ft_torque" site="ft_site"/>
  </sensor>
</mujoco>
"""


def _chain_text(arm: ArmParams, options: CellOptions) -> str:
    """The nested segment bodies (each with its hinge, inertial and marker site), the last one carrying the contact."""
    n = arm.n_segments
    markers = markers_for(n)
    offsets = options.skin_offset_m or ((0.0, 0.0),) * (n + 1)
    mount = _quat_wxyz(rotation_from_rpy_deg(*options.mount_rpy_deg))

    def marker(k: int, base_along: float = 0.0) -> str:
        along, normal = offsets[k]
        return f'<site name="marker_{markers[k]}" pos="0 {base_along + along:.17g} {normal:.17g}"/>'

    opening: list[str] = []
    for j in range(n):
        outer, inner = " " * (4 + 2 * j), " " * (6 + 2 * j)
        pos = "0 0 0" if j == 0 else f"0 {arm.lengths_m[j - 1]:.17g} 0"
        body = [f'{outer}<body name="{SEGMENTS[j]}" pos="{pos}">', *(inner + t for t in _segment_text(arm, j))]
        body.append(inner + marker(j))
        opening.extend(body)
    last, inner = arm.lengths_m[-1], " " * (4 + 2 * n)
    opening += [
        inner + marker(n, last),
        f'{inner}<body name="hand_contact" pos="0 {last:.17g} 0">',
        f'{inner}  <site name="ft_site" pos="0 0 0" quat="{mount}"/>',
        f"{inner}</body>",
    ]
    closing = [" " * (4 + 2 * j) + "</body>" for j in reversed(range(n))]
    return "\n".join(opening + closing)


def _segment_text(arm: ArmParams, j: int) -> tuple[str, str]:
    """Segment ``j``'s hinge and inertial elements."""
    joint = (
        f'<joint name="{JOINTS[j]}" type="hinge" axis="1 0 0" pos="0 0 0" limited="false" '
        f'frictionloss="{arm.frictionloss_nm[j]:.17g}" damping="{arm.damping_nms[j]:.17g}" '
        f'stiffness="{arm.stiffness_nm_per_rad[j]:.17g}" springref="{arm.springref_rad[j]:.17g}" '
        f'solreffriction="{FRICTION_SOLREF}" solimpfriction="{FRICTION_SOLIMP}"/>'
    )
    i_com = arm.inertia_com_kgm2[j]
    inertial = (
        f'<inertial pos="0 {arm.com_along_m[j]:.17g} {arm.com_normal_m[j]:.17g}" mass="{arm.masses_kg[j]:.17g}" '
        f'diaginertia="{i_com:.17g} {0.1 * i_com:.17g} {i_com:.17g}"/>'
    )
    return joint, inertial


def _strap_text(n_segments: int) -> str:
    """How the handle holds the contact body: a weld (hand strapped, M_x carried) or, for 2 segments, a bearing."""
    kind, pose = ("weld", 'relpose="0 0 0 1 0 0 0"') if n_segments == 3 else ("connect", 'anchor="0 0 0"')
    return (
        f'<{kind} name="strap" body1="hand_contact" body2="robot_handle" {pose}\n'
        f'          solref="{WELD_SOLREF}" solimp="{WELD_SOLIMP}"/>'
    )


@dataclass
class EngineRun:
    """What MuJoCo computed at every recorded step (t >= 0), before any sensor or marker noise.

    Attributes
    ----------
    t_s : (N,) step times since the session start, s.
    q_rad, qdot_rad_s, qddot_rad_s2 : (N, n) the arm's joint state in the engine (not the command), n segments.
    q_command_rad : (N, n) the joint angles the robot imposed through the handle.
    force_site_n, torque_site_nm : (N, 3) the engine's sensors in the sensor site's axes (the mount).
    rotation_world_from_site : (N, 3, 3) the site's orientation in world (engine).
    markers_m : (N, n + 1, 3) marker site positions in world (``markers_for(n)``: shoulder, elbow, [wrist,] hand).
    weld_drift_m, weld_drift_rad : (N,) distance and pitch difference between the contact body and the handle (a
        2-segment chain's bearing leaves the pitch free: its difference is the forearm's tracking error).
    """

    t_s: np.ndarray
    q_rad: np.ndarray
    qdot_rad_s: np.ndarray
    qddot_rad_s2: np.ndarray
    q_command_rad: np.ndarray
    force_site_n: np.ndarray
    torque_site_nm: np.ndarray
    rotation_world_from_site: np.ndarray
    markers_m: np.ndarray
    weld_drift_m: np.ndarray
    weld_drift_rad: np.ndarray
    model: Any = field(repr=False)
    trunk_tilt_rad: float = 0.0  # q_rad and q_command_rad are relative to the trunk, turned by this about world x

    def wrench_world(self) -> np.ndarray:
        """(N, 3) ``[F_y, F_z, M_x]`` in world: the engine's sensor rotated by the engine's site orientation."""
        force = np.einsum("nij,nj->ni", self.rotation_world_from_site, self.force_site_n)
        torque = np.einsum("nij,nj->ni", self.rotation_world_from_site, self.torque_site_nm)
        return np.column_stack((force[:, 1], force[:, 2], torque[:, 0]))

    def out_of_plane(self) -> float:
        """Largest |F_x|, |M_y|, |M_z| in world (the planar arm should produce none)."""
        force = np.einsum("nij,nj->ni", self.rotation_world_from_site, self.force_site_n)
        torque = np.einsum("nij,nj->ni", self.rotation_world_from_site, self.torque_site_nm)
        return float(max(np.abs(force[:, 0]).max(), np.abs(torque[:, 1:]).max()))

    def torque_split_nm(self, every: int = 10) -> tuple[np.ndarray, np.ndarray]:
        """(gravity, inertial) joint torques from MuJoCo's RNE on every ``every``-th step: (K, n) each, Nm.

        Gravity is ``rne(q, 0, 0)``; inertial is ``rne(q, qdot, qddot) - rne(q, 0, 0)`` (M qddot + Coriolis).
        """
        data = mujoco.MjData(self.model)
        rows = range(0, self.t_s.size, every)
        nv = self.model.nv
        gravity, inertial = np.zeros((len(rows), nv)), np.zeros((len(rows), nv))
        full, static = np.zeros(nv), np.zeros(nv)
        for i, k in enumerate(rows):
            data.qpos[:] = self.q_rad[k]
            data.qvel[:] = 0.0
            mujoco.mj_kinematics(self.model, data)
            mujoco.mj_comPos(self.model, data)
            mujoco.mj_comVel(self.model, data)
            mujoco.mj_rne(self.model, data, 0, static)
            data.qvel[:] = self.qdot_rad_s[k]
            data.qacc[:] = self.qddot_rad_s2[k]
            mujoco.mj_comVel(self.model, data)
            mujoco.mj_rne(self.model, data, 1, full)
            gravity[i], inertial[i] = static, full - static
        return gravity, inertial


def _handle_poses(q: np.ndarray, lengths: Sequence[float], shoulder: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Mocap positions (N, 3) and quaternions (N, 4, wxyz) of the handle for joint angles (N, n), lengths (n,)."""
    phi = np.cumsum(q, axis=1)
    y = shoulder[1] + (np.asarray(lengths) * np.cos(phi)).sum(axis=1)
    z = shoulder[2] + (np.asarray(lengths) * np.sin(phi)).sum(axis=1)
    pos = np.column_stack((np.full_like(y, shoulder[0]), y, z))
    pitch = phi[:, -1]
    quat = np.column_stack((np.cos(pitch / 2), np.sin(pitch / 2), np.zeros_like(y), np.zeros_like(y)))
    return pos, quat


class EngineHook(Protocol):
    """What a caller adds to the engine per step (a patient's joint torques, a moving contact point...)."""

    def prepare(self, model: Any, data: Any, t_s: np.ndarray) -> None:
        """Once, before the first ``mj_forward``; ``t_s`` (N,) every step's time since the session start, s."""

    def before_step(self, k: int, model: Any, data: Any) -> None:
        """Before step ``k`` (index into ``t_s``), after the handle's commanded pose is set."""


def run_engine(arm: ArmParams, options: CellOptions, hook: EngineHook | None = None) -> EngineRun:
    """Drive the handle along ``options.trajectory`` and record the engine's state and sensors at every step.

    ``hook`` (optional) may change the model before the run and the data before each step; without it the run
    is the cell's alone.
    """
    model = mujoco.MjModel.from_xml_string(mjcf_text(arm, options))
    data = mujoco.MjData(model)
    dt = options.timestep_s
    n_lead = round(options.lead_in_s / dt)
    n_rec = round(options.duration_s / dt)
    t_all = (np.arange(n_lead + n_rec) - n_lead) * dt
    q_cmd = options.trajectory.angles_rad(t_all)
    q_world = q_cmd.copy()
    q_world[:, 0] += options.trunk_tilt_rad  # the joint angles are the trunk's, the handle's pose the world's
    pos, quat = _handle_poses(q_world, arm.lengths_m, options.shoulder_m)
    data.qpos[:] = q_cmd[0]
    data.qvel[:] = options.trajectory.velocities_rad_s(t_all[:1])[0]
    data.mocap_pos[0], data.mocap_quat[0] = pos[0], quat[0]
    if hook is not None:
        hook.prepare(model, data, t_all)
    mujoco.mj_forward(model, data)

    site = model.site("ft_site").id
    contact = model.body("hand_contact").id
    n = arm.n_segments
    marker_ids = [model.site(f"marker_{name}").id for name in markers_for(n)]
    q = np.empty((n_rec, n))
    qdot, qddot, sensor = np.empty((n_rec, n)), np.empty((n_rec, n)), np.empty((n_rec, 6))
    rot, markers = np.empty((n_rec, 3, 3)), np.empty((n_rec, n + 1, 3))
    drift_m, contact_quat = np.empty(n_rec), np.empty((n_rec, 4))
    for k in range(n_lead + n_rec):
        data.mocap_pos[0] = pos[k]
        data.mocap_quat[0] = quat[k]
        r = k - n_lead
        if hook is not None:
            hook.before_step(k, model, data)
        if r >= 0:  # the state the step starts from; sensors, kinematics and qacc below belong to it too
            q[r], qdot[r] = data.qpos, data.qvel
        mujoco.mj_step(model, data)
        if r >= 0:
            qddot[r] = data.qacc
            sensor[r] = data.sensordata
            rot[r] = data.site_xmat[site].reshape(3, 3)
            markers[r] = data.site_xpos[marker_ids]
            drift_m[r] = np.linalg.norm(data.xpos[contact] - pos[k])
            contact_quat[r] = data.xquat[contact]
    pitch = 2.0 * np.arctan2(contact_quat[:, 1], contact_quat[:, 0])
    drift_rad = np.angle(np.exp(1j * (pitch - np.cumsum(q_world[n_lead:], axis=1)[:, -1])))
    return EngineRun(
        t_s=t_all[n_lead:],
        q_rad=q,
        qdot_rad_s=qdot,
        qddot_rad_s2=qddot,
        q_command_rad=q_cmd[n_lead:],
        force_site_n=sensor[:, :3],
        torque_site_nm=sensor[:, 3:],
        rotation_world_from_site=rot,
        markers_m=markers,
        weld_drift_m=drift_m,
        weld_drift_rad=np.abs(drift_rad),
        model=model,
        trunk_tilt_rad=options.trunk_tilt_rad,
    )


def inertial_ratio(run: EngineRun) -> dict[str, dict[str, float]]:
    """Per joint, inertial over gravity torque (MuJoCo's RNE on the engine's state): RMS over RMS, peak over peak."""
    gravity, inertial = run.torque_split_nm()
    rms = np.sqrt((inertial**2).mean(axis=0)) / np.sqrt((gravity**2).mean(axis=0))
    peak = np.abs(inertial).max(axis=0) / np.abs(gravity).max(axis=0)
    joints = joints_for(run.q_rad.shape[1])
    return {
        "rms": {name: float(r) for name, r in zip(joints, rms, strict=True)},
        "peak": {name: float(r) for name, r in zip(joints, peak, strict=True)},
    }


def peak_speed(run: EngineRun) -> tuple[float, ...]:
    """(n,) the largest |qdot| each joint reached in the engine, rad/s."""
    return tuple(float(v) for v in np.abs(run.qdot_rad_s).max(axis=0))


def degrees_range(run: EngineRun) -> list[tuple[float, float]]:
    """Per joint (lowest, highest) engine angle, deg."""
    lo, hi = np.degrees(run.q_rad.min(axis=0)), np.degrees(run.q_rad.max(axis=0))
    return [(float(a), float(b)) for a, b in zip(lo, hi, strict=True)]


def wrench_world_from_sensor_angle(run: EngineRun, mount: np.ndarray) -> np.ndarray:
    """(N, 3, 3) the turning sensor's orientation the robot knows: its commanded pitch, then the mount."""
    pitch = np.cumsum(run.q_command_rad, axis=1)[:, -1] + run.trunk_tilt_rad
    c, s = np.cos(pitch), np.sin(pitch)
    rx = np.zeros((pitch.size, 3, 3))
    rx[:, 0, 0] = 1.0
    rx[:, 1, 1], rx[:, 1, 2], rx[:, 2, 1], rx[:, 2, 2] = c, -s, s, c
    return rx @ mount


def angle_deg(rotation_a: np.ndarray, rotation_b: np.ndarray) -> np.ndarray:
    """(N,) angle between two stacks of rotations, deg."""
    rel = np.einsum("nji,njk->nik", rotation_a, rotation_b)
    cos = np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return np.degrees(np.arccos(cos))


__all__ = [
    "JOINTS",
    "MARKERS",
    "PAPER_COULOMB_NM",
    "SPRING_NM_PER_RAD",
    "SPRING_REF_RAD",
    "ArmParams",
    "CellOptions",
    "EngineHook",
    "EngineRun",
    "angle_deg",
    "degrees_range",
    "draw_arm",
    "inertial_ratio",
    "mjcf_text",
    "paper_sine",
    "peak_speed",
    "run_engine",
    "wrench_world_from_sensor_angle",
]
