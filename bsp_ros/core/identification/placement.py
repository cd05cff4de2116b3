"""How skin markers a few mm off the joint centres (different every day) move the torque equation."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.dynamics import base_torque_angle_derivatives, pair_cross, pair_turned
from bsp_ros.core.model import running_sum


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


def wrench_from_torques(q_rad: np.ndarray, lengths_m: np.ndarray, tau_nm: np.ndarray) -> np.ndarray:
    """(N, 3) ``[F_y, F_z, M_x]`` whose ``-J^T F`` is ``tau_nm`` (a 2-segment chain transmits no moment).

    In closed form (Cramer's rule on 2 x 2 systems; batched LAPACK solves cost ten times as much): the moment
    cancels from the difference of neighbouring joints' torques, ``tau_i - tau_(i+1) = -(a_i F_y + b_i F_z)`` with
    ``(a_i, b_i) = l_i (-sin phi_i, cos phi_i)``, which gives the force, and the last joint's torque the moment.
    Singular where the system is (the elbow straight), like any solve of it.
    """
    n = q_rad.shape[1]
    phi = running_sum(q_rad)
    lengths = np.asarray(lengths_m, dtype=np.float64)
    a, b = -lengths * np.sin(phi), lengths * np.cos(phi)  # (N, n) d(y, z) of the contact point per segment turn
    out = np.zeros((q_rad.shape[0], 3))
    if n == 3:
        # Rows: (a_0, b_0) F = tau_1 - tau_0 and (a_1, b_1) F = tau_2 - tau_1.
        r0, r1 = tau_nm[:, 1] - tau_nm[:, 0], tau_nm[:, 2] - tau_nm[:, 1]
        a0, b0, a1, b1 = a[:, 0], b[:, 0], a[:, 1], b[:, 1]
    else:
        # Rows: -J^T F = tau without a moment: (dy_i, dz_i) F = -tau_i, dy_i and dz_i summing the distal segments.
        r0, r1 = -tau_nm[:, 0], -tau_nm[:, 1]
        a0, b0, a1, b1 = a[:, 0] + a[:, 1], b[:, 0] + b[:, 1], a[:, 1], b[:, 1]
    det = a0 * b1 - a1 * b0
    with np.errstate(divide="ignore", invalid="ignore"):
        out[:, 0] = (r0 * b1 - r1 * b0) / det
        out[:, 1] = (a0 * r1 - a1 * r0) / det
    if n == 3:
        out[:, 2] = -tau_nm[:, 2] - a[:, 2] * out[:, 0] - b[:, 2] * out[:, 1]
    return out


def placement_columns(
    q_rad: np.ndarray,
    qd_rad_s: np.ndarray,
    qdd_rad_s2: np.ndarray,
    lengths_m: np.ndarray,
    tau_nm: np.ndarray,
    base_values: np.ndarray,
) -> np.ndarray:
    """How each marker's offset from its joint centre would change the torque equation, per m of offset.

    The markers define the chain the torques and the regressor are computed on. Were the true joint centres
    ``o`` away from them (in the frame of the segment the marker sits on: along, normal), the torques of the
    handle wrench would act on other lever arms and gravity on other segment angles. To first order the
    equation ``tau = Y theta`` gains ``D o``; ``D`` is returned, computed at the current base parameters, in closed
    form: a centre moved by ``delta`` turns the segments ending at it by ``(axis x delta) / length`` and moves
    the lever arms of the handle's wrench by ``delta``.

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
    lengths = np.asarray(lengths_m, dtype=np.float64)
    force = wrench_from_torques(q_rad, lengths, tau_nm)  # (N, 3) the handle's [F_y, F_z, M_x]
    force_y, force_z = force[:, 0], force[:, 1]
    phi = running_sum(np.ascontiguousarray(q_rad.T)[None])[0]  # (n, N): each segment's samples contiguous
    axis = [(c, s) for c, s in zip(np.cos(phi), np.sin(phi), strict=True)]
    turning = base_torque_angle_derivatives(q_rad, qd_rad_s, qdd_rad_s2, lengths, base_values)  # (N, n, n)
    frame_of = [*range(n), n - 1]
    columns = np.zeros((q_rad.shape[0], n, 2 * (n + 1)))
    for k in range(n + 1):
        along = axis[frame_of[k]]
        for c, direction in enumerate((along, pair_turned(along))):
            delta = (-direction[0], -direction[1])  # the true centre, if the marker sits o = +1 m off it
            model = np.zeros((q_rad.shape[0], n))
            if k >= 1:  # the segment ending at the centre turns
                model += turning[:, :, k - 1] * (pair_cross(axis[k - 1], delta) / lengths[k - 1])[:, None]
            if k < n:  # the segment starting at it turns the other way
                model -= turning[:, :, k] * (pair_cross(axis[k], delta) / lengths[k])[:, None]
            # The handle's lever arm about joint i (contact point minus joint i) moves with either end: with the
            # contact point for every joint, with joint k's centre for joint k alone (the others' lever is 0).
            # tau_meas = Y theta + [d(Y theta)/do - d tau/do] o
            if k == n:
                columns[:, :, 2 * k + c] = model + (delta[0] * force_z - delta[1] * force_y)[:, None]
            else:
                columns[:, :, 2 * k + c] = model
                lever = (-delta[0], -delta[1])
                columns[:, k, 2 * k + c] = model[:, k] + (lever[0] * force_z - lever[1] * force_y)
            if 1 <= k < n:
                columns[:, :k, 2 * k + c] += _length_lever(axis[k - 1], direction, force_y, force_z)[:, None]
    return columns


def _length_lever(
    proximal: tuple[np.ndarray, np.ndarray],
    direction: tuple[np.ndarray, np.ndarray],
    force_y: np.ndarray,
    force_z: np.ndarray,
) -> np.ndarray:
    """(N,) how a marker's offset of 1 m along ``direction`` (world (y, z) per sample, fixed in the distal
    segment) changes the handle's lever arm about every joint proximal to it, through the proximal segment's length.

    The torques are computed on a chain of the session's median marker distances. A marker fixed in the distal
    segment off its joint centre moves, as that joint turns, along the proximal segment (``proximal``, its unit
    axis per sample): the marker distance varies about its median by the offset's projection on that axis, and the
    chain of medians puts the handle that much off along it. Over a narrow range the variation is nearly constant
    and the median takes it up; with the elbow turning 80 deg, the columns without it missed 24-90 % of the part of
    an offset's effect that varies sample by sample (``test_placement.py``), and offsets fitted freely on a
    noise-free planned session came out at up to twice their true value.
    """
    projection = direction[0] * proximal[0] + direction[1] * proximal[1]
    varying = projection - np.median(projection)
    return np.asarray(varying * (proximal[0] * force_z - proximal[1] * force_y))
