"""`bsp identify`'s uncertainty budget: each quantity's terms, what the options put in them, their sum."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from bsp_ros.cli import main


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("budget") / "session"
    assert main(["simulate", "--out", str(path), "--duration", "30", "--seed", "5"]) == 0
    return path


def _identify(bag: Path, out: Path, *options: str) -> dict:
    assert main(["identify", str(bag), "--json", str(out), "--format", "none", *options]) == 0
    return json.loads(out.read_text())


def _identified(document: dict) -> list[dict]:
    """The quantities the identification decided (static moments and passive parameters)."""
    static = [q["static_moment_kgm"] for q in document["segments"].values()]
    passive = [q for joint in document["joints"].values() for key, q in joint.items() if key == "coulomb_nm"]
    return static + passive


def test_each_std_is_the_root_of_its_budget_s_squares(bag: Path, tmp_path: Path) -> None:
    document = _identify(bag, tmp_path / "e.json")
    for q in _identified(document):
        assert math.fsum(u**2 for u in q["budget"].values()) == pytest.approx(q["std"] ** 2, rel=1e-9)
    upper = document["segments"]["upper_arm"]["static_moment_kgm"]["budget"]
    # Untared, with the assumed 2 mm placement: both are in the std, and they outweigh the sensor's noise.
    assert upper["sensor_zero"] > upper["sensor_noise"] and upper["marker_placement"] > upper["sensor_noise"]


def test_markers_on_the_centres_and_a_known_zero_leave_the_sensor_noise(bag: Path, tmp_path: Path) -> None:
    options = ("--marker-placement-sd-mm", "0", "--zero-sd-n", "0", "--zero-sd-nm", "0")
    document = _identify(bag, tmp_path / "exact.json", *options)
    assert document["session"]["config"]["marker_placement_sd_m"] == 0.0
    for q in _identified(document):
        assert set(q["budget"]) <= {"sensor_noise", "friction_shape"}, q["budget"]
    wide = _identify(bag, tmp_path / "wide.json")
    exact_std = document["segments"]["forearm"]["static_moment_kgm"]["std"]
    assert exact_std < 0.2 * wide["segments"]["forearm"]["static_moment_kgm"]["std"]
