"""The identified arm as markers for RViz and Foxglove: a pure function of the angles, lengths and estimate (no ROS).

The arm moves in the world y-z plane (docs/contract.md, section 1); the markers place it there from the shoulder's
position: its segments as one line, its joint centres and contact point as small spheres, each segment's centre of
mass as a sphere whose volume grows with the mass (the estimate's ``mass_kg`` at ``com_m`` along the segment), a
translucent shell for the mass one std higher, a line over the COM's +-1 std along the segment, the weight support as
an arrow at the contact point, and the verdict as text above the shoulder. `arm_visualizer` turns them into a
``visualization_msgs/MarkerArray`` (:mod:`bsp_ros.live.marker_messages`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.model import absolute_angles_rad, joint_positions_m
from bsp_ros.core.streams import joints_for, segments_for

__all__ = [
    "COM_DIAMETER_M_PER_CBRT_KG",
    "SUPPORT_M_PER_N",
    "MarkerKind",
    "MarkerSpec",
    "SegmentFrame",
    "arm_markers",
    "com_diameter_m",
    "segment_frames",
]

#: A COM sphere's diameter per cube root of its mass (m / kg^(1/3)): its volume grows with the mass; 2 kg: 7.6 cm.
COM_DIAMETER_M_PER_CBRT_KG = 0.06
#: The support arrow's length per newton of force (m/N): 20 N draw as 0.2 m.
SUPPORT_M_PER_N = 0.01
JOINT_DIAMETER_M = 0.03
LINE_WIDTH_M = 0.015

VALID_RGBA = (0.2, 0.75, 0.3, 1.0)
INVALID_RGBA = (0.95, 0.55, 0.1, 1.0)
SEGMENT_RGBA = (0.55, 0.6, 0.7, 1.0)
JOINT_RGBA = (0.95, 0.95, 0.95, 1.0)
SUPPORT_RGBA = (0.8, 0.2, 0.8, 1.0)
SHELL_ALPHA = 0.25


class MarkerKind(StrEnum):
    """The marker shapes used (``visualization_msgs/Marker`` types of the same names)."""

    SPHERE = "sphere"
    LINE_STRIP = "line_strip"
    LINE_LIST = "line_list"
    ARROW = "arrow"
    TEXT = "text_view_facing"


@dataclass(frozen=True, kw_only=True)
class MarkerSpec:
    """One marker in ``world``.

    Attributes
    ----------
    ns, id : its namespace (``segments``, ``joints``, ``com``, ``com_std``, ``com_range``, ``support``, ``verdict``)
        and id within it (RViz toggles namespaces).
    kind : its shape.
    position_m : (3,) its centre (spheres, text), m; zeros for point lists.
    scale : (3,) the Marker's ``scale``: diameters (spheres), line width (lines), shaft and head diameters and head
        length (arrow), text height (z), m.
    rgba : colour and opacity, 0-1.
    points_m : (K, 3) the points of lines and arrows (start, end), m; empty otherwise.
    text : the text of a text marker.
    """

    ns: str
    id: int
    kind: MarkerKind
    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rgba: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    points_m: tuple[tuple[float, float, float], ...] = ()
    text: str = ""


@dataclass(frozen=True, kw_only=True)
class SegmentFrame:
    """A segment's frame in ``world``: origin at its proximal joint, +y along the segment, +x world's +x.

    Attributes
    ----------
    segment : the segment's name (``upper_arm``, ...).
    origin_m : (3,) the proximal joint's position, m.
    rotation_xyzw : (4,) quaternion taking segment-frame vectors into ``world`` (a rotation about +x by the
        segment's absolute angle).
    """

    segment: str
    origin_m: tuple[float, float, float]
    rotation_xyzw: tuple[float, float, float, float] = field(default=(0.0, 0.0, 0.0, 1.0))


def com_diameter_m(mass_kg: float) -> float:
    """The diameter of a COM sphere of ``mass_kg`` (m; 0 for a mass at or below 0)."""
    return COM_DIAMETER_M_PER_CBRT_KG * math.cbrt(max(mass_kg, 0.0))


def _chain_world_m(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike, shoulder_m: npt.ArrayLike) -> np.ndarray:
    """(n + 1, 3) the shoulder, the distal joints and the contact point in ``world`` (m)."""
    yz = joint_positions_m(np.asarray(q_rad, dtype=np.float64)[None, :], lengths_m)[0]
    x, y, z = (float(v) for v in np.asarray(shoulder_m, dtype=np.float64).reshape(3))
    return np.column_stack((np.full(len(yz), x), y + yz[:, 0], z + yz[:, 1]))


def _point(p: np.ndarray) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]))


def segment_frames(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike, shoulder_m: npt.ArrayLike) -> list[SegmentFrame]:
    """Each segment's frame in ``world`` (for TF), proximal to distal."""
    chain = _chain_world_m(q_rad, lengths_m, shoulder_m)
    phi = absolute_angles_rad(np.asarray(q_rad, dtype=np.float64)[None, :])[0]
    names = segments_for(len(phi))
    return [
        SegmentFrame(
            segment=name,
            origin_m=_point(chain[j]),
            rotation_xyzw=(math.sin(phi[j] / 2), 0.0, 0.0, math.cos(phi[j] / 2)),
        )
        for j, name in enumerate(names)
    ]


def _chain_markers(chain: np.ndarray) -> list[MarkerSpec]:
    """The segments as one line, the joint centres and the contact point as spheres."""
    joint_names = (*joints_for(len(chain) - 1), "contact_point")
    out = [
        MarkerSpec(
            ns="segments",
            id=0,
            kind=MarkerKind.LINE_STRIP,
            scale=(LINE_WIDTH_M, 0.0, 0.0),
            rgba=SEGMENT_RGBA,
            points_m=tuple(_point(p) for p in chain),
        )
    ]
    out += [
        MarkerSpec(
            ns="joints",
            id=k,
            kind=MarkerKind.SPHERE,
            position_m=_point(p),
            scale=(JOINT_DIAMETER_M,) * 3,
            rgba=JOINT_RGBA,
            text=name,
        )
        for k, (name, p) in enumerate(zip(joint_names, chain, strict=True))
    ]
    return out


def _com_markers(chain: np.ndarray, estimate: Estimate) -> list[MarkerSpec]:
    """Each segment's COM sphere by its mass, the +1 std shell, and the COM's +-1 std along the segment."""
    colour = VALID_RGBA if estimate.valid else INVALID_RGBA
    out: list[MarkerSpec] = []
    for j, segment in enumerate(segments_for(len(chain) - 1)):
        mass, com = estimate.quantity("mass_kg", segment), estimate.quantity("com_m", segment)
        if mass is None or com is None or mass.value is None or com.value is None:
            continue
        axis = chain[j + 1] - chain[j]
        unit = axis / np.linalg.norm(axis)
        centre = chain[j] + com.value * unit
        diameter = com_diameter_m(mass.value)
        out.append(
            MarkerSpec(
                ns="com", id=j, kind=MarkerKind.SPHERE, position_m=_point(centre), scale=(diameter,) * 3, rgba=colour
            )
        )
        if mass.std is not None:
            shell = com_diameter_m(mass.value + mass.std)
            out.append(
                MarkerSpec(
                    ns="com_std",
                    id=j,
                    kind=MarkerKind.SPHERE,
                    position_m=_point(centre),
                    scale=(shell,) * 3,
                    rgba=(*colour[:3], SHELL_ALPHA),
                )
            )
        if com.std is not None:
            ends = (_point(centre - com.std * unit), _point(centre + com.std * unit))
            out.append(
                MarkerSpec(
                    ns="com_range",
                    id=j,
                    kind=MarkerKind.LINE_LIST,
                    scale=(LINE_WIDTH_M / 2, 0.0, 0.0),
                    rgba=colour,
                    points_m=ends,
                )
            )
    return out


def _verdict_text(estimate: Estimate | None, precision_reached: bool | None) -> str:
    if estimate is None:
        return "waiting for an estimate"
    verdict = estimate.quality.verdict
    text = "VALID" if estimate.valid else f"INVALID ({verdict.code if verdict is not None else 'no verdict'})"
    if precision_reached is not None:
        text += ", precision " + ("reached" if precision_reached else "not yet")
    return text


def arm_markers(
    q_rad: npt.ArrayLike,
    lengths_m: npt.ArrayLike,
    shoulder_m: npt.ArrayLike,
    estimate: Estimate | None,
    support_yzx: Sequence[float] | None = None,
    precision_reached: bool | None = None,
) -> list[MarkerSpec]:
    """The arm at one posture as markers in ``world``.

    Parameters
    ----------
    q_rad : (n,) joint angles (rad, docs/contract.md section 1).
    lengths_m : (n,) segment lengths (m).
    shoulder_m : (3,) the shoulder's position in ``world`` (m).
    estimate : the latest estimate (its masses and COMs), or None before one.
    support_yzx : the weight support ``[F_y (N), F_z (N), M_x (Nm)]`` on the hand, or None when none is published.
    precision_reached : the precision signal, or None without a target.

    Returns
    -------
    list of MarkerSpec
        Namespaces ``segments``, ``joints``, ``com``, ``com_std``, ``com_range``, ``support``, ``verdict``.
    """
    chain = _chain_world_m(q_rad, lengths_m, shoulder_m)
    out = _chain_markers(chain)
    if estimate is not None:
        out += _com_markers(chain, estimate)
    if support_yzx is not None:
        force = np.array([0.0, float(support_yzx[0]), float(support_yzx[1])])
        tip = chain[-1] + SUPPORT_M_PER_N * force
        out.append(
            MarkerSpec(
                ns="support",
                id=0,
                kind=MarkerKind.ARROW,
                scale=(0.01, 0.02, 0.03),
                rgba=SUPPORT_RGBA,
                points_m=(_point(chain[-1]), _point(tip)),
            )
        )
    label = chain[0] + np.array([0.0, 0.0, 0.25])
    out.append(
        MarkerSpec(
            ns="verdict",
            id=0,
            kind=MarkerKind.TEXT,
            position_m=_point(label),
            scale=(0.0, 0.0, 0.05),
            rgba=(VALID_RGBA if estimate is not None and estimate.valid else INVALID_RGBA),
            text=_verdict_text(estimate, precision_reached),
        )
    )
    return out
