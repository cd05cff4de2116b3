"""What `bsp_identifier` says about its wrench frame's rotation: a typed finding in every estimate while it lasts,
once in its log, and on /diagnostics.

Two things make an estimate wrong without making it look wrong: a rotation source that sends nothing (the stated
rotation then stands in: :attr:`FindingCode.ROTATION_FROM_MOUNTING`, a note) and a transform that disagrees with the
stated rotation (the transform is used: :attr:`FindingCode.ROTATION_DISAGREES`, weak). Each names the parameter to
set; its text is rendered from the code's spec, the same in the estimate, the log and /diagnostics.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsp_ros.cell import CellDescription
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.live.online.frames import DISAGREE_DEG, NO_TRANSFORM, WrenchFrames

__all__ = ["FrameNotices", "stated_rotation"]

#: The /diagnostics key suffix of each code (``wrench_frame.<frame>.<kind>``).
KINDS = {FindingCode.ROTATION_FROM_MOUNTING: "missing", FindingCode.ROTATION_DISAGREES: "disagrees"}


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

    def findings(self, frames: WrenchFrames) -> list[Finding]:
        """The findings that hold now: a frame whose stated rotation stands in for a transform that did not come
        within ``tf_wait_s``, and a frame whose fixed transform is more than :data:`DISAGREE_DEG` off it."""
        out = []
        common = {"world": frames.world_frame, "source": self.source, "stated": self.stated}
        stated_xyzw = _xyzw(frames.parameter_rotation)
        for frame, origin in frames.sources.items():
            if origin == NO_TRANSFORM:
                values = {**common, "frame": frame, "tf_wait_s": frames.tf_wait_s, "rotation_xyzw": stated_xyzw}
                out.append(Finding(code=FindingCode.ROTATION_FROM_MOUNTING, values=values))
        for frame, angle in frames.disagreement_deg.items():
            if frame in frames.rotations:
                values = {
                    **common,
                    "frame": frame,
                    "received_xyzw": _xyzw(frames.rotations[frame]),
                    "angle_deg": angle,
                    "limit_deg": DISAGREE_DEG,
                    "stated_xyzw": stated_xyzw,
                }
                out.append(Finding(code=FindingCode.ROTATION_DISAGREES, values=values))
        return out

    def _lines(self, frames: WrenchFrames) -> dict[tuple[str, str], str]:
        """(kind, frame) -> its notice, for every notice that holds now."""
        return {(KINDS[f.code], str(f.values["frame"])): f.text for f in self.findings(frames)}

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
