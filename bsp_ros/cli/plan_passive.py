"""`bsp plan`'s passive-curve check: what one simulated session of the plan tells of the passive curves."""

from __future__ import annotations

import argparse
import math
from typing import Any


def passive_check_lines(plan: Any, args: argparse.Namespace) -> tuple[str, str | None]:
    """The lines printed for the plan's simulated passive-curve check, and a warning where curves stay unresolved.

    One simulated session of ``plan`` per trunk posture (the table arm of ``--sex``, ``--body-mass``,
    ``--height``, with nonlinear two-joint passive moments; tared; markers within 3 mm, kept for every posture) is
    identified with the plan's passive model; with ``auto`` it is the plan's own check of the nominal arm
    (``Plan.check``), on which its model was chosen. Per joint: the passive curve's std (RMS over the planned range) and
    the smallest passive moment the plan follows within 10 %, also as a share of the joint's gravity torque.
    """
    from bsp_ros.core.planning.simulated import (
        CURVE_TARGET,
        REALISTIC_PASSIVE_SHARE,
        SKIN_BOUND_M,
        simulated_plan_check,
    )
    from bsp_ros.core.simulation import SubjectTruth

    n = plan.request.nominal.n_joints
    # With auto the plan's model was chosen on such a session of the nominal arm: the same session, not a second.
    check = plan.check or simulated_plan_check(
        plan, SubjectTruth.from_anthropometry(args.sex, args.body_mass, args.height, n)
    )
    arm = "nominal arm" if plan.check is not None else "table arm"
    postures = len(plan.request.trunk_tilts_rad)
    lines = [
        f"passive curves, one simulated session ({postures} posture{'s' if postures > 1 else ''}; {arm} with "
        f"nonlinear two-joint passive moments, tared sensor, markers placed within {1e3 * SKIN_BOUND_M:g} mm of the "
        f"joint centres; --passive {check.model}):"
    ]
    notes = []
    for joint, std in check.curve_rms_std_nm.items():
        gravity = check.gravity_rms_nm[joint]
        if not math.isfinite(std):
            lines.append(f"  {joint:8s} curve not identified by the simulated session")
            notes.append(f"{joint} not identified")
            continue
        smallest = check.smallest_followed_nm(joint)
        share = 100.0 * smallest / gravity
        lines.append(
            f"  {joint:8s} curve std {std:.2g} Nm (RMS): followed within {100 * CURVE_TARGET:g} % where its passive "
            f"moment is at least {smallest:.2g} Nm, {share:.2g} % of its gravity torque ({gravity:.2g} Nm RMS)"
        )
        notes.append(f"{joint} {smallest:.2g} Nm ({share:.2g} % of gravity)")
    lines.append(
        "  static moments of the simulated session: "
        + ", ".join(_static_moment_text(s, v, sd) for s, (v, sd) in check.static_moments.items())
    )
    if not check.valid:
        lines.append(f"  the simulated session was not valid: {check.message}")
    # The plan file carries it too, for the cell that loads the plan rather than reading the console.
    plan.notes.append(
        f"smallest passive moment followed within {100 * CURVE_TARGET:g} % (one simulated session): " + ", ".join(notes)
    )
    unresolved = check.unresolved_joints()
    if not unresolved:
        return "\n".join(lines), None
    hints = []
    if not check.valid and check.model != "auto":
        hints.append("plan for --passive auto (the coupled and nonlinear terms a real arm's passive moments need)")
    if postures < 2:
        hints.append("record it at a second trunk posture (--trunk-tilt-deg 0 25)")
    hints += ["widen the therapist's ranges where the patient allows", "lengthen the session (--duration)"]
    joints = [f"the {joint}" for joint in unresolved]
    named = joints[0] if len(joints) == 1 else ", ".join(joints[:-1]) + " and " + joints[-1]
    if check.valid:
        head = (
            f"this plan cannot follow the passive curve of {named} within {100 * CURVE_TARGET:g} % for a passive "
            f"moment up to {100 * REALISTIC_PASSIVE_SHARE:g} % of gravity, what relaxed arms show (one simulated "
            "session, above): its curve will be reported with that std"
        )
    else:
        head = (
            f"one simulated session of this plan with --passive {check.model} was not valid (above), so the passive "
            f"curves of {named} are not followed"
        )
    return "\n".join(lines), f"{head}. To follow them: " + ", or ".join(hints)


def _static_moment_text(segment: str, value_kgm: float, std_kgm: float) -> str:
    """``segment +- X %`` of the simulated session, or ``segment not identified`` where it gave no value."""
    if not (math.isfinite(value_kgm) and math.isfinite(std_kgm)) or value_kgm == 0.0:
        return f"{segment} not identified"
    return f"{segment} +- {100 * std_kgm / abs(value_kgm):.2g} %"
