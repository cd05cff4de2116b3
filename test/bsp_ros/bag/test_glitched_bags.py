"""Bags without chunk CRCs: plausibility checks are the damage detector; a lost /tf_static is never valid."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from bag_surgery import flip_bit_of_value, rewrite_without_crcs

from bsp_ros.bag import write_session_bag
from bsp_ros.bag.offline import identify_bag
from bsp_ros.core import glitches
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell


@pytest.fixture(scope="module")
def simulated() -> SimulatedSession:
    """40 s of the human arm cell (rotated sensor: roll 180, yaw 30 deg)."""
    return simulate_cell(human_arm_cell(duration_s=40.0, seed=8))


@pytest.fixture(scope="module")
def clean(simulated: SimulatedSession, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    bag = write_session_bag(tmp_path_factory.mktemp("clean") / "clean", simulated.session)
    return identify_bag(rewrite_without_crcs(bag))


def within_3_std(clean: dict[str, Any], glitched: dict[str, Any]) -> None:
    assert glitched["quality"]["valid"], glitched["quality"]["message"]
    for group in ("segments", "joints"):
        for owner, quantities in clean[group].items():
            for key, q in quantities.items():
                if q["source"] == "data":
                    got = glitched[group][owner][key]["value"]
                    assert abs(got - q["value"]) < 3 * q["std"], (owner, key, got, q)


def test_a_clean_bag_without_crcs_reports_no_implausible_samples(clean: dict[str, Any]) -> None:
    assert clean["quality"]["valid"]
    assert clean["bag"]["chunks_without_crc"] >= 1
    assert clean["bag"]["implausible_samples_removed"] == {}
    assert FindingCode.BAG_POSSIBLY_DAMAGED not in [f.code for f in findings_of(clean["quality"])]


def test_a_bit_flip_in_a_marker_coordinate_is_removed_and_reported(
    simulated: SimulatedSession, clean: dict[str, Any], tmp_path: Path
) -> None:
    bag = rewrite_without_crcs(write_session_bag(tmp_path / "flipped", simulated.session))
    y = float(simulated.session.markers["elbow"].position_m[800, 1])
    flipped = flip_bit_of_value(bag, "/mocap/elbow", 800, y, 52)  # lowest exponent bit: doubles or halves
    assert abs(flipped - y) > 0.05
    document = identify_bag(bag)
    within_3_std(clean, document)
    assert document["bag"]["implausible_samples_removed"] == {"marker_elbow": 1}
    assert document["bag"]["crc_errors"] == 0
    damage = [f for f in findings_of(document["quality"]) if f.code is FindingCode.BAG_POSSIBLY_DAMAGED]
    assert [list(pair) for f in damage for pair in f.values["implausible"]] == [["marker_elbow", 1]]
    assert document["quality"]["warnings"][0] == damage[0].text  # first: what to trust least


@pytest.mark.parametrize(
    ("name", "kind"),
    [("spikes", "wrench_spikes"), ("absurd", "wrench_absurd"), ("jump", "marker_hand"), ("swap", "marker_elbow")],
)
def test_glitches_in_a_bag_without_crcs_are_removed_and_counted(
    name: str, kind: str, simulated: SimulatedSession, clean: dict[str, Any], tmp_path: Path
) -> None:
    session = {
        "spikes": lambda s: glitches.wrench_spikes(s, 10, 1000.0, seed=4),
        "absurd": lambda s: glitches.set_wrench_sample(s, 500, 1e30, 1),
        "jump": lambda s: glitches.displace_marker(s, "hand", 600, (0.0, 0.06, 0.0)),
        "swap": lambda s: glitches.swap_markers(s, "elbow", "hand", 1200),
    }[name](simulated.session)
    document = identify_bag(rewrite_without_crcs(write_session_bag(tmp_path / name, session)))
    within_3_std(clean, document)
    # A spike in the first or last second (no joint angles there) is dropped before the count.
    expected = (8, 9, 10) if name == "spikes" else (1,)
    assert document["bag"]["implausible_samples_removed"].get(kind) in expected


def test_a_rotated_sensor_without_tf_static_is_invalid_and_names_the_transform(
    simulated: SimulatedSession, tmp_path: Path
) -> None:
    bag = rewrite_without_crcs(write_session_bag(tmp_path / "notf", simulated.session), drop_topics=("/tf_static",))
    document = identify_bag(bag)
    quality = document["quality"]
    assert document["bag"]["rotation_source"] == "assumed"
    assert not quality["valid"] and quality["level"] == "invalid"
    found = findings_of(quality)
    (assumed,) = [f for f in found if f.code is FindingCode.ROTATION_ASSUMED]
    assert assumed.values["frame"] == "ft_sensor"  # names the transform: world -> ft_sensor
    assert FindingCode.MODEL_MISFIT in [f.code for f in found], quality["message"]
    # The read's own note on the rotation comes as a finding too.
    assert FindingCode.BAG_NOTE in [f.code for f in findings_of(quality)]
