"""The estimate's typed blocks (tare, timing, rotation, marker placement, bag): real documents' blocks written back
exactly, and typed reads that give a simulated session's known delay and tare."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.estimate_blocks import (
    BagSection,
    DelayBlock,
    DelaySource,
    RotationBlock,
    SensorZero,
    TareBlock,
    TimingBlock,
)
from bsp_ros.core.estimate_schema import Estimate, Level, Quality
from bsp_ros.core.methods import Method
from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings, identify_session
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.core.simulation import SensorSpec, TareSpec, human_arm_cell, simulate_cell, simulate_tare, tare_rotations
from bsp_ros.core.simulation.cell import DEFAULT_START_NS
from bsp_ros.core.tare import estimate_tare

SAMPLES = Path(__file__).resolve().parents[3] / "bags"
QUALITY_BLOCKS = ("tare", "timing", "rotation", "marker_placement")


@pytest.fixture(scope="module", params=["human_arm_60s", "human_arm_occluded_60s", "paper_arm_60s"])
def document(request: pytest.FixtureRequest) -> dict:
    """The estimate of a sample bag, as JSON carries it."""
    return json.loads(json.dumps(identify_bag(SAMPLES / request.param)))


def test_every_block_of_a_real_document_is_typed_and_written_back_exactly(document: dict) -> None:
    estimate = Estimate.from_json(document)
    assert json.dumps(estimate.to_json()) == json.dumps(document)
    quality = estimate.quality
    for key in QUALITY_BLOCKS:
        block = getattr(quality, key)
        assert block is not None and key not in quality.extra, key
        assert json.dumps(block.to_json()) == json.dumps(document["quality"][key]), key
    assert estimate.bag is not None and "bag" not in estimate.extra and estimate.bags is None
    assert json.dumps(estimate.bag.to_json()) == json.dumps(document["bag"])
    # The typed values are the document's.
    assert estimate.bag.messages == document["bag"]["messages"] and estimate.bag.files == tuple(
        document["bag"]["files"]
    )
    assert quality.rotation is not None and quality.rotation.sources == (estimate.bag.rotation_source,) == ("tf",)
    assert not quality.rotation.per_sample and quality.rotation.range_deg == 0.0
    assert quality.tare is not None and not quality.tare.applied and quality.tare_file is None
    assert quality.tare.zero_sd == SensorZero(force_n=ZERO_SD_N, moment_nm=ZERO_SD_NM)  # the defaults assumed
    assert list(quality.tare.std_added or {}) == document["diagnostics"]["parameters"]
    placement = quality.marker_placement
    assert placement is not None and placement.assumed_sd_mm == (2.0,) * (len(estimate.segments) + 1)
    assert placement.scale_from_data >= 1.0 and all(
        sd == pytest.approx(a * placement.scale_from_data, rel=1e-3)
        for sd, a in zip(placement.sd_mm, placement.assumed_sd_mm, strict=True)
    )


def test_a_block_of_another_shape_stays_untyped_and_is_written_back_as_it_was(document: dict) -> None:
    odd = json.loads(json.dumps(document))
    odd["quality"]["tare"] = {"applied": "yes"}  # by hand
    odd["quality"]["timing"]["wrench_delay_s"] = 0  # an integer: the typed form would write 0.0
    odd["quality"]["rotation"]["from_a_newer_version"] = 1
    odd["bag"]["lost_messages"] = "unknown"
    estimate = Estimate.from_json(odd)
    quality = estimate.quality
    assert quality.tare is None and quality.timing is None and quality.rotation is None and estimate.bag is None
    assert quality.marker_placement is not None  # the others are typed still
    assert quality.extra["tare"] == {"applied": "yes"} and not quality.tare_applied
    assert json.dumps(estimate.to_json()) == json.dumps(odd)


def test_the_blocks_keep_the_order_they_were_set_in_and_a_replaced_one_its_place() -> None:
    delay = TimingBlock(
        recordings=(DelayBlock(wrench_delay_s=0.01, wrench_delay_std_s=0.0, source=DelaySource.PARAMETER),)
    )
    tare = TareBlock(applied=False, file=None, zero_sd=SensorZero(force_n=1.0, moment_nm=0.02))
    rotation = RotationBlock(sources=("session",), per_sample=False, range_deg=0.0)
    # The live window's order: the timing first, then the tare and the sensitivity.
    quality = Quality(valid=True, level=Level.OK, message="ok", extra={"removed_samples": {}})
    quality = quality.with_timing(delay).with_tare(tare).with_extra({"offset_sensitivity": {}}).with_rotation(rotation)
    quality = quality.with_rotation(rotation.with_source("tf", appended=False))
    keys = list(quality.to_json())[8:]
    assert keys == ["removed_samples", "timing", "tare", "offset_sensitivity", "rotation"]
    assert quality.to_json()["rotation"]["source"] == "tf"
    again = Quality.from_json(json.loads(json.dumps(quality.to_json())))
    assert again == quality and json.dumps(again.to_json()) == json.dumps(quality.to_json())
    with pytest.raises(ValueError, match="typed blocks"):
        quality.with_extra({"tare": tare.to_json()})


def test_several_recordings_have_a_timing_each_and_a_bag_section_each() -> None:
    first = simulate_cell(human_arm_cell(duration_s=30.0, seed=21)).session
    later = simulate_cell(human_arm_cell(duration_s=30.0, seed=22, start_ns=DEFAULT_START_NS + 60 * 10**9)).session
    document = json.loads(json.dumps(identify_recordings([first, later], IdentifyOptions(wrench_delay_s=0.002))))
    estimate = Estimate.from_json(document)
    timing = estimate.quality.timing
    assert timing is not None and len(timing.recordings) == 2 and "recordings" in document["quality"]["timing"]
    assert all(r.source is DelaySource.PARAMETER and r.wrench_delay_s == 0.002 for r in timing.recordings)
    assert json.dumps(estimate.to_json()) == json.dumps(document)
    section = BagSection(
        files=("a_0.mcap",),
        messages={"/ft_sensor/wrench": 3},
        lost_messages=None,
        crc_errors=0,
        truncated=False,
        chunks_without_crc=0,
        rotation_source="tf",
        damage=(),
        implausible_samples_removed={},
    )
    both = estimate.with_bag(section, recording=0).with_bag(
        dataclasses.replace(section, files=("b_0.mcap",)), recording=1
    )
    written = json.loads(json.dumps(both.to_json()))
    assert [b["files"] for b in written["bags"]] == [["a_0.mcap"], ["b_0.mcap"]] and "bag" not in written
    assert Estimate.from_json(written).bags == both.bags and list(written)[-1] == "bags"


def test_the_typed_timing_reads_a_simulated_sessions_known_delay() -> None:
    clock_offset_s = 0.03  # the wrench clock 30 ms late
    session = simulate_cell(human_arm_cell(duration_s=40.0, seed=23, sensor=SensorSpec(clock_offset_s=clock_offset_s)))
    estimated = Estimate.from_json(identify_session(session.session, IdentifyOptions(marker_placement_sd_m=0.0)))
    assert estimated.quality.timing is not None
    delay = estimated.quality.timing.delay
    assert delay.source is DelaySource.ESTIMATED and delay.estimated_delay_s == delay.wrench_delay_s
    assert abs(delay.wrench_delay_s - clock_offset_s) < 3.0 * delay.wrench_delay_std_s < 0.02
    given = Estimate.from_json(identify_session(session.session, IdentifyOptions(wrench_delay_s=clock_offset_s)))
    assert given.quality.timing == TimingBlock(
        recordings=(DelayBlock(wrench_delay_s=clock_offset_s, wrench_delay_std_s=0.0, source=DelaySource.PARAMETER),)
    )


def test_the_typed_tare_reads_a_simulated_sessions_known_tare() -> None:
    sensor = SensorSpec(force_bias_n=(3.0, -1.0, 2.0), torque_bias_nm=(0.1, 0.05, -0.02), handle_mass_kg=0.3)
    cell = human_arm_cell(duration_s=40.0, seed=24, sensor=sensor)
    swing = TareSpec(duration_s=20.0, swing_rpy_deg=(20.0, 20.0, 0.0))
    recording = simulate_tare(cell, swing)
    rotations = tare_rotations(cell, swing, (recording.wrench.t_ns - cell.start_ns) * 1e-9 - swing.start_offset_s)
    w = recording.wrench
    tare = estimate_tare(w.t_ns, w.force_n, w.torque_nm, "ft_sensor", rotations, source="tare_rec")
    simulated = simulate_cell(cell)
    estimate = Estimate.from_json(identify_session(simulated.session, IdentifyOptions(tare=tare)))
    typed = estimate.quality.tare
    assert typed is not None and typed.applied and typed.file == "tare_rec" and typed.zero_sd is None
    assert estimate.quality.tare_applied and estimate.quality.tare_file == "tare_rec"
    added = typed.std_added or {}
    assert all(added[f"static_moment_kgm/{s}"] > 0.0 for s in ("upper_arm", "forearm", "hand"))
    # The tared estimate finds the simulated arm: the offsets and the handle are gone from it.
    assert estimate.valid
    for segment, beta in zip(("upper_arm", "forearm", "hand"), simulated.truth.static_moments_kgm, strict=True):
        q = estimate.quantity("static_moment_kgm", segment)
        assert q is not None and q.value is not None and q.std is not None
        assert abs(q.value - beta) < 3.0 * q.std, (segment, q.value, beta, q.std)
    assert np.isfinite(typed.to_json()["std_added"]["static_moment_kgm/hand"])


def test_an_invalid_live_estimate_has_no_blocks() -> None:
    from bsp_ros.core.findings import Finding, FindingCode

    invalid = Estimate.invalid(Method.JOINT, Finding(code=FindingCode.INPUT_WAITING, values={"what": "wrench"}))
    assert invalid.quality.tare is None and invalid.quality.timing is None and invalid.bag is None
    assert Estimate.from_json(invalid.to_json()) == invalid
