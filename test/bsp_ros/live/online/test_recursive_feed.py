"""The recursive mode's per-sample path: what it refuses and what it waits for."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.streams import joints_for
from bsp_ros.live.online.recursive_feed import RecursiveFeed

LENGTHS_M = np.array([0.3, 0.27, 0.08])


def test_names_the_joints_of_its_coulomb_terms() -> None:
    assert RecursiveFeed(3, PassiveModel.parse("coulomb")).passive_joints == joints_for(3)


def test_refuses_a_non_finite_wrench_and_a_repeated_stamp() -> None:
    feed = RecursiveFeed(3, PassiveModel.parse("coulomb"))
    assert feed.add_wrench(1_000_000, np.array([np.nan, 1.0, 0.1]), LENGTHS_M) == (False, None)
    assert feed.add_wrench(2_000_000, np.array([0.0, -5.0, 0.1]), LENGTHS_M)[0]
    assert feed.add_wrench(2_000_000, np.array([0.0, -5.0, 0.1]), LENGTHS_M) == (False, None)


def test_takes_a_wrench_but_does_not_update_without_lengths_or_angles_near_it() -> None:
    feed = RecursiveFeed(3, PassiveModel.parse("coulomb"))
    assert feed.add_wrench(1_000_000, np.array([0.0, -5.0, 0.1]), None) == (True, None)
    feed.add_joint_state(0, np.array([-0.3, 0.5, 0.1]), np.array([0.1, 0.1, 0.1]))
    assert feed.add_wrench(900_000_000, np.array([0.0, -5.0, 0.1]), LENGTHS_M) == (True, None)  # 0.9 s away
