"""How skin markers a few mm off the joint centres (different every day) move the torque equation."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.dynamics import base_torques_nm
from bsp_ros.core.model import contact_jacobian, joint_positions_m

# Finite-difference step of a marker offset (m): the torques are smooth in it over millimetres.
_STEP_M = 1e-3


def chain_placement_sd_m(
    n_joints: int, marker_placement_sd_m: float, handle_pose_sd_m: float, contact_from_robot: bool
) -> np.ndarray:
    """(n + 1,) how far (1 sd per axis, m) each chain point may sit from where the data put it, shoulder to contact
    point: a skin marker ``marker_placement_sd_m``; a contact point from the robot's handle pose ``handle_pose_sd_m``
    (the robot's registration to the motion-capture ``world``)."""
    sd = np.full(n_joints + 1, float(marker_placement_sd_m))
    if contact_from_robot:
        sd[-1] = handle_pose_sd_m
    return sd


def _angles_from_points(points: np.ndarray) -> np.ndarray:
    """Joint angles (N, n) of chain points (N, n + 1, 2)."""
    steps = np.diff(points, axis=1)
    phi = np.arctan2(steps[..., 1], steps[..., 0])
    return np.concatenate((phi[:, :1], np.diff(phi, axis=1)), axis=1)


def wrench_from_torques(q_rad: np.ndarray, lengths_m: np.ndarray, tau_nm: np.ndarray) -> np.ndarray:
    """(N, 3) ``[F_y, F_z, M_x]`` whose ``-J^T F`` is ``tau_nm`` (a 2-segment chain transmits no moment)."""
    jacobian = contact_jacobian(q_rad, lengths_m)  # (N, 3, n)
    n = q_rad.shape[1]
    out = np.zeros((q_rad.shape[0], 3))
    rows = slice(0, 3) if n == 3 else slice(0, 2)
    out[:, rows] = np.linalg.solve(-np.transpose(jacobian[:, rows, :], (0, 2, 1)), tau_nm[..., None])[..., 0]
    return out


def placement_columns(
    q_rad: np.ndarray,
    qd_rad_s: np.ndarray,
    qdd_rad_s2: np.ndarray,
    lengths_m: np.ndarray,
    tau_nm: np.ndarray,
    base_values: np.ndarray,
) -> np.ndarray:
    """How each marker's offset from its joint centre would change the torque equation, per mm of offset.

    The markers define the chain the torques and the regressor are computed on. Were the true joint centres
    ``o`` away from them (in the frame of the segment the marker sits on: along, normal), the torques of the
    handle wrench would act on other lever arms and gravity on other segment angles. To first order the
    equation ``tau = Y theta`` gains ``D o``; ``D`` is returned, computed at the current base parameters.

    Parameters
    ----------
    q_rad, qd_rad_s, qdd_rad_s2 : (N, n) angles, velocities, accelerations from the markers.
    lengths_m : (n,) marker-derived segment lengths (m).
    tau_nm : (N, n) torques ``-J^T F`` on the marker chain.
    base_values : (3n,) base parameters ``[beta, gamma, zeta]`` of the current fit.

    Returns
    -------
    (N, n, 2 (n + 1)) columns (Nm per m of offset): marker k's ``along`` then ``normal`` offset, markers from
    the shoulder to the contact point (the contact point's offset in the last segment's frame).
    """
    n = q_rad.shape[1]
    wrench = wrench_from_torques(q_rad, lengths_m, tau_nm)
    points = joint_positions_m(q_rad, lengths_m)  # (N, n + 1, 2) the marker chain
    phi = np.cumsum(q_rad, axis=1)
    frame_of = [*range(n), n - 1]
    model = base_torques_nm(q_rad, qd_rad_s, qdd_rad_s2, lengths_m, base_values)
    columns = np.zeros((q_rad.shape[0], n, 2 * (n + 1)))
    for k in range(n + 1):
        angle = phi[:, frame_of[k]]
        along = np.stack((np.cos(angle), np.sin(angle)), axis=-1)
        for c, direction in enumerate((along, np.stack((-along[:, 1], along[:, 0]), axis=-1))):
            moved = points.copy()
            moved[:, k] -= _STEP_M * direction  # the true centre, if the marker sits o = +step off it
            q_true = _angles_from_points(moved)
            lever = moved[:, -1:, :] - moved[:, :n, :]  # (N, n, 2) contact point from each joint
            tau_true = -(lever[..., 0] * wrench[:, None, 1] - lever[..., 1] * wrench[:, None, 0] + wrench[:, None, 2])
            model_true = base_torques_nm(q_true, qd_rad_s, qdd_rad_s2, lengths_m, base_values)
            # tau_meas = Y theta + [d(Y theta)/do - d tau/do] o
            columns[:, :, 2 * k + c] = ((model_true - model) - (tau_true - tau_nm)) / _STEP_M
    return columns
