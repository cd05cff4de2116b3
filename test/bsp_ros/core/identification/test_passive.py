"""Passive models: the live filter's one-sample row against the batch columns."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.identification.passive import PassiveModel


@pytest.mark.parametrize("label", ["coulomb", "coulomb+viscous", "coulomb+offset+stiffness"])
def test_one_sample_row_matches_the_batch_columns(label: str) -> None:
    model = PassiveModel.parse(label)
    q = np.array([[0.3, -0.2], [0.1, 0.0]])
    v = np.array([[0.05, -0.02], [0.0, 0.04]])
    for t in range(2):
        for joint in range(2):
            expected = model.columns(q, v, joint)[t]
            np.testing.assert_array_equal(model.row_one(float(q[t, joint]), float(v[t, joint])), expected)
