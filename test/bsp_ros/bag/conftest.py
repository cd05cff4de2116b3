"""Fixtures of the bag tests: small simulated sessions and bags written into tmp_path."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bsp_ros.bag import write_session_bag
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, paper_mechanical_arm_cell, simulate_cell


@pytest.fixture(scope="session")
def human_session() -> SimulatedSession:
    """20 s of the default human arm cell (3 segments)."""
    return simulate_cell(human_arm_cell(duration_s=20.0, seed=4))


@pytest.fixture(scope="session")
def paper_session() -> SimulatedSession:
    """10 s of the paper's 2-segment mechanical arm."""
    return simulate_cell(paper_mechanical_arm_cell(duration_s=10.0, seed=5))


@pytest.fixture
def write_bag(tmp_path: Path) -> Callable[..., Path]:
    """Write a session as a bag under tmp_path and return its directory."""
    counter = iter(range(1000))

    def write(simulated: SimulatedSession, **kwargs: object) -> Path:
        out = tmp_path / f"bag{next(counter)}"
        return write_session_bag(out, simulated.session, simulated.truth.to_dict(), **kwargs)  # type: ignore[arg-type]

    return write
