"""A cell's own nodes, written with plain rclpy (no bsp_ros code): an arm of known segments, its wrench and
markers out, `/bsp/estimate` in, checked against the truth. Exit 0 if the estimate matches, 1 if not.

The arm moves in the sagittal plane y-z (CONTRACT.md), without friction, at up to about 1 rad/s^2: the wrench
the hand exerts on the sensor balances the arm's weight and its rigid-body inertia,
``J(q)^T w = -dV/dq - Q(q, q', q'')`` with ``V = g sum_k S_k sin(phi_k)``, ``S`` the grouped static moments,
``phi`` the absolute segment angles and ``Q`` the generalized inertial forces of the segments' masses and
inertias (written here from the segments' centre-of-mass accelerations, not from any bsp_ros model).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data

G = 9.81
LENGTHS_M = np.array([0.30, 0.27, 0.08])
MASSES_KG = np.array([2.0, 1.2, 0.45])
COM_M = np.array([0.13, 0.12, 0.05])
INERTIA_COM_KGM2 = np.array([0.018, 0.009, 0.0005])  # about each centre of mass, normal to the plane
SHOULDER_M = np.array([0.0, 0.0, 1.2])
MARKERS = ("shoulder", "elbow", "wrist", "hand")


def static_moments_kgm() -> np.ndarray:
    """S_j = m_j l_j + a_j * (mass of the distal segments)."""
    distal = np.concatenate([np.cumsum(MASSES_KG[::-1])[::-1][1:], [0.0]])
    return MASSES_KG * COM_M + LENGTHS_M * distal


OFFSET_RAD = np.array([-0.4, 0.7, 0.1])
AMPLITUDE_RAD = np.array([0.6, 0.6, 0.5])
OMEGA_RAD_S = 2 * math.pi * np.array([0.11, 0.17, 0.23])
PHASE_RAD = np.array([0.0, 1.0, 2.0])


def angles_rad(t_s: float) -> np.ndarray:
    return OFFSET_RAD + AMPLITUDE_RAD * np.sin(OMEGA_RAD_S * t_s + PHASE_RAD)


def motion(t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint angles (rad), velocities (rad/s) and accelerations (rad/s^2) at ``t_s``."""
    phase = OMEGA_RAD_S * t_s + PHASE_RAD
    return (
        angles_rad(t_s),
        AMPLITUDE_RAD * OMEGA_RAD_S * np.cos(phase),
        -AMPLITUDE_RAD * OMEGA_RAD_S**2 * np.sin(phase),
    )


def _along(phi: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def _normal(phi: np.ndarray) -> np.ndarray:
    return np.stack([-np.sin(phi), np.cos(phi)], axis=-1)


def inertial_forces(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Generalized inertial forces (Nm): sum_k m_k (dp_k/dq_j) . a_k + I_k (dphi_k/dq_j) phi_k''.

    p_k is segment k's centre of mass, a_k its acceleration: each segment's tip and centre of mass move on
    circles about its proximal joint, ``l (phi'' n(phi) - phi'^2 u(phi))``, summed down the chain.
    """
    phi, phid, phidd = np.cumsum(q), np.cumsum(qd), np.cumsum(qdd)
    u, n = _along(phi), _normal(phi)
    tip_acc = LENGTHS_M[:, None] * (phidd[:, None] * n - (phid**2)[:, None] * u)
    com_acc = COM_M[:, None] * (phidd[:, None] * n - (phid**2)[:, None] * u)
    acc = np.cumsum(tip_acc, axis=0) - tip_acc + com_acc  # proximal tips, then this segment's centre of mass
    forces = np.zeros(3)
    for j in range(3):
        for k in range(j, 3):
            # Moving q_j turns segments j..k about joint j: p_k moves along the normal of each segment between.
            dp = np.sum(LENGTHS_M[j:k, None] * n[j:k], axis=0) + COM_M[k] * n[k]
            forces[j] += MASSES_KG[k] * dp @ acc[k] + INERTIA_COM_KGM2[k] * phidd[k]
    return forces


def points_m(q: np.ndarray) -> np.ndarray:
    """Shoulder, elbow, wrist, contact point in world (x = 0)."""
    phi = np.cumsum(q)
    steps = np.stack([np.zeros(3), LENGTHS_M * np.cos(phi), LENGTHS_M * np.sin(phi)], axis=1)
    return SHOULDER_M + np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])


def wrench_yzx(q: np.ndarray, qd: np.ndarray | None = None, qdd: np.ndarray | None = None) -> np.ndarray:
    """[F_y, F_z, M_x] the hand exerts on the sensor at the contact point, in world (at rest without qd, qdd)."""
    phi = np.cumsum(q)
    moments = static_moments_kgm()
    # Planar Jacobian of the contact point (y, z, angle) with respect to q: column j sums segments k >= j.
    jac = np.zeros((3, 3))
    for j in range(3):
        jac[0, j] = -np.sum(LENGTHS_M[j:] * np.sin(phi[j:]))
        jac[1, j] = np.sum(LENGTHS_M[j:] * np.cos(phi[j:]))
        jac[2, j] = 1.0
    generalized_gravity = np.array([-G * np.sum(moments[j:] * np.cos(phi[j:])) for j in range(3)])
    inertial = np.zeros(3) if qd is None or qdd is None else inertial_forces(q, qd, qdd)
    return np.linalg.solve(jac.T, generalized_gravity - inertial)


class PlainCell(Node):
    def __init__(self, seed: int) -> None:
        super().__init__("plain_rclpy_cell")
        self.rng = np.random.default_rng(seed)
        self.start = time.monotonic()
        self.wrench_pub = self.create_publisher(WrenchStamped, "/ft_sensor/wrench", qos_profile_sensor_data)
        self.marker_pubs = {
            name: self.create_publisher(PoseStamped, f"/mocap/{name}", qos_profile_sensor_data) for name in MARKERS
        }
        self.estimate: dict[str, dict[str, str]] = {}
        self.create_subscription(DiagnosticArray, "/bsp/estimate", self.on_estimate, 10)
        self.create_timer(0.01, self.on_wrench_tick)
        self.create_timer(0.02, self.on_marker_tick)

    def _stamp(self, msg: WrenchStamped | PoseStamped, frame_id: str) -> float:
        now = self.get_clock().now()
        msg.header.stamp = now.to_msg()
        msg.header.frame_id = frame_id
        return time.monotonic() - self.start

    def on_wrench_tick(self) -> None:
        msg = WrenchStamped()
        t_s = self._stamp(msg, "world")
        fy, fz, mx = wrench_yzx(*motion(t_s)) + self.rng.normal(0.0, [0.05, 0.05, 0.005])
        msg.wrench.force.y, msg.wrench.force.z, msg.wrench.torque.x = float(fy), float(fz), float(mx)
        self.wrench_pub.publish(msg)

    def on_marker_tick(self) -> None:
        stamp_msg = PoseStamped()
        t_s = self._stamp(stamp_msg, "world")
        for name, point in zip(MARKERS, points_m(angles_rad(t_s)), strict=True):
            msg = PoseStamped()
            msg.header = stamp_msg.header
            x, y, z = point + self.rng.normal(0.0, 0.0005, 3)
            msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = float(x), float(y), float(z)
            msg.pose.orientation.w = 1.0
            self.marker_pubs[name].publish(msg)

    def on_estimate(self, msg: DiagnosticArray) -> None:
        self.estimate = {status.name: {kv.key: kv.value for kv in status.values} for status in msg.status}

    def valid(self) -> bool:
        return self.estimate.get("bsp/quality", {}).get("valid") == "True"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--settle", type=float, default=10.0, help="keep going this long after the first valid one")
    args = parser.parse_args()
    rclpy.init()
    node = PlainCell(seed=11)
    try:
        deadline = time.monotonic() + args.timeout
        while time.monotonic() < deadline and not node.valid():
            rclpy.spin_once(node, timeout_sec=0.05)
        settle_until = time.monotonic() + args.settle
        while time.monotonic() < min(settle_until, deadline):
            rclpy.spin_once(node, timeout_sec=0.05)
        truth = dict(zip(("upper_arm", "forearm", "hand"), static_moments_kgm().tolist(), strict=True))
        imported = any(name.split(".")[0] in ("bsp_ros", "msg_adapters") for name in sys.modules)
        result = {"valid": node.valid(), "truth": truth, "estimate": {}, "std": {}, "bsp_ros_imported": imported}
        for segment in truth:
            values = node.estimate.get(f"bsp/{segment}", {})
            if "static_moment_kgm" in values:
                result["estimate"][segment] = float(values["static_moment_kgm"])
                result["std"][segment] = float(values["static_moment_kgm.std"])
        print(json.dumps(result), flush=True)
        ok = result["valid"] and len(result["estimate"]) == 3 and not imported
        for segment, true in truth.items():
            if ok:
                error = abs(result["estimate"][segment] - true)
                ok = error < max(4 * result["std"][segment], 0.02 * true)
        return 0 if ok else 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
