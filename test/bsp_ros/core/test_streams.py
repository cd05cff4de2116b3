"""The streams' shared frames: common_frames against numpy's intersect1d."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.streams import common_frames


def _cases(rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    grid = np.arange(0, 2_000_000_000, 20_000_000, dtype=np.int64)
    occluded = grid[rng.random(grid.size) > 0.1]
    return [
        (grid, grid.copy()),  # one capture system: every frame shared
        (grid, occluded),  # one marker occluded at times
        (occluded, grid),
        (grid, grid + 1),  # no frame shared
        (grid[:50], grid[50:]),
        (grid, grid[:0]),
    ]


@pytest.mark.parametrize("case", range(6))
def test_common_frames_equal_intersect1d(case: int) -> None:
    t_a, t_b = _cases(np.random.default_rng(3))[case]
    expected = np.intersect1d(t_a, t_b, assume_unique=True, return_indices=True)
    got = common_frames(t_a, t_b)
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_array_equal(g, e)
        assert g.dtype == e.dtype


def test_common_frames_repeated_stamps_take_the_first() -> None:
    # A recorded stream may repeat a stamp: equal arrays that are not strictly increasing take intersect1d's path.
    t = np.array([0, 10, 10, 20, 30], dtype=np.int64)
    common, i_a, i_b = common_frames(t, t.copy(), assume_unique=False)
    np.testing.assert_array_equal(common, [0, 10, 20, 30])
    np.testing.assert_array_equal(i_a, [0, 1, 3, 4])
    np.testing.assert_array_equal(i_b, [0, 1, 3, 4])
