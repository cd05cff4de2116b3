"""A simulated session fed through the causal angle estimator, as the live nodes would see it."""

from __future__ import annotations

import dataclasses

import pytest
from live_inputs import live_inputs

from bsp_ros.core import simulation as sim


@pytest.fixture(scope="session")
def live_streams():
    """(simulated session, wrench stamps, world wrench (N,3), causal angle samples stamped by group delay,
    unfiltered angles (t_ns, q_rad, lengths_m) per accepted frame)."""
    return live_inputs(sim.human_arm_cell(seed=13, duration_s=60.0))


@pytest.fixture(scope="session")
def elastic_live_streams():
    """:func:`live_streams` of an arm with an elastic passive offset of 0.2 Nm at every joint."""
    spec = sim.human_arm_cell(seed=14, duration_s=60.0)
    passive = dataclasses.replace(spec.passive, offset_nm=(0.2, 0.2, 0.2))
    return live_inputs(dataclasses.replace(spec, passive=passive))
