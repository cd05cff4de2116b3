"""The identifier's worker-process outputs: serialised messages that decode back to the estimate."""

from __future__ import annotations

import json

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.recursive import RecursiveIdentifier
from bsp_ros.core.methods import LiveMode, Method
from bsp_ros.core.model import gravity_regressor
from bsp_ros.core.pipeline import IdentifyOptions, recursive_estimate
from bsp_ros.live.nodes import estimate_jobs as jobs
from bsp_ros.live.nodes.estimate_jobs import _typestore as typestore
from bsp_ros.live.online.identifier_modes import ModeEstimate
from msg_adapters.diagnostics import read_diagnostic_array


def _valid_recursive_result():
    rng = np.random.default_rng(5)
    beta = np.array([0.8, 0.3, 0.05])
    identifier = RecursiveIdentifier(3)
    for k in range(30_000):
        phase = np.array([1.0, 1.3, 1.7]) * k / 1000
        q, v = np.array([0.3, 0.6, 0.2]) + 0.2 * np.sin(phase), 0.2 * np.cos(phase)
        tau = gravity_regressor(q[None])[0] @ beta + 0.3 * np.sign(v) + rng.normal(0, 0.01, 3)
        identifier.update(k * 1_000_000, q, v, tau)
    result = identifier.result()
    assert result.valid, result.message
    return result


def test_recursive_outputs_decode_to_the_same_estimate() -> None:
    store = typestore()
    # As RecursiveMode's update hands it over: the filter's estimate with its mode, its passive moments not in it.
    estimate = recursive_estimate(_valid_recursive_result(), np.array([0.3, 0.27, 0.08]), IdentifyOptions())
    outputs = jobs.outputs_from_estimate(ModeEstimate(estimate.with_mode(LiveMode.RECURSIVE), 42, with_passive=False))
    assert outputs.valid and set(outputs.cdr) == {
        "estimate",
        "json",
        *(f"inertia/{s}" for s in ("upper_arm", "forearm", "hand")),
    }
    document = json.loads(store.deserialize_cdr(outputs.cdr["json"], "std_msgs/msg/String").data)
    assert document["mode"] == "recursive" and document["method"] == "recursive" and document["quality"]["valid"]
    assert Estimate.from_json(document).mode is LiveMode.RECURSIVE
    assert abs(document["segments"]["upper_arm"]["static_moment_kgm"]["value"] - 0.8) < 0.01
    array = read_diagnostic_array(store.deserialize_cdr(outputs.cdr["estimate"], "diagnostic_msgs/msg/DiagnosticArray"))
    assert array.t_ns == 42 and any(s.name.endswith("/quality") for s in array.status)
    inertia = store.deserialize_cdr(outputs.cdr["inertia/hand"], "geometry_msgs/msg/InertiaStamped")
    assert inertia.inertia.m == document["segments"]["hand"]["mass_kg"]["value"]


def test_an_invalid_estimate_has_no_inertia_or_passive_outputs() -> None:
    stale = Finding(code=FindingCode.INPUT_STALE, values={"what": "wrench", "silent_s": 0.5})
    outputs = jobs.outputs_of(Estimate.invalid(Method.JOINT, stale), 7, with_passive=True)
    assert not outputs.valid and outputs.message == stale.text and set(outputs.cdr) == {"estimate", "json"}
    assert [f.code for f in outputs.findings] == [FindingCode.INPUT_STALE]


def test_a_recursive_estimate_with_the_robot_contact_point_holds_the_robot_placement_sd() -> None:
    result, lengths = _valid_recursive_result(), np.array([0.3, 0.27, 0.08])
    by_marker = recursive_estimate(result, lengths, IdentifyOptions()).to_json()
    by_robot = recursive_estimate(result, lengths, IdentifyOptions(), contact_from_robot=True).to_json()
    assert by_marker["quality"]["contact_point"] == "hand_marker"
    assert by_robot["quality"]["contact_point"] == "robot_handle_pose"
    # The hand's length spans the wrist marker (2 mm) and the contact point: 2 mm by marker, 0.5 mm by the robot.
    hand_std = [d["segments"]["hand"]["length_m"]["std"] for d in (by_marker, by_robot)]
    np.testing.assert_allclose(hand_std, [np.hypot(0.002, 0.002), np.hypot(0.002, 0.0005)], rtol=0.05)
    forearm = [d["segments"]["forearm"]["length_m"]["std"] for d in (by_marker, by_robot)]
    assert forearm[0] == forearm[1]
