"""What `bsp_identifier` says about its wrench frame's rotation: once in its log, and on /diagnostics while it lasts.

Two things make an estimate wrong without making it look wrong: a rotation source that sends nothing (the stated
rotation then stands in) and a transform that disagrees with the stated rotation (the transform is used). Each is
said once, naming the parameter to set.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsp_ros.cell import CellDescription
from bsp_ros.live.online.frames import DISAGREE_DEG, NO_TRANSFORM, WrenchFrames

__all__ = ["FrameNotices", "stated_rotation"]


def _xyzw(rotation: np.ndarray) -> list[float]:
    from msg_adapters.rotation import quaternion_from_matrix

    return [round(float(v), 6) for v in quaternion_from_matrix(rotation)]


@dataclass
class FrameNotices:
    """The notices of one node's wrench frames.

    Parameters
    ----------
    source : where transforms come from (:attr:`FrameSource.description`).
    stated : where the stated rotation comes from, e.g. ``parameter wrench_frame_rotation_xyzw (cell file
        /x/cell.yaml: ft_sensor.rotation_xyzw)``: what a user sets.
    """

    source: str
    stated: str
    said: set[tuple[str, str]] = field(default_factory=set)

    def _lines(self, frames: WrenchFrames) -> dict[tuple[str, str], str]:
        """(kind, frame) -> its notice, for every notice that holds now."""
        out = {}
        for frame, origin in frames.sources.items():
            if origin == NO_TRANSFORM:
                out[("missing", frame)] = (
                    f"no transform {frames.world_frame} -> {frame} from {self.source} within tf_wait_s "
                    f"({frames.tf_wait_s:g} s): the stated rotation {self.stated} = "
                    f"{_xyzw(frames.parameter_rotation)} is used; publish the sensor's transform or check that "
                    "rotation"
                )
        for frame, angle in frames.disagreement_deg.items():
            if frame in frames.rotations:
                out[("disagrees", frame)] = (
                    f"the transform {frames.world_frame} -> {frame} from {self.source} is "
                    f"{_xyzw(frames.rotations[frame])}, {angle:.1f} deg off the stated rotation {self.stated} = "
                    f"{_xyzw(frames.parameter_rotation)} (more than {DISAGREE_DEG:g} deg): the transform is used; "
                    "set that rotation to the transform's if the sensor is mounted so"
                )
        return out

    def new_lines(self, frames: WrenchFrames) -> list[str]:
        """The notices not said yet (each once per node)."""
        fresh = [(key, line) for key, line in self._lines(frames).items() if key not in self.said]
        self.said.update(key for key, _ in fresh)
        return [line for _, line in fresh]

    def diagnostics(self, frames: WrenchFrames) -> dict[str, str]:
        """The notices that hold now, as /diagnostics values (``wrench_frame.<frame>.missing`` / ``.disagrees``)."""
        return {f"wrench_frame.{frame}.{kind}": line for (kind, frame), line in self._lines(frames).items()}


def stated_rotation(given_xyzw: tuple[float, ...], cell: CellDescription) -> str:
    """Where ``wrench_frame_rotation_xyzw`` came from, for the notices: the cell file's mounting (its default), or
    the parameter given otherwise."""
    if np.allclose(np.asarray(given_xyzw, dtype=np.float64), cell.rotation_xyzw, atol=1e-9):
        return f"wrench_frame_rotation_xyzw ({cell.where('ft_sensor.rotation_xyzw')})"
    return "parameter wrench_frame_rotation_xyzw"
