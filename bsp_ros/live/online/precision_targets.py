"""What a live session is for, from the identifier's parameters: the parameters whose std the precision signal waits
for and each one's target, named one by one (``target_parameters``) or taken from a `bsp plan` JSON (``plan_file``).

A plan predicts, for its motion and duration, the relative std `bsp identify` will report for each parameter whose
nominal value it knows (the static moments; a passive term's nominal is not known beforehand, so it has an absolute
std only). A session that has reached those stds has measured what it was planned for, possibly before its end.
"""

from __future__ import annotations

import json
import math
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

from bsp_ros.core.identification.passive import TERMS, PassiveModel
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError
from bsp_ros.live.online.precision import PrecisionTarget

__all__ = [
    "PLAN_SCHEMA",
    "SEGMENT_QUANTITIES",
    "check_target_parameters",
    "precision_target_from_parameters",
    "targets_from_plan",
]

#: The schema of a `bsp plan` JSON (docs/contract.md, section 8).
PLAN_SCHEMA = "bsp_ros/plan/1"
#: The quantities of a segment a target may name (docs/contract.md, section 4); a joint's are its passive model's.
SEGMENT_QUANTITIES = ("static_moment_kgm", "mass_kg", "com_m", "first_moment_kgm")

Targets = dict[tuple[str, str], float]
#: The node the parameters are of, for the messages.
NAME = "bsp_identifier"


def check_target_parameters(
    text: str, segments: Sequence[str], joints: Sequence[str], joint_quantities: Collection[str]
) -> tuple[tuple[str, str], ...]:
    """The parameters ``text`` names: ``owner.quantity`` joined by commas (``forearm.static_moment_kgm,
    elbow.coulomb_nm``), '' none.

    Parameters
    ----------
    text : the parameter's value.
    segments, joints : the chain's segments and joints.
    joint_quantities : the passive model's parameter keys (``coulomb_nm``...): what a joint's estimate carries.

    Raises
    ------
    ValueError
        Naming the entry that is not ``owner.quantity`` of the chain and the estimate, and what would be.
    """
    out: list[tuple[str, str]] = []
    for entry in (e.strip() for e in text.split(",")):
        if not entry:
            continue
        owner, _, quantity = entry.partition(".")
        if owner in segments:
            known: Collection[str] = SEGMENT_QUANTITIES
        elif owner in joints:
            known = joint_quantities
        else:
            raise ValueError(
                f"{entry!r} names no segment or joint of the chain ({', '.join((*segments, *joints))}); "
                "write owner.quantity, e.g. forearm.static_moment_kgm"
            )
        if quantity not in known:
            raise ValueError(f"{entry!r}: {owner} has no {quantity!r} in the estimate (it has {', '.join(known)})")
        if (owner, quantity) not in out:
            out.append((owner, quantity))
    return tuple(out)


def targets_from_plan(path: str | Path, segments: Sequence[str], window_s: float | None) -> Targets:
    """The relative std a `bsp plan` JSON predicts for each parameter with a known nominal value (its static moments):
    ``{(owner, quantity): relative std (fraction)}``.

    Parameters
    ----------
    path : the plan's JSON file.
    segments : the identifier's chain: the plan must be for the same segments.
    window_s : the span the estimate holds (the windowed mode's window), s; None where it holds the whole session
        (the recursive mode). A window shorter than the plan holds less data than the plan's std is predicted for.

    Raises
    ------
    ValueError
        The file cannot be read, is not a plan, is for another chain, predicts no relative std, or is longer than the
        window; the message names the file and the value.
    """
    try:
        plan = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"cannot read the plan {path}: {error}") from None
    if not isinstance(plan, dict) or plan.get("schema") != PLAN_SCHEMA:
        found = plan.get("schema") if isinstance(plan, dict) else type(plan).__name__
        raise ValueError(f"{path} is not a `bsp plan --json` file (schema {PLAN_SCHEMA}, found {found!r})")
    if list(plan.get("segments") or ()) != list(segments):
        raise ValueError(
            f"the plan {path} is for the segments {plan.get('segments')!r}, the identifier's are {list(segments)!r}"
        )
    duration_s = plan.get("duration_s")
    if window_s is not None and isinstance(duration_s, int | float) and duration_s > window_s + 1e-9:
        raise ValueError(
            f"the plan {path} predicts its std for {duration_s:g} s, the window holds {window_s:g} s: set window_s to "
            f"{duration_s:g} or more (a shorter window would not reach the plan's std)"
        )
    targets = _predicted(plan.get("predicted"), segments)
    if not targets:
        raise ValueError(f"the plan {path} predicts no relative std for a parameter of {list(segments)!r}")
    return targets


def _predicted(rows: Any, segments: Sequence[str]) -> Targets:
    """The plan's ``predicted`` rows with a finite relative std above 0, of the chain's segments."""
    targets: Targets = {}
    for row in rows if isinstance(rows, list) else ():
        if not isinstance(row, dict):
            continue
        owner, quantity, relative = row.get("owner"), row.get("quantity"), row.get("relative_std")
        if owner not in segments or quantity not in SEGMENT_QUANTITIES or not isinstance(relative, int | float):
            continue
        if math.isfinite(relative) and relative > 0:
            targets[(str(owner), str(quantity))] = float(relative)
    return targets


def precision_target_from_parameters(
    p: Mapping[str, Any], target_segments: Sequence[str], passive: PassiveModel, window_s: float | None
) -> PrecisionTarget | None:
    """What the session is for, from the identifier's parameters (None: no target): a plan's predicted relative
    stds (``plan_file``), else each of ``target_parameters`` within ``target_std_percent``, else the static moment of
    each of ``target_segments`` within it; held for ``precision_hold_s``.

    Parameters
    ----------
    p : the checked parameter values (``target_std_percent`` %, ``precision_hold_s`` s, ``target_parameters``,
        ``plan_file``, ``n_segments``).
    target_segments : the checked ``target_segments``.
    passive : the passive model: what a joint's estimate carries.
    window_s : the span each estimate holds, s (None: the whole session, the recursive mode).

    Raises
    ------
    InputError
        A value the parameters do not take, naming the parameter: both a plan and a percentage, an unknown parameter,
        a plan that cannot be read or is for another chain or a longer session than the window.
    """
    percent, hold_s, plan_file = p["target_std_percent"], p["precision_hold_s"], p["plan_file"]
    segments, joints = segments_for(p["n_segments"]), joints_for(p["n_segments"])
    joint_quantities = [TERMS[term][0] for term in passive.terms if term in TERMS]
    try:
        parameters = check_target_parameters(p["target_parameters"], segments, joints, joint_quantities)
    except ValueError as error:
        raise InputError(f"{NAME}: parameter target_parameters: {error}") from None
    if plan_file and (percent > 0.0 or parameters):
        raise InputError(
            f"{NAME}: parameter plan_file gives the targets: leave target_std_percent at 0 and target_parameters "
            f"empty (got {percent:g} and {p['target_parameters']!r})"
        )
    if plan_file:
        try:
            return PrecisionTarget(relative_std=targets_from_plan(plan_file, segments, window_s), hold_s=hold_s)
        except ValueError as error:
            raise InputError(f"{NAME}: parameter plan_file: {error}") from None
    if percent <= 0.0:
        return None
    if parameters:
        return PrecisionTarget(relative_std={key: percent / 100.0 for key in parameters}, hold_s=hold_s)
    return PrecisionTarget.static_moments(percent, target_segments, hold_s=hold_s)
