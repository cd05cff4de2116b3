"""`bsp simulate`: simulate a rehab cell session and write it as a rosbag2 bag with its truth.json."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Any

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
    parser.add_argument("--out", required=True, type=Path, metavar="DIR", help="bag directory to create")
    parser.add_argument(
        "--subject",
        choices=("human", "paper-arm"),
        default="human",
        help="3-segment human arm, or the method paper's 2-segment mechanical arm (default: human)",
    )
    parser.add_argument("--duration", type=float, default=120.0, metavar="S", help="length in s (default 120)")
    parser.add_argument("--wrench-hz", type=float, metavar="HZ", help="wrench rate (default 100)")
    parser.add_argument("--marker-hz", type=float, metavar="HZ", help="marker frame rate (default 50)")
    parser.add_argument("--seed", type=int, default=0, metavar="N", help="seed of every random draw (default 0)")
    human = parser.add_argument_group("human subject (de Leva table means)")
    human.add_argument("--body-mass", type=float, metavar="KG", help="body mass (default 75)")
    human.add_argument("--height", type=float, metavar="M", help="stature (default 1.78)")
    human.add_argument("--sex", choices=("male", "female"), help="table to use (default male)")
    noise = parser.add_argument_group("noise and occlusion")
    noise.add_argument("--force-noise", type=float, metavar="N", help="force noise per axis, N (1 sd)")
    noise.add_argument("--torque-noise", type=float, metavar="NM", help="moment noise per axis, Nm (1 sd)")
    noise.add_argument("--marker-noise", type=float, metavar="M", help="marker noise per axis, m (1 sd)")
    noise.add_argument("--dropout", type=float, metavar="FRACTION", help="fraction of marker frames lost (0-0.9)")
    passive = parser.add_argument_group("passive joint moments (one value per joint, shoulder first)")
    passive.add_argument("--coulomb", type=float, nargs="+", metavar="NM", help="Coulomb amplitudes, Nm")
    passive.add_argument("--stiffness", type=float, nargs="+", metavar="NM_PER_RAD", help="stiffnesses, Nm/rad")
    passive.add_argument("--viscous", type=float, nargs="+", metavar="NMS", help="viscous coefficients, Nm s/rad")
    passive.add_argument("--passive-offset", type=float, nargs="+", metavar="NM", help="constant elastic offsets, Nm")
    passive.add_argument("--neutral", type=float, nargs="+", metavar="RAD", help="neutral angles of the stiffness, rad")
    passive.add_argument(
        "--friction-transition",
        type=float,
        metavar="RAD_S",
        help="width of a smooth (tanh) friction transition, rad/s (default 0: a sign step)",
    )
    passive.add_argument(
        "--stribeck-ratio", type=float, metavar="R", help="friction at rest over the Coulomb level (default 1: none)"
    )
    passive.add_argument("--stribeck-speed", type=float, metavar="RAD_S", help="Stribeck speed scale, rad/s (0.01)")
    cell = parser.add_argument_group("cell nuisances (sensor frame unless stated)")
    cell.add_argument("--force-offset", type=float, nargs=3, metavar="N", help="F/T force offset at the start, N")
    cell.add_argument("--torque-offset", type=float, nargs=3, metavar="NM", help="F/T moment offset at the start, Nm")
    cell.add_argument("--force-drift", type=float, nargs=3, metavar="N_PER_S", help="force offset drift, N/s")
    cell.add_argument("--torque-drift", type=float, nargs=3, metavar="NM_PER_S", help="moment offset drift, Nm/s")
    cell.add_argument("--handle-mass", type=float, metavar="KG", help="handle payload between sensor and hand, kg")
    cell.add_argument(
        "--handle-com", type=float, nargs=3, metavar="M", help="handle COM from the contact point, sensor frame, m"
    )
    cell.add_argument(
        "--skin-offset",
        type=float,
        nargs="+",
        metavar="M",
        help="skin marker offsets from the joint centres: (along, normal) per marker, proximal first, m",
    )
    cell.add_argument(
        "--no-tf-static", action="store_true", help="leave /tf_static out of the bag (the sensor rotation is lost)"
    )
    cell.add_argument(
        "--spikes", type=float, metavar="FRACTION", help="fraction of wrench samples that are force spikes (0-0.5)"
    )
    cell.add_argument("--spike-size", type=float, metavar="N", help="spike amplitude, N (default 1000)")
    tare = parser.add_argument_group("tare recording (--tare: the handle free, no arm; --duration is its length)")
    tare.add_argument("--tare", action="store_true", help="write the cell's tare recording instead of a session")
    tare.add_argument(
        "--tare-swing",
        type=float,
        nargs=3,
        metavar="DEG",
        help="swing the sensor's roll, pitch, yaw by these amplitudes (default 0 0 0: at rest), deg",
    )
    tare.add_argument("--tare-period", type=float, metavar="S", help="period of the swing, s (default 10)")
    tare.add_argument(
        "--tare-start", type=float, metavar="S", help="start relative to the session start, s (default -60)"
    )
    return parser


def _spec(args: argparse.Namespace) -> Any:
    """The CellSpec the options describe (validation is the simulator's)."""
    from bsp_ros.core import simulation

    if args.subject == "human":
        subject = {
            key: value
            for key, value in (("sex", args.sex), ("body_mass_kg", args.body_mass), ("height_m", args.height))
            if value is not None
        }
        spec = simulation.human_arm_cell(**subject)
    else:
        given = [
            flag
            for flag, value in (("--body-mass", args.body_mass), ("--height", args.height), ("--sex", args.sex))
            if value is not None
        ]
        if given:
            raise InputError(
                f"{', '.join(given)} apply to a human subject only; --subject paper-arm is a fixed mechanical arm"
            )
        spec = simulation.paper_mechanical_arm_cell()
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
    markers: dict[str, Any] = {}
    if args.marker_hz is not None:
        markers["marker_hz"] = args.marker_hz
    if args.marker_noise is not None:
        markers["noise_m"] = args.marker_noise
    if args.dropout is not None:
        markers["dropout_fraction"] = args.dropout
    if args.skin_offset is not None:
        n_markers = spec.n_segments + 1
        if len(args.skin_offset) != 2 * n_markers:
            raise InputError(
                f"--skin-offset needs {2 * n_markers} values ((along, normal) for each of {n_markers} markers), "
                f"got {len(args.skin_offset)}"
            )
        markers["skin_offset_m"] = tuple(zip(args.skin_offset[::2], args.skin_offset[1::2], strict=True))
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
            if len(values) != spec.n_segments:
                raise InputError(
                    f"--{option.replace('_', '-')} needs {spec.n_segments} values (one per joint) "
                    f"for --subject {args.subject}, got {len(values)}"
                )
            passive[field] = tuple(values)
    return dataclasses.replace(
        spec,
        sensor=dataclasses.replace(spec.sensor, **sensor),
        markers=dataclasses.replace(spec.markers, **markers),
        passive=dataclasses.replace(spec.passive, **passive),
        duration_s=args.duration,
        seed=args.seed,
    )


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
    spec = _spec(args)
    if args.tare:
        return _run_tare(args, spec)
    tare_only = [f"--{n.replace('_', '-')}" for n in ("tare_swing", "tare_period", "tare_start") if getattr(args, n)]
    if tare_only:
        raise InputError(f"{', '.join(tare_only)} apply to a tare recording only (add --tare)")
    simulated = simulate_cell(spec)
    write_session_bag(
        out, simulated.session, simulated.truth.to_dict(), seed=args.seed, tf_static=spec.sensor.tf_static
    )
    session = simulated.session
    counts = ", ".join(f"{name} {series.t_ns.size}" for name, series in session.markers.items())
    print(
        f"wrote {out} ({session.n_segments} segments, {args.duration:g} s): wrench {session.wrench.t_ns.size}, "
        f"markers: {counts}; truth in {out / TRUTH_FILE}",
        file=sys.stdout,
    )
    return 0


def _run_tare(args: argparse.Namespace, spec: Any) -> int:
    """Write the cell's tare recording (wrench, and /tf for a swinging sensor; no markers)."""
    import numpy as np

    from bsp_ros.bag import TRUTH_FILE, write_session_bag
    from bsp_ros.core.simulation import TareSpec, simulate_tare
    from bsp_ros.core.streams import Session
    from msg_adapters import TransformSample, quaternion_from_matrix

    options: dict[str, Any] = {"duration_s": args.duration}
    if args.tare_swing is not None:
        options["swing_rpy_deg"] = tuple(args.tare_swing)
    if args.tare_period is not None:
        options["swing_period_s"] = args.tare_period
    if args.tare_start is not None:
        options["start_offset_s"] = args.tare_start
    tare = simulate_tare(spec, TareSpec(**options))
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
        f"wrote tare recording {args.out} ({args.duration:g} s, wrench {tare.wrench.t_ns.size}, "
        f"/tf {len(samples)}); truth in {args.out / TRUTH_FILE}",
        file=sys.stdout,
    )
    return 0
