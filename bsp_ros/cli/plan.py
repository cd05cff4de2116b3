"""`bsp plan`: design a robot trajectory that makes every reported parameter identifiable."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import (
    finite_float,
    float_within,
    int_within,
    positive_at_most,
    positive_float,
)
from bsp_ros.cli.identify_options import add_placement_arguments, add_zero_arguments
from bsp_ros.errors import InputError

# The planner's own limits (bsp_ros.core.planning), spelled out so the parser needs no numpy (a test keeps them
# equal): a value beyond them is refused by argparse naming the option.
MAX_SPEED_RAD_S = 0.5
MAX_DURATION_S = 86_400.0
NOISE_LIMITS = {"--force-noise": 100.0, "--torque-noise": 10.0, "--marker-noise": 0.1}
MAX_RATE_HZ = 5000.0
MAX_ACCELERATION_RAD_S2 = 5.0

# A static moment predicted less precise than this (relative std, %) makes a session of little use: the report
# could not show a change of a few percent between sessions (its MDC95 is about 2.8 std).
TARGET_STD_PERCENT = 1.0
# `bsp plan` looks for a duration that reaches the target by doubling, up to this factor of the one asked for.
LONGEST_SUGGESTION_FACTOR = 32
LONGEST_SUGGESTION_S = 1800.0


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp plan`."""
    parser = subparsers.add_parser(
        "plan",
        help="plan an identification protocol (trajectory + predicted stds)",
        description=(
            "Design the trajectory the robot imposes on the arm: operating points and direction reversals in "
            "every joint, within the therapist's ranges and the speed limit, optimised so that the static "
            "moments and the passive moments can be told apart. Writes the handle poses in world (y, z, pitch) "
            "and the joint angles over time as JSON and CSV, and prints every parameter's predicted std for the "
            "given sensor noise. Refuses ranges, speeds or sessions it cannot honour, with the value named."
        ),
    )
    _add_arm_arguments(parser)
    _add_limit_arguments(parser)
    _add_session_arguments(parser)
    _add_noise_arguments(parser)
    _add_identify_arguments(parser)
    _add_output_arguments(parser)
    return parser


def _add_arm_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the arm's group: segment lengths or the table's body data, and where the shoulder is."""
    arm = parser.add_argument_group("the arm (segment lengths: measured, a previous estimate, or the table)")
    arm.add_argument(
        "--lengths",
        type=float_within(0.01, 1.0),
        nargs="+",
        metavar="M",
        help="segment lengths shoulder->elbow, elbow->wrist[, wrist->handle centre], m (default: de Leva table "
        "scaled to --height)",
    )
    arm.add_argument(
        "--segments", type=int, choices=(2, 3), default=3, help="segments when --lengths is not given (default 3)"
    )
    arm.add_argument(
        "--height", type=positive_float, default=1.78, metavar="M", help="stature for table lengths, m (default 1.78)"
    )
    arm.add_argument(
        "--body-mass",
        type=positive_float,
        default=75.0,
        metavar="KG",
        help="body mass for the table inertia and static moments the prediction assumes (default 75)",
    )
    arm.add_argument("--sex", choices=("male", "female"), default="male", help="anthropometric table (default male)")
    arm.add_argument(
        "--shoulder",
        type=finite_float,
        nargs=2,
        required=True,
        metavar=("Y", "Z"),
        help="shoulder position in world, m (y anterior, z up)",
    )


def _add_limit_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the therapist's limits: each joint's range and the largest speed."""
    limits = parser.add_argument_group("the therapist's limits (required: never extrapolated)")
    limits.add_argument(
        "--shoulder-range",
        type=finite_float,
        nargs=2,
        required=True,
        metavar=("LOW", "HIGH"),
        help="q1, upper arm from the horizontal, deg (hanging forward-down is negative)",
    )
    limits.add_argument(
        "--elbow-range",
        type=finite_float,
        nargs=2,
        required=True,
        metavar=("LOW", "HIGH"),
        help="q2, forearm relative to the upper arm, deg (kept 5 deg from straight/folded)",
    )
    limits.add_argument(
        "--wrist-range",
        type=finite_float,
        nargs=2,
        metavar=("LOW", "HIGH"),
        help="q3, hand relative to the forearm, deg (required for 3 segments)",
    )
    limits.add_argument(
        "--max-speed",
        type=positive_at_most(MAX_SPEED_RAD_S),
        default=0.03,
        metavar="RAD_S",
        help="largest joint speed, rad/s (default 0.03: quasi-static)",
    )


def _add_session_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the session's group: its length, postures, passive model, precision target and optimiser."""
    session = parser.add_argument_group("the session")
    session.add_argument(
        "--duration",
        type=positive_at_most(MAX_DURATION_S),
        default=120.0,
        metavar="S",
        help="session length, s (default 120)",
    )
    session.add_argument(
        "--passive",
        default="coulomb+offset+stiffness",
        metavar="MODEL",
        help="passive model to identify: coulomb, coulomb+offset, coulomb+offset+stiffness, auto (the data choose "
        "nonlinear and two-joint elastic terms, as bsp identify --passive auto) or any bsp identify --passive model; "
        "with elastic terms one simulated session of the plan says how closely it follows each joint's passive "
        "curve (default coulomb+offset+stiffness)",
    )
    session.add_argument(
        "--trunk-tilt-deg",
        type=float_within(-90.0, 90.0),
        nargs="+",
        metavar="DEG",
        default=[0.0],
        help="record the plan once per trunk posture (the same motion relative to the trunk; deg, in the sense of "
        "the shoulder angle) and identify the recordings together (bsp identify BAG1 BAG2 --trunk-tilt-deg ...): "
        "a second posture separates elastic passive moments from gravity (default: 0, one upright recording)",
    )
    session.add_argument(
        "--target-std",
        type=positive_float,
        default=TARGET_STD_PERCENT,
        metavar="PERCENT",
        help="warn when a static moment's predicted relative std (the total bsp identify will report: sensor noise, "
        "marker placement, sensor zero, model choice) exceeds this, and say which duration reaches it or which "
        f"term no duration shrinks (default {TARGET_STD_PERCENT:g} %%)",
    )
    _add_motion_arguments(session)


def _add_motion_arguments(session: argparse._ArgumentGroup) -> None:
    """Add to the session's group how the motion is shaped: operating points, amplitudes, objective, a faster
    motion for the inertias, two speeds, the optimiser's budget."""
    session.add_argument(
        "--operating-points",
        type=int_within(1, 20),
        metavar="K",
        help="operating points (1-20; default: the best of 1, 2 and 3)",
    )
    session.add_argument(
        "--amplitude",
        type=positive_float,
        nargs="+",
        metavar="DEG",
        help="oscillation amplitude per joint about each operating point, deg (default optimised)",
    )
    session.add_argument(
        "--objective",
        choices=("d-optimal", "static"),
        default="d-optimal",
        help="d-optimal: log-determinant of the predicted covariance; static: largest predicted "
        "relative std of the static moments (default d-optimal)",
    )
    session.add_argument(
        "--excite-inertia",
        action="store_true",
        help="plan a faster motion that excites the arm's inertia (two sines per joint at the speed limit, the "
        "fastest period from --max-acceleration, at least 2 s): the grouped segment inertias are identified from "
        "the data; their std is predicted from one simulated session (give --max-speed, e.g. 0.15)",
    )
    session.add_argument(
        "--speeds",
        type=positive_at_most(MAX_SPEED_RAD_S),
        nargs=2,
        metavar=("SLOW", "FAST"),
        help="a two-speed session: the motion first at SLOW (below a reflex threshold), then the same angles at FAST "
        "(at most --max-speed), each the peak joint speed in rad/s and the fast part as long as the slow one; bsp "
        "identify then reports the speed-dependent (neural) resistance apart from the passive part "
        "(speed_dependence). FAST must be 2 to 8 times SLOW, e.g. --max-speed 0.12 --speeds 0.03 0.12",
    )
    session.add_argument(
        "--max-acceleration",
        type=positive_at_most(MAX_ACCELERATION_RAD_S2),
        default=0.3,
        metavar="RAD_S2",
        help="largest joint acceleration with --excite-inertia, rad/s^2 (default 0.3)",
    )
    session.add_argument(
        "--max-evaluations",
        type=int_within(10, 100_000),
        default=400,
        metavar="N",
        help="optimiser budget per number of operating points (default 400)",
    )


def _add_noise_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the sensor noise and rates the predicted stds assume."""
    noise = parser.add_argument_group("sensor noise for the predicted stds")
    noise.add_argument(
        "--force-noise",
        type=float_within(0.0, NOISE_LIMITS["--force-noise"]),
        default=0.05,
        metavar="N",
        help="force noise per axis, N (default 0.05)",
    )
    noise.add_argument(
        "--torque-noise",
        type=float_within(0.0, NOISE_LIMITS["--torque-noise"]),
        default=0.005,
        metavar="NM",
        help="moment noise per axis, Nm (default 0.005)",
    )
    noise.add_argument(
        "--marker-noise",
        type=float_within(0.0, NOISE_LIMITS["--marker-noise"]),
        default=1e-4,
        metavar="M",
        help="marker noise per axis, m (default 1e-4)",
    )
    noise.add_argument(
        "--wrench-hz", type=positive_at_most(MAX_RATE_HZ), default=100.0, metavar="HZ", help="wrench rate (default 100)"
    )
    noise.add_argument(
        "--marker-hz",
        type=positive_at_most(MAX_RATE_HZ),
        default=50.0,
        metavar="HZ",
        help="marker frame rate (default 50)",
    )


def _add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the output group: the plan's files and its publication on ROS 2."""
    out = parser.add_argument_group("output")
    out.add_argument(
        "--json", type=Path, metavar="FILE", help="write the plan (knots, samples, predicted stds) as JSON"
    )
    out.add_argument(
        "--csv", type=Path, metavar="FILE", help="write t, joint angles and velocities, handle y z pitch as CSV"
    )
    out.add_argument(
        "--rate", type=positive_float, default=10.0, metavar="HZ", help="sample rate of the files, Hz (default 10)"
    )
    out.add_argument(
        "--publish",
        action="store_true",
        help="publish trajectory_msgs/JointTrajectory and nav_msgs/Path (latched) with rclpy until Ctrl-C",
    )
    out.add_argument(
        "--topic-prefix",
        default="bsp/plan",
        metavar="NS",
        help="topics NS/joint_trajectory and NS/handle_path (default bsp/plan)",
    )
    out.add_argument("--frame-id", default="world", metavar="FRAME", help="frame of the handle path (default world)")
    out.add_argument(
        "--plane-x",
        type=finite_float,
        default=0.0,
        metavar="M",
        help="x of the movement plane (the shoulder's x) for the published path, m (default 0)",
    )


def _add_identify_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of `bsp identify` the predicted std depends on (the same names and defaults)."""
    group = parser.add_argument_group(
        "how the sessions will be identified (the predicted std holds what bsp identify's will)"
    )
    add_placement_arguments(group)
    group.add_argument(
        "--robot-handle-pose",
        action="store_true",
        help="the contact point will come from the robot's handle pose (/robot/handle_pose), not a skin marker",
    )
    group.add_argument(
        "--tare",
        action="store_true",
        help="the sessions will be tared (bsp tare, then bsp identify --tare FILE): the zero's share is a tare's "
        "(a recording at rest), not --zero-sd-n/--zero-sd-nm",
    )
    add_zero_arguments(group)


def _session(args: argparse.Namespace) -> Any:
    """The :class:`~bsp_ros.core.planning.budget.SessionSpec` of the identify options."""
    from bsp_ros.core.pipeline import IdentifyOptions
    from bsp_ros.core.planning.budget import SessionSpec

    identify = IdentifyOptions(
        marker_placement_sd_m=args.marker_placement_sd_mm / 1000.0,
        handle_pose_sd_m=args.handle_pose_sd_mm / 1000.0,
        zero_sd_n=args.zero_sd_n,
        zero_sd_nm=args.zero_sd_nm,
    )
    return SessionSpec(identify=identify, tared=args.tare, contact_from_robot=args.robot_handle_pose)


def _request(args: argparse.Namespace) -> Any:
    from bsp_ros.core.anthropometry import length_from_height_m
    from bsp_ros.core.identification.passive import PassiveModel
    from bsp_ros.core.planning import JointLimits, NoiseSpec, NominalArm, PlanRequest
    from bsp_ros.core.streams import segments_for

    if args.lengths:
        lengths = tuple(args.lengths)
    else:
        lengths = tuple(length_from_height_m(args.sex, name, args.height) for name in segments_for(args.segments))
    n = len(lengths)
    if args.lengths and n not in (2, 3):
        raise InputError(f"--lengths takes 2 or 3 segment lengths (m), got {n}")
    for option, pair in (("--shoulder-range", args.shoulder_range), ("--elbow-range", args.elbow_range)):
        _check_range(option, pair)
    if args.wrist_range is not None:
        _check_range("--wrist-range", args.wrist_range)
    if args.amplitude and len(args.amplitude) != n:
        raise InputError(f"--amplitude takes one value per joint ({n}, shoulder first), got {len(args.amplitude)}")
    try:
        passive = PassiveModel.parse(args.passive)
    except InputError as error:
        raise InputError(f"--passive {args.passive}: {error}") from None
    ranges = [tuple(args.shoulder_range), tuple(args.elbow_range)]
    if n == 3:
        if args.wrist_range is None:
            raise InputError("a 3-segment arm needs --wrist-range LOW HIGH (deg): the planner never assumes a limit")
        ranges.append(tuple(args.wrist_range))
    elif args.wrist_range is not None:
        raise InputError("--wrist-range given for a 2-segment chain (no wrist)")
    return PlanRequest(
        nominal=NominalArm.from_anthropometry(lengths, args.sex, args.body_mass),
        shoulder_yz_m=tuple(args.shoulder),
        limits=JointLimits(tuple(ranges), args.max_speed),
        duration_s=args.duration,
        passive=passive,
        n_points=args.operating_points,
        amplitude_deg=tuple(args.amplitude) if args.amplitude else None,
        noise=NoiseSpec(args.force_noise, args.torque_noise, args.marker_noise, args.wrench_hz, args.marker_hz),
        objective=args.objective,
        max_evaluations=args.max_evaluations,
        trunk_tilts_rad=tuple(math.radians(t) for t in args.trunk_tilt_deg),
        session=_session(args),
    )


def _check_range(option: str, pair: list[float]) -> None:
    if not pair[0] < pair[1]:
        raise InputError(f"{option} takes LOW HIGH with LOW < HIGH (deg), got {pair[0]:g} {pair[1]:g}")


def worst_static_std_percent(plan: Any) -> tuple[str, float]:
    """The static moment with the largest predicted relative std (the total `bsp identify` will report), and that
    std in %."""
    rows = [r for r in plan.reported.table() if r["quantity"] == "static_moment_kgm" and r["relative_std"]]
    worst = max(rows, key=lambda r: r["relative_std"])
    return worst["owner"], 100.0 * float(worst["relative_std"])


def duration_free_excess(plan: Any, target_percent: float) -> tuple[str, float, str] | None:
    """The static moment whose terms a longer session does not shrink (marker placement, sensor zero) exceed
    ``target_percent`` alone, their relative std in % and the larger of them; None where none does."""
    from bsp_ros.core.planning.budget import DURATION_FREE_TERMS

    budget = plan.reported
    free = budget.duration_free_std()
    picks = [i for i, (key, _) in enumerate(budget.names) if key == "static_moment_kgm"]
    percent = {i: 100.0 * float(free[i] / abs(budget.nominal[i])) for i in picks}
    worst = max(picks, key=lambda i: percent[i])
    if not percent[worst] > target_percent:
        return None
    shares = budget.contributions(worst)
    term = max((str(t) for t in DURATION_FREE_TERMS if str(t) in shares), key=lambda t: shares[t])
    return budget.names[worst][1], percent[worst], term


def precision_warning(plan: Any, target_percent: float, replan: Any) -> str | None:
    """A warning when the plan's static moments fall short of ``target_percent``, naming a duration that does not.

    ``replan(duration_s)`` plans the same request for another duration (an InputError if it cannot); the
    durations tried double from the one asked for, so the duration named was planned and predicted, not guessed.
    Where the marker placement and the sensor zero alone exceed the target, no duration is tried: they do not
    shrink with the session's length (measured on the default plan: 4.37, 4.39, 4.39 % at 120, 240, 480 s).
    """
    from bsp_ros.core.identification.ledger import Term

    owner, worst = worst_static_std_percent(plan)
    if worst <= target_percent:
        return None
    asked = plan.request.duration_s
    head = (
        f"this plan cannot reach useful precision: the {owner}'s static moment is predicted to +- {worst:.3g} % "
        f"(1 std, as bsp identify will report it; target {target_percent:g} %)"
    )
    excess = duration_free_excess(plan, target_percent)
    if excess is not None:
        where, percent, term = excess
        return (
            f"{head}; no session length reaches it: the {where}'s marker placement and sensor zero alone give "
            f"{percent:.3g} %, mostly {term}, and a longer session does not shrink them: {Term(term).remedy}, and "
            "bsp plan --tare or --marker-placement-sd-mm predicts the std then"
        )
    duration = asked
    while duration < min(LONGEST_SUGGESTION_FACTOR * asked, LONGEST_SUGGESTION_S):
        duration = min(2 * duration, LONGEST_SUGGESTION_S)
        try:
            longer = replan(duration)
        except InputError:
            continue
        _, worst_then = worst_static_std_percent(longer)
        if worst_then <= target_percent:
            return (
                f"{head}; a {duration:.0f} s session reaches {worst_then:.3g} % (planned with the same options: "
                f"--duration {duration:.0f})"
            )
    return _no_duration_warning(plan, head, owner, duration)


def _no_duration_warning(plan: Any, head: str, owner: str, duration: float) -> str:
    """The warning where no session up to ``duration`` (s) reaches the target: why, and what would."""
    passive = plan.request.passive
    if passive.select or "stiffness" in passive.terms:
        # In one vertical plane a joint's gravity torque is a smooth function of the joint angles, as the elastic
        # moments are: no motion in that plane separates them, only a change of gravity's direction does.
        return (
            f"{head}; no session up to {duration:.0f} s reaches it: with elastic passive moments (--passive "
            f"{passive.label}) the {owner}'s gravity torque is a smooth function of the joint angles in this plane, "
            "as the elastic moment is, and no motion in the plane separates them. Widen the ranges, or record the "
            "plan a second time with the trunk tilted (--trunk-tilt-deg 0 25 predicts it; bsp identify UPRIGHT "
            "TILTED --trunk-tilt-deg 0 25 identifies both), or identify with the Coulomb model, which assumes no "
            "elastic moment and says when the data refute it"
        )
    return f"{head}; no session up to {duration:.0f} s reaches it: widen the ranges or reduce the sensor noise"


def format_plan(plan: Any) -> str:
    """The plan summary and predicted std table, as printed."""
    from bsp_ros.core.streams import joints_for

    joints = joints_for(plan.request.nominal.n_joints)
    lines = [
        f"planned {plan.trajectory.duration_s:.0f} s, {plan.centres_deg.shape[0]} operating point(s), "
        f"passive model {plan.request.passive.label}"
        + (
            f", recorded at trunk tilts {', '.join(f'{math.degrees(t):g}' for t in plan.request.trunk_tilts_rad)} deg "
            f"({plan.trajectory.duration_s:.0f} s each)"
            if len(plan.request.trunk_tilts_rad) > 1
            else ""
        ),
        "operating points (deg): " + "; ".join(", ".join(f"{v:.1f}" for v in row) for row in plan.centres_deg),
        "amplitudes (deg): " + ", ".join(f"{j} {a:.1f}" for j, a in zip(joints, plan.amplitudes_deg, strict=True)),
        "peak speed (rad/s): "
        + ", ".join(f"{j} {v:.4f}" for j, v in zip(joints, plan.trajectory.peak_speed_rad_s, strict=True)),
        "inertial / gravity torque (anthropometric inertia): "
        + ", ".join(f"{j} {100 * r:.3f}%" for j, r in zip(joints, plan.inertia_ratio, strict=True)),
        f"predicted condition number {plan.prediction.condition_number:.3g}",
        *_choice_lines(plan),
        _assumptions_line(plan),
        f"{'parameter':36s} {'nominal':>10s} {'predicted std':>14s} {'largest term':>27s} {'relative':>9s}",
    ]
    budget = plan.reported
    for i, row in enumerate(budget.table()):
        nominal = "" if row["nominal"] is None else f"{row['nominal']:.4g}"
        relative = "" if row["relative_std"] is None else f"{100 * row['relative_std']:.3f}%"
        term, sd = budget.largest_term(i)
        largest = f"{term} {sd:.3g}"
        name = row["quantity"] + "/" + row["owner"]
        lines.append(f"{name:36s} {nominal:>10s} {row['std']:14.3g} {largest:>27s} {relative:>9s}")
    lines += [f"note: {note}" for note in plan.notes]
    return "\n".join(lines)


def _choice_lines(plan: Any) -> list[str]:
    """With ``--passive auto``, which model the predicted std is of and why another arm may differ."""
    choice = plan.auto_choice
    if choice is None:
        return []
    left = ", ".join(model.label for model in choice.open_models) or "none"
    valid = "" if choice.check_valid else " (that session's estimate was not valid: see below)"
    return [
        f"passive model auto: on the nominal arm (the cell's nonlinear, coupled passive moments, one simulated session)"
        f" bsp identify chooses {choice.chosen.label}{valid}; the predicted std is that model's, with the spread of "
        f"the models the data left open ({left}) as bsp identify adds it, on average over sessions",
        "  another arm (stiffer or more nonlinear passive moments) may choose another model, with another std; one "
        "session's model-choice term is one draw of that spread and may come out several times smaller or larger",
    ]


def _assumptions_line(plan: Any) -> str:
    """What the predicted std assumes of the session beside its sensor noise, in one line."""
    session = plan.request.session
    identify = session.identify
    zero_n, zero_nm = session.zero_sd(plan.request.noise)
    zero = "tared" if session.tared else f"untared, zero {zero_n:g} N / {zero_nm:g} Nm"
    contact = (
        f"contact point from the robot {1e3 * identify.handle_pose_sd_m:g} mm"
        if session.contact_from_robot
        else "contact point a skin marker"
    )
    return (
        f"predicted std: what bsp identify will report (sensor noise, markers {1e3 * identify.marker_placement_sd_m:g}"
        f" mm, {contact}, sensor {zero}{', model choice' if plan.request.passive.select else ''})"
    )


def inertia_lines(plan: Any, args: argparse.Namespace) -> str:
    """The grouped inertias' std one simulated session of ``plan`` reports (the table arm of --height, tared)."""
    from bsp_ros.core.planning import simulated_inertia_std
    from bsp_ros.core.simulation import SubjectTruth

    n = plan.request.nominal.n_joints
    subject = SubjectTruth.from_anthropometry(args.sex, args.body_mass, args.height, n)
    found = simulated_inertia_std(plan, subject)
    lines = ["grouped inertia, std of one simulated session (table arm, tared sensor, skin markers 2 mm):"]
    for segment, (value, std, source) in found.items():
        lines.append(f"  {segment:10s} {value:.4g} kg m^2 +- {100 * std / abs(value):.2g}% ({source})")
    # The plan file carries it too (its notes), for the cell that loads the plan rather than reading the console.
    plan.notes.append(
        "grouped inertia std predicted by one simulated session: "
        + ", ".join(f"{s} {100 * std / abs(v):.2g}% ({source})" for s, (v, std, source) in found.items())
    )
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Plan, write the files, print the predicted stds; publish on request."""
    from bsp_ros.core.planning import plan_inertia_protocol, plan_protocol, write_plan_csv, write_plan_json

    request = _request(args)
    if args.excite_inertia and (args.amplitude or args.operating_points):
        raise InputError("--excite-inertia designs its own motion: leave out --amplitude and --operating-points")
    if args.excite_inertia and args.speeds:
        raise InputError("--excite-inertia designs its own motion: leave out --speeds")

    def planner(req: Any) -> Any:
        if args.speeds:
            from bsp_ros.core.planning.two_speed import plan_two_speed

            return plan_two_speed(req, args.speeds[0], args.speeds[1], plan_protocol)
        return plan_inertia_protocol(req, args.max_acceleration) if args.excite_inertia else plan_protocol(req)

    plan = planner(request)
    print(format_plan(plan))
    if args.excite_inertia:
        print(inertia_lines(plan, args))
    warnings = []
    if request.passive.select or "stiffness" in request.passive.terms:
        from bsp_ros.cli.plan_passive import passive_check_lines

        text, curve_warning = passive_check_lines(plan, args)
        print(text)
        warnings += [curve_warning] if curve_warning else []
    warning = precision_warning(
        plan, args.target_std, lambda duration_s: planner(dataclasses.replace(request, duration_s=duration_s))
    )
    warnings = ([warning] if warning is not None else []) + warnings
    if warnings:
        sys.stdout.flush()  # the table first, then the warnings, when both go to a terminal
        for text in warnings:
            print(f"warning: {text}", file=sys.stderr)
    if args.json:
        write_plan_json(args.json, plan, args.rate)
        print(f"wrote {args.json}")
    if args.csv:
        write_plan_csv(args.csv, plan, args.rate)
        print(f"wrote {args.csv}")
    if args.publish:
        _publish(plan, args)
    sys.stdout.flush()
    return 0


def _publish(plan: Any, args: argparse.Namespace) -> None:
    """Publish the plan latched (reliable, transient local, depth 1) with plain rclpy until Ctrl-C.

    A cell that starts later still receives it: that is the "on request" behaviour without a service.
    """

    import rclpy  # only here: offline `bsp plan` never imports rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from bsp_ros.core.planning.files import sampled_path
    from bsp_ros.core.streams import joints_for
    from bsp_ros.live.runtime.ros import message_class as get_message
    from msg_adapters.trajectory import build_handle_path, build_joint_trajectory

    rclpy.init()
    node = rclpy.create_node("protocol_publisher")
    try:
        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        prefix = args.topic_prefix.rstrip("/")
        joint_pub = node.create_publisher(
            get_message("trajectory_msgs/msg/JointTrajectory"), f"{prefix}/joint_trajectory", latched
        )
        path_pub = node.create_publisher(get_message("nav_msgs/msg/Path"), f"{prefix}/handle_path", latched)
        samples = sampled_path(plan, args.rate)
        start_ns = node.get_clock().now().nanoseconds
        joints = joints_for(plan.request.nominal.n_joints)
        joint_pub.publish(
            build_joint_trajectory(
                get_message, start_ns, joints, samples["t_s"], samples["q_rad"], samples["qdot_rad_s"]
            )
        )
        path_pub.publish(
            build_handle_path(get_message, start_ns, args.frame_id, samples["t_s"], samples["handle"], args.plane_x)
        )
        print(f"publishing {prefix}/joint_trajectory and {prefix}/handle_path (latched); Ctrl-C to stop", flush=True)
        # Not rclpy.spin: a SIGTERM that shuts the context down while its wait is being set up left spin() waiting
        # for ever (1 in 6-10 runs on a loaded machine; `test_plan.py`'s publisher); a short wait sees it.
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
