"""`bsp simulate`: simulate a rehab cell session and write it as a rosbag2 bag with its truth.json."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import positive_float
from bsp_ros.cli.simulate_errors import option_names
from bsp_ros.errors import InputError


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp simulate`."""
    parser = subparsers.add_parser(
        "simulate",
        help="simulate a session and write it as a bag (+ truth.json)",
        description=(
            "Simulate a rehab cell session (wrench, markers, /tf_static) and write it as a rosbag2 MCAP bag "
            "directory with the ground truth in truth.json. Name the directory after the session, never after "
            "a person."
        ),
    )
    parser.add_argument("--out", required=True, type=Path, metavar="DIR", help="bag directory to create (required)")
    parser.add_argument(
        "--subject",
        choices=("human", "paper-arm"),
        default="human",
        help="3-segment human arm, or the method paper's 2-segment mechanical arm (default: human)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="length in s (default: 120, or the plan's length with --trajectory)",
    )
    parser.add_argument("--wrench-hz", type=float, metavar="HZ", help="wrench rate (default: 100)")
    parser.add_argument("--marker-hz", type=float, metavar="HZ", help="marker frame rate (default: 50)")
    parser.add_argument("--seed", type=int, default=0, metavar="N", help="seed of every random draw (default: 0)")
    _add_motion_arguments(parser)
    _add_human_arguments(parser)
    _add_noise_arguments(parser)
    _add_passive_arguments(parser)
    _add_cell_arguments(parser)
    _add_sensor_arguments(parser)
    _add_tare_arguments(parser)
    return parser


def _add_motion_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the motion group: the robot's motion (sines or a plan) and whether the arm has inertia."""
    motion = parser.add_argument_group("motion and physics")
    motion.add_argument(
        "--inertia",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="rigid-body dynamics M q'' + C q' + tau_G (segment inertias: de Leva for a human, slender bars for "
        "the paper's arm); --no-inertia: quasi-static, as the method paper models it (default: on)",
    )
    motion.add_argument(
        "--speed-scale",
        type=float,
        metavar="X",
        help="run the built-in sines X times faster (periods divided by X) (default: 1)",
    )
    motion.add_argument(
        "--trajectory",
        type=Path,
        metavar="PLAN",
        help="follow a `bsp plan` trajectory (JSON or CSV) instead of the built-in sines (default: the sines)",
    )


def _add_human_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the human subject's group: the body data that scale de Leva's table means."""
    human = parser.add_argument_group("human subject (de Leva table means)")
    human.add_argument("--body-mass", type=positive_float, metavar="KG", help="body mass (default: 75)")
    human.add_argument("--height", type=positive_float, metavar="M", help="stature (default: 1.78)")
    human.add_argument("--sex", choices=("male", "female"), help="table to use (default: male)")


def _add_noise_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the noise group: the sensors' noise and the markers' occlusion."""
    noise = parser.add_argument_group("noise and occlusion")
    noise.add_argument("--force-noise", type=float, metavar="N", help="force noise per axis, N (1 sd) (default: 0.05)")
    noise.add_argument(
        "--torque-noise", type=float, metavar="NM", help="moment noise per axis, Nm (1 sd) (default: 0.005)"
    )
    noise.add_argument(
        "--marker-noise", type=float, metavar="M", help="marker noise per axis, m (1 sd) (default: 0.0001)"
    )
    noise.add_argument(
        "--dropout", type=float, metavar="FRACTION", help="fraction of marker frames lost (0-0.9) (default: 0)"
    )


def _add_passive_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the passive group: the joints' passive moments, one value per joint."""
    passive = parser.add_argument_group("passive joint moments (one value per joint, shoulder first)")
    passive.add_argument(
        "--coulomb",
        type=float,
        nargs="+",
        metavar="NM",
        help="Coulomb amplitudes, Nm (default: 0.5 0.28 0.06, paper arm 0.139 0.161)",
    )
    passive.add_argument(
        "--stiffness", type=float, nargs="+", metavar="NM_PER_RAD", help="stiffnesses, Nm/rad (default: 0)"
    )
    passive.add_argument(
        "--viscous", type=float, nargs="+", metavar="NMS", help="viscous coefficients, Nm s/rad (default: 0)"
    )
    passive.add_argument(
        "--passive-offset", type=float, nargs="+", metavar="NM", help="constant elastic offsets, Nm (default: 0)"
    )
    passive.add_argument(
        "--neutral", type=float, nargs="+", metavar="RAD", help="neutral angles of the stiffness, rad (default: 0)"
    )
    passive.add_argument(
        "--friction-transition",
        type=float,
        metavar="RAD_S",
        help="width of a smooth (tanh) friction transition, rad/s (default: 0, a sign step)",
    )
    passive.add_argument(
        "--stribeck-ratio", type=float, metavar="R", help="friction at rest over the Coulomb level (default: 1, none)"
    )
    passive.add_argument(
        "--stribeck-speed", type=float, metavar="RAD_S", help="Stribeck speed scale, rad/s (default: 0.01)"
    )


def _add_cell_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the cell's nuisances: sensor offsets and drift, the handle, skin markers, spikes, trunk, start."""
    cell = parser.add_argument_group("cell nuisances (sensor frame unless stated)")
    cell.add_argument(
        "--force-offset", type=float, nargs=3, metavar="N", help="F/T force offset at the start, N (default: 0 0 0)"
    )
    cell.add_argument(
        "--torque-offset", type=float, nargs=3, metavar="NM", help="F/T moment offset at the start, Nm (default: 0 0 0)"
    )
    cell.add_argument(
        "--force-drift", type=float, nargs=3, metavar="N_PER_S", help="force offset drift, N/s (default: 0 0 0)"
    )
    cell.add_argument(
        "--torque-drift", type=float, nargs=3, metavar="NM_PER_S", help="moment offset drift, Nm/s (default: 0 0 0)"
    )
    cell.add_argument(
        "--handle-mass", type=float, metavar="KG", help="handle payload between sensor and hand, kg (default: 0)"
    )
    cell.add_argument(
        "--handle-com",
        type=float,
        nargs=3,
        metavar="M",
        help="handle COM from the contact point, sensor frame, m (default: 0 0 0)",
    )
    cell.add_argument(
        "--skin-offset",
        type=float,
        nargs="+",
        metavar="M",
        help="skin marker offsets from the joint centres: (along, normal) per marker, proximal first, m "
        "(default: on the centres)",
    )
    cell.add_argument(
        "--skin-offset-mm",
        type=float,
        metavar="MM",
        help="re-place the skin markers per session: each marker's (along, normal) offset drawn uniformly within "
        "+-MM per axis from --seed, added to --skin-offset (0-100) (default: 0)",
    )
    cell.add_argument(
        "--no-tf-static",
        action="store_true",
        help="leave the sensor's transform out of the bag (/tf_static, or /tf with --sensor-turns) (default: kept)",
    )
    cell.add_argument(
        "--spikes",
        type=float,
        metavar="FRACTION",
        help="fraction of wrench samples that are force spikes (0-0.5) (default: 0)",
    )
    cell.add_argument("--spike-size", type=float, metavar="N", help="spike amplitude, N (default: 1000)")
    cell.add_argument(
        "--trunk-tilt-deg",
        type=float,
        metavar="DEG",
        help="the patient's trunk tilted by this much (deg, in the sense of the shoulder angle: world +y towards +z; "
        "-90..90): the shoulder's passive moment follows the angle to the trunk, and the built-in motion turns with "
        "the trunk (a second posture; bsp identify BAG1 BAG2 --trunk-tilt-deg 0 DEG) (default: 0)",
    )
    cell.add_argument(
        "--start-offset-s",
        type=float,
        metavar="S",
        help="start this many seconds after the default start time (0-86400): a further recording of the same "
        "session (default: 0)",
    )


def _add_sensor_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the F/T sensor's group: its mounting, filter and clock."""
    sensor = parser.add_argument_group("F/T sensor mounting and timing")
    sensor.add_argument(
        "--sensor-turns",
        action="store_true",
        help="the sensor sits on the robot flange and turns with the handle's pitch: the wrench is in the turning "
        "frame and its orientation goes on /tf at every wrench sample (default: fixed, on /tf_static)",
    )
    sensor.add_argument(
        "--robot-handle-pose",
        action="store_true",
        help="the robot publishes the contact point from its kinematics on /robot/handle_pose at every wrench "
        "sample (bsp identify then takes it for the hand marker) (default: not published)",
    )
    sensor.add_argument(
        "--wrench-filter-delay-s",
        type=float,
        metavar="S",
        help="group delay of the sensor's causal low-pass, s (0-1) (default: 0, no filter)",
    )
    sensor.add_argument(
        "--wrench-filter",
        choices=("first-order", "moving-average"),
        help="the low-pass: first-order (time constant = delay) or moving-average (window = 2 x delay) "
        "(default: first-order)",
    )
    sensor.add_argument(
        "--wrench-average",
        action="store_true",
        help="each wrench sample is the mean over its sample period (default: the value at its stamp)",
    )
    sensor.add_argument(
        "--wrench-clock-offset-s",
        type=float,
        metavar="S",
        help="the wrench clock runs this much behind the marker clock: samples are stamped S late (+-1) (default: 0)",
    )


def _add_tare_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the tare group: the cell's tare recording in place of a session."""
    tare = parser.add_argument_group("tare recording (--tare: the handle free, no arm; --duration is its length)")
    tare.add_argument(
        "--tare", action="store_true", help="write the cell's tare recording instead of a session (default: a session)"
    )
    tare.add_argument(
        "--tare-swing",
        type=float,
        nargs=3,
        metavar="DEG",
        help="swing the sensor's roll, pitch, yaw by these amplitudes, deg (default: 0 0 0, at rest)",
    )
    tare.add_argument("--tare-period", type=float, metavar="S", help="period of the swing, s (default: 10)")
    tare.add_argument(
        "--tare-start", type=float, metavar="S", help="start relative to the session start, s (default: -60)"
    )


def _check_option(option: str, value: float | None, lo: float, hi: float, unit: str = "") -> float | None:
    """Return an optional number if it is finite and within ``[lo, hi]``; InputError naming the option."""
    if value is None:
        return None
    if not (math.isfinite(value) and lo <= value <= hi):
        raise InputError(f"{option} must be within [{lo:g}, {hi:g}]{unit}, got {value!r}")
    return value


def _trajectory(args: argparse.Namespace, spec: Any) -> Any:
    """The motion: the cell's sines (sped up by --speed-scale) or the --trajectory plan."""
    speed = _check_option("--speed-scale", args.speed_scale, 1e-3, 100.0)
    if args.trajectory is None:
        return spec.trajectory if speed is None else spec.trajectory.speed_scaled(speed)
    if speed is not None:
        raise InputError("--speed-scale applies to the built-in sines; a --trajectory plan runs at its planned speed")
    from bsp_ros.core.planning import planned_trajectory_from_file

    planned = planned_trajectory_from_file(args.trajectory)
    if planned.n_joints != spec.n_segments:
        raise InputError(
            f"--trajectory {args.trajectory} moves {planned.n_joints} joints; "
            f"--subject {args.subject} has {spec.n_segments}"
        )
    return planned


def _spec(args: argparse.Namespace) -> Any:
    """The CellSpec the options describe (validation is the simulator's, or names the option here).

    The options are checked group by group (subject, sensor, markers, passive moments, motion, trunk, start), so
    that of several bad options the first group's is named.
    """
    spec = _subject_spec(args)
    sensor = _sensor_changes(args)
    markers = _marker_changes(args, spec.n_segments)
    passive = _passive_changes(args, spec.n_segments)
    trajectory = _trajectory(args, spec)
    tilt_deg = _check_option("--trunk-tilt-deg", args.trunk_tilt_deg, -90.0, 90.0) or 0.0
    if tilt_deg and args.trajectory is None:  # the robot moves the arm through the same postures relative to the trunk
        centre = list(trajectory.center_deg)
        centre[0] += tilt_deg
        trajectory = dataclasses.replace(trajectory, center_deg=tuple(centre))
    start_offset_s = _check_option("--start-offset-s", args.start_offset_s, 0.0, 86_400.0) or 0.0
    duration = args.duration
    if duration is None:
        duration = trajectory.duration_s if args.trajectory is not None else 120.0
    return dataclasses.replace(
        spec,
        sensor=dataclasses.replace(spec.sensor, **sensor),
        markers=dataclasses.replace(spec.markers, **markers),
        passive=dataclasses.replace(spec.passive, **passive),
        trajectory=trajectory,
        duration_s=duration,
        seed=args.seed,
        inertia=args.inertia,
        robot_handle_pose=args.robot_handle_pose,
        trunk_tilt_rad=math.radians(tilt_deg),
        start_ns=spec.start_ns + round(start_offset_s * 1e9),
    )


def _subject_spec(args: argparse.Namespace) -> Any:
    """The default CellSpec of ``--subject``: a human arm scaled by the body data given, or the paper's arm.

    Raises
    ------
    InputError
        If body data are given for the paper's mechanical arm.
    """
    from bsp_ros.core import simulation

    if args.subject == "human":
        subject = {
            key: value
            for key, value in (("sex", args.sex), ("body_mass_kg", args.body_mass), ("height_m", args.height))
            if value is not None
        }
        return simulation.human_arm_cell(**subject)
    given = [
        flag
        for flag, value in (("--body-mass", args.body_mass), ("--height", args.height), ("--sex", args.sex))
        if value is not None
    ]
    if given:
        raise InputError(
            f"{', '.join(given)} apply to a human subject only; --subject paper-arm is a fixed mechanical arm"
        )
    return simulation.paper_mechanical_arm_cell()


def _sensor_changes(args: argparse.Namespace) -> dict[str, Any]:
    """The ``SensorSpec`` fields the options set (rates in Hz, noise in N and Nm, offsets, handle, filter, clock).

    Raises
    ------
    InputError
        If ``--wrench-filter-delay-s`` is outside [0, 1] s or ``--wrench-clock-offset-s`` outside [-1, 1] s.
    """
    sensor: dict[str, Any] = {}
    if args.wrench_hz is not None:
        sensor["wrench_hz"] = args.wrench_hz
    if args.force_noise is not None:
        sensor["force_noise_n"] = args.force_noise
    if args.torque_noise is not None:
        sensor["torque_noise_nm"] = args.torque_noise
    for option, key in (
        ("force_offset", "force_bias_n"),
        ("torque_offset", "torque_bias_nm"),
        ("force_drift", "force_drift_n_per_s"),
        ("torque_drift", "torque_drift_nm_per_s"),
        ("handle_com", "handle_com_m"),
    ):
        if getattr(args, option) is not None:
            sensor[key] = tuple(getattr(args, option))
    if args.handle_mass is not None:
        sensor["handle_mass_kg"] = args.handle_mass
    if args.no_tf_static:
        sensor["tf_static"] = False
    if args.spikes is not None:
        sensor["spike_fraction"] = args.spikes
    if args.spike_size is not None:
        sensor["spike_n"] = args.spike_size
    if args.sensor_turns:
        sensor["turns_with_handle"] = True
    delay = _check_option("--wrench-filter-delay-s", args.wrench_filter_delay_s, 0.0, 1.0, " s")
    if delay is not None:
        sensor["filter_delay_s"] = delay
    if args.wrench_filter is not None:
        sensor["filter_kind"] = args.wrench_filter.replace("-", "_")
    if args.wrench_average:
        sensor["average_over_period"] = True
    clock = _check_option("--wrench-clock-offset-s", args.wrench_clock_offset_s, -1.0, 1.0, " s")
    if clock is not None:
        sensor["clock_offset_s"] = clock
    return sensor


def _marker_changes(args: argparse.Namespace, n_segments: int) -> dict[str, Any]:
    """The ``MarkerSpec`` fields the options set (frame rate in Hz, noise in m, dropout, skin offsets in m).

    Parameters
    ----------
    args : the parsed options.
    n_segments : the arm's segments; it carries ``n_segments + 1`` markers.

    Raises
    ------
    InputError
        If ``--skin-offset`` does not give (along, normal) for every marker or ``--skin-offset-mm`` is outside
        [0, 100] mm.
    """
    markers: dict[str, Any] = {}
    if args.marker_hz is not None:
        markers["marker_hz"] = args.marker_hz
    if args.marker_noise is not None:
        markers["noise_m"] = args.marker_noise
    if args.dropout is not None:
        markers["dropout_fraction"] = args.dropout
    if args.skin_offset is not None:
        n_markers = n_segments + 1
        if len(args.skin_offset) != 2 * n_markers:
            raise InputError(
                f"--skin-offset needs {2 * n_markers} values ((along, normal) for each of {n_markers} markers), "
                f"got {len(args.skin_offset)} (a random re-placement within +-MM is --skin-offset-mm MM)"
            )
        markers["skin_offset_m"] = tuple(zip(args.skin_offset[::2], args.skin_offset[1::2], strict=True))
    bound_mm = _check_option("--skin-offset-mm", args.skin_offset_mm, 0.0, 100.0, " mm")
    if bound_mm is not None:
        markers["skin_offset_bound_m"] = bound_mm / 1000.0
    return markers


def _passive_changes(args: argparse.Namespace, n_segments: int) -> dict[str, Any]:
    """The ``PassiveTruth`` fields the options set (friction shape, and per joint: Nm, Nm/rad, Nm s/rad, rad).

    Parameters
    ----------
    args : the parsed options.
    n_segments : the arm's segments, one joint each.

    Raises
    ------
    InputError
        If a per-joint option does not give one value per joint.
    """
    passive: dict[str, Any] = {}
    for option, key in (
        ("friction_transition", "friction_transition_rad_s"),
        ("stribeck_ratio", "stribeck_ratio"),
        ("stribeck_speed", "stribeck_speed_rad_s"),
    ):
        if getattr(args, option) is not None:
            passive[key] = getattr(args, option)
    for option, field in (
        ("coulomb", "coulomb_nm"),
        ("stiffness", "stiffness_nm_per_rad"),
        ("viscous", "viscous_nms"),
        ("passive_offset", "offset_nm"),
        ("neutral", "neutral_rad"),
    ):
        values = getattr(args, option)
        if values is not None:
            if len(values) != n_segments:
                raise InputError(
                    f"--{option.replace('_', '-')} needs {n_segments} values (one per joint) "
                    f"for --subject {args.subject}, got {len(values)}"
                )
            passive[field] = tuple(values)
    return passive


def run(args: argparse.Namespace) -> int:
    """Simulate and write the bag; return the exit code."""
    from bsp_ros.bag import TRUTH_FILE, BagWriteError, write_session_bag
    from bsp_ros.core.simulation import simulate_cell
    from bsp_ros.validation import check_output_dir

    out: Path = args.out
    if out.exists():
        raise BagWriteError(f"{out} exists already: refusing to overwrite (choose another --out)")
    check_output_dir("--out", out)  # before simulating: under a regular file or where nothing can be created
    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    if args.tare:
        session_only = [
            f"--{n.replace('_', '-')}"
            for n in (
                "trajectory",
                "speed_scale",
                "sensor_turns",
                "skin_offset_mm",
                "robot_handle_pose",
                "trunk_tilt_deg",
            )
            if getattr(args, n) is not None and getattr(args, n) is not False
        ]
        if session_only:
            raise InputError(f"{', '.join(session_only)} apply to a session only, not to a --tare recording")
        with option_names():
            tare_spec = _spec(args)
        return _run_tare(args, tare_spec)
    tare_only = [f"--{n.replace('_', '-')}" for n in ("tare_swing", "tare_period", "tare_start") if getattr(args, n)]
    if tare_only:
        raise InputError(f"{', '.join(tare_only)} apply to a tare recording only (add --tare)")
    with option_names():  # the simulator's checks name its spec fields; the user typed options
        spec = _spec(args)
    simulated = simulate_cell(spec)
    samples = _orientation_samples(simulated)
    write_session_bag(
        out,
        simulated.session,
        simulated.truth.to_dict(),
        seed=args.seed,
        tf_static=spec.sensor.tf_static and not spec.sensor.turns_with_handle,
        tf_samples=samples,
    )
    session = simulated.session
    counts = ", ".join(f"{name} {series.t_ns.size}" for name, series in session.markers.items())
    print(
        f"wrote {out} ({session.n_segments} segments, {spec.duration_s:g} s"
        f"{', inertia' if spec.inertia else ', quasi-static'}): wrench {session.wrench.t_ns.size}, "
        f"markers: {counts}"
        + (f", /robot/handle_pose {session.handle_pose.t_ns.size}" if session.handle_pose is not None else "")
        + (f", /tf {len(samples)}" if samples else "")
        + f"; truth in {out / TRUTH_FILE}",
        file=sys.stdout,
    )
    return 0


def _orientation_samples(simulated: Any) -> list[Any]:
    """The turning sensor's orientation, one /tf transform ``world -> sensor`` per wrench sample."""
    import numpy as np

    from msg_adapters import TransformSample, quaternion_from_matrix

    frame = simulated.session.wrench.frame_id
    return [
        TransformSample(int(t), "world", frame, np.zeros(3), quaternion_from_matrix(r))
        for t, r in zip(simulated.tf_t_ns.tolist(), simulated.tf_rotations_world_from_sensor, strict=True)
    ]


def _run_tare(args: argparse.Namespace, spec: Any) -> int:
    """Write the cell's tare recording (wrench, and /tf for a swinging sensor; no markers)."""
    import numpy as np

    from bsp_ros.bag import TRUTH_FILE, write_session_bag
    from bsp_ros.core.simulation import TareSpec, simulate_tare
    from bsp_ros.core.streams import Session
    from msg_adapters import TransformSample, quaternion_from_matrix

    options: dict[str, Any] = {"duration_s": spec.duration_s}
    if args.tare_swing is not None:
        options["swing_rpy_deg"] = tuple(args.tare_swing)
    if args.tare_period is not None:
        options["swing_period_s"] = args.tare_period
    if args.tare_start is not None:
        options["start_offset_s"] = args.tare_start
    with option_names():
        tare_options = TareSpec(**options)
    tare = simulate_tare(spec, tare_options)
    frame = tare.wrench.frame_id
    samples = [
        TransformSample(int(t), "world", frame, np.zeros(3), quaternion_from_matrix(r))
        for t, r in zip(tare.tf_t_ns.tolist(), tare.rotations_world_from_sensor, strict=True)
    ]
    session = Session(wrench=tare.wrench, markers={}, rotation_world_from_sensor=tare.rotation_world_from_sensor)
    # A swinging sensor's orientation is on /tf; a fixed one on /tf_static (unless the bag lost it).
    write_session_bag(
        args.out,
        session,
        tare.truth,
        seed=args.seed,
        tf_static=spec.sensor.tf_static and not samples,
        tf_samples=samples,
    )
    print(
        f"wrote tare recording {args.out} ({spec.duration_s:g} s, wrench {tare.wrench.t_ns.size}, "
        f"/tf {len(samples)}); truth in {args.out / TRUTH_FILE}",
        file=sys.stdout,
    )
    return 0
