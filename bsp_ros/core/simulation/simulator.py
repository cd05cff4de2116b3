"""The simulated cell: a planar arm moved by a robot, its wrench on a (fixed or turning) sensor and skin markers."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from bsp_ros.core.simulation.cell import CellSpec
from bsp_ros.core.simulation.checks import GRAVITY_M_S2, JITTER_CLIP_PERIODS, rotations_about_x
from bsp_ros.core.simulation.dynamics import PlanarChain, inverse_dynamics_nm
from bsp_ros.core.simulation.markers import skin_offsets_m
from bsp_ros.core.simulation.tare import TareSpec, tare_wrench
from bsp_ros.core.simulation.trajectory import TrajectorySpec, joint_accelerations_rad_s2
from bsp_ros.core.simulation.truth import SessionTruth, simulation_settings
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries, markers_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_stamps_ns


@dataclass(frozen=True)
class SimulatedSession:
    """A simulated session and its truth.

    Attributes
    ----------
    session : the recorded streams (markers keyed ``shoulder``/``elbow``/(``wrist``)/``hand``).
    truth : what the session really was.
    tf_t_ns : (K,) int64 stamps of the sensor's orientation samples (a sensor that turns with the handle;
        empty for a fixed one, whose orientation is ``session.rotation_world_from_sensor``).
    tf_rotations_world_from_sensor : (K, 3, 3) the sensor's orientation at ``tf_t_ns`` (for ``/tf``).
    """

    session: Session
    truth: SessionTruth
    tf_t_ns: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    tf_rotations_world_from_sensor: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))


class CellSimulator:
    """The simulated cell, usable sample by sample (a real-time publisher) or for a whole session.

    Physics (docs/contract.md): a planar chain in the world y-z plane moved along ``spec.trajectory`` so that
    ``M(q) q'' + C(q, q') q' + tau_G(q) + tau_p = -J(q)^T F_end`` (``spec.inertia``; otherwise the
    quasi-static ``tau_G(q) + tau_p = -J^T F_end``), the left side from a Newton-Euler recursion over each
    segment's mass, COM (on or off the axis) and inertia (:mod:`.dynamics`), with the trajectory's analytic
    velocities and accelerations. ``F_end = [Fy, Fz, Mx]`` is the wrench the hand exerts on the sensor at
    the contact point, in ``world``; a 2-segment chain holds a bearing: Mx = 0. Fx = My = Mz = 0 in
    ``world``. The sensor reads that wrench in its own axes, fixed or turning with the handle, through its
    filter and clock (``SensorSpec``), plus offsets and drift, the handle's weight, noise and spikes; the
    markers sit on the skin (``MarkerSpec`` offsets, given or drawn per session). :meth:`sample_tare_wrench`
    gives the handle-free readings of a tare.

    Random draws: one seeded ``np.random.Generator`` per stream (wrench stamps, wrench noise, marker
    stamps, and noise and dropouts per marker, wrench spikes, skin re-placement), all seeded by
    ``spec.seed``, so a stream's values do not depend on how calls to the other streams interleave, and
    sampling in chunks gives the same values as sampling all at once (the filter is evaluated on the
    continuous physics, so it carries no state between calls).

    Parameters
    ----------
    spec : CellSpec
    """

    def __init__(self, spec: CellSpec) -> None:
        if not isinstance(spec, CellSpec):
            raise InputError(f"spec must be a CellSpec, got {spec!r}")
        self._spec = spec
        n = spec.n_segments
        subject = spec.subject
        self._marker_names = markers_for(n)
        self._lengths = np.asarray(subject.lengths_m)
        self._masses = np.asarray(subject.masses_kg)
        self._coms = np.asarray(subject.com_m)
        self._com_normal = np.asarray(subject.com_perpendicular_m)
        self._chain = PlanarChain(
            subject.lengths_m, subject.masses_kg, subject.com_m, subject.com_perpendicular_m, subject.inertia_com_kgm2
        )
        self._rotation = spec.sensor.rotation_world_from_sensor
        self._rotation.setflags(write=False)
        self._shoulder = np.asarray(spec.markers.shoulder_m)
        self._skin_offsets = skin_offsets_m(spec.markers, len(self._marker_names), spec.seed)
        self._pitch_reference_rad = self._mean_pitch_rad()
        self._lags_s, self._weights = spec.sensor.filter_kernel()
        children = np.random.SeedSequence(spec.seed).spawn(3 + 2 * len(self._marker_names))
        rngs = [np.random.default_rng(child) for child in children]
        self._rng_wrench_stamps, self._rng_wrench_noise, self._rng_marker_stamps = rngs[:3]
        k = len(self._marker_names)
        self._rng_marker_noise = dict(zip(self._marker_names, rngs[3 : 3 + k], strict=True))
        self._rng_dropout = dict(zip(self._marker_names, rngs[3 + k :], strict=True))
        self._lost: dict[str, bool | None] = dict.fromkeys(self._marker_names)
        # Its own stream (not one of the spawned children above), so spikes leave every other draw unchanged.
        self._rng_spikes = np.random.default_rng(np.random.SeedSequence([spec.seed, 13]))
        settings = simulation_settings(spec, self._skin_offsets, self._pitch_reference_rad)
        self._truth = SessionTruth(spec.subject, spec.passive, spec.trajectory, settings)

    def _mean_pitch_rad(self) -> float:
        """The last segment's mean absolute angle over the session (a sine's centre exactly)."""
        trajectory = self._spec.trajectory
        if isinstance(trajectory, TrajectorySpec):
            return float(np.radians(np.sum(trajectory.center_deg)))
        t = np.linspace(0.0, self._spec.duration_s, 2001)
        return float(np.mean(np.sum(trajectory.angles_rad(t), axis=1)))

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
        """(3, 3) the sensor's mounting rotation into ``world`` (read-only; a turning sensor's at mean pitch)."""
        return self._rotation

    @property
    def skin_offsets_m(self) -> tuple[tuple[float, float], ...]:
        """The session's skin marker offsets ``(along, normal)`` per marker, m (``()``: on the centres)."""
        return self._skin_offsets

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

    def joint_accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """True joint accelerations: (N,) s -> (N, n) rad/s^2."""
        return joint_accelerations_rad_s2(self._spec.trajectory, t_s)

    def handle_pitch_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """The handle's pitch: the last segment's absolute angle minus its session mean, (N,) s -> (N,) rad."""
        return np.sum(self.joint_angles_rad(t_s), axis=1) - self._pitch_reference_rad

    def rotations_world_from_sensor(self, t_s: npt.ArrayLike) -> np.ndarray:
        """The sensor's orientation at ``t_s`` (marker clock): (N,) s -> (N, 3, 3).

        ``Rx(pitch(t)) @ R_mount`` for a sensor that turns with the handle, ``R_mount`` for a fixed one.
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        if not self._spec.sensor.turns_with_handle:
            return np.broadcast_to(self._rotation, (t.size, 3, 3)).copy()
        return rotations_about_x(self.handle_pitch_rad(t)) @ self._rotation

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
        offsets = self._skin_offsets
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

    def handle_positions_m(self, t_s: npt.ArrayLike) -> np.ndarray:
        """The contact point in ``world`` as the robot's kinematics give it (no skin offset): (N,) s -> (N, 3) m."""
        points = self._joint_points_yz(self.joint_angles_rad(t_s))
        return np.column_stack([np.full(points.shape[0], self._shoulder[0]), points[:, -1, :]])

    def gravity_torque_nm(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Torque needed at each joint to hold the arm against gravity: (N,) s -> (N, n) Nm.

        ``tau_G,i = g * sum_{j >= i} m_j (y_com_j - y_joint_i)``: each segment's weight times the
        horizontal lever arm of its COM about joint i (positive: the COM is anterior of the joint). A
        closed form of the statics, beside the recursion of :meth:`inverse_dynamics_nm`.
        """
        q = self.joint_angles_rad(t_s)
        points = self._joint_points_yz(q)
        phi = np.cumsum(q, axis=1)
        com_y = points[:, :-1, 0] + self._coms * np.cos(phi) - self._com_normal * np.sin(phi)  # (N, n)
        n = self.n_segments
        tau = np.zeros_like(q)
        for i in range(n):
            for j in range(i, n):
                tau[:, i] += self._masses[j] * GRAVITY_M_S2 * (com_y[:, j] - points[:, i, 0])
        return tau

    def inverse_dynamics_nm(self, t_s: npt.ArrayLike) -> np.ndarray:
        """``M(q) q'' + C(q, q') q' + tau_G(q)`` along the trajectory: (N,) s -> (N, n) Nm.

        Without ``spec.inertia``: ``tau_G(q)`` alone (the recursion at zero velocity and acceleration).
        """
        q = self.joint_angles_rad(t_s)
        if not self._spec.inertia:
            zero = np.zeros_like(q)
            return inverse_dynamics_nm(self._chain, q, zero, zero)
        return inverse_dynamics_nm(
            self._chain, q, self.joint_velocities_rad_s(t_s), self.joint_accelerations_rad_s2(t_s)
        )

    def passive_torque_nm(self, t_s: npt.ArrayLike) -> np.ndarray:
        """True passive moments (the torque the driver must supply): (N,) s -> (N, n) Nm."""
        q = self.joint_angles_rad(t_s)
        q[:, 0] -= self._spec.trunk_tilt_rad  # the shoulder's passive angle is relative to the trunk
        qdot = self.joint_velocities_rad_s(t_s)
        p = self._spec.passive
        return p.friction_nm(qdot) + np.asarray(p.viscous_nms) * qdot + p.elastic_nm(q)

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
        t_s : (N,) float, s since the session start (marker clock).

        Returns
        -------
        (N, 3) float64 ndarray
            ``[Fy (N), Fz (N), Mx (Nm)]`` solving ``-J^T F = M q'' + C q' + tau_G + tau_p`` (without
            inertia ``-J^T F = tau_G + tau_p``; Mx = 0 for 2 segments).
        """
        tau = self.inverse_dynamics_nm(t_s) + self.passive_torque_nm(t_s)
        jac = self.contact_jacobian(t_s)
        out = np.zeros((tau.shape[0], 3))
        if self.n_segments == 3:
            out[:] = np.linalg.solve(-jac.transpose(0, 2, 1), tau[..., None])[..., 0]
        else:
            out[:, :2] = np.linalg.solve(-jac[:, :2, :].transpose(0, 2, 1), tau[..., None])[..., 0]
        return out

    def sensor_reading(self, t_s: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """What the sensor feels at ``t_s`` (marker clock) before its filter, offsets and noise.

        Returns
        -------
        force (N, 3) N and moment (N, 3) Nm in the sensor's axes: ``R(t)^T F_world`` plus the handle's
        weight ``R(t)^T m g`` and its moment.
        """
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        world = self.wrench_world(t)
        force_w = np.zeros((t.size, 3))
        torque_w = np.zeros((t.size, 3))
        force_w[:, 1:] = world[:, :2]
        torque_w[:, 0] = world[:, 2]
        s = self._spec.sensor
        if s.turns_with_handle:
            rotation = self.rotations_world_from_sensor(t)
            load_f, load_m = s.payload_wrench(rotation)
            # Row vectors: v_sensor = R^T v_world  <=>  v_sensor_row = v_world_row @ R.
            return np.einsum("ni,nij->nj", force_w, rotation) + load_f, np.einsum(
                "ni,nij->nj", torque_w, rotation
            ) + load_m
        load_f, load_m = s.payload_wrench(self._rotation)
        return force_w @ self._rotation + load_f, torque_w @ self._rotation + load_m

    def filtered_reading(self, t_s: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`sensor_reading` through the sensor's filter and averaging, at measurement times ``t_s``."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        if self._lags_s.size == 1:
            return self.sensor_reading(t - self._lags_s[0])
        force, torque = self.sensor_reading((t[:, None] - self._lags_s[None, :]).ravel())
        k = self._lags_s.size
        return (
            np.einsum("nkj,k->nj", force.reshape(t.size, k, 3), self._weights),
            np.einsum("nkj,k->nj", torque.reshape(t.size, k, 3), self._weights),
        )

    # ---- stamps --------------------------------------------------------------------------------------

    def _stamps(self, rate_hz: float, phase_s: float, jitter_s: float, rng: np.random.Generator) -> np.ndarray:
        count = max(math.ceil((self._spec.duration_s - phase_s) * rate_hz), 1)
        nominal = phase_s + np.arange(count, dtype=np.float64) / rate_hz
        offsets = np.round(nominal * 1e9)
        if jitter_s > 0.0:
            clip = JITTER_CLIP_PERIODS * 1e9 / rate_hz
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

    def orientation_stamps_ns(self, wrench_t_ns: npt.ArrayLike) -> np.ndarray:
        """Marker-clock stamps at which wrench samples stamped ``wrench_t_ns`` were measured (their ``/tf``)."""
        stamps = check_stamps_ns("wrench_t_ns", wrench_t_ns)
        return stamps - np.int64(round(self._spec.sensor.clock_offset_s * 1e9))

    # ---- noisy samples -------------------------------------------------------------------------------

    def sample_wrench(self, t_ns: npt.ArrayLike) -> WrenchSeries:
        """Noisy wrench in the sensor frame at the given stamps.

        Parameters
        ----------
        t_ns : (N,) int64, strictly increasing stamps, ns (wrench clock: measured ``clock_offset_s``
            earlier on the marker clock).

        Returns
        -------
        WrenchSeries
            Force (N, 3) N and moment (N, 3) Nm in ``sensor.frame_id`` axes, referenced at the contact
            point: the filtered reading (:meth:`filtered_reading`) ``+ offset(t) + noise`` (offset with its
            drift; spikes if ``spike_fraction`` > 0).
        """
        stamps = check_stamps_ns("t_ns", t_ns)
        s = self._spec.sensor
        t_stamp = self.seconds_since_start(stamps)
        reading_f, reading_m = self.filtered_reading(t_stamp - s.clock_offset_s)
        noise = self._rng_wrench_noise.standard_normal((stamps.size, 6))
        offset_f, offset_m = s.offset_at(t_stamp)
        force = reading_f + offset_f + s.force_noise_n * noise[:, :3]
        if s.spike_fraction > 0.0:
            draws = self._rng_spikes.random((stamps.size, 3))
            hit = draws[:, 0] < s.spike_fraction
            axis = (draws[hit, 1] * 3).astype(int)
            force[np.flatnonzero(hit), axis] += np.where(draws[hit, 2] < 0.5, -s.spike_n, s.spike_n)
        torque = reading_m + offset_m + s.torque_noise_nm * noise[:, 3:]
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
        return tare_wrench(self._spec, tare, stamps, self._rng_wrench_noise.standard_normal((stamps.size, 6)))

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
        the mounting rotation; the identity if ``spec.sensor.tf_static`` is False, as a reader of a bag
        without the transform takes it), ``.truth``, and for a sensor that turns with the handle its
        orientation at every wrench sample (``tf_t_ns``, on the marker clock; none if the transform is lost).
    """
    sim = CellSimulator(spec)
    wrench = sim.sample_wrench(sim.wrench_stamps_ns())
    markers = sim.sample_markers(sim.marker_stamps_ns())
    rotation = np.array(sim.rotation_world_from_sensor) if spec.sensor.tf_static else np.eye(3)
    handle_pose = None
    if spec.robot_handle_pose:
        pose_t_ns = sim.orientation_stamps_ns(wrench.t_ns)
        handle_pose = MarkerSeries(pose_t_ns, sim.handle_positions_m(sim.seconds_since_start(pose_t_ns)))
    session = Session(wrench=wrench, markers=markers, rotation_world_from_sensor=rotation, handle_pose=handle_pose)
    if spec.sensor.turns_with_handle and spec.sensor.tf_static:
        tf_t_ns = sim.orientation_stamps_ns(wrench.t_ns)
        rotations = sim.rotations_world_from_sensor(sim.seconds_since_start(tf_t_ns))
        return SimulatedSession(session, sim.truth, tf_t_ns, rotations)
    return SimulatedSession(session=session, truth=sim.truth)
