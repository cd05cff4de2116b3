"""How far an unmodelled constant passive offset at a joint would move the static moments."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.stacked import Fit, Problem
from bsp_ros.core.streams import joints_for, segments_for

# The elastic offset whose effect on the static moments the estimate states (Nm).
SENSITIVITY_OFFSET_NM = 0.05


def passive_offset_sensitivity(problem: Problem, fit: Fit, n: int) -> dict[str, dict[str, float]]:
    """Joint -> segment -> how far an unmodelled constant passive offset of 0.05 Nm at that joint moves the
    static moment (kg m), to first order: ``A^-1 X^T W u`` with ``u`` the offset's torque column."""
    joints, segments = joints_for(n), segments_for(n)
    out: dict[str, dict[str, float]] = {}
    if any(key == "offset_nm" for key, _ in problem.names):
        return out  # the offset is modelled: nothing assumed
    try:
        for j, joint in enumerate(joints):
            # X^T W u over the joint's used rows: its weight times their column sums (0 off them).
            rhs = SENSITIVITY_OFFSET_NM * fit.weights[j] * problem.joint_rows(j)[0].sum(axis=0)
            shift = np.linalg.solve(fit.design, rhs)[:n]
            out[joint] = {segment: float(v) for segment, v in zip(segments, shift, strict=True)}
    except np.linalg.LinAlgError:
        return {}
    return out
