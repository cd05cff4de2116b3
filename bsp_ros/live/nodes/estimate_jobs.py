"""The estimates `bsp_identifier` computes, serialised for their topics."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from rosbags.typesys import Stores, get_typestore

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding
from bsp_ros.core.weight_support import support_inputs
from bsp_ros.live.estimate_messages import (
    diagnostics_from_estimate,
    inertias_from_estimate,
    passive_moments_from_estimate,
)
from bsp_ros.live.online.identifier_modes import ModeEstimate
from msg_adapters.diagnostics import build_diagnostic_array
from msg_adapters.inertia import build_inertia_stamped
from msg_adapters.joint_state import build_joint_state

__all__ = ["EstimateOutputs", "outputs_from_estimate", "outputs_of"]

_store: Any = None


def _typestore() -> Any:
    """The rosbags Jazzy type store: it serialises CDR without a message class per call."""
    global _store
    if _store is None:
        _store = get_typestore(Stores.ROS2_JAZZY)
    return _store


@dataclass(frozen=True)
class EstimateOutputs:
    """One estimate, serialised for its topics (the rosbags type store: no message class per call).

    ``cdr`` maps an output (``estimate``, ``json``, ``inertia/<segment>``,
    ``passive``) to serialised CDR, which rclpy's ``Publisher.publish`` takes as it is.
    """

    valid: bool
    message: str
    cdr: dict[str, bytes]
    # The estimate's findings (what the node's diagnostics level is decided on).
    findings: tuple[Finding, ...] = ()
    # The static moments and their covariance for the weight support (bsp_ros.core.weight_support), or None.
    support: dict[str, Any] | None = None


def outputs_of(estimate: Estimate, stamp_ns: int, with_passive: bool) -> EstimateOutputs:
    """Serialise an estimate for ``bsp/estimate``, ``bsp/estimate_json`` (its docs/contract.md document),
    ``bsp/<segment>/inertia`` and, when ``with_passive``, ``bsp/passive_moments``; stamped ``stamp_ns``."""
    store = _typestore()

    def types(name: str) -> Any:
        return store.types[name]

    def cdr(msg: Any, type_name: str) -> bytes:
        return bytes(store.serialize_cdr(msg, type_name))

    text = json.dumps(estimate.to_json(), allow_nan=False)
    out = {
        "estimate": cdr(
            build_diagnostic_array(types, diagnostics_from_estimate(estimate, stamp_ns)),
            "diagnostic_msgs/msg/DiagnosticArray",
        ),
        "json": cdr(types("std_msgs/msg/String")(data=text), "std_msgs/msg/String"),
    }
    if estimate.valid:
        for segment, inertia in inertias_from_estimate(estimate, stamp_ns).items():
            out[f"inertia/{segment}"] = cdr(build_inertia_stamped(types, inertia), "geometry_msgs/msg/InertiaStamped")
        passive = passive_moments_from_estimate(estimate, stamp_ns)
        if passive is not None and with_passive:
            out["passive"] = cdr(build_joint_state(types, passive), "sensor_msgs/msg/JointState")
    quality = estimate.quality
    return EstimateOutputs(
        estimate.valid, quality.message, out, findings=quality.findings, support=support_inputs(estimate)
    )


def outputs_from_estimate(estimate: ModeEstimate) -> EstimateOutputs:
    """Serialise one update's estimate of an identifier mode (:func:`outputs_of`)."""
    return outputs_of(estimate.estimate, estimate.stamp_ns, with_passive=estimate.with_passive)
