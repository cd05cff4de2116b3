"""A node's parameters with the cell description's values as their defaults (``cell_file``, the shipped cell when
unset): a parameter given on the command line or in a params file still wins."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from bsp_ros.cell import CellDescription, read_cell_file
from bsp_ros.errors import InputError
from bsp_ros.live.runtime.parameters import Param, declare_parameters

__all__ = [
    "ANGLES_FROM_CELL",
    "CELL_FILE",
    "IDENTIFIER_FROM_CELL",
    "SIMULATOR_FROM_CELL",
    "declare_with_cell",
    "load_cell",
    "with_cell_defaults",
]

#: A parameter's default taken from the cell description.
FromCell = Mapping[str, Callable[[CellDescription], Any]]

CELL_FILE = Param(
    name="cell_file",
    default="",
    description="the cell description (bsp_ros/cell/1 YAML: world frame, the F/T sensor's frame, topic, mounting "
    "rotation, transform topic and tare, the marker, handle pose and EMG topics): the default of the parameters it "
    "names ('': the shipped bsp_ros/config/cell.yaml, the simulated cell)",
)

IDENTIFIER_FROM_CELL: FromCell = {
    "world_frame": lambda c: c.world_frame,
    "wrench_topic": lambda c: c.wrench_topic,
    "wrench_frame_topic": lambda c: c.transform_topic,
    "wrench_frame_rotation_xyzw": lambda c: [float(v) for v in c.rotation_xyzw],
    "tare_file": lambda c: "" if c.tare_file is None else str(c.tare_file),
    "emg_topic": lambda c: c.emg_topic,
}
SIMULATOR_FROM_CELL: FromCell = {
    "wrench_topic": lambda c: c.wrench_topic,
    "marker_topic_prefix": lambda c: c.marker_topic_prefix,
    "transform_topic": lambda c: c.transform_topic,
    "sensor_roll_pitch_yaw_deg": lambda c: list(c.roll_pitch_yaw_deg),
}
ANGLES_FROM_CELL: FromCell = {
    "marker_topic_prefix": lambda c: c.marker_topic_prefix,
    "handle_pose_topic": lambda c: c.handle_pose_topic,
}


def load_cell(cell_file: str) -> CellDescription:
    """The cell description of a ``cell_file`` parameter ('': the shipped one).

    Raises
    ------
    InputError
        Naming the parameter, the file and the bad value.
    """
    try:
        return read_cell_file(cell_file or None)
    except InputError as error:
        raise InputError(f"parameter cell_file: {error}") from None


def with_cell_defaults(params: Sequence[Param], cell: CellDescription, from_cell: FromCell) -> tuple[Param, ...]:
    """``params`` with the defaults ``from_cell`` names taken from ``cell`` (the others as they are)."""
    return tuple(dataclasses.replace(p, default=from_cell[p.name](cell)) if p.name in from_cell else p for p in params)


def declare_with_cell(
    node: Any, params: Sequence[Param], from_cell: FromCell
) -> tuple[dict[str, Any], CellDescription]:
    """Declare :data:`CELL_FILE`, read the cell, then declare ``params`` (but ``cell_file``) with its values as
    their defaults; return every value (overrides applied, ``cell_file`` included) and the cell.

    Raises
    ------
    InputError
        A bad cell file or parameter value (named).
    """
    values = declare_parameters(node, [CELL_FILE])
    cell = load_cell(values[CELL_FILE.name])
    rest = [p for p in with_cell_defaults(params, cell, from_cell) if p.name != CELL_FILE.name]
    values.update(declare_parameters(node, rest))
    return values, cell
