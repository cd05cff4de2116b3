"""The rotation between two TF frames over time: /tf_static links fixed, /tf links slerped at each stamp."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from msg_adapters.rotation import matrices_from_quaternions
from msg_adapters.tf import TransformSample

__all__ = ["RotationTrack", "TransformBuffer", "matrices_from_quaternions", "slerp_quaternions"]

# Two rotations of a /tf link closer than this (rad) are the same one republished: the link does not turn.
SAME_ROTATION_RAD = 1e-9


def slerp_quaternions(stamps_ns: np.ndarray, quaternions_xyzw: np.ndarray, t_ns: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation of a quaternion track at ``t_ns``, held beyond its ends.

    Parameters
    ----------
    stamps_ns : (K,) strictly increasing int64 stamps, ns (K >= 1).
    quaternions_xyzw : (K, 4) unit quaternions, made sign-continuous here (q and -q are one rotation).
    t_ns : (N,) int64 stamps to evaluate at, ns.

    Returns
    -------
    (N, 4) unit quaternions.
    """
    q = np.array(quaternions_xyzw, dtype=np.float64)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    t = np.asarray(t_ns, dtype=np.int64)
    if q.shape[0] == 1:
        return np.broadcast_to(q[0], (t.size, 4)).copy()
    # Shortest path: flip each quaternion into the hemisphere of its predecessor.
    flips = np.concatenate(([1.0], np.sign(np.einsum("ij,ij->i", q[1:], q[:-1]))))
    flips[flips == 0] = 1.0
    q *= np.cumprod(flips)[:, None]
    i = np.clip(np.searchsorted(stamps_ns, t, side="right") - 1, 0, stamps_ns.size - 2)
    span = (stamps_ns[i + 1] - stamps_ns[i]).astype(np.float64)
    u = np.clip((t - stamps_ns[i]).astype(np.float64) / span, 0.0, 1.0)[:, None]
    a, b = q[i], q[i + 1]
    cos = np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)[:, None]
    theta = np.arccos(cos)
    small = theta < 1e-6
    sin = np.where(small, 1.0, np.sin(theta))
    wa = np.where(small, 1.0 - u, np.sin((1.0 - u) * theta) / sin)
    wb = np.where(small, u, np.sin(u * theta) / sin)
    out = wa * a + wb * b
    return np.asarray(out / np.linalg.norm(out, axis=1, keepdims=True))


@dataclass(frozen=True)
class RotationTrack:
    """``R_target_from_source`` at the stamps asked for.

    Attributes
    ----------
    rotations : (N, 3, 3) one rotation per stamp (read-only, one shared rotation when the chain is fixed).
    turning : True when a /tf link of the chain changes (more than one distinct rotation): the rotation
        is then per sample; False when the chain is fixed (/tf_static, or /tf republishing one rotation).
    source : ``"tf"`` when a /tf link is in the chain, else ``"tf_static"``.
    span_ns : (first, last) stamps over which every turning link has samples; None when nothing turns.
    held : (N,) bool, stamps outside ``span_ns``: the nearest orientation of the track is held there.
    """

    rotations: np.ndarray
    turning: bool
    source: str
    span_ns: tuple[int, int] | None
    held: np.ndarray

    @property
    def session_rotation(self) -> np.ndarray:
        """(3, 3) when the chain is fixed, else the (N, 3, 3) per-sample rotations."""
        if not self.turning and self.rotations.shape[0]:
            return np.asarray(self.rotations[0])
        return self.rotations

    def held_summary(self, t_ns: npt.ArrayLike) -> tuple[int, float]:
        """How many stamps of ``t_ns`` (the ones the track was made for) are held, and the longest hold, s."""
        if self.span_ns is None or not self.held.any():
            return 0, 0.0
        t = np.asarray(t_ns, dtype=np.int64)[self.held]
        beyond = np.maximum(self.span_ns[0] - t, t - self.span_ns[1])
        return int(self.held.sum()), float(beyond.max()) / 1e9


@dataclass
class _Link:
    """One child frame's transform to its parent: fixed (/tf_static) or stamped samples (/tf)."""

    parent: str
    static: np.ndarray | None = None  # (4,) quaternion
    stamps: list[int] | None = None
    quaternions: list[np.ndarray] | None = None
    _arrays: tuple[np.ndarray, np.ndarray] | None = None
    _turning: bool | None = None

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Sorted unique stamps (K,) and quaternions (K, 4) (the last one given wins for a repeated stamp)."""
        if self._arrays is None:
            assert self.stamps is not None and self.quaternions is not None
            stamps = np.asarray(self.stamps, dtype=np.int64)
            quats = np.asarray(self.quaternions, dtype=np.float64).reshape(-1, 4)
            order = np.argsort(stamps, kind="stable")[::-1]  # newest-given first among equal stamps
            _, first = np.unique(stamps[order], return_index=True)
            keep = order[first]
            self._arrays = (stamps[keep], quats[keep] / np.linalg.norm(quats[keep], axis=1, keepdims=True))
        return self._arrays

    @property
    def dynamic(self) -> bool:
        return bool(self.stamps)

    def turning(self) -> bool:
        if self._turning is None:
            if not self.dynamic:
                self._turning = False
            else:
                quats = self.arrays()[1]
                # Rotation angle from the chord between aligned quaternions (arccos of a dot product near 1
                # loses half the digits): |q - q0| = 2 sin(alpha / 2), rotation angle = 2 alpha.
                aligned = quats * np.where(quats @ quats[0] < 0.0, -1.0, 1.0)[:, None]
                chord = np.linalg.norm(aligned - quats[0], axis=1)
                angle = 4.0 * np.arcsin(np.clip(chord / 2.0, 0.0, 1.0))
                self._turning = bool((angle > SAME_ROTATION_RAD).any())
        return self._turning

    def at(self, t_ns: np.ndarray) -> np.ndarray:
        """(N, 3, 3) ``R_parent_from_child`` at ``t_ns``."""
        if self.dynamic:
            stamps, quats = self.arrays()
            return matrices_from_quaternions(slerp_quaternions(stamps, quats, t_ns))
        assert self.static is not None
        return np.broadcast_to(matrices_from_quaternions(self.static[None, :])[0], (t_ns.size, 3, 3))


class TransformBuffer:
    """The transforms of ``/tf_static`` (fixed) and ``/tf`` (stamped), per child frame, as tf2 keeps them.

    A link's rotation at a stamp is its /tf samples slerped (held beyond the first and last one), or its
    /tf_static transform; a chain composes its links at each stamp (translations are ignored: the wrench
    is referenced at the contact point). A child given a new parent forgets its old samples.

    Parameters
    ----------
    max_age_ns : /tf samples older than this before a link's newest are forgotten (live use); None keeps all.
    """

    def __init__(self, max_age_ns: int | None = None) -> None:
        self.max_age_ns = max_age_ns
        self._links: dict[str, _Link] = {}

    def add_static(self, samples: Iterable[TransformSample]) -> None:
        """Add /tf_static transforms (the last per child wins)."""
        for sample in samples:
            link = self._link(sample)
            link.static = np.asarray(sample.rotation_xyzw, dtype=np.float64)
            link._turning = None

    def add(self, samples: Iterable[TransformSample]) -> None:
        """Add /tf transforms (each keeps its stamp)."""
        for sample in samples:
            link = self._link(sample)
            if link.stamps is None or link.quaternions is None:
                link.stamps, link.quaternions = [], []
            link.stamps.append(int(sample.t_ns))
            link.quaternions.append(np.asarray(sample.rotation_xyzw, dtype=np.float64))
            link._arrays, link._turning = None, None
            if self.max_age_ns is not None and len(link.stamps) > 2:
                newest = max(link.stamps)
                keep = [k for k, s in enumerate(link.stamps) if newest - s <= self.max_age_ns]
                if len(keep) < len(link.stamps):
                    keep = keep if len(keep) >= 2 else sorted(range(len(link.stamps)), key=link.stamps.__getitem__)[-2:]
                    link.stamps = [link.stamps[k] for k in keep]
                    link.quaternions = [link.quaternions[k] for k in keep]

    def _link(self, sample: TransformSample) -> _Link:
        link = self._links.get(sample.child_frame)
        if link is None or link.parent != sample.parent_frame:
            link = self._links[sample.child_frame] = _Link(sample.parent_frame)
        return link

    def _ancestors(self, frame: str) -> list[str]:
        """``frame`` and its ancestors up to the root (a cycle stops where it closes)."""
        chain = [frame]
        while chain[-1] in self._links:
            parent = self._links[chain[-1]].parent
            if parent in chain:
                break
            chain.append(parent)
        return chain

    def chain(self, target: str, source: str) -> tuple[list[str], list[str]] | None:
        """The child frames of the links from ``source`` and from ``target`` up to their first common ancestor."""
        up_source, up_target = self._ancestors(source), self._ancestors(target)
        for k, ancestor in enumerate(up_source):
            if ancestor in up_target:
                return up_source[:k], up_target[: up_target.index(ancestor)]
        return None

    def connected(self, target: str, source: str) -> bool:
        """Whether a chain of transforms joins the two frames."""
        return self.chain(target, source) is not None

    def track(self, target: str, source: str, t_ns: npt.ArrayLike) -> RotationTrack | None:
        """``R_target_from_source`` at each stamp of ``t_ns``, or None when the frames are not connected.

        Parameters
        ----------
        target, source : frame ids (e.g. ``world`` and the wrench's frame).
        t_ns : (N,) int64 stamps, ns.
        """
        t = np.atleast_1d(np.asarray(t_ns, dtype=np.int64))
        found = self.chain(target, source)
        if found is None:
            return None
        from_source, from_target = found

        links = [self._links[c] for c in from_source + from_target]
        turning = [link for link in links if link.turning()]
        # A fixed chain is one rotation: composed once and shared by every stamp, not once per stamp of a 1 kHz
        # stream.
        stamps = t if turning or t.size == 0 else t[:1]

        def compose(children: list[str]) -> np.ndarray:
            rotation = np.broadcast_to(np.eye(3), (stamps.size, 3, 3))
            for child in children:  # R_ancestor_from_frame = R_parent_from_child @ R_child_from_frame
                rotation = np.einsum("nij,njk->nik", self._links[child].at(stamps), rotation)
            return np.asarray(rotation)

        rotations = np.einsum("nji,njk->nik", compose(from_target), compose(from_source))
        if turning or t.size == 0:
            rotations = np.ascontiguousarray(rotations)
        else:
            rotations = np.broadcast_to(rotations[0], (t.size, 3, 3))
        span = None
        held = np.zeros(t.size, dtype=bool)
        if turning:
            first = max(int(link.arrays()[0][0]) for link in turning)
            last = min(int(link.arrays()[0][-1]) for link in turning)
            span = (first, last)
            held = (t < first) | (t > last)
        source_name = "tf" if any(link.dynamic for link in links) else "tf_static"
        return RotationTrack(rotations, bool(turning), source_name, span, held)
