"""Shared fixtures: simulated sessions with known truth (seeded)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim


def noise_free(spec: sim.CellSpec) -> sim.CellSpec:
    """The same cell with every noise source, bias and dropout switched off."""
    sensor = dataclasses.replace(
        spec.sensor,
        force_noise_n=0.0,
        torque_noise_nm=0.0,
        stamp_jitter_s=0.0,
    )
    markers = dataclasses.replace(spec.markers, noise_m=0.0, dropout_fraction=0.0)
    return dataclasses.replace(spec, sensor=sensor, markers=markers)


@pytest.fixture(scope="session")
def without_noise():
    """The :func:`noise_free` transformation, for tests that build their own cells."""
    return noise_free


@pytest.fixture(scope="session")
def human_session() -> sim.SimulatedSession:
    """120 s of a 3-segment arm drawn from the anthropometric prior, paper-like noise."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(7))
    return sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=7))


@pytest.fixture(scope="session")
def human_session_noise_free() -> sim.SimulatedSession:
    """120 s of the table-mean 3-segment arm with no noise at all."""
    return sim.simulate_cell(noise_free(sim.human_arm_cell(seed=1)))


@pytest.fixture(scope="session")
def paper_arm_session() -> sim.SimulatedSession:
    """120 s of the method paper's 2-segment mechanical arm (Table 1), paper-like noise."""
    return sim.simulate_cell(sim.paper_mechanical_arm_cell(seed=3))
