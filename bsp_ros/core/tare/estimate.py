"""A tare from a recording with the handle free: offset and handle load by least squares, outliers left out."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.identification.covariance import hac_covariance
from bsp_ros.core.tare.model import (
    GRAVITY_M_S2,
    MAX_REJECTED_FRACTION,
    MIN_SWING_DEG,
    MIN_TARE_DURATION_S,
    MIN_TARE_SAMPLES,
    OUTLIER_MAD,
    Tare,
    gravity_in_sensor,
    skew,
)
from bsp_ros.errors import DataError, InputError


def _check_recording(
    t_ns: npt.ArrayLike, force_n: npt.ArrayLike, torque_nm: npt.ArrayLike, rotations: npt.ArrayLike | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    t = np.asarray(t_ns)
    force = np.asarray(force_n, dtype=np.float64)
    torque = np.asarray(torque_nm, dtype=np.float64)
    n = t.size
    if t.ndim != 1 or force.shape != (n, 3) or torque.shape != (n, 3):
        raise InputError(
            f"tare wrench must be (N,) stamps and (N, 3) force/moment, got {t.shape}, {force.shape}, {torque.shape}"
        )
    if not np.issubdtype(t.dtype, np.integer):
        raise InputError(f"tare stamps must be integer ns, got dtype {t.dtype}")
    bad = ~(np.isfinite(force).all(axis=1) & np.isfinite(torque).all(axis=1))
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"the tare recording has {int(bad.sum())} wrench samples with NaN/Inf (the first at index {first}, "
            f"force {force[first].tolist()}, moment {torque[first].tolist()}): record it again"
        )
    rot = None
    if rotations is not None:
        rot = np.asarray(rotations, dtype=np.float64)
        if rot.shape != (n, 3, 3) or not np.isfinite(rot).all():
            raise InputError(f"tare rotations must be finite (N, 3, 3) = ({n}, 3, 3), got {rot.shape}")
    order = np.argsort(t, kind="stable")
    t, force, torque = t[order].astype(np.int64), force[order], torque[order]
    rot = rot[order] if rot is not None else None
    if n < MIN_TARE_SAMPLES:
        raise DataError(f"the tare recording has {n} wrench samples: at least {MIN_TARE_SAMPLES} are needed")
    duration = float(t[-1] - t[0]) * 1e-9
    if duration < MIN_TARE_DURATION_S:
        raise DataError(f"the tare recording lasts {duration:.3g} s: at least {MIN_TARE_DURATION_S:g} s are needed")
    return t, force, torque, rot


def _mean_rotation(rotations: np.ndarray) -> np.ndarray:
    """The rotation nearest (Frobenius) to the mean of ``rotations`` (chordal L2 mean)."""
    u, _, vt = np.linalg.svd(rotations.mean(axis=0))
    d = np.sign(np.linalg.det(u @ vt))
    return np.asarray(u @ np.diag([1.0, 1.0, d]) @ vt)


def _ols_hac(design: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least squares over samples of stacked axes.

    Parameters
    ----------
    design : (N, 3, p) per-sample rows.
    target : (N, 3).

    Returns
    -------
    values (p,), covariance (p, p) (HAC over samples), residual (N, 3).
    """
    a = design.reshape(-1, design.shape[-1])
    values = np.linalg.lstsq(a, target.reshape(-1), rcond=None)[0]
    residual = target - np.einsum("nkp,p->nk", design, values)
    gram = a.T @ a
    scores = np.einsum("nkp,nk->np", design, residual)
    covariance, _ = hac_covariance(gram, scores)
    return values, covariance, residual


def estimate_tare(
    t_ns: npt.ArrayLike,
    force_n: npt.ArrayLike,
    torque_nm: npt.ArrayLike,
    frame_id: str,
    rotations_world_from_sensor: npt.ArrayLike | None = None,
    source: str = "",
) -> Tare:
    """Estimate a tare from a recording with the handle free.

    When the orientations are known and the gravity direction in the sensor frame swings by at least
    ``MIN_SWING_DEG`` (rms) in two independent directions, the force offset and handle mass come from
    ``F = oF + m g R^T e`` and the moment offset and handle first moment ``s = m c`` from
    ``M = oM + s x g R^T e`` (``e = (0, 0, -1)``), each by linear least squares; otherwise the constant
    load (the mean wrench) is estimated. Samples beyond 6 robust standard deviations (MAD) of the residuals
    on any axis are left out as outliers and counted (``n_rejected``). Standard deviations are Newey-West
    HAC from the residuals, so a slowly drifting or coloured sensor signal is not counted as independent
    samples.

    Parameters
    ----------
    t_ns : (N,) int64 stamps, ns.
    force_n, torque_nm : (N, 3) the sensor's readings, sensor frame, N and Nm.
    frame_id : the sensor frame.
    rotations_world_from_sensor : (N, 3, 3) the sensor's orientation at each sample, or None if unknown.
    source : the recording's name (for the file; never a person's).

    Returns
    -------
    Tare

    Raises
    ------
    DataError
        Fewer than 50 samples, shorter than 5 s, NaN/Inf samples, or more than 10 % outliers.
    InputError
        Mismatched shapes or non-integer stamps.
    """
    t, force, torque, rotations = _check_recording(t_ns, force_n, torque_nm, rotations_world_from_sensor)
    n = t.size
    swing = (0.0, 0.0)
    mean_rotation = None
    if rotations is not None:
        down = gravity_in_sensor(rotations)
        spread = np.linalg.svd(down - down.mean(axis=0), compute_uv=False) / math.sqrt(n)
        swing = (math.degrees(math.asin(min(spread[0], 1.0))), math.degrees(math.asin(min(spread[1], 1.0))))
        mean_rotation = _mean_rotation(rotations)
    common: dict[str, Any] = {
        "frame_id": frame_id,
        "n_samples": n,
        "start_time_ns": int(t[0]),
        "duration_s": float(t[-1] - t[0]) * 1e-9,
        "swing_deg": swing,
        "rotation_world_from_sensor": mean_rotation,
        "source": source,
    }
    separated = rotations is not None and min(swing) >= MIN_SWING_DEG
    if rotations is not None and separated:
        d = GRAVITY_M_S2 * gravity_in_sensor(rotations)  # (N, 3)
        eye = np.broadcast_to(np.eye(3), (n, 3, 3))
        designs = (np.concatenate([eye, d[:, :, None]], axis=2), np.concatenate([eye, -skew(d)], axis=2))
    else:
        designs = (np.broadcast_to(np.eye(3), (n, 3, 3)),) * 2  # the constant load: a mean per axis

    def solve(keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        f_values, f_cov, _ = _ols_hac(designs[0][keep], force[keep])
        m_values, m_cov, _ = _ols_hac(designs[1][keep], torque[keep])
        p_f = f_values.size
        covariance = np.zeros((p_f + m_values.size,) * 2)
        covariance[:p_f, :p_f], covariance[p_f:, p_f:] = f_cov, m_cov
        residual = np.hstack(
            [
                force - np.einsum("nkp,p->nk", designs[0], f_values),
                torque - np.einsum("nkp,p->nk", designs[1], m_values),
            ]
        )
        return np.concatenate([f_values, m_values]), covariance, residual

    # Spikes (a knock on the handle, a glitch) must not move the tare: samples off the robust spread of
    # the residuals (median absolute deviation) are left out and counted.
    keep = np.ones(n, dtype=bool)
    for _ in range(4):
        values, covariance, residual = solve(keep)
        centred = residual[keep] - np.median(residual[keep], axis=0)
        scale = np.maximum(1.4826 * np.median(np.abs(centred), axis=0), 1e-12)
        inliers = (np.abs(residual - np.median(residual[keep], axis=0)) <= OUTLIER_MAD * scale).all(axis=1)
        if np.array_equal(inliers, keep):
            break
        keep = inliers
        if keep.sum() < (1.0 - MAX_REJECTED_FRACTION) * n:
            raise DataError(
                f"the tare recording is not steady: {n - int(keep.sum())} of {n} samples lie off the model's "
                f"robust spread (was the handle touched?): record it again"
            )
    if not keep.all():
        values, covariance, residual = solve(keep)
    common["n_samples"] = int(keep.sum())
    common["n_rejected"] = int(n - keep.sum())
    # Residual spread over sample-to-sample noise: about 1 for a steady load and a white sensor, far more
    # when the load changed during the recording (an arm attached, the handle held).
    used = residual[keep]
    step_noise = 1.4826 * np.median(np.abs(np.diff(used, axis=0)), axis=0) / math.sqrt(2.0)
    spread = np.sqrt((used**2).mean(axis=0))
    ratios = spread[step_noise > 0] / step_noise[step_noise > 0]
    common["unsteadiness"] = float(ratios.max()) if ratios.size else 1.0
    return Tare(
        load="separated" if separated else "constant",
        values=values,
        covariance=covariance,
        residual_rms=tuple(np.sqrt((residual[keep] ** 2).mean(axis=0)).tolist()),
        **common,
    )
