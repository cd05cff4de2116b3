"""How a force/torque sensor offset moves the identified parameters, and the tare's share of their uncertainty."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.estimate_blocks import SensorZero, TareBlock
from bsp_ros.core.estimate_schema import Quality
from bsp_ros.core.findings import FindingCode, note
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.model import contact_lever_sums
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.core.streams import segments_for

__all__ = [
    "FORCE_STEP_N",
    "REPORTED_OFFSET_N",
    "TORQUE_STEP_NM",
    "ZERO_SD_N",
    "ZERO_SD_NM",
    "TareShare",
    "account_for_tare",
    "add_tare_covariance",
    "offset_sensitivity",
    "offset_torques_nm",
    "response_sensitivity",
    "tare_share",
    "zero_covariance",
]

# Finite-difference steps: small enough to stay linear (and off the bounds), far above round-off.
FORCE_STEP_N = 0.01
TORQUE_STEP_NM = 0.001
# The offset the estimate's sensitivity block is quoted for.
REPORTED_OFFSET_N = 0.1

Refit = Callable[[IdentificationData], IdentificationResult]


def _mean_rotation(rotation: np.ndarray) -> np.ndarray:
    if rotation.ndim == 2:
        return rotation
    u, _, vt = np.linalg.svd(rotation.mean(axis=0))
    return np.asarray(u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt)


def _world_unit_torques(data: IdentificationData) -> np.ndarray:
    """(3, N, n) joint torques of a unit ``F_y`` (N), ``F_z`` (N) and ``M_x`` (Nm) in ``world``: ``-J^T e``."""
    dy, dz = contact_lever_sums(data.q_rad, data.lengths_m)
    return np.stack((-dy, -dz, np.full_like(dy, -1.0)))


def _world_from_sensor_offsets(rotation_world_from_sensor: npt.ArrayLike) -> np.ndarray:
    """(3, 6) map from a sensor-frame offset ``[F (3) N, M (3) Nm]`` to the planar ``[F_y, F_z, M_x]`` in world."""
    rotation = _mean_rotation(np.asarray(rotation_world_from_sensor, dtype=np.float64))
    out = np.zeros((3, 6))
    out[:2, :3] = rotation[1:3, :]
    out[2, 3:] = rotation[0, :]
    return out


def offset_torques_nm(data: IdentificationData, rotation_world_from_sensor: npt.ArrayLike) -> np.ndarray:
    """Joint torques a unit sensor-frame offset adds to the measured torques.

    Parameters
    ----------
    data : the identification samples (angles, segment lengths).
    rotation_world_from_sensor : (3, 3) the sensor's orientation ((N, 3, 3): their mean is used).

    Returns
    -------
    (6, N, n) ``-J^T [ (R e)_y, (R e)_z, (R e')_x ]`` for unit force offsets along the sensor's x, y, z (N)
    and unit moment offsets about them (Nm), in that order.
    """
    mapping = _world_from_sensor_offsets(rotation_world_from_sensor)
    return np.einsum("wk,wni->kni", mapping, _world_unit_torques(data))


def offset_sensitivity(
    data: IdentificationData, rotation_world_from_sensor: npt.ArrayLike, refit: Refit
) -> tuple[np.ndarray, IdentificationResult]:
    """``G = d(parameters) / d(offset)`` of the estimator as fitted, by finite differences.

    A sensor-frame offset ``o`` adds ``-J^T (R o)`` to every measured torque (``offset_torques_nm``). For a
    weighted least-squares fit that is ``G = (A^T W A)^-1 A^T W D`` with ``D`` those torques; rather than
    rebuild the estimator's rows, weights and bounds here, the estimator is re-run with an offset added
    (0.01 N or 0.001 Nm, in its linear range), so ``G`` is right whatever the estimator does. Only the
    planar ``F_y``, ``F_z``, ``M_x`` in ``world`` reach the model, so three re-runs (plus the reference)
    give all six sensor-frame columns.

    Parameters
    ----------
    data : the samples identified.
    rotation_world_from_sensor : (3, 3) sensor orientation of the session.
    refit : the estimator (e.g. ``identify_data`` without its elastic check).

    Returns
    -------
    G : (p, 6) parameter change per N of force offset (columns x, y, z) and per Nm of moment offset.
    base : the estimator's result on the unperturbed data (the reference of the differences).
    """
    base = refit(data)
    unit = _world_unit_torques(data)
    g_world = np.empty((base.values.size, 3))
    for k in range(3):
        step = FORCE_STEP_N if k < 2 else TORQUE_STEP_NM
        shifted = dataclasses.replace(data, tau_nm=data.tau_nm + step * unit[k], warnings=list(data.warnings))
        g_world[:, k] = (refit(shifted).values - base.values) / step
    return g_world @ _world_from_sensor_offsets(rotation_world_from_sensor), base


def response_sensitivity(
    result: IdentificationResult, data: IdentificationData, rotation_world_from_sensor: npt.ArrayLike
) -> np.ndarray | None:
    """``G`` of :func:`offset_sensitivity` from the estimate's own ``torque_response`` (no re-run of the
    estimator: milliseconds, where the re-runs take seconds on a long session); None where the method has none.

    Parameters
    ----------
    result : the identification of ``data``.
    data : the samples identified.
    rotation_world_from_sensor : (3, 3) sensor orientation of the session ((N, 3, 3): their mean).

    Returns
    -------
    (p, 6) parameter change per N of force offset (sensor x, y, z) and per Nm of moment offset, or None.
    """
    if result.torque_response is None:
        return None
    unit = _world_unit_torques(data)
    g_world = result.torque_response.columns(unit)
    return g_world @ _world_from_sensor_offsets(rotation_world_from_sensor)


def add_tare_covariance(
    result: IdentificationResult, g: np.ndarray, wrench_covariance: np.ndarray
) -> tuple[IdentificationResult, np.ndarray]:
    """``result`` with the tare's uncertainty ``G Sigma G^T`` added to its covariance, and the added term.

    Parameters
    ----------
    result : the identification.
    g : (p, 6) from :func:`offset_sensitivity`.
    wrench_covariance : (6, 6) covariance of the wrench the tare subtracted (force N, moment Nm).
    """
    added = g @ np.asarray(wrench_covariance, dtype=np.float64) @ g.T
    added = 0.5 * (added + added.T)
    return result.plus_term(Term.SENSOR_ZERO, added), added


def zero_covariance(zero_sd_n: float, zero_sd_nm: float) -> np.ndarray:
    """(6, 6) covariance of an untared sensor's zero: ``zero_sd_n`` (N) per force axis, ``zero_sd_nm`` (Nm) per
    moment axis, independent."""
    return np.diag([zero_sd_n**2] * 3 + [zero_sd_nm**2] * 3)


@dataclass(frozen=True, kw_only=True)
class TareShare:
    """What the sensor's zero means for an estimate: its ``quality.tare`` and ``quality.offset_sensitivity``.

    Attributes
    ----------
    tare : whether a tare was applied, and the zero's share of each parameter's std.
    offset_sensitivity : the document's ``offset_sensitivity`` block.
    """

    tare: TareBlock
    offset_sensitivity: Mapping[str, object]

    def applied_to(self, quality: Quality) -> Quality:
        """``quality`` with both blocks, the tare's first."""
        return quality.with_tare(self.tare).with_extra({"offset_sensitivity": self.offset_sensitivity})


def tare_share(
    result: IdentificationResult,
    g: np.ndarray | None,
    frame_id: str,
    tare_file: str | None,
    added: np.ndarray | None = None,
    zero_sd: tuple[float, float] | None = None,
) -> TareShare:
    """The ``quality.tare`` and ``quality.offset_sensitivity`` blocks of the estimate.

    ``offset_sensitivity.static_moment_kgm[segment]`` is how much a 0.1 N force offset along the sensor's
    x, y, z moves that static moment (kg m), ``static_moment_percent`` the largest of the three in % of the
    estimate; ``null`` where the estimate could not be differentiated. Without a tare, ``tare.zero_sd`` is
    the assumed zero (``{"force_n", "moment_nm"}``, 1 SD per axis) whose share of the std is ``std_added``.
    """
    n = sum(1 for key, _ in result.names if key == "static_moment_kgm")
    block: dict[str, Any] = {
        "offset_n": REPORTED_OFFSET_N,
        "frame_id": frame_id,
        "static_moment_kgm": {},
        "static_moment_percent": {},
    }
    for segment in segments_for(n):
        i = result.index("static_moment_kgm", segment)
        if g is None or not np.isfinite(g[i, :3]).all():
            block["static_moment_kgm"][segment] = None
            block["static_moment_percent"][segment] = None
            continue
        change = REPORTED_OFFSET_N * g[i, :3]
        value = abs(float(result.values[i]))
        block["static_moment_kgm"][segment] = [float(c) for c in change]
        block["static_moment_percent"][segment] = (
            float(100.0 * np.abs(change).max() / value) if value > 0 and np.isfinite(value) else None
        )
    zero = None
    if tare_file is None and zero_sd is not None:
        zero = SensorZero(force_n=zero_sd[0], moment_nm=zero_sd[1])
    std_added = None
    if added is not None:
        std_added = {
            f"{key}/{owner}": float(np.sqrt(max(added[i, i], 0.0))) for i, (key, owner) in enumerate(result.names)
        }
    tare = TareBlock(applied=tare_file is not None, file=tare_file, zero_sd=zero, std_added=std_added)
    return TareShare(tare=tare, offset_sensitivity=block)


def account_for_tare(
    result: IdentificationResult,
    data: IdentificationData,
    rotation_world_from_sensor: npt.ArrayLike,
    frame_id: str,
    tare: Any,
    refit: Refit,
    zero_sd: tuple[float, float] | None = (ZERO_SD_N, ZERO_SD_NM),
) -> tuple[IdentificationResult, TareShare]:
    """Sensitivity to a sensor offset, and ``result`` with the uncertainty of the wrench's zero added.

    With a tare, its own uncertainty; without, the assumed ``zero_sd`` (force N, moment Nm; 1 SD per sensor
    axis; None or zeros: none). The sensitivity is the estimate's own ``torque_response`` where it has one.

    Parameters
    ----------
    result : the identification of ``data``.
    data : the samples identified (already corrected by the tare, if any).
    rotation_world_from_sensor : (3, 3) the sensor's orientation in the session.
    frame_id : the wrench frame.
    tare : the :class:`bsp_ros.core.tare.Tare` applied, or None.
    refit : the estimator, re-run for the finite differences where ``result`` has no ``torque_response``.
    zero_sd : the untared zero's (force N, moment Nm) 1 SD, see :data:`ZERO_SD_N`.

    Returns
    -------
    ``result`` with the zero's share in its covariance and a tare's notes in its findings; the ``tare`` and
    ``offset_sensitivity`` blocks for ``quality`` (see :func:`tare_share`).
    """
    from bsp_ros.core.tare import recording_warnings, tare_warnings

    rotation = _mean_rotation(np.asarray(rotation_world_from_sensor, dtype=np.float64))
    usable = result.valid and np.isfinite(result.values).all()
    g = None
    if usable:
        g = response_sensitivity(result, data, rotation)
        if g is None:
            g, _ = offset_sensitivity(data, rotation, refit)
    added = None
    if tare is not None:
        notes = recording_warnings(tare) + tare_warnings(tare, rotation)
        result = result.with_findings(*(note(FindingCode.TARE_NOTE, w) for w in notes))
        if g is not None:
            h = tare.wrench_jacobian(rotation)
            result, added = add_tare_covariance(result, g, h @ tare.covariance @ h.T)
    elif g is not None and zero_sd is not None and max(zero_sd) > 0.0:
        result, added = add_tare_covariance(result, g, zero_covariance(*zero_sd))
    source = (tare.file or tare.source or "tare") if tare is not None else None
    return result, tare_share(result, g, frame_id, source, added, zero_sd)
