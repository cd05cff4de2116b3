"""A centred Hampel gate on a live wrench stream: spikes kept out of the recursive filter, as offline drops them."""

from __future__ import annotations

import collections
from typing import Generic, TypeVar

import numpy as np

from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.robust import MAD_TO_SD

__all__ = ["SpikeGate"]

_DEFAULTS = JointConfig()
# The offline spike test's: the median of the 11 samples around each, 8 robust sd of the deviations from it.
HALF = _DEFAULTS.spike_window // 2
N_SD = _DEFAULTS.outlier_sd
# Deviations at or below these ([F_y, F_z] N, M_x Nm) are never spikes: a quantised sensor's MAD can be 0, and a
# glitch this small moves no estimate.
FLOOR_YZX = (0.5, 0.5, 0.05)
# The deviations' robust sd is taken over the newest SCALE_SAMPLES, again every RESCALE_EVERY samples; nothing is
# judged before MIN_SCALE_SAMPLES (the recursive filter's warm-up takes no sample for its first 10 s anyway).
SCALE_SAMPLES = 2048
RESCALE_EVERY = 256
MIN_SCALE_SAMPLES = 64

Item = TypeVar("Item")


class SpikeGate(Generic[Item]):
    """Judges each wrench against the median of the ``2 HALF + 1`` wrenches around it (a Hampel filter, as
    ``hampel_outliers`` judges a recorded session): a spike deviates from it by more than ``N_SD`` robust sd of the
    stream's recent deviations in a channel. A median keeps steps, so friction's real steps at a reversal pass.

    Centred, each verdict waits for ``HALF`` later wrenches (5 ms at 1 kHz): the recursive filter waits half a
    second for the kinematics at a wrench's stamp anyway. The payload of each wrench comes back with its verdict.
    """

    def __init__(self) -> None:
        self.spikes = 0
        self._deviations = np.zeros((SCALE_SAMPLES, 3))
        self._seen = 0
        self._scale: list[float] | None = None
        self._items: collections.deque[tuple[list[float], Item]] = collections.deque()
        self._judged = 0  # how many of the items at the front were judged (kept as the next ones' neighbours)

    def reset(self) -> None:
        """Start over (a clock jump, a new session): the waiting wrenches are dropped, the deviations' scale kept
        (the same sensor)."""
        self._items.clear()
        self._judged = 0

    def push(self, wrench_yzx: list[float], payload: Item) -> tuple[Item, bool] | None:
        """Add one wrench ``[F_y, F_z, M_x]`` (N, Nm); the one ``HALF`` wrenches before it, judged now, with whether
        it is a spike (None while the first wrenches wait)."""
        self._items.append((wrench_yzx, payload))
        i = self._judged
        if len(self._items) - i <= HALF:
            return None
        neighbours = [w for w, _ in list(self._items)[max(0, i - HALF) : i + HALF + 1]]
        value, item = self._items[i]
        spike = self._judge(value, neighbours)
        self._judged += 1
        if self._judged > HALF:
            self._items.popleft()
            self._judged -= 1
        self.spikes += spike
        return item, spike

    def _judge(self, value: list[float], neighbours: list[list[float]]) -> bool:
        middle = len(neighbours) // 2
        deviation = [v - sorted(column)[middle] for v, column in zip(value, zip(*neighbours, strict=True), strict=True)]
        self._deviations[self._seen % SCALE_SAMPLES] = deviation
        self._seen += 1
        if self._seen == MIN_SCALE_SAMPLES or (self._seen > MIN_SCALE_SAMPLES and self._seen % RESCALE_EVERY == 0):
            recent = self._deviations[: min(self._seen, SCALE_SAMPLES)]
            spread = np.median(np.abs(recent - np.median(recent, axis=0)), axis=0)
            self._scale = (MAD_TO_SD * spread).tolist()
        if self._scale is None:
            return False
        return any(abs(d) > max(N_SD * s, floor) for d, s, floor in zip(deviation, self._scale, FLOOR_YZX, strict=True))
