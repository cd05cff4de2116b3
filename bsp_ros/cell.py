"""The cell description: one YAML file (schema ``bsp_ros/cell/1``) naming the cell's frames, topics, the force
sensor's mounting rotation and tare, read alike by the simulator, the nodes and the offline commands."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bsp_ros.errors import InputError

__all__ = [
    "CELL_SCHEMA",
    "DISAGREE_DEG",
    "SHIPPED_CELL",
    "CellDescription",
    "angle_between_deg",
    "cell_description_from_mapping",
    "check_cell_description",
    "read_cell_file",
]

CELL_SCHEMA = "bsp_ros/cell/1"
#: A recorded or received rotation further than this from the one a cell states is reported (one of the two
#: describes another sensor mounting), deg.
DISAGREE_DEG = 1.0
#: The shipped description (the simulated cell): the default of the nodes' ``cell_file`` and of `bsp record` /
#: `bsp play` ``--cell``.
SHIPPED_CELL = Path(__file__).resolve().parent / "config" / "cell.yaml"

_TOPIC = re.compile(r"^/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
_PREFIX = re.compile(r"^/?([A-Za-z_][A-Za-z0-9_]*/)*$")
_FRAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_./-]*$")
_KEYS: dict[str, frozenset[str]] = {
    "": frozenset({"schema", "world_frame", "ft_sensor", "markers", "contact_point", "emg"}),
    "ft_sensor": frozenset(
        {"frame", "wrench_topic", "rotation_xyzw", "roll_pitch_yaw_deg", "transform_topic", "tare_file"}
    ),
    "markers": frozenset({"topic_prefix"}),
    "contact_point": frozenset({"handle_pose_topic"}),
    "emg": frozenset({"envelope_topic"}),
}


@dataclass(frozen=True, kw_only=True)
class CellDescription:
    """One cell, as its YAML file describes it (every name a default a node parameter or option may override).

    Attributes
    ----------
    source : the file it was read from ('' when built in memory), for messages.
    world_frame : frame of the markers and of gravity (z up).
    sensor_frame : the wrench's ``header.frame_id``.
    wrench_topic : the WrenchStamped topic.
    rotation_xyzw : (4,) the sensor's mounting, rotation ``world <- sensor`` as a unit quaternion ``[x, y, z, w]``
        (``w >= 0``).
    transform_topic : geometry_msgs/TransformStamped of the sensor frame in world (the rotation's topic where
        tf2_msgs is not installed).
    tare_file : a `bsp tare` file of this sensor (resolved against the cell file's folder), or None.
    marker_topic_prefix : PoseStamped topics are this prefix + the marker name.
    handle_pose_topic : the robot's contact point (PoseStamped in world), '' for none.
    emg_topic : the muscles' EMG envelopes (std_msgs/Float32MultiArray, docs/contract.md), '' for none.
    """

    source: str = ""
    world_frame: str = "world"
    sensor_frame: str = "ft_sensor"
    wrench_topic: str = "/ft_sensor/wrench"
    rotation_xyzw: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    transform_topic: str = "/ft_sensor/transform"
    tare_file: Path | None = None
    marker_topic_prefix: str = "/mocap/"
    handle_pose_topic: str = "/robot/handle_pose"
    emg_topic: str = "/emg/envelope"

    @property
    def rotation_world_from_sensor(self) -> np.ndarray:
        """(3, 3) rotation ``world <- sensor`` of :attr:`rotation_xyzw`."""
        from msg_adapters.rotation import matrix_from_quaternion

        return np.asarray(matrix_from_quaternion(self.rotation_xyzw), dtype=np.float64)

    @property
    def roll_pitch_yaw_deg(self) -> tuple[float, float, float]:
        """The mounting as fixed-axis roll, pitch, yaw (deg; ``Rz(yaw) Ry(pitch) Rx(roll)``, tf2's ``setRPY``)."""
        from scipy.spatial.transform import Rotation

        angles = Rotation.from_quat(self.rotation_xyzw).as_euler("xyz", degrees=True)
        roll, pitch, yaw = (float(a) for a in angles)
        return roll, pitch, yaw

    def marker_topic(self, name: str) -> str:
        """The PoseStamped topic of marker ``name`` (``shoulder``, ``elbow``, ``wrist``, ``hand``)."""
        return self.marker_topic_prefix + name

    def where(self, key: str) -> str:
        """``key`` of the file, for a message naming what to set (``cell file X: ft_sensor.rotation_xyzw``)."""
        return f"cell file {self.source}: {key}" if self.source else f"cell description {key}"


def angle_between_deg(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation taking (3, 3) rotation ``b`` to ``a``, deg (0..180)."""
    cosine = (float(np.trace(np.asarray(a).T @ np.asarray(b))) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cosine))))


def _problems(cell: CellDescription) -> list[str]:
    """One clause per bad value of ``cell``, naming its key and the value."""
    out = []
    for key, value in (("world_frame", cell.world_frame), ("ft_sensor.frame", cell.sensor_frame)):
        if not isinstance(value, str) or not _FRAME.match(value):
            out.append(f"{key} must be a frame name (letters, digits, _ . / -, not starting with /), got {value!r}")
    if cell.world_frame == cell.sensor_frame:
        out.append(f"ft_sensor.frame must differ from world_frame, both are {cell.world_frame!r}")
    topics = (
        ("ft_sensor.wrench_topic", cell.wrench_topic, False),
        ("ft_sensor.transform_topic", cell.transform_topic, False),
        ("contact_point.handle_pose_topic", cell.handle_pose_topic, True),
        ("emg.envelope_topic", cell.emg_topic, True),
    )
    for key, value, may_be_empty in topics:
        if not isinstance(value, str) or not (_TOPIC.match(value) or (may_be_empty and value == "")):
            out.append(f"{key} must be a ROS topic name (/-separated letters, digits, _), got {value!r}")
    if not isinstance(cell.marker_topic_prefix, str) or not _PREFIX.match(cell.marker_topic_prefix):
        prefix = cell.marker_topic_prefix
        out.append(f"markers.topic_prefix must be a topic prefix ending in / (e.g. /mocap/), got {prefix!r}")
    q = np.asarray(cell.rotation_xyzw, dtype=np.float64) if _numbers(cell.rotation_xyzw, 4) else None
    if q is None:
        out.append(f"ft_sensor.rotation_xyzw must be 4 finite numbers [x, y, z, w], got {cell.rotation_xyzw!r}")
    elif abs(float(np.linalg.norm(q)) - 1.0) > 1e-3:
        out.append(f"ft_sensor.rotation_xyzw {list(cell.rotation_xyzw)} has norm {np.linalg.norm(q):.4g}, not 1")
    if cell.tare_file is not None and not Path(cell.tare_file).is_file():
        out.append(f"ft_sensor.tare_file {cell.tare_file} is not a file (`bsp tare TARE_BAG --out FILE` makes one)")
    return out


def _numbers(value: Any, n: int) -> bool:
    """Whether ``value`` is a sequence of ``n`` finite numbers (no booleans, no strings)."""
    if not isinstance(value, list | tuple) or len(value) != n:
        return False
    return all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value)


def check_cell_description(cell: CellDescription) -> CellDescription:
    """Return ``cell`` if every value is usable.

    Raises
    ------
    InputError
        One line naming the file and, for each bad value, its key and the value (clauses joined by ``; ``).
    """
    problems = _problems(cell)
    if problems:
        where = f"cell file {cell.source}" if cell.source else "cell description"
        raise InputError(f"{where}: " + "; ".join(problems))
    return cell


def _section(data: dict[str, Any], name: str, source: str) -> dict[str, Any]:
    """``data[name]`` as a mapping whose keys are all known ({} when absent)."""
    section = data.get(name, {}) if name else data
    if section is None:
        section = {}
    if not isinstance(section, dict):
        raise InputError(f"cell file {source}: {name} must be a mapping, got {section!r}")
    unknown = sorted(set(map(str, section)) - _KEYS[name])
    if unknown:
        known = ", ".join(sorted(_KEYS[name]))
        inside = f" in {name}" if name else ""
        raise InputError(f"cell file {source}: unknown key(s) {', '.join(unknown)}{inside} (known: {known})")
    return section


def _rotation_xyzw(sensor: dict[str, Any], source: str) -> tuple[float, float, float, float] | list[Any]:
    """The mounting as a unit quaternion from ``rotation_xyzw`` or ``roll_pitch_yaw_deg`` (one of them)."""
    if "rotation_xyzw" in sensor and "roll_pitch_yaw_deg" in sensor:
        raise InputError(f"cell file {source}: give ft_sensor.rotation_xyzw or ft_sensor.roll_pitch_yaw_deg, not both")
    if "roll_pitch_yaw_deg" not in sensor:
        value = sensor.get("rotation_xyzw", [0.0, 0.0, 0.0, 1.0])
        if not _numbers(value, 4) or abs(float(np.linalg.norm(value)) - 1.0) > 1e-3:
            return list(value) if isinstance(value, list | tuple) else [value]  # refused by check_cell_description
        q = np.asarray(value, dtype=np.float64)
    else:
        rpy = sensor["roll_pitch_yaw_deg"]
        if not _numbers(rpy, 3):
            raise InputError(f"cell file {source}: ft_sensor.roll_pitch_yaw_deg must be 3 finite angles, got {rpy!r}")
        from scipy.spatial.transform import Rotation

        q = np.asarray(Rotation.from_euler("xyz", rpy, degrees=True).as_quat(), dtype=np.float64)
    q = q / np.linalg.norm(q)
    q = -q if q[3] < 0.0 else q
    x, y, z, w = (float(v) for v in q)
    return x, y, z, w


def cell_description_from_mapping(data: Any, source: str = "", folder: Path | None = None) -> CellDescription:
    """A checked :class:`CellDescription` of a parsed cell file (``folder``: where relative tare paths start).

    Raises
    ------
    InputError
        A wrong schema, an unknown key, or a bad value (each named, see :func:`check_cell_description`).
    """
    if not isinstance(data, dict):
        raise InputError(f"cell file {source}: expected a mapping with schema {CELL_SCHEMA}, got {type(data).__name__}")
    top = _section(data, "", source)
    if top.get("schema") != CELL_SCHEMA:
        raise InputError(f"cell file {source}: schema must be {CELL_SCHEMA}, got {top.get('schema')!r}")
    sensor = _section(top, "ft_sensor", source)
    markers = _section(top, "markers", source)
    contact = _section(top, "contact_point", source)
    emg = _section(top, "emg", source)
    defaults = CellDescription()
    tare = sensor.get("tare_file") or None
    tare_path = None if tare is None else (folder or Path.cwd()) / Path(str(tare)).expanduser()
    cell = CellDescription(
        source=source,
        world_frame=top.get("world_frame", defaults.world_frame),
        sensor_frame=sensor.get("frame", defaults.sensor_frame),
        wrench_topic=sensor.get("wrench_topic", defaults.wrench_topic),
        rotation_xyzw=_rotation_xyzw(sensor, source),  # type: ignore[arg-type]  # a bad one is named by the check
        transform_topic=sensor.get("transform_topic", defaults.transform_topic),
        tare_file=tare_path,
        marker_topic_prefix=markers.get("topic_prefix", defaults.marker_topic_prefix),
        handle_pose_topic=contact.get("handle_pose_topic", defaults.handle_pose_topic) or "",
        emg_topic=emg.get("envelope_topic", defaults.emg_topic) or "",
    )
    return check_cell_description(cell)


def read_cell_file(path: str | Path | None = None) -> CellDescription:
    """Read and check a cell file (None or '': the shipped :data:`SHIPPED_CELL`).

    Raises
    ------
    InputError
        The file is missing, not YAML, or holds a bad value (named).
    """
    import yaml

    file = SHIPPED_CELL if path is None or str(path) == "" else Path(path).expanduser()
    try:
        text = file.read_text("utf-8")
    except FileNotFoundError:
        hint = "copy bsp_ros/config/cell.yaml and describe the cell"
        raise InputError(f"cell file {file}: no such file ({hint})") from None
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(f"cell file {file}: cannot be read ({error})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise InputError(f"cell file {file}: not YAML ({' '.join(str(error).split())})") from None
    return cell_description_from_mapping(data, str(file), file.resolve().parent)
