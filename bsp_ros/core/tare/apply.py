"""Applying a tare to a session's wrench, and what applying it needs to say."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt

from bsp_ros.core.streams import Session, WrenchSeries
from bsp_ros.core.tare.model import MAX_UNSTEADINESS, Tare, gravity_in_sensor
from bsp_ros.errors import InputError

# A constant load is only right at the orientation it was recorded at.
MAX_CONSTANT_LOAD_TILT_DEG = 1.0
# Sensor orientations of a session and its tare further apart than this point at a lost transform.
MAX_TARE_SESSION_TILT_DEG = 45.0


def tare_wrench(
    wrench: WrenchSeries, tare: Tare, rotation_world_from_sensor: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """The wrench with the tare's offset and handle load removed.

    Parameters
    ----------
    wrench : the session's wrench (sensor frame).
    tare : the tare of the same sensor.
    rotation_world_from_sensor : (3, 3) the sensor's orientation during the session, or (N, 3, 3) one
        per sample.

    Returns
    -------
    force_n : (N, 3) corrected force, N.
    torque_nm : (N, 3) corrected moment, Nm.
    covariance : (6, 6) covariance of the subtracted wrench (force N, moment Nm), the same for every
        sample: the tare's error is one constant offset over the session, not noise.
    warnings : what the caller should report (e.g. a constant load applied at another orientation).

    Raises
    ------
    InputError
        The tare is of another frame.
    """
    if wrench.frame_id != tare.frame_id:
        raise InputError(
            f"the tare is of frame {tare.frame_id!r} but the wrench is in {wrench.frame_id!r}: "
            "a tare only applies to the sensor it was recorded with"
        )
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    if rotation.ndim == 3:
        if rotation.shape != (np.asarray(wrench.t_ns).size, 3, 3):
            raise InputError(f"per-sample rotations must be (N, 3, 3) with N wrench samples, got {rotation.shape}")
        h_all = np.stack([tare.wrench_jacobian(r) for r in rotation]) if tare.load == "separated" else None
        load_all = h_all @ tare.values if h_all is not None else np.broadcast_to(tare.values, (rotation.shape[0], 6))
        h_mean = h_all.mean(axis=0) if h_all is not None else np.eye(6)
        return (
            np.asarray(wrench.force_n, dtype=np.float64) - load_all[:, :3],
            np.asarray(wrench.torque_nm, dtype=np.float64) - load_all[:, 3:],
            h_mean @ tare.covariance @ h_mean.T,
            tare_warnings(tare, rotation),
        )
    warnings = tare_warnings(tare, rotation)
    h = tare.wrench_jacobian(rotation)
    load = h @ tare.values
    force = np.asarray(wrench.force_n, dtype=np.float64) - load[:3]
    torque = np.asarray(wrench.torque_nm, dtype=np.float64) - load[3:]
    return force, torque, h @ tare.covariance @ h.T, warnings


def recording_warnings(tare: Tare) -> list[str]:
    """What is doubtful about the tare recording itself (an unsteady load, outliers left out)."""
    out = []
    if tare.unsteadiness > MAX_UNSTEADINESS:
        out.append(
            f"tare: the load changed during the recording (residual {tare.unsteadiness:.3g} x the sample-to-sample "
            "noise): was an arm attached or the handle held? The tare's std is large accordingly; record it again"
        )
    if tare.n_rejected:
        out.append(f"tare: {tare.n_rejected} outlier samples left out of {tare.n_samples + tare.n_rejected}")
    return out


def tare_warnings(tare: Tare, rotation_world_from_sensor: npt.ArrayLike) -> list[str]:
    """What applying ``tare`` at this session orientation ((3, 3), or (N, 3, 3)) needs to say, if anything.

    A constant load applied more than ``MAX_CONSTANT_LOAD_TILT_DEG`` away from its recorded orientation is
    wrong by the handle's weight; any tare applied more than ``MAX_TARE_SESSION_TILT_DEG`` away from where
    it was recorded points at a lost or wrong transform (the sensor is mounted once for both).
    """
    if tare.rotation_world_from_sensor is None:
        if tare.load == "constant":
            return [
                "tare: a constant load recorded without the sensor's orientation was applied; it is right only "
                "if the sensor was held as in the session"
            ]
        return []
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64).reshape(-1, 3, 3)
    cosines = gravity_in_sensor(rotation) @ gravity_in_sensor(tare.rotation_world_from_sensor)
    tilt = math.degrees(math.acos(float(np.clip(cosines.min(), -1.0, 1.0))))
    if tilt > MAX_TARE_SESSION_TILT_DEG:
        return [
            f"tare: the session's sensor orientation is {tilt:.3g} deg from the tare's: a lost or wrong "
            "world -> sensor transform (/tf_static)? The handle's weight is removed in the wrong direction"
        ]
    if tare.load == "constant" and tilt > MAX_CONSTANT_LOAD_TILT_DEG:
        return [
            f"tare: constant load recorded with the sensor tilted up to {tilt:.3g} deg from its session "
            "orientation: the handle's weight is not removed correctly (record a tare that swings the sensor)"
        ]
    return []


def corrected_session(session: Session, tare: Tare | None) -> Session:
    """``session`` with the tare applied to its wrench (unchanged when ``tare`` is None).

    The sensor's orientation is ``session.rotation_world_from_sensor``. See :func:`tare_wrench`.
    """
    if tare is None:
        return session
    force, torque, _, _ = tare_wrench(session.wrench, tare, session.rotation_world_from_sensor)
    return dataclasses.replace(session, wrench=dataclasses.replace(session.wrench, force_n=force, torque_nm=torque))
