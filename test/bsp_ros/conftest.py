"""Fixtures of the live tests: a fresh ROS domain id per test (conftest.py puts this directory on sys.path)."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from ros_domains import next_domain_id


@pytest.fixture
def ros_domain() -> int:
    """A fresh ROS domain id for one test (a killed node lingers in discovery until its lease ends)."""
    return next_domain_id()


@pytest.fixture
def ros_domains() -> Callable[[], int]:
    """A function giving a fresh ROS domain id at each call (tests running several cells)."""
    return next_domain_id
