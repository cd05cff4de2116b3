"""A cell description in a bag's terms: its topics (:func:`topic_map_from_cell`, `bsp identify --cell`) and its
sensor mounting in ``metadata.yaml``'s ``custom_data`` (written by `bsp record` from its cell file, read back where
the bag records no transform, so a bag identifies with the rotation its cell stated)."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from bsp_ros.bag.topics import StatedRotation, TopicMap

if TYPE_CHECKING:
    from bsp_ros.cell import CellDescription

__all__ = [
    "CELL_KEYS",
    "SHIPPED_NOTE",
    "cell_file_said",
    "custom_data_from_cell",
    "is_shipped_cell",
    "stated_from_custom_data",
    "topic_map_from_cell",
]

#: ``custom_data`` keys (rosbag2 keeps any string pairs there).
CELL_KEYS = {
    "world_frame": "bsp_ros.cell.world_frame",
    "sensor_frame": "bsp_ros.cell.sensor_frame",
    "rotation_xyzw": "bsp_ros.cell.rotation_xyzw",
    "file": "bsp_ros.cell.file",
    "shipped": "bsp_ros.cell.shipped_simulated",
}
#: Said wherever the shipped simulated cell's file gave the mounting: on a real cell it is the simulator's rotation.
SHIPPED_NOTE = "the shipped simulated cell's mounting; set --cell / cell_file for your cell"


def is_shipped_cell(cell: CellDescription) -> bool:
    """Whether ``cell`` states the shipped simulated cell's mounting: read from its file (``bsp_ros/config/cell.yaml``)
    with the rotation that file gives."""
    import numpy as np

    from bsp_ros.cell import SHIPPED_CELL, read_cell_file

    if not cell.source or Path(cell.source).expanduser().resolve() != SHIPPED_CELL.resolve():
        return False
    return bool(np.allclose(cell.rotation_xyzw, read_cell_file(SHIPPED_CELL).rotation_xyzw, atol=1e-9))


def cell_file_said(cell: CellDescription) -> str:
    """The cell file a recording used, for its one line: ``cell file PATH``, and where it states the shipped simulated
    cell's mounting, :data:`SHIPPED_NOTE`."""
    return f"cell file {cell.source}: {SHIPPED_NOTE}" if is_shipped_cell(cell) else f"cell file {cell.source}"


def custom_data_from_cell(cell: CellDescription) -> dict[str, str]:
    """The ``custom_data`` pairs stating ``cell``'s sensor mounting (frames, quaternion, the file's name, and whether
    that file is the shipped simulated cell's: ``"true"`` or ``"false"``)."""
    return {
        CELL_KEYS["world_frame"]: cell.world_frame,
        CELL_KEYS["sensor_frame"]: cell.sensor_frame,
        CELL_KEYS["rotation_xyzw"]: json.dumps([float(v) for v in cell.rotation_xyzw]),
        CELL_KEYS["file"]: cell.source,
        CELL_KEYS["shipped"]: json.dumps(is_shipped_cell(cell)),
    }


def stated_from_custom_data(custom: Mapping[str, str]) -> tuple[StatedRotation | None, str]:
    """The mounting a bag's ``custom_data`` states, or None, and why not ('' where it states none at all).

    Returns
    -------
    (StatedRotation or None, problem)
        ``problem`` names a mounting that is there but unusable (a warning for the read).
    """
    if CELL_KEYS["rotation_xyzw"] not in custom:
        return None, ""
    text = custom[CELL_KEYS["rotation_xyzw"]]
    try:
        values = json.loads(text)
        ok = isinstance(values, list) and len(values) == 4 and all(isinstance(v, int | float) for v in values)
        quaternion = tuple(float(v) for v in values) if ok else ()
    except (ValueError, TypeError):
        quaternion = ()
    norm = math.sqrt(sum(v * v for v in quaternion)) if quaternion else 0.0
    world, sensor = custom.get(CELL_KEYS["world_frame"], ""), custom.get(CELL_KEYS["sensor_frame"], "")
    if len(quaternion) != 4 or not all(map(math.isfinite, quaternion)) or abs(norm - 1.0) > 1e-3:
        return None, f"the bag's metadata states a sensor rotation that is not a unit quaternion ({text!r}): not used"
    if not world or not sensor:
        return None, "the bag's metadata states a sensor rotation without its frames: not used"
    x, y, z, w = (v / norm for v in quaternion)
    shipped = f": {SHIPPED_NOTE}" if custom.get(CELL_KEYS["shipped"]) == "true" else ""
    where = f"the bag's metadata (cell file {custom.get(CELL_KEYS['file'], '?')} when recorded{shipped})"
    return StatedRotation(world, sensor, (x, y, z, w), "metadata", where), ""


def topic_map_from_cell(cell: CellDescription) -> TopicMap:
    """The topics a bag of ``cell`` has under the cell's names, and the mounting it states (source ``cell``)."""
    defaults = TopicMap()
    return TopicMap(
        wrench=cell.wrench_topic,
        markers={name: cell.marker_topic(name) for name in defaults.markers},
        handle_pose=cell.handle_pose_topic,
        transform=cell.transform_topic,
        stated=StatedRotation(
            cell.world_frame, cell.sensor_frame, cell.rotation_xyzw, "cell", cell.where("ft_sensor.rotation_xyzw")
        ),
        world_frame=cell.world_frame,
        emg=cell.emg_topic,
    )
