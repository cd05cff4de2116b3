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
    return parser


def _spec(args: argparse.Namespace) -> Any:
    """The CellSpec the options describe (validation is the simulator's)."""
    from bsp_ros import simulation

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
    markers: dict[str, Any] = {}
    if args.marker_hz is not None:
        markers["marker_hz"] = args.marker_hz
    if args.marker_noise is not None:
        markers["noise_m"] = args.marker_noise
    if args.dropout is not None:
        markers["dropout_fraction"] = args.dropout
    passive: dict[str, Any] = {}
    for option, field in (("coulomb", "coulomb_nm"), ("stiffness", "stiffness_nm_per_rad"), ("viscous", "viscous_nms")):
        values = getattr(args, option)
        if values is not None:
            if len(values) != spec.n_segments:
                raise InputError(
                    f"--{option} needs {spec.n_segments} values (one per joint) for --subject {args.subject}, "
                    f"got {len(values)}"
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
    from bsp_ros.simulation import simulate_cell
    from bsp_ros.validation import check_output_dir

    out: Path = args.out
    if out.exists():
        raise BagWriteError(f"{out} exists already: refusing to overwrite (choose another --out)")
    check_output_dir("--out", out)  # before simulating: under a regular file or where nothing can be created
    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    simulated = simulate_cell(_spec(args))
    write_session_bag(out, simulated.session, simulated.truth.to_dict(), seed=args.seed)
    session = simulated.session
    counts = ", ".join(f"{name} {series.t_ns.size}" for name, series in session.markers.items())
    print(
        f"wrote {out} ({session.n_segments} segments, {args.duration:g} s): wrench {session.wrench.t_ns.size}, "
        f"markers: {counts}; truth in {out / TRUTH_FILE}",
        file=sys.stdout,
    )
    return 0
