"""The live estimate carries what holds of its wrench frame's rotation as a typed finding: the cell's mounting standing
in for a transform that never came (a note), a transform more than 1 deg off the mounting (weak, the transform used).
Fed a simulated session through the node's frame logic, the estimate stays valid and holds the truth within 3 std."""

from __future__ import annotations

import json
from functools import partial

import numpy as np
import pytest

from bsp_ros.core.findings import Finding, FindingCode, Severity, findings_of
from bsp_ros.core.simulation import rotation_from_rpy_deg
from bsp_ros.live.online.frame_notices import FrameNotices
from bsp_ros.live.online.frames import WrenchFrames
from bsp_ros.live.online.identifier_modes import ModeEstimate
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.live_identifier import LiveIdentifier
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample
from msg_adapters.wrench import WrenchSample

FRAME = "ft_sensor"
MOUNT = rotation_from_rpy_deg(180.0, 0.0, 30.0)  # the sensor's real mounting
STATED = "wrench_frame_rotation_xyzw (cell file cell.yaml: ft_sensor.rotation_xyzw)"
SOURCE = "topic /ft_sensor/transform (TransformStamped)"


def _identifier(frames: WrenchFrames) -> LiveIdentifier[ModeEstimate]:
    notices = FrameNotices(SOURCE, STATED)
    settings = IdentifierSettings.from_parameters({"window_s": 20.0})
    return LiveIdentifier(settings, lambda estimate: estimate, pytest.fail, partial(notices.findings, frames))


def _feed(identifier: LiveIdentifier, frames: WrenchFrames, streams, until_s: float) -> int:
    """The first ``until_s`` of ``streams`` as the node hands them: each wrench in the sensor's axes (mounted at
    :data:`MOUNT`) with the rotation ``frames`` gives at its stamp; returns the newest stamp, ns."""
    _, stamps, wrench, _, raw = streams
    end = int(stamps[0]) + int(until_s * 1e9)
    identifier.add_lengths(raw[0][2])
    w = 0
    for t_ns, q_rad, _ in raw:
        if t_ns > end:
            break
        while w < len(stamps) and stamps[w] <= t_ns:
            f_y, f_z, m_x = wrench[w]
            force, torque = MOUNT.T @ np.array([0.0, f_y, f_z]), MOUNT.T @ np.array([m_x, 0.0, 0.0])
            identifier.received("wrench", t_ns)
            rotation = frames.rotation_for(FRAME, t_ns, int(stamps[w]))
            identifier.add_wrench(WrenchSample(int(stamps[w]), FRAME, force, torque), rotation)
            w += 1
        identifier.add_raw_angles(t_ns, q_rad, t_ns)
    return int(stamps[w - 1])


def _estimate(identifier: LiveIdentifier, now_ns: int) -> dict:
    document = json.loads(json.dumps(identifier.update(now_ns).estimate.to_json(), allow_nan=False))
    assert document["quality"]["valid"], document["quality"]["message"]
    return document


def _assert_truth_within_3_std(document: dict, streams) -> None:
    truth = streams[0].truth.static_moments_kgm
    for segment, beta in zip(("upper_arm", "forearm", "hand"), truth, strict=True):
        q = document["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - beta) < 3 * q["std"], (segment, q, beta)


def _only(document: dict, code: FindingCode) -> Finding:
    found = [f for f in findings_of(document["quality"]) if f.code in KINDS]
    assert [f.code for f in found] == [code], found
    return found[0]


KINDS = (FindingCode.ROTATION_FROM_MOUNTING, FindingCode.ROTATION_DISAGREES)


def _static_moments(document: dict) -> dict[str, float]:
    return {s: q["static_moment_kgm"]["value"] for s, q in document["segments"].items()}


@pytest.fixture(scope="module")
def agreeing(live_streams) -> dict:
    """The estimate of a transform that agrees with the stated mounting: what the transform alone gives."""
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=MOUNT, tf_wait_s=2.0)
    frames.on_transforms([TransformSample(1, "world", FRAME, np.zeros(3), quaternion_from_matrix(MOUNT))], static=True)
    identifier = _identifier(frames)
    waiting = identifier.update(0).estimate  # an invalid estimate before any input: no frame finding either
    assert [f.code for f in waiting.quality.findings] == [FindingCode.INPUT_WAITING]
    return _estimate(identifier, _feed(identifier, frames, live_streams, 25.0))


def test_the_mounting_that_stood_in_for_a_missing_transform_is_a_note_of_the_estimate(live_streams) -> None:
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=MOUNT, tf_wait_s=2.0)
    identifier = _identifier(frames)
    now = _feed(identifier, frames, live_streams, 25.0)
    assert identifier.counters()["waiting_for_tf"] > 0  # the wrenches of the first 2 s waited for a transform
    document = _estimate(identifier, now)
    finding = _only(document, FindingCode.ROTATION_FROM_MOUNTING)
    assert finding.severity is Severity.NOTE
    assert finding.values["frame"] == FRAME and finding.values["tf_wait_s"] == 2.0
    np.testing.assert_allclose(finding.values["rotation_xyzw"], quaternion_from_matrix(MOUNT), atol=1e-6)
    assert finding.text in document["quality"]["warnings"]  # said where a reader of the estimate looks
    np.testing.assert_array_equal(frames.rotations[FRAME], MOUNT)
    _assert_truth_within_3_std(document, live_streams)


def test_a_transform_off_the_stated_mounting_is_used_and_a_weak_finding_of_the_estimate(
    live_streams, agreeing: dict
) -> None:
    stated = MOUNT @ rotation_from_rpy_deg(0.0, 0.0, 10.0)  # the cell file says otherwise, by 10 deg
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=stated, tf_wait_s=2.0)
    sample = TransformSample(1, "world", FRAME, np.zeros(3), quaternion_from_matrix(MOUNT))
    frames.on_transforms([sample], static=True)
    identifier = _identifier(frames)
    document = _estimate(identifier, _feed(identifier, frames, live_streams, 25.0))
    finding = _only(document, FindingCode.ROTATION_DISAGREES)
    assert finding.severity is Severity.WEAK
    assert finding.values["angle_deg"] == pytest.approx(10.0, abs=1e-6) and finding.values["limit_deg"] == 1.0
    np.testing.assert_allclose(finding.values["received_xyzw"], quaternion_from_matrix(MOUNT), atol=1e-6)
    assert "ft_sensor.rotation_xyzw" in finding.text and finding.text in document["quality"]["warnings"]
    # The transform, not the stated mounting, was applied: the same numbers as where the two agree.
    assert _static_moments(document) == pytest.approx(_static_moments(agreeing), rel=1e-12)
    _assert_truth_within_3_std(document, live_streams)


def test_a_transform_that_agrees_with_the_mounting_adds_nothing(live_streams, agreeing: dict) -> None:
    assert not [f for f in findings_of(agreeing["quality"]) if f.code in KINDS]
    _assert_truth_within_3_std(agreeing, live_streams)
