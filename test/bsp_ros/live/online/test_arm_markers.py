"""The arm's markers against a noise-free simulated session: the joint spheres sit on the simulated markers, each
COM where the truth puts it with a sphere by its mass, the std shell and range around it, the support as an arrow,
and the segment frames along the segments."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.live.online.arm_markers import (
    COM_DIAMETER_M_PER_CBRT_KG,
    SUPPORT_M_PER_N,
    MarkerKind,
    MarkerSpec,
    arm_markers,
    segment_frames,
)
from msg_adapters.rotation import matrix_from_quaternion

SEGMENTS = ("upper_arm", "forearm", "hand")
MARKERS = ("shoulder", "elbow", "wrist", "hand")


@pytest.fixture(scope="module")
def frame(without_noise: Any) -> tuple[np.ndarray, dict[str, Any]]:
    """(4, 3) the shoulder, elbow, wrist and hand markers of one frame of a noise-free session, and its truth."""
    simulated = sim.simulate_cell(without_noise(sim.human_arm_cell(seed=3, duration_s=10.0)))
    markers = simulated.session.markers
    k = len(markers["shoulder"].t_ns) // 2
    return np.array([markers[name].position_m[k] for name in MARKERS]), simulated.truth.to_dict()


def _angles_and_lengths(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles and lengths from marker positions, by hand (contract section 1: angles in the y-z plane)."""
    steps = np.diff(points[:, 1:], axis=0)
    phi = np.arctan2(steps[:, 1], steps[:, 0])
    return np.concatenate(([phi[0]], np.diff(phi))), np.hypot(steps[:, 0], steps[:, 1])


def _truth_estimate(truth: dict[str, Any], valid: bool = True) -> Estimate:
    segments = {
        s: {
            "mass_kg": {"value": truth["segments"][s]["mass_kg"], "std": 0.1, "source": "data+prior"},
            "com_m": {"value": truth["segments"][s]["com_m"], "std": 0.02, "source": "data+prior"},
        }
        for s in SEGMENTS
    }
    return Estimate.from_json({"method": "joint", "segments": segments, "joints": {}, "quality": {"valid": valid}})


def _one(specs: list[MarkerSpec], ns: str, marker_id: int = 0) -> MarkerSpec:
    found = [s for s in specs if s.ns == ns and s.id == marker_id]
    assert len(found) == 1, (ns, marker_id)
    return found[0]


def test_the_joint_spheres_and_the_segment_line_sit_on_the_simulated_markers(frame: Any) -> None:
    points, _ = frame
    q, lengths = _angles_and_lengths(points)
    specs = arm_markers(q, lengths, points[0], None)
    for k in range(4):
        joint = _one(specs, "joints", k)
        assert joint.kind is MarkerKind.SPHERE
        np.testing.assert_allclose(joint.position_m[1:], points[k, 1:], atol=1e-9)
        assert joint.position_m[0] == pytest.approx(points[0, 0])
    line = _one(specs, "segments")
    np.testing.assert_allclose(np.array(line.points_m)[:, 1:], points[:, 1:], atol=1e-9)
    assert {s.ns for s in specs} == {"segments", "joints", "verdict"}  # nothing of an estimate before one
    assert _one(specs, "verdict").text == "waiting for an estimate"


def test_each_com_sits_where_the_truth_puts_it_sized_by_its_mass_with_its_std(frame: Any) -> None:
    points, truth = frame
    q, lengths = _angles_and_lengths(points)
    specs = arm_markers(q, lengths, points[0], _truth_estimate(truth), precision_reached=True)
    for j, segment in enumerate(SEGMENTS):
        mass, com = truth["segments"][segment]["mass_kg"], truth["segments"][segment]["com_m"]
        unit = (points[j + 1] - points[j]) / np.linalg.norm(points[j + 1, 1:] - points[j, 1:])
        unit[0] = 0.0
        expected = points[j] + com * unit
        sphere, shell, line = _one(specs, "com", j), _one(specs, "com_std", j), _one(specs, "com_range", j)
        np.testing.assert_allclose(sphere.position_m[1:], expected[1:], atol=1e-9)
        assert sphere.scale[0] == pytest.approx(COM_DIAMETER_M_PER_CBRT_KG * mass ** (1 / 3))
        assert shell.scale[0] == pytest.approx(COM_DIAMETER_M_PER_CBRT_KG * (mass + 0.1) ** (1 / 3))
        assert shell.rgba[3] < 1.0 and sphere.rgba[3] == 1.0 and shell.position_m == sphere.position_m
        ends = np.array(line.points_m)
        np.testing.assert_allclose(np.linalg.norm(ends - expected, axis=1), [0.02, 0.02], atol=1e-9)
    masses = [truth["segments"][s]["mass_kg"] for s in SEGMENTS]
    diameters = [_one(specs, "com", j).scale[0] for j in range(3)]
    assert np.argsort(masses).tolist() == np.argsort(diameters).tolist()  # the heavier segment, the larger sphere
    assert _one(specs, "verdict").text == "VALID, precision reached"
    invalid = arm_markers(q, lengths, points[0], _truth_estimate(truth, valid=False))
    assert _one(invalid, "com", 0).rgba != _one(specs, "com", 0).rgba


def test_the_support_is_an_arrow_at_the_contact_point_along_its_force(frame: Any) -> None:
    points, _ = frame
    q, lengths = _angles_and_lengths(points)
    arrow = _one(arm_markers(q, lengths, points[0], None, support_yzx=(3.0, 20.0, 0.1)), "support")
    start, end = np.array(arrow.points_m)
    np.testing.assert_allclose(start[1:], points[-1, 1:], atol=1e-9)
    np.testing.assert_allclose(end - start, SUPPORT_M_PER_N * np.array([0.0, 3.0, 20.0]), atol=1e-12)
    assert arrow.kind is MarkerKind.ARROW


def test_each_segment_frame_starts_at_its_proximal_joint_with_y_along_the_segment(frame: Any) -> None:
    points, _ = frame
    q, lengths = _angles_and_lengths(points)
    frames = segment_frames(q, lengths, points[0])
    assert [f.segment for f in frames] == list(SEGMENTS)
    for j, f in enumerate(frames):
        np.testing.assert_allclose(f.origin_m[1:], points[j, 1:], atol=1e-9)
        rotation = matrix_from_quaternion(np.array(f.rotation_xyzw))
        direction = points[j + 1] - points[j]
        direction[0] = 0.0
        np.testing.assert_allclose(rotation @ [0.0, 1.0, 0.0], direction / np.linalg.norm(direction), atol=1e-9)
        np.testing.assert_allclose(rotation @ [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], atol=1e-12)
        assert math.isclose(float(np.linalg.norm(f.rotation_xyzw)), 1.0)
