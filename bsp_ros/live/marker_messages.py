"""Marker specs (:mod:`bsp_ros.live.online.arm_markers`) as ``visualization_msgs/msg/MarkerArray``, segment frames as
``tf2_msgs/msg/TFMessage``: message building only, by the class lookup the caller passes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bsp_ros.live.online.arm_markers import MarkerKind, MarkerSpec, SegmentFrame
from msg_adapters._types import TypeLookup
from msg_adapters.stamps import build_header
from msg_adapters.tf import TransformSample, build_tf_message

__all__ = ["LIFETIME_S", "build_marker_array", "build_segment_tf"]

#: A marker not renewed within this vanishes (a segment's COM once the estimate has none), s.
LIFETIME_S = 1.0
# visualization_msgs/Marker's type constants.
_TYPES = {
    MarkerKind.ARROW: 0,
    MarkerKind.SPHERE: 2,
    MarkerKind.LINE_STRIP: 4,
    MarkerKind.LINE_LIST: 5,
    MarkerKind.TEXT: 9,
}


def _marker(types: TypeLookup, spec: MarkerSpec, header: Any) -> Any:
    point = types("geometry_msgs/msg/Point")
    marker = types("visualization_msgs/msg/Marker")()
    marker.header = header
    marker.ns, marker.id, marker.type, marker.action = spec.ns, spec.id, _TYPES[spec.kind], 0
    marker.pose.position = point(x=spec.position_m[0], y=spec.position_m[1], z=spec.position_m[2])
    marker.pose.orientation.w = 1.0
    marker.scale.x, marker.scale.y, marker.scale.z = (float(v) for v in spec.scale)
    marker.color.r, marker.color.g, marker.color.b, marker.color.a = (float(v) for v in spec.rgba)
    marker.lifetime.sec = int(LIFETIME_S)
    marker.lifetime.nanosec = round((LIFETIME_S % 1) * 1e9)
    marker.points = [point(x=p[0], y=p[1], z=p[2]) for p in spec.points_m]
    marker.text = spec.text if spec.kind is MarkerKind.TEXT else ""
    return marker


def build_marker_array(types: TypeLookup, specs: Sequence[MarkerSpec], frame_id: str, stamp_ns: int) -> Any:
    """A ``visualization_msgs/msg/MarkerArray`` of ``specs`` in ``frame_id``, stamped ``stamp_ns``."""
    header = build_header(types, stamp_ns, frame_id)
    return types("visualization_msgs/msg/MarkerArray")(markers=[_marker(types, s, header) for s in specs])


def build_segment_tf(
    types: TypeLookup, frames: Sequence[SegmentFrame], parent_frame: str, prefix: str, stamp_ns: int
) -> Any:
    """A ``tf2_msgs/msg/TFMessage`` of each segment's frame (child ``<prefix><segment>``) in ``parent_frame``."""
    samples = [
        TransformSample(stamp_ns, parent_frame, prefix + f.segment, np.array(f.origin_m), np.array(f.rotation_xyzw))
        for f in frames
    ]
    return build_tf_message(types, samples)
