"""Several recordings of one arm identified as one: their samples stacked, each with its trunk's tilt."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.emg import combined_emg
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.errors import InputError

# Segment lengths of the recordings further apart than this: a marker moved between them. Markers that stay on
# give the same lengths to a few hundredths of a mm (simulated, marker noise 0.15 mm); a marker re-attached
# within 3 mm changes a length by 0.3-5 mm (measured over 4 seeds: every one had a segment beyond 1.5 mm).
MAX_LENGTH_SPREAD_M = 0.001


def combine_recordings(
    recordings: Sequence[IdentificationData], trunk_tilts_rad: Sequence[float]
) -> IdentificationData:
    """One identification input from recordings of the same arm, in time order, each with its trunk tilt.

    Between recordings the patient may sit differently: with the trunk tilted by ``psi`` (rad, in the sense of
    ``q_1``: from world +y towards +z), gravity turns relative to the arm while the passive moments follow the
    joint angles. Their samples are stacked with ``trunk_rad = psi`` per sample, so that the shoulder's passive
    angle is ``q_1 - psi`` (:attr:`IdentificationData.passive_q_rad`). Two recordings at different tilts
    separate an elastic passive moment from gravity where one posture cannot (a smooth function of the joint
    angles in both).

    Parameters
    ----------
    recordings : one or more, from the same cell and markers, not overlapping in time.
    trunk_tilts_rad : one tilt per recording (rad; 0: upright).

    Returns
    -------
    IdentificationData
        The recordings' samples in time order; segment lengths the sample-weighted mean (their std the larger
        of the recordings' and the spread between them); ``trunk_rad`` None when every tilt is 0. One
        recording with no tilt comes back unchanged.

    Raises
    ------
    InputError
        No recording, a tilt count that differs from the recordings', a tilt beyond 90 deg, different numbers
        of segments, or recordings that overlap in time.
    """
    tilts = _checked_tilts(recordings, trunk_tilts_rad)
    if len(recordings) == 1 and tilts[0] == 0.0:
        return recordings[0]
    order = _time_order(recordings)
    ordered = [recordings[k] for k in order]
    lengths = _pooled_lengths(ordered)
    robot = {r.contact_from_robot for r in ordered}
    warnings = _merged_warnings(order, ordered, lengths.warnings, len(robot) > 1)
    qd, qdd = _stacked_rates(ordered)
    trunk = np.concatenate([np.full(r.t_ns.size, tilts[k]) for k, r in zip(order.tolist(), ordered, strict=True)])
    return IdentificationData(
        t_ns=np.concatenate([r.t_ns for r in ordered]),
        q_rad=np.concatenate([r.q_rad for r in ordered]),
        velocity_rad_s=np.concatenate([r.velocity_rad_s for r in ordered]),
        tau_nm=np.concatenate([r.tau_nm for r in ordered]),
        lengths_m=lengths.mean_m,
        lengths_std_m=lengths.std_m,
        velocity_noise_rad_s=np.max([r.velocity_noise_rad_s for r in ordered], axis=0),
        n_wrench_samples=sum(r.n_wrench_samples for r in ordered),
        warnings=warnings,
        removed_samples=_summed_removed(ordered),
        qd_rad_s=qd,
        qdd_rad_s2=qdd,
        contact_from_robot=robot == {True},
        trunk_rad=trunk if tilts.any() else None,
        recording_index=np.concatenate([np.full(r.t_ns.size, k) for k, r in enumerate(ordered)]),
        out_of_plane=np.max([r.out_of_plane for r in ordered], axis=0)
        if all(r.out_of_plane is not None for r in ordered)
        else None,
        markers_moved=lengths.moved,
        emg=combined_emg([r.emg for r in ordered]),
    )


def _checked_tilts(recordings: Sequence[IdentificationData], trunk_tilts_rad: Sequence[float]) -> np.ndarray:
    """The trunk tilts as an array, rad, shape (number of recordings,).

    Raises
    ------
    InputError
        No recording, a tilt count that differs from the recordings', or a tilt not finite or beyond 90 deg.
    """
    if not recordings:
        raise InputError("no recording to identify")
    if len(trunk_tilts_rad) != len(recordings):
        raise InputError(f"{len(trunk_tilts_rad)} trunk tilts for {len(recordings)} recordings: give one per recording")
    tilts = np.asarray(trunk_tilts_rad, dtype=np.float64)
    if not (np.isfinite(tilts).all() and (np.abs(tilts) <= np.pi / 2).all()):
        raise InputError(
            f"trunk tilts must be finite and within +-90 deg, got {np.degrees(tilts).round(1).tolist()} deg"
        )
    return tilts


def _time_order(recordings: Sequence[IdentificationData]) -> np.ndarray:
    """The recordings' indices in the order of their first stamps (stable for equal ones), shape (number of
    recordings,).

    Raises
    ------
    InputError
        Recordings with different numbers of segments, or recordings that overlap in time.
    """
    n = {r.n_joints for r in recordings}
    if len(n) > 1:
        raise InputError(f"the recordings have different numbers of segments ({sorted(n)}): they are not one arm")
    order = np.argsort([int(r.t_ns[0]) for r in recordings], kind="stable")
    ordered = [recordings[k] for k in order]
    for k, (a, b) in enumerate(itertools.pairwise(ordered)):
        if b.t_ns[0] <= a.t_ns[-1]:
            raise InputError(
                f"recordings {order[k] + 1} and {order[k + 1] + 1} overlap in time: recordings of one arm follow each "
                "other (the same recording given twice?)"
            )
    return order


@dataclass(frozen=True, kw_only=True)
class _PooledLengths:
    """The recordings' segment lengths as one arm's.

    Attributes
    ----------
    mean_m : the sample-weighted mean length of each segment, m; shape (n,).
    std_m : each segment's std, the larger of the recordings' and half the spread between them, m; shape (n,).
    moved : whether some segment's lengths differ by more than :data:`MAX_LENGTH_SPREAD_M` (a marker moved).
    warnings : one per such segment, in words.
    """

    mean_m: np.ndarray
    std_m: np.ndarray
    moved: bool
    warnings: list[str]


def _pooled_lengths(ordered: Sequence[IdentificationData]) -> _PooledLengths:
    """The segment lengths of the recordings ``ordered`` (in time order) pooled, and where a marker moved."""
    counts = np.array([r.t_ns.size for r in ordered], dtype=np.float64)
    lengths = np.array([r.lengths_m for r in ordered])
    mean_lengths = counts @ lengths / counts.sum()
    spread = lengths.max(axis=0) - lengths.min(axis=0)
    warnings = []
    for j in np.flatnonzero(spread > MAX_LENGTH_SPREAD_M).tolist():
        warnings.append(
            f"segment {j + 1}'s length differs by {1e3 * spread[j]:.1f} mm between the recordings: a marker moved "
            "between them (the mean length is used, its std holds the difference, and each recording's own marker "
            "placement is in every std)"
        )
    lengths_std = np.maximum(np.max([r.lengths_std_m for r in ordered], axis=0), spread / 2.0)
    return _PooledLengths(
        mean_m=mean_lengths,
        std_m=lengths_std,
        moved=bool((spread > MAX_LENGTH_SPREAD_M).any()),
        warnings=warnings,
    )


def _merged_warnings(
    order: np.ndarray, ordered: Sequence[IdentificationData], length_warnings: list[str], mixed_contact: bool
) -> list[str]:
    """The combined recording's warnings: the segment lengths' (``length_warnings``), each recording's own under
    its number as given (``order`` maps the time order ``ordered`` back to it), and one when the contact point
    came from the robot's handle pose in some recordings only (``mixed_contact``)."""
    warnings = list(length_warnings)
    for k, r in zip(order.tolist(), ordered, strict=True):
        warnings += [f"recording {k + 1}: {w}" for w in r.warnings]
    if mixed_contact:
        warnings.append(
            "the contact point came from the robot's handle pose in some recordings only: the skin marker's "
            "placement sd is used for all"
        )
    return warnings


def _summed_removed(ordered: Sequence[IdentificationData]) -> dict[str, int]:
    """The samples removed from the recordings ``ordered``, by reason, summed over them."""
    removed: dict[str, int] = {}
    for r in ordered:
        for key, count in r.removed_samples.items():
            removed[key] = removed.get(key, 0) + count
    return removed


def _stacked_rates(ordered: Sequence[IdentificationData]) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The smooth joint velocities (rad/s) and accelerations (rad/s^2) of the recordings ``ordered`` stacked,
    each of shape (N, n); both None unless every recording has both."""
    if not all(r.qd_rad_s is not None and r.qdd_rad_s2 is not None for r in ordered):
        return None, None
    return np.concatenate([r.qd_rad_s for r in ordered]), np.concatenate([r.qdd_rad_s2 for r in ordered])
