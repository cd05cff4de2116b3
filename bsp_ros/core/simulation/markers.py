"""The simulated motion capture: marker streams, noise, occlusion and skin markers off the joint centres."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.checks import float_tuple
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive

MAX_SKIN_OFFSET_M = 0.1


@normalising
@dataclass(frozen=True, kw_only=True)
class MarkerSpec:
    """The motion-capture streams (one marker per joint centre, ``hand`` at the contact point).

    Attributes
    ----------
    marker_hz : frame rate, Hz (> 0, at most 5000).
    phase_s : first nominal frame after the session start, s (0 <= phase < 1 s).
    stamp_jitter_s : one standard deviation of the frame stamp jitter, s (clipped like the wrench's).
    shoulder_m : (3,) fixed shoulder position in ``world``, m; the arm moves in the plane x = shoulder x.
    noise_m : white Gaussian position noise per axis (x included), m (1 sd).
    dropout_fraction : long-run fraction of frames lost, per marker independently, in [0, 0.9].
    dropout_mean_frames : mean length of a gap of lost frames (>= 1), frames.
    skin_offset_m : per marker (proximal to distal: shoulder, elbow, (wrist,) hand), the skin marker's
        offset from the joint centre ``(along, normal)`` in m, fixed in the segment that starts at that
        joint (the hand marker: in the hand, the last segment); ``along`` points distally along the
        segment axis, ``normal`` 90 deg counter-clockwise from it in the y-z plane. Empty: on the centres.
    skin_offset_bound_m : a per-session re-placement of the markers (0-0.1 m; 0: none): each marker's
        ``(along, normal)`` offset gains a draw uniform within +-bound per axis, from the session's seed
        (:func:`skin_offsets_m`).
    """

    marker_hz: float = 50.0
    phase_s: float = 0.0071
    stamp_jitter_s: float = 0.0
    shoulder_m: tuple[float, float, float] = (0.20, 0.0, 1.20)
    noise_m: float = 1e-4
    dropout_fraction: float = 0.0
    dropout_mean_frames: float = 10.0
    skin_offset_m: tuple[tuple[float, float], ...] = ()
    skin_offset_bound_m: float = 0.0

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the numbers as floats, the positions as tuples of floats."""
        out: dict[str, Any] = {"marker_hz": check_positive("marker_hz", given.marker_hz, 5000.0)}
        out["phase_s"] = check_finite_scalar("marker phase_s", given.phase_s, 0.0, 1.0)
        if out["phase_s"] >= 1.0:
            raise InputError(f"marker phase_s must be below 1 s, got {out['phase_s']!r}")
        out["stamp_jitter_s"] = check_finite_scalar("marker stamp_jitter_s", given.stamp_jitter_s, 0.0, 0.1)
        out["shoulder_m"] = float_tuple("shoulder_m", given.shoulder_m, 3, -100.0, 100.0)
        out["noise_m"] = check_finite_scalar("marker noise_m", given.noise_m, 0.0, 0.1)
        out["dropout_fraction"] = check_finite_scalar("dropout_fraction", given.dropout_fraction, 0.0, 0.9)
        out["dropout_mean_frames"] = check_finite_scalar("dropout_mean_frames", given.dropout_mean_frames, 1.0, 1e6)
        offsets = given.skin_offset_m
        if isinstance(offsets, str | bytes) or not isinstance(offsets, Sequence | np.ndarray):
            raise InputError(f"skin_offset_m must be a sequence of (along, normal) pairs, got {offsets!r}")
        pairs = tuple(
            float_tuple(f"skin_offset_m[{k}]", pair, 2, -MAX_SKIN_OFFSET_M, MAX_SKIN_OFFSET_M)
            for k, pair in enumerate(offsets)
        )
        if pairs and len(pairs) not in (3, 4):
            raise InputError(f"skin_offset_m needs one (along, normal) pair per marker (3 or 4), got {len(pairs)}")
        out["skin_offset_m"] = pairs
        out["skin_offset_bound_m"] = check_finite_scalar(
            "skin_offset_bound_m", given.skin_offset_bound_m, 0.0, MAX_SKIN_OFFSET_M
        )
        return out


def skin_offsets_m(markers: MarkerSpec, n_markers: int, seed: int) -> tuple[tuple[float, float], ...]:
    """The session's skin marker offsets: the given ones plus the seeded re-placement.

    Parameters
    ----------
    markers : the marker spec (``skin_offset_m``, ``skin_offset_bound_m``).
    n_markers : markers of the chain (3 or 4), proximal first.
    seed : the session's seed; the draw has a stream of its own, so it leaves every other draw unchanged.

    Returns
    -------
    ``n_markers`` pairs ``(along, normal)`` in m, or ``()`` if there is neither an offset nor a bound.
    """
    base = np.asarray(markers.skin_offset_m, dtype=np.float64).reshape(-1, 2)
    if markers.skin_offset_bound_m <= 0.0:
        return tuple((float(a), float(b)) for a, b in base)
    if base.size == 0:
        base = np.zeros((n_markers, 2))
    rng = np.random.default_rng(np.random.SeedSequence([seed, 17]))
    drawn = base + rng.uniform(-markers.skin_offset_bound_m, markers.skin_offset_bound_m, (n_markers, 2))
    return tuple((float(a), float(b)) for a, b in drawn)
