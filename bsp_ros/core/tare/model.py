"""The tare of an F/T sensor: its offset and the handle's load, their covariance, and the tare file's schema."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.normalised import normalising
from bsp_ros.errors import InputError

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


def skew(v: np.ndarray) -> np.ndarray:
    """(N, 3) vectors -> (N, 3, 3) cross-product matrices ``[v]_x``."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def gravity_in_sensor(rotation_world_from_sensor: npt.ArrayLike) -> np.ndarray:
    """Unit 'down' direction in the sensor frame, ``R^T (0, 0, -1)``: (3, 3) -> (3,), (N, 3, 3) -> (N, 3)."""
    rotation = np.asarray(rotation_world_from_sensor, dtype=np.float64)
    return np.asarray(-rotation[..., 2, :])


@normalising
@dataclass(frozen=True, kw_only=True)
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

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: float64 arrays, the covariance made exactly symmetric."""
        if given.load not in LOADS:
            raise InputError(f"tare load must be one of {LOADS}, got {given.load!r}")
        p = 10 if given.load == "separated" else 6
        values = np.asarray(given.values, dtype=np.float64)
        covariance = np.asarray(given.covariance, dtype=np.float64)
        if values.shape != (p,) or covariance.shape != (p, p):
            raise InputError(f"a {given.load} tare has {p} parameters, got {values.shape} and {covariance.shape}")
        if not (np.isfinite(values).all() and np.isfinite(covariance).all()):
            raise InputError("a tare's values and covariance must be finite")
        if not isinstance(given.frame_id, str) or not given.frame_id:
            raise InputError(f"tare frame_id must be a non-empty string, got {given.frame_id!r}")
        out = {"values": values, "covariance": 0.5 * (covariance + covariance.T)}
        if given.rotation_world_from_sensor is not None:
            rotation = np.asarray(given.rotation_world_from_sensor, dtype=np.float64)
            if rotation.shape != (3, 3) or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6):
                raise InputError(f"tare rotation_world_from_sensor must be a rotation matrix, got {rotation!r}")
            out["rotation_world_from_sensor"] = rotation
        return out

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
        down = GRAVITY_M_S2 * gravity_in_sensor(rotation)
        h = np.zeros((6, 10))
        h[:3, :3] = np.eye(3)
        h[:3, 3] = down
        h[3:, 4:7] = np.eye(3)
        h[3:, 7:10] = -skew(down[None, :])[0]  # s x d = -[d]_x s
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
