"""A tare from a recording with the handle free: offset and handle load by least squares, outliers left out."""

from __future__ import annotations

import math
from dataclasses import dataclass

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
    orientation = _orientation(rotations)
    separated = rotations is not None and min(orientation.swing_deg) >= MIN_SWING_DEG
    inliers = _without_outliers(_designs(rotations if separated else None, n), force, torque)
    fit, keep = inliers.fit, inliers.keep
    return Tare(
        load="separated" if separated else "constant",
        values=fit.values,
        covariance=fit.covariance,
        residual_rms=tuple(np.sqrt((fit.residual[keep] ** 2).mean(axis=0)).tolist()),
        frame_id=frame_id,
        n_samples=int(keep.sum()),
        start_time_ns=int(t[0]),
        duration_s=float(t[-1] - t[0]) * 1e-9,
        swing_deg=orientation.swing_deg,
        rotation_world_from_sensor=orientation.mean_rotation,
        source=source,
        n_rejected=int(n - keep.sum()),
        unsteadiness=_unsteadiness(fit.residual[keep]),
    )


@dataclass(frozen=True, kw_only=True)
class _Orientation:
    """How the sensor was held during the recording.

    Attributes
    ----------
    swing_deg : rms swing of the gravity direction in the sensor frame along its two principal directions, deg
        (0, 0 when the orientation is unknown).
    mean_rotation : the mean orientation, world from sensor; shape (3, 3), or None when unknown.
    """

    swing_deg: tuple[float, float]
    mean_rotation: np.ndarray | None


def _orientation(rotations: np.ndarray | None) -> _Orientation:
    """The swing and mean of the sensor's orientations ``rotations`` (N, 3, 3), world from sensor, or None."""
    if rotations is None:
        return _Orientation(swing_deg=(0.0, 0.0), mean_rotation=None)
    down = gravity_in_sensor(rotations)
    spread = np.linalg.svd(down - down.mean(axis=0), compute_uv=False) / math.sqrt(rotations.shape[0])
    swing = (math.degrees(math.asin(min(spread[0], 1.0))), math.degrees(math.asin(min(spread[1], 1.0))))
    return _Orientation(swing_deg=swing, mean_rotation=_mean_rotation(rotations))


def _designs(rotations: np.ndarray | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The per-sample rows of the force and of the moment model, each of shape (N, 3, p).

    With the orientations ``rotations`` (N, 3, 3) the force is ``oF + m g R^T e`` and the moment
    ``oM + s x g R^T e`` (p = 4 and 6); without them (None), the constant load: a mean per axis (p = 3) over
    the ``n`` samples.
    """
    if rotations is not None:
        d = GRAVITY_M_S2 * gravity_in_sensor(rotations)  # (N, 3)
        eye = np.broadcast_to(np.eye(3), (n, 3, 3))
        return np.concatenate([eye, d[:, :, None]], axis=2), np.concatenate([eye, -skew(d)], axis=2)
    return (np.broadcast_to(np.eye(3), (n, 3, 3)),) * 2


@dataclass(frozen=True, kw_only=True)
class _TareFit:
    """The force and moment models fitted on some samples.

    Attributes
    ----------
    values : the force model's parameters, then the moment model's; shape (p,).
    covariance : their covariance, block diagonal (force, moment); shape (p, p).
    residual : the residual of every sample, force (N) then moment (Nm) axes; shape (N, 6).
    """

    values: np.ndarray
    covariance: np.ndarray
    residual: np.ndarray


def _fit_tare(
    designs: tuple[np.ndarray, np.ndarray], force: np.ndarray, torque: np.ndarray, keep: np.ndarray
) -> _TareFit:
    """The force and moment models (``designs``, each (N, 3, p)) fitted to the samples ``keep`` (N,) bool of
    ``force`` (N) and ``torque`` (Nm), each (N, 3); the residual is of every sample."""
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
    return _TareFit(values=np.concatenate([f_values, m_values]), covariance=covariance, residual=residual)


@dataclass(frozen=True, kw_only=True)
class _Inliers:
    """A fit without the outliers.

    Attributes
    ----------
    fit : the fit on the inliers.
    keep : which samples are inliers; shape (N,) bool.
    """

    fit: _TareFit
    keep: np.ndarray


def _without_outliers(designs: tuple[np.ndarray, np.ndarray], force: np.ndarray, torque: np.ndarray) -> _Inliers:
    """The fit of :func:`_fit_tare` on every sample, refitted without the samples off the residuals' robust spread
    until they no longer change (at most 4 passes).

    Raises
    ------
    DataError
        More than ``MAX_REJECTED_FRACTION`` of the samples are outliers.
    """
    n = force.shape[0]
    # Spikes (a knock on the handle, a glitch) must not move the tare: samples off the robust spread of
    # the residuals (median absolute deviation) are left out and counted.
    keep = np.ones(n, dtype=bool)
    for _ in range(4):
        fit = _fit_tare(designs, force, torque, keep)
        residual = fit.residual
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
        fit = _fit_tare(designs, force, torque, keep)
    return _Inliers(fit=fit, keep=keep)


def _unsteadiness(used: np.ndarray) -> float:
    """The largest ratio over the axes of the residual rms to the sample-to-sample noise, from the inliers'
    residuals ``used`` (M, 6); 1 when no axis has noise."""
    # Residual spread over sample-to-sample noise: about 1 for a steady load and a white sensor, far more
    # when the load changed during the recording (an arm attached, the handle held).
    step_noise = 1.4826 * np.median(np.abs(np.diff(used, axis=0)), axis=0) / math.sqrt(2.0)
    spread = np.sqrt((used**2).mean(axis=0))
    ratios = spread[step_noise > 0] / step_noise[step_noise > 0]
    return float(ratios.max()) if ratios.size else 1.0
