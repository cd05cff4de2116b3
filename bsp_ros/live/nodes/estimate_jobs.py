"""The estimates `bsp_identifier` computes, serialised for their topics."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_typestore

from bsp_ros.core.estimate import invalid_document
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.weight_support import support_inputs
from bsp_ros.live.estimate_messages import (
    diagnostics_from_estimate,
    inertias_from_estimate,
    passive_moments_from_estimate,
)
from bsp_ros.live.online.identifier_modes import ModeEstimate, recursive_document
from bsp_ros.live.online.windowed import WindowEstimator, WindowSamples
from msg_adapters.diagnostics import build_diagnostic_array
from msg_adapters.inertia import build_inertia_stamped
from msg_adapters.joint_state import build_joint_state

__all__ = [
    "EstimateOutputs",
    "internal_error_document",
    "outputs_from_document",
    "outputs_from_estimate",
    "recursive_document",
    "recursive_estimate",
    "window_estimate",
]

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


def internal_error_document(method: str, error: BaseException) -> dict[str, Any]:
    """The invalid estimate published when computing one failed unexpectedly (the error is logged beside it)."""
    return invalid_document(method, Finding(code=FindingCode.INTERNAL_ERROR, values={"error": repr(error)}))


def outputs_from_document(document: dict[str, Any], stamp_ns: int, with_passive: bool) -> EstimateOutputs:
    """Serialise an estimate document (docs/contract.md schema) for ``bsp/estimate``, ``bsp/estimate_json``,
    ``bsp/<segment>/inertia`` and, when ``with_passive``, ``bsp/passive_moments``."""
    store = _typestore()

    def types(name: str) -> Any:
        return store.types[name]

    def cdr(msg: Any, type_name: str) -> bytes:
        return bytes(store.serialize_cdr(msg, type_name))

    out = {
        "estimate": cdr(
            build_diagnostic_array(types, diagnostics_from_estimate(document, stamp_ns)),
            "diagnostic_msgs/msg/DiagnosticArray",
        ),
        "json": cdr(types("std_msgs/msg/String")(data=json.dumps(document, allow_nan=False)), "std_msgs/msg/String"),
    }
    estimate = Estimate.from_json(document)
    valid = estimate.valid
    if valid:
        for segment, inertia in inertias_from_estimate(document, stamp_ns).items():
            out[f"inertia/{segment}"] = cdr(build_inertia_stamped(types, inertia), "geometry_msgs/msg/InertiaStamped")
        passive = passive_moments_from_estimate(document, stamp_ns)
        if passive is not None and with_passive:
            out["passive"] = cdr(build_joint_state(types, passive), "sensor_msgs/msg/JointState")
    quality = estimate.quality
    return EstimateOutputs(valid, quality.message, out, findings=quality.findings, support=support_inputs(estimate))


def outputs_from_estimate(estimate: ModeEstimate) -> EstimateOutputs:
    """Serialise one update's estimate of an identifier mode (:func:`outputs_from_document`)."""
    return outputs_from_document(estimate.document, estimate.stamp_ns, with_passive=estimate.with_passive)


def window_estimate(estimator: WindowEstimator, window: WindowSamples) -> EstimateOutputs:
    """The estimate of a window copied by ``WindowedIdentifier.snapshot``, stamped with its newest wrench;
    ``estimator`` keeps the model checks' schedule (one thread at a time)."""
    estimate = estimator.estimate_window(window)
    estimate.document["mode"] = "windowed"
    return outputs_from_document(estimate.document, estimate.last_wrench_t_ns or 0, with_passive=True)


def recursive_estimate(
    result: IdentificationResult,
    lengths_m: np.ndarray,
    options: IdentifyOptions,
    stamp_ns: int,
    contact_from_robot: bool = False,
) -> EstimateOutputs:
    """The estimate of a recursive filter state (its passive moments go out per sample, not here)."""
    document = recursive_document(result, lengths_m, options, contact_from_robot)
    document["mode"] = "recursive"
    return outputs_from_document(document, stamp_ns, with_passive=False)
