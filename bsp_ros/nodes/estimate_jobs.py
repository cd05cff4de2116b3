"""The estimates `bsp_identifier` computes in its worker process (module-level, so they pickle by name)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from bsp_ros.estimate import estimate_document
from bsp_ros.identification.data import IdentificationData
from bsp_ros.identification.result import IdentificationResult
from bsp_ros.online.windowed import WindowConfig, WindowedIdentifier, WindowSamples
from bsp_ros.pipeline import IdentifyOptions, fuse

_windowed: WindowedIdentifier | None = None  # the child's own: it keeps the elastic-check schedule


def init_worker(n_segments: int, config: WindowConfig, niceness: int = 0) -> None:
    """Set up the worker process; ``niceness`` lowers its scheduling priority (``os.nice``)."""
    global _windowed
    if niceness:
        os.nice(niceness)
    _windowed = WindowedIdentifier(n_segments, config)


def ping() -> bool:
    """Nothing: the first call waits until the child has imported numpy and scipy."""
    return True


def window_estimate(window: WindowSamples) -> tuple[dict[str, Any], int]:
    """The estimate document of a window copied by ``WindowedIdentifier.snapshot`` and its newest wrench stamp."""
    assert _windowed is not None, "init_worker was not run"
    estimate = _windowed.estimate_window(window)
    return estimate.document, estimate.last_wrench_t_ns or 0


def recursive_document(result: IdentificationResult, lengths_m: np.ndarray, options: IdentifyOptions) -> dict[str, Any]:
    """The estimate document of a recursive result (fused with the anthropometric prior when valid)."""
    n = lengths_m.size
    data = IdentificationData(
        np.zeros(0, dtype=np.int64),
        np.zeros((0, n)),
        np.zeros((0, n)),
        np.zeros((0, n)),
        lengths_m,
        np.zeros(n),
        np.zeros(n),
    )
    posterior = fuse(result, data, options.subject) if result.valid else None
    return estimate_document(result, data, posterior, options.subject)
