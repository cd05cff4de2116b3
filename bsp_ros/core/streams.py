"""The recorded streams of one cell session as numpy arrays (what a bag or the simulator yields)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

SEGMENTS_3 = ("upper_arm", "forearm", "hand")
JOINTS_3 = ("shoulder", "elbow", "wrist")
# Proximal then distal marker of each segment: the hand segment ends at the contact point (`hand` marker).
MARKERS_3 = ("shoulder", "elbow", "wrist", "hand")
MARKERS_2 = ("shoulder", "elbow", "hand")


def segments_for(n_segments: int) -> tuple[str, ...]:
    """Segment names of a chain of ``n_segments`` (2: the paper's mechanical arm, 3: a human arm)."""
    return SEGMENTS_3[:n_segments]


def joints_for(n_segments: int) -> tuple[str, ...]:
    """Joint names of a chain of ``n_segments``."""
    return JOINTS_3[:n_segments]


def markers_for(n_segments: int) -> tuple[str, ...]:
    """Marker names of a chain of ``n_segments``, proximal to distal, ending at the contact point."""
    return MARKERS_3 if n_segments == 3 else MARKERS_2


@dataclass(frozen=True)
class WrenchSeries:
    """Wrench the hand exerts on the sensor, in the sensor frame, referenced at the contact point.

    Attributes
    ----------
    t_ns : (N,) int64, header stamps in nanoseconds.
    force_n : (N, 3) float64, force in N.
    torque_nm : (N, 3) float64, moment in Nm.
    frame_id : the ``header.frame_id`` of the messages.
    """

    t_ns: np.ndarray
    force_n: np.ndarray
    torque_nm: np.ndarray
    frame_id: str = "world"


def common_frames(
    t_a_ns: np.ndarray, t_b_ns: np.ndarray, assume_unique: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stamps two streams share and where they sit in each (the first of repeated ones): ``np.intersect1d(t_a_ns,
    t_b_ns, assume_unique, return_indices=True)``, the same arrays.

    Markers of one capture system usually share every frame: then the stamps are returned as they are, without
    intersect1d's sort (60 ms over a 10-minute session's markers).

    Parameters
    ----------
    t_a_ns, t_b_ns : (M_a,), (M_b,) int64 stamps, ns.
    assume_unique : each holds every stamp once (a cleaned stream's frames).

    Returns
    -------
    common : (K,) the shared stamps, ns; i_a, i_b : (K,) their indices in ``t_a_ns`` and ``t_b_ns``.
    """
    if t_a_ns.shape == t_b_ns.shape and np.array_equal(t_a_ns, t_b_ns) and bool((np.diff(t_a_ns) > 0).all()):
        index = np.arange(t_a_ns.size)
        return t_a_ns.copy(), index, index.copy()
    common, i_a, i_b = np.intersect1d(t_a_ns, t_b_ns, assume_unique=assume_unique, return_indices=True)
    return common, i_a, i_b


@dataclass(frozen=True)
class MarkerSeries:
    """Positions of one marker in ``world`` (m): (M,) int64 stamps and (M, 3) positions.

    A frame in which the marker was occluded is simply absent.
    """

    t_ns: np.ndarray
    position_m: np.ndarray


@dataclass(frozen=True)
class EmgSeries:
    """Surface EMG envelopes of the arm's muscles, one value per channel and sample (optional in a session).

    Attributes
    ----------
    t_ns : (N,) int64 sample times, ns (in a bag the log time: the message carries no stamp).
    envelope : (N, C) float64 envelopes in the cell's own unit (V, uV or % of a maximal contraction: the
        activity rule compares each channel with its own quiet baseline, so any scale serves).
    channels : (C,) the channels' names (muscles, e.g. ``biceps``).
    other_layout : messages whose channel names or count differ from the first message's, left out of the
        arrays (a stream whose channels change is no usable EMG).
    """

    t_ns: np.ndarray
    envelope: np.ndarray
    channels: tuple[str, ...]
    other_layout: int = 0


@dataclass(frozen=True)
class Session:
    """All streams of one session.

    Attributes
    ----------
    wrench : the force/torque stream.
    markers : marker name (``shoulder``, ``elbow``, ``wrist``, ``hand``) -> its series.
    rotation_world_from_sensor : (3, 3) rotation taking wrench-frame vectors into ``world``.
    handle_pose : the contact point in ``world`` as the robot's kinematics give it (its handle pose), or None
        where the cell publishes none: then the ``hand`` skin marker stands for the contact point.
    emg : the arm muscles' EMG envelopes, or None where the cell records no EMG.
    """

    wrench: WrenchSeries
    markers: dict[str, MarkerSeries]
    rotation_world_from_sensor: np.ndarray = field(default_factory=lambda: np.eye(3))
    handle_pose: MarkerSeries | None = None
    emg: EmgSeries | None = None

    @property
    def n_segments(self) -> int:
        """3 with a wrist marker, otherwise 2."""
        return 3 if "wrist" in self.markers else 2
