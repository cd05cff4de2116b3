"""The clinic's simulated history, built once per test session."""

from __future__ import annotations

import pytest
from clinic_history import History, build_history


@pytest.fixture(scope="session")
def history(tmp_path_factory: pytest.TempPathFactory) -> History:
    """See :mod:`clinic_history`."""
    return build_history(tmp_path_factory.mktemp("clinic") / "clinic.sqlite")
