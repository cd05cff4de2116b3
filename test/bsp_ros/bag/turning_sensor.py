"""A session whose F/T sensor turns with the handle (its orientation on /tf), built from the core model."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from bsp_ros.core.simulation import CellSimulator, SessionTruth, human_arm_cell
from bsp_ros.core.streams import Session, WrenchSeries
from msg_adapters import TransformSample, quaternion_from_matrix


@dataclass(frozen=True)
class TurningSession:
    """The streams (wrench in the turning sensor frame), the truth, and the sensor's orientation on /tf."""

    session: Session
    truth: SessionTruth
    coulomb_nm: tuple[float, ...]
    tf_samples: list[TransformSample]
    range_deg: float


def turning_session(duration_s: float, seed: int, tf_hz: float, frame: str = "ft_sensor") -> TurningSession:
    """A human-arm session whose sensor turns about world x with the hand's absolute angle.

    The wrench is the simulator's noise-free world wrench rotated into the sensor frame at each wrench
    stamp (``R(t)^T F_world``), plus white noise; /tf carries ``world -> frame`` at ``tf_hz`` on its own
    phase, from before the first to after the last wrench stamp.
    """
    spec = human_arm_cell(duration_s=duration_s, seed=seed)
    sim = CellSimulator(spec)
    mount = np.array(sim.rotation_world_from_sensor)

    def rotation(t_s: np.ndarray) -> np.ndarray:
        hand = sim.joint_angles_rad(t_s).sum(axis=1)  # the handle turns with the hand's absolute angle
        turn = Rotation.from_rotvec(np.outer(hand - np.radians(-43.3 + 29.5 + 0.2), [1.0, 0.0, 0.0])).as_matrix()
        return np.einsum("nij,jk->nik", turn, mount)

    t_ns = sim.wrench_stamps_ns()
    t_s = sim.seconds_since_start(t_ns)
    world = sim.wrench_world(t_s)
    force_w = np.column_stack((np.zeros(t_ns.size), world[:, 0], world[:, 1]))
    torque_w = np.column_stack((world[:, 2], np.zeros(t_ns.size), np.zeros(t_ns.size)))
    r = rotation(t_s)
    rng = np.random.default_rng(seed + 1000)
    force = np.einsum("nji,nj->ni", r, force_w) + spec.sensor.force_noise_n * rng.standard_normal((t_ns.size, 3))
    torque = np.einsum("nji,nj->ni", r, torque_w) + spec.sensor.torque_noise_nm * rng.standard_normal((t_ns.size, 3))
    tf_ns = spec.start_ns - 3_300_000 + np.arange(int((duration_s + 0.2) * tf_hz), dtype=np.int64) * round(1e9 / tf_hz)
    tf_r = rotation(sim.seconds_since_start(tf_ns))
    samples = [
        TransformSample(int(t), "world", frame, np.zeros(3), quaternion_from_matrix(m))
        for t, m in zip(tf_ns, tf_r, strict=True)
    ]
    angles = Rotation.from_matrix(np.einsum("nij,kj->nik", r, mount)).as_rotvec()[:, 0]
    session = Session(
        wrench=WrenchSeries(t_ns, force, torque, frame),
        markers=sim.sample_markers(sim.marker_stamps_ns()),
        rotation_world_from_sensor=mount,
    )
    return TurningSession(session, sim.truth, spec.passive.coulomb_nm, samples, float(np.degrees(np.ptp(angles))))


def assert_within_3_std(document: dict, turning: TurningSession) -> None:
    """A valid estimate whose static moments and Coulomb amplitudes hold the truth within 3 std."""
    quality = document["quality"]
    assert quality["valid"], quality["message"]
    for segment, beta in zip(("upper_arm", "forearm", "hand"), turning.truth.static_moments_kgm, strict=True):
        q = document["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - beta) <= 3 * q["std"], (segment, q, beta)
    for joint, c in zip(("shoulder", "elbow", "wrist"), turning.coulomb_nm, strict=True):
        q = document["joints"][joint]["coulomb_nm"]
        assert abs(q["value"] - c) <= 3 * q["std"], (joint, q, c)
