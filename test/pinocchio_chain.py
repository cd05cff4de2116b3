"""The planar arm as a pinocchio model: the independent rigid-body oracle several tests check against."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def planar_chain(
    pin: Any,
    lengths_m: Sequence[float],
    masses_kg: Sequence[float],
    com_m: Sequence[float],
    com_normal_m: Sequence[float],
    inertia_com_kgm2: Sequence[float],
    base_m: Sequence[float] = (0.0, 0.0, 0.0),
    gravity_m_s2: float = 9.81,
) -> Any:
    """Revolute joints about world x, each segment along its parent's +y at q = 0 (docs/contract.md's sagittal plane).

    Segment frames: y along the segment, z its counter-clockwise normal, x the joint axis; only the inertia
    about x acts in the plane (the others are set to something plausible and unused).
    """
    model = pin.Model()
    parent = 0
    for j, (m, c, d, inertia) in enumerate(zip(masses_kg, com_m, com_normal_m, inertia_com_kgm2, strict=True)):
        offset = np.asarray(base_m, dtype=float) if j == 0 else np.array([0.0, lengths_m[j - 1], 0.0])
        parent = model.addJoint(parent, pin.JointModelRX(), pin.SE3(np.eye(3), offset), f"joint{j}")
        rotational = np.diag([inertia, 0.1 * inertia + 1e-6, inertia])
        model.appendBodyToJoint(parent, pin.Inertia(m, np.array([0.0, c, d]), rotational), pin.SE3.Identity())
    model.gravity.linear = np.array([0.0, 0.0, -gravity_m_s2])
    return model
