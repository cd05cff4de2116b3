"""Tare of the F/T sensor: its offset and the handle's load, from a recording with the handle free."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.identification.covariance import hac_covariance
from bsp_ros.core.streams import Session, WrenchSeries
from bsp_ros.errors import DataError, InputError

__all__ = [
    "LOADS",
    "MIN_SWING_DEG",
    "MIN_TARE_DURATION_S",
    "TARE_SCHEMA",
    "Tare",
    "corrected_session",
    "estimate_tare",
    "read_tare_file",
    "recording_warnings",
    "tare_warnings",
    "tare_wrench",
    "write_tare_file",
]

TARE_SCHEMA = "bsp_ros/core/tare/1"
GRAVITY_M_S2 = 9.81
MIN_TARE_DURATION_S = 5.0
MIN_TARE_SAMPLES = 50
# The gravity direction in the sensor frame must swing by this much (rms, in two independent directions)
# before the handle's mass and centre of mass are told apart from the sensor's offset.
MIN_SWING_DEG = 3.0
# Samples whose residual is beyond this many robust standard deviations (MAD) on any axis are outliers,
# and a recording with more than this fraction of them is not a steady tare.
OUTLIER_MAD = 6.0
MAX_REJECTED_FRACTION = 0.1
# A tare whose residual spread exceeds its sample-to-sample noise this many times did not see a steady load.
MAX_UNSTEADINESS = 5.0
LOADS = ("separated", "constant")
_SEPARATED_NAMES = (
    "force_offset_x_n",
    "force_offset_y_n",
    "force_offset_z_n",
    "handle_mass_kg",
    "torque_offset_x_nm",
    "torque_offset_y_nm",
    "torque_offset_z_nm",
    "handle_first_moment_x_kgm",
    "handle_first_moment_y_kgm",
    "handle_first_moment_z_kgm",
)
_CONSTANT_NAMES = (
    "force_load_x_n",
    "force_load_y_n",
    "force_load_z_n",
    "torque_load_x_nm",
    "torque_load_y_nm",
    "torque_load_z_nm",
)


def _skew(v: np.ndarray) -> np.ndarray:
    """(N, 3) vectors -> (N, 3, 3) cross-product matrices ``[v]_x``."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _gravity_in_sensor(rotation_world_from_sensor: npt.ArrayLike) -> np.ndarray:
    """Unit 'down' direction in the sensor frame, ``R^T (0, 0, -1)``: (3, 3) -> (3,), (N, 3, 3) -> (N, 3)."""
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    return np.asarray(-rotation[..., 2, :])


@dataclass(frozen=True)
class Tare:
    """A tare: what the sensor reads with the handle free, as a function of its orientation.

    ``load == "separated"``: the parameters are ``[oF (3) N, m kg, oM (3) Nm, s (3) kg m]`` (sensor-frame
    offsets, the handle's mass and first moment ``s = m c``) and the sensor reads
    ``F = oF + R^T m g``, ``M = oM + s x R^T g`` (g = (0, 0, -9.81) m/s^2 in ``world``).
    ``load == "constant"``: the orientation did not vary enough (or was unknown); the parameters are the
    constant load ``[F (3) N, M (3) Nm]`` read at the recorded orientation, offset and handle together.

    Attributes
    ----------
    frame_id : the sensor frame the wrench was given in.
    load : ``"separated"`` or ``"constant"``.
    values : (p,) parameters (10 separated, 6 constant).
    covariance : (p, p) their covariance (Newey-West HAC from the residuals).
    n_samples : wrench samples used.
    n_rejected : samples left out as outliers (beyond ``OUTLIER_MAD`` robust std of the residuals).
    unsteadiness : largest ratio over the axes of the residual rms to the sample-to-sample noise (about 1
        for a steady tare; above ``MAX_UNSTEADINESS`` the load changed during the recording).
    start_time_ns, duration_s : when the recording started and how long it lasted.
    swing_deg : (2,) rms swing of the gravity direction in the sensor frame along its two principal
        directions, deg (zeros without orientation).
    rotation_world_from_sensor : (3, 3) the mean orientation during the recording, None if unknown.
    residual_rms : (6,) rms residual per force (N) and moment (Nm) axis.
    source : where it came from (a bag's name; never a person's).
    file : the file it was read from (not part of the file itself).
    """

    frame_id: str
    load: str
    values: np.ndarray
    covariance: np.ndarray
    n_samples: int
    start_time_ns: int
    duration_s: float
    swing_deg: tuple[float, float] = (0.0, 0.0)
    rotation_world_from_sensor: np.ndarray | None = None
    residual_rms: tuple[float, ...] = (0.0,) * 6
    source: str = ""
    n_rejected: int = 0
    unsteadiness: float = 1.0
    file: str = dataclasses.field(default="", compare=False)

    def __post_init__(self) -> None:
        if self.load not in LOADS:
            raise InputError(f"tare load must be one of {LOADS}, got {self.load!r}")
        p = 10 if self.load == "separated" else 6
        values = np.asarray(self.values, dtype=np.float64)
        covariance = np.asarray(self.covariance, dtype=np.float64)
        if values.shape != (p,) or covariance.shape != (p, p):
            raise InputError(f"a {self.load} tare has {p} parameters, got {values.shape} and {covariance.shape}")
        if not (np.isfinite(values).all() and np.isfinite(covariance).all()):
            raise InputError("a tare's values and covariance must be finite")
        if not isinstance(self.frame_id, str) or not self.frame_id:
            raise InputError(f"tare frame_id must be a non-empty string, got {self.frame_id!r}")
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "covariance", 0.5 * (covariance + covariance.T))
        if self.rotation_world_from_sensor is not None:
            rotation = np.asarray(self.rotation_world_from_sensor, dtype=np.float64)
            if rotation.shape != (3, 3) or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6):
                raise InputError(f"tare rotation_world_from_sensor must be a rotation matrix, got {rotation!r}")
            object.__setattr__(self, "rotation_world_from_sensor", rotation)

    # ---- parameters ----------------------------------------------------------------------------------

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the parameters, in order."""
        return _SEPARATED_NAMES if self.load == "separated" else _CONSTANT_NAMES

    @property
    def std(self) -> np.ndarray:
        """(p,) one standard deviation of each parameter."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def _pick(self, separated: slice, constant: slice) -> tuple[np.ndarray, np.ndarray]:
        picks = separated if self.load == "separated" else constant
        return self.values[picks], self.std[picks]

    @property
    def force_offset_n(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,) force offset (separated) or constant force load, sensor frame, N; and its (3,) std."""
        return self._pick(slice(0, 3), slice(0, 3))

    @property
    def torque_offset_nm(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,) moment offset (separated) or constant moment load, sensor frame, Nm; and its (3,) std."""
        return self._pick(slice(4, 7), slice(3, 6))

    @property
    def handle_mass_kg(self) -> tuple[float, float] | None:
        """The handle's mass and its std, kg (None for a constant load)."""
        if self.load != "separated":
            return None
        return float(self.values[3]), float(self.std[3])

    @property
    def handle_com_m(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(3,) the handle's COM from the wrench reference point, sensor frame, m, and its (3,) std (delta method).

        None for a constant load or a handle too light to locate (mass below 5 std).
        """
        if self.load != "separated":
            return None
        mass, first = self.values[3], self.values[7:10]
        if not mass > 5.0 * self.std[3]:
            return None
        jacobian = np.zeros((3, 10))
        jacobian[:, 7:10] = np.eye(3) / mass
        jacobian[:, 3] = -first / mass**2
        cov = jacobian @ self.covariance @ jacobian.T
        return first / mass, np.sqrt(np.clip(np.diag(cov), 0.0, None))

    # ---- what it predicts ------------------------------------------------------------------------------

    def wrench_jacobian(self, rotation_world_from_sensor: npt.ArrayLike) -> np.ndarray:
        """The sensor-frame wrench the tare predicts is ``H @ values``; return ``H``.

        Parameters
        ----------
        rotation_world_from_sensor : (3, 3) the sensor's orientation (ignored for a constant load).

        Returns
        -------
        (6, p) ``H``: rows force x, y, z (N), moment x, y, z (Nm).
        """
        if self.load == "constant":
            return np.eye(6)
        rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
        if rotation.shape != (3, 3) or not np.isfinite(rotation).all():
            raise InputError(f"rotation_world_from_sensor must be a finite (3, 3) matrix, got {rotation!r}")
        down = GRAVITY_M_S2 * _gravity_in_sensor(rotation)
        h = np.zeros((6, 10))
        h[:3, :3] = np.eye(3)
        h[:3, 3] = down
        h[3:, 4:7] = np.eye(3)
        h[3:, 7:10] = -_skew(down[None, :])[0]  # s x d = -[d]_x s
        return h

    def predicted_wrench(self, rotation_world_from_sensor: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(3,) force N and (3,) moment Nm the sensor reads with the handle free at this orientation."""
        wrench = self.wrench_jacobian(rotation_world_from_sensor) @ self.values
        return wrench[:3], wrench[3:]

    # ---- file form -------------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The ``bsp_ros/core/tare/1`` document (plain Python types; see the README's Tare section)."""

        def vector(values: np.ndarray, std: np.ndarray) -> dict[str, list[float]]:
            return {"value": [float(v) for v in values], "std": [float(s) for s in std]}

        force, force_std = self.force_offset_n
        torque, torque_std = self.torque_offset_nm
        mass, com = self.handle_mass_kg, self.handle_com_m
        payload = None
        if mass is not None:
            payload = {
                "mass_kg": {"value": mass[0], "std": mass[1]},
                "com_m": vector(*com) if com is not None else None,
                "first_moment_kgm": vector(self.values[7:10], self.std[7:10]),
            }
        rotation = self.rotation_world_from_sensor
        return {
            "schema": TARE_SCHEMA,
            "frame_id": self.frame_id,
            "load": self.load,
            "force_offset_n": vector(force, force_std),
            "torque_offset_nm": vector(torque, torque_std),
            "payload": payload,
            "parameters": list(self.names),
            "covariance": [[float(c) for c in row] for row in self.covariance],
            "recording": {
                "source": self.source,
                "start_time_ns": int(self.start_time_ns),
                "duration_s": float(self.duration_s),
                "n_samples": int(self.n_samples),
                "rejected_samples": int(self.n_rejected),
                "unsteadiness": float(self.unsteadiness),
                "swing_deg": [float(s) for s in self.swing_deg],
                "rotation_world_from_sensor": None if rotation is None else [[float(x) for x in r] for r in rotation],
                "residual_rms": [float(r) for r in self.residual_rms],
            },
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Tare:
        """Read back a ``bsp_ros/core/tare/1`` document.

        Raises
        ------
        InputError
            On a foreign schema, a missing key or a bad value (named).
        """
        if not isinstance(data, Mapping):
            raise InputError(f"a tare file holds a mapping, got {type(data).__name__}")
        if data.get("schema") != TARE_SCHEMA:
            raise InputError(f"tare schema must be {TARE_SCHEMA!r}, got {data.get('schema')!r}")
        try:
            load = data["load"]
            names = _SEPARATED_NAMES if load == "separated" else _CONSTANT_NAMES
            if tuple(data["parameters"]) != names:
                raise InputError(f"tare parameters must be {list(names)}, got {data['parameters']!r}")
            force = data["force_offset_n"]["value"]
            torque = data["torque_offset_nm"]["value"]
            if load == "separated":
                payload = data["payload"]
                values = [*force, payload["mass_kg"]["value"], *torque, *payload["first_moment_kgm"]["value"]]
            else:
                values = [*force, *torque]
            recording = data["recording"]
            rotation = recording.get("rotation_world_from_sensor")
            return cls(
                frame_id=data["frame_id"],
                load=load,
                values=np.asarray(values, dtype=np.float64),
                covariance=np.asarray(data["covariance"], dtype=np.float64),
                n_samples=int(recording["n_samples"]),
                start_time_ns=int(recording["start_time_ns"]),
                duration_s=float(recording["duration_s"]),
                swing_deg=tuple(float(s) for s in recording.get("swing_deg", (0.0, 0.0))),  # type: ignore[arg-type]
                rotation_world_from_sensor=None if rotation is None else np.asarray(rotation, dtype=np.float64),
                residual_rms=tuple(float(r) for r in recording.get("residual_rms", (0.0,) * 6)),
                source=str(recording.get("source", "")),
                n_rejected=int(recording.get("rejected_samples", 0)),
                unsteadiness=float(recording.get("unsteadiness", 1.0)),
            )
        except (KeyError, TypeError, ValueError) as error:
            if isinstance(error, InputError):
                raise
            raise InputError(f"tare file: missing or malformed entry ({error.__class__.__name__}: {error})") from None


# --------------------------------------------------------------------------------------------------------
# estimation
# --------------------------------------------------------------------------------------------------------


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
        down = _gravity_in_sensor(rotations)
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
        d = GRAVITY_M_S2 * _gravity_in_sensor(rotations)  # (N, 3)
        eye = np.broadcast_to(np.eye(3), (n, 3, 3))
        designs = (np.concatenate([eye, d[:, :, None]], axis=2), np.concatenate([eye, -_skew(d)], axis=2))
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


# --------------------------------------------------------------------------------------------------------
# applying a tare
# --------------------------------------------------------------------------------------------------------

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
    cosines = _gravity_in_sensor(rotation) @ _gravity_in_sensor(tare.rotation_world_from_sensor)
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


# --------------------------------------------------------------------------------------------------------
# file
# --------------------------------------------------------------------------------------------------------


def write_tare_file(path: str | Path, tare: Tare) -> Path:
    """Write ``tare`` as YAML (schema ``bsp_ros/core/tare/1``); refuse to overwrite."""
    import yaml

    out = Path(path)
    if out.exists():
        raise InputError(f"{out} exists already: refusing to overwrite a tare (choose another --out)")
    out.parent.mkdir(parents=True, exist_ok=True)
    text = "# bsp_ros tare: F/T sensor offset and handle payload (README, Tare)\n"
    text += yaml.safe_dump(tare.to_dict(), sort_keys=False, default_flow_style=None, width=120)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(text, "utf-8")
    tmp.replace(out)
    return out


def read_tare_file(path: str | Path) -> Tare:
    """Read a tare file written by :func:`write_tare_file`.

    Raises
    ------
    InputError
        The file is missing, not YAML, or not a ``bsp_ros/core/tare/1`` document.
    """
    import yaml

    file = Path(path)
    if not file.is_file():
        raise InputError(f"tare file {file} does not exist")
    try:
        data = yaml.safe_load(file.read_text("utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise InputError(f"tare file {file} is not YAML: {error}") from None
    return dataclasses.replace(Tare.from_dict(data), file=file.name)
