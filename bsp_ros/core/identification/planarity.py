"""How far the arm leaves the sagittal plane, from the markers' lateral coordinates, and what that costs the curves."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from bsp_ros.core.model import gravity_regressor
from bsp_ros.core.streams import MarkerSeries, common_frames


def out_of_plane_fraction(markers: dict[str, MarkerSeries], chain: Sequence[str]) -> np.ndarray:
    """(n,) each segment's lateral excursion over the session as a fraction of its length.

    The model is planar: the lateral (world x) coordinates are projected away. A real arm (oblique joint axes, a
    shoulder that moves) swings a few mm out of the plane, and the planar gravity torque is then wrong by about
    that fraction. Per segment, the spread of its distal marker's x relative to its proximal one, less the
    markers' noise (from frame-to-frame differences), as a peak-to-peak range (2 sqrt 2 sd) over the in-plane
    length. Zero where the two markers share no frame.

    Parameters
    ----------
    markers : chain markers in ``world`` (m), by name.
    chain : the marker names shoulder to contact point.
    """
    out = np.zeros(len(chain) - 1)
    for j, (proximal, distal) in enumerate(itertools.pairwise(chain)):
        a, b = markers.get(proximal), markers.get(distal)
        if a is None or b is None:
            continue
        t_ns, i_a, i_b = common_frames(a.t_ns, b.t_ns, assume_unique=False)
        if t_ns.size < 10:
            continue
        pa, pb = a.position_m[i_a], b.position_m[i_b]
        finite = np.isfinite(pa).all(axis=1) & np.isfinite(pb).all(axis=1)
        if finite.sum() < 10:
            continue
        lateral = pb[finite, 0] - pa[finite, 0]
        length = float(np.median(np.linalg.norm(pb[finite, 1:] - pa[finite, 1:], axis=1)))
        noise_var = float(np.var(np.diff(lateral))) / 2.0
        signal_sd = np.sqrt(max(float(np.var(lateral)) - noise_var, 0.0))
        out[j] = 2.0 * np.sqrt(2.0) * signal_sd / max(length, 1e-3)
    return out


def planar_error_nm(q_rad: np.ndarray, static_moments_kgm: np.ndarray, out_of_plane: np.ndarray) -> np.ndarray:
    """(n,) RMS over the samples of the gravity torque the planar model may miss at each joint, Nm.

    Segment k's share of joint j's gravity torque, ``Y[t, j, k] beta_k``, is taken as wrong by segment k's
    out-of-plane fraction (:func:`out_of_plane_fraction`).

    Parameters
    ----------
    q_rad : (N, n) joint angles, rad.
    static_moments_kgm : (n,) the identified static moments, kg m.
    out_of_plane : (n,) per segment, fraction.
    """
    shares = np.abs(gravity_regressor(q_rad) * np.asarray(static_moments_kgm)[None, None, :])  # (N, n, n)
    return np.sqrt(np.mean((shares @ np.asarray(out_of_plane)) ** 2, axis=0))
