"""The simulated histories re-place every marker, shoulder to contact point, at the placement sd `bsp identify`
assumes, and the estimate sees the markers where they were put."""

from __future__ import annotations

import math
import random

import numpy as np

from bsp_ros.clinic.histories import PLACEMENT_SD_MM, Patient, session_estimate, skin_offsets_m
from bsp_ros.core.pipeline import IdentifyOptions


def _draws(placement_sd_mm: float, count: int = 4000) -> np.ndarray:
    """(count, 4, 2) offsets in mm, one session per row."""
    rng = random.Random(3)
    drawn = [
        skin_offsets_m(rng, placement_sd_mm=placement_sd_mm, skin_mm=3.0, distal_skin_mm=0.0) for _ in range(count)
    ]
    return 1e3 * np.asarray(drawn)


def test_the_placement_sd_is_the_one_identify_assumes() -> None:
    assert PLACEMENT_SD_MM == 1e3 * IdentifyOptions().marker_placement_sd_m == 2.0


def test_every_marker_is_re_placed_at_the_placement_sd() -> None:
    drawn = _draws(PLACEMENT_SD_MM)
    # Each of the 8 coordinates: mean 0 and sd 2 mm within 5 standard errors (0.1 mm and 0.11 mm at 4000 draws).
    assert np.all(np.abs(drawn.mean(axis=0)) < 0.16)
    assert np.all(np.abs(drawn.std(axis=0) - PLACEMENT_SD_MM) < 0.12)
    # Without it: the shoulder and elbow markers uniform within +-3 mm (sd 3 / sqrt 3), the wrist and hand exact.
    uniform = _draws(0.0)
    assert np.all(uniform[:, 2:] == 0.0) and np.abs(uniform[:, :2]).max() <= 3.0
    assert np.all(np.abs(uniform[:, :2].std(axis=0) - 3.0 / math.sqrt(3.0)) < 0.1)


def test_the_estimate_sees_the_hand_markers_where_they_were_put() -> None:
    """The hand's length is the distance of the wrist and hand markers, both fixed in the hand: re-placed, it is the
    true length plus the hand marker's offset along the hand less the wrist marker's (and their normal offsets'
    difference in quadrature)."""
    seed = 11
    exact = session_estimate(Patient(), 0, seed, skin_mm=0.0)
    moved = session_estimate(Patient(), 0, seed, placement_sd_mm=PLACEMENT_SD_MM)
    (_, _, wrist, hand) = skin_offsets_m(
        random.Random(seed), placement_sd_mm=PLACEMENT_SD_MM, skin_mm=0.0, distal_skin_mm=0.0
    )
    length_m = exact["segments"]["hand"]["length_m"]["value"]
    expected_m = math.hypot(length_m + hand[0] - wrist[0], hand[1] - wrist[1])
    assert abs(wrist[0] - hand[0]) > 1e-3  # the seed moves the two markers apart by more than the tolerance below
    assert abs(moved["segments"]["hand"]["length_m"]["value"] - expected_m) < 1e-4
