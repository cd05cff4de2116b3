"""bench/finding_kinds.py: the benches count invalid estimates and warnings by finding code and where, on simulated
sessions whose elbow is a known spring the default (Coulomb) model lacks.

The live node's settings (no elastic fallback) make such an estimate invalid; with the fallback it is valid and
names the spring. Two sessions with springs of different stiffness word their findings with different numbers and
still count as the same kinds.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest
from rosbags.typesys import Stores, get_typestore

from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.pipeline import IdentifyOptions, estimate_recordings
from bsp_ros.live.nodes.estimate_jobs import outputs_of

# The benchmarks are scripts, not a package: their directory is put on the path as they run it.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import bench_live_latency
import finding_kinds
import two_postures

NODE = IdentifyOptions(elastic_fallback=False)  # as bsp_identifier: a missing elastic moment is a verdict


def _spring_session(seed: int, elbow_nm_per_rad: float) -> sim.SimulatedSession:
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), stiffness_nm_per_rad=(0.0, elbow_nm_per_rad, 0.0), neutral_rad=(0.0, 1.8, 0.0)
    )
    return sim.simulate_cell(sim.human_arm_cell(seed=seed, passive=passive, duration_s=60.0))


@pytest.fixture(scope="module")
def springs() -> tuple[sim.SimulatedSession, sim.SimulatedSession]:
    return _spring_session(12, 1.2), _spring_session(13, 0.8)


def test_alike_findings_count_together_whatever_their_numbers(
    springs: tuple[sim.SimulatedSession, sim.SimulatedSession],
) -> None:
    stiff, soft = (estimate_recordings([s.session], NODE).to_json()["quality"] for s in springs)
    assert stiff["warnings"] != soft["warnings"]  # worded with each session's own numbers
    for quality in (stiff, soft):
        assert not quality["valid"]
        assert finding_kinds.cause_of(quality) == "elastic_lacking"
        kinds = finding_kinds.warning_kinds(quality)
        assert len(kinds) == len(quality["warnings"])
        # The spring is at the elbow, and only there.
        assert "elastic_term elbow" in kinds
        assert not {"elastic_term shoulder", "elastic_term wrist"} & set(kinds)


def test_a_valid_estimate_names_the_spring_among_its_warnings(
    springs: tuple[sim.SimulatedSession, sim.SimulatedSession],
) -> None:
    quality = estimate_recordings([springs[0].session], IdentifyOptions(elastic_fallback=True)).to_json()["quality"]
    assert quality["valid"]
    assert "elastic_term elbow" in finding_kinds.warning_kinds(quality)


def _on_the_wire(estimate: Estimate) -> str:
    """The ``bsp/estimate_json`` message's text as a subscriber reads it: the node's CDR, deserialised."""
    cdr = outputs_of(estimate, 1_700_000_000_000_000_000, with_passive=False).cdr["json"]
    message: Any = get_typestore(Stores.ROS2_JAZZY).deserialize_cdr(cdr, "std_msgs/msg/String")
    return str(message.data)


def test_the_live_latency_bench_counts_an_invalid_estimate_by_its_verdict(
    springs: tuple[sim.SimulatedSession, sim.SimulatedSession],
) -> None:
    session = springs[0].session
    assert bench_live_latency.invalid_cause(_on_the_wire(estimate_recordings([session], NODE))) == "elastic_lacking"
    fallen_back = estimate_recordings([session], IdentifyOptions(elastic_fallback=True))
    assert bench_live_latency.invalid_cause(_on_the_wire(fallen_back)) is None


def test_two_postures_tells_a_run_without_an_estimate(
    springs: tuple[sim.SimulatedSession, sim.SimulatedSession],
) -> None:
    document = json.loads(json.dumps(estimate_recordings([springs[1].session], NODE).to_json()))
    assert two_postures._cause(document) == "elastic_lacking"
    assert two_postures._cause({"quality": {"valid": False}}) == two_postures.NO_ESTIMATE  # bsp identify wrote none


def test_an_invalid_document_without_a_known_verdict_has_no_finding() -> None:
    newer = {"code": "a_code_of_a_newer_version", "severity": "invalid", "where": "", "text": "?", "values": {}}
    for quality in ({"valid": False}, {"valid": False, "findings": [newer]}):
        assert finding_kinds.cause_of(quality) == finding_kinds.NO_FINDING
        assert finding_kinds.warning_kinds(quality) == []
