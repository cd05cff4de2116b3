"""What a live window is: its settings, a copy of its samples, and its estimate."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.streams import EmgSeries
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class WindowConfig:
    """Settings of :class:`WindowedIdentifier`.

    Attributes
    ----------
    window_s : length of the sliding window (s).
    stale_s : an input whose newest stamp is older than this (against the other input or the caller's
        clock) makes the estimate invalid.
    options : method, passive model and subject, as for `bsp identify`.
    max_rate_hz : faster wrench streams are block-averaged down to this rate before identifying, so an
        update at 1 kHz costs what one at 50 Hz does. The model's torques change below 2 Hz, and a block mean
        keeps a white noise's information about them; measured on a 30 s window of 1 kHz wrench and 100 Hz
        markers, 200, 100 and 50 Hz give the same estimates and std to 3 digits, at 92, 52 and 36 ms.
    """

    window_s: float = 30.0
    stale_s: float = 0.5
    options: IdentifyOptions = field(default_factory=IdentifyOptions)
    max_rate_hz: float = 50.0
    # The model checks (elastic, drift, Stribeck) refit the window several times; at 5 Hz every 25th update
    # (5 s) keeps an update well inside its period. In between, each update refits what the last check chose.
    elastic_check_every: int = 25

    def __post_init__(self) -> None:
        check_positive("window_s", self.window_s, 3600.0)
        check_finite_scalar("stale_s", self.stale_s, 0.01, 60.0)
        check_positive("max_rate_hz", self.max_rate_hz, 1e5)
        check_positive("elastic_check_every", self.elastic_check_every, 1000)


@dataclass(frozen=True)
class WindowEstimate:
    """One update: the typed estimate, whether it is valid, and the newest wrench stamp it used."""

    estimate: Estimate
    valid: bool
    last_wrench_t_ns: int | None

    @property
    def document(self) -> dict[str, Any]:
        """The estimate's docs/contract.md document (JSON-ready, made anew on each call)."""
        return self.estimate.to_json()


@dataclass(frozen=True, kw_only=True)
class WindowSamples:
    """A copy of one window's samples, taken by :meth:`WindowedIdentifier.snapshot`.

    Attributes
    ----------
    wrench_t_ns : (N,) wrench stamps (ns); wrench_yzx : (N, 3) ``[F_y, F_z, M_x]`` in ``world``.
    angle_t_ns : (M,) joint-angle stamps (ns), from 2 s before the window (filter run-in);
    angle_rows : (M, 2n) unfiltered angles (rad) then segment lengths (m).
    refused : refused samples by input and reason; clock_jumps : clock jumps seen so far.
    rotation_world_from_sensor : (3, 3) the wrench sensor's orientation, wrench_frame_id : its frame, when a
        tare was applied to the wrench (its uncertainty then joins the estimate's).
    contact_from_robot : the angles' contact point is the robot's handle pose, not the hand's skin marker.
    epoch : how many times the buffers were cleared (a clock jump, a new transform or contact point) before the
        copy: an estimator restarts its model checks when it changes.
    emg : the EMG envelopes from shortly before the window on (stamped at receipt on the stamps' clock), None
        where none came: its active stretches are left out of the window's identification, as offline.
    """

    wrench_t_ns: np.ndarray
    wrench_yzx: np.ndarray
    angle_t_ns: np.ndarray
    angle_rows: np.ndarray
    refused: dict[str, int]
    clock_jumps: int
    # The wrench sensor's orientation and frame, for a tare's uncertainty (set by the node when it applies one).
    rotation_world_from_sensor: np.ndarray | None = None
    wrench_frame_id: str = ""
    contact_from_robot: bool = False
    epoch: int = 0
    emg: EmgSeries | None = None
