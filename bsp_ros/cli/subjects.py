"""`bsp subjects`: what is known of a subject once (body data, measured and affected arm), applied to every session."""

from __future__ import annotations

import argparse
from typing import Any

from bsp_ros.cli.argtypes import positive_float
from bsp_ros.errors import InputError


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp subjects`."""
    from bsp_ros.cli.sessions import add_store_option

    common = argparse.ArgumentParser(add_help=False)
    add_store_option(common, sub=True)
    parser = subparsers.add_parser(
        "subjects",
        help="set a subject's body data and arms once (used for every session's prior and the report)",
        description="The subject record: body mass, height and sex for the anthropometric prior of every "
        "session, the arm measured by default and which arm is affected.",
    )
    add_store_option(parser, sub=False)
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    put = actions.add_parser("set", parents=[common], help="set (or change) fields of a subject record")
    put.add_argument("subject", metavar="ID", help="pseudonymous subject id [A-Za-z0-9_-]{1,64}")
    put.add_argument("--body-mass", type=positive_float, metavar="KG", help="body mass, kg")
    put.add_argument("--height", type=positive_float, metavar="M", help="body height, m")
    put.add_argument("--sex", choices=("male", "female"), help="anthropometric table")
    put.add_argument("--arm", choices=("left", "right"), help="the arm measured by default")
    put.add_argument(
        "--affected", choices=("left", "right", "both", "neither"), help="which arm is affected (e.g. after a stroke)"
    )
    put.add_argument(
        "--allow-identifying-id",
        action="store_true",
        help="store a subject id even though it looks like a person's name or a birth date",
    )
    show = actions.add_parser("show", parents=[common], help="show a subject record")
    show.add_argument("subject", metavar="ID")
    return parser


def _describe(record: Any) -> str:
    fields = [
        f"body mass {record.body_mass_kg:g} kg" if record.body_mass_kg is not None else "body mass not set",
        f"height {record.height_m:g} m" if record.height_m is not None else "height not set",
        f"sex {record.sex}" if record.sex else "sex not set",
        f"measured arm {record.arm}" if record.arm else "measured arm not set",
        f"affected arm {record.affected}" if record.affected else "affected arm not set",
    ]
    return f"{record.subject}: " + ", ".join(fields)


def run(args: argparse.Namespace) -> int:
    """Run one `bsp subjects` action; return the exit code."""
    from bsp_ros.clinic.store import SubjectRecord, open_store
    from bsp_ros.clinic.store.subject import check_pseudonymous_id
    from bsp_ros.errors import StoreError

    if args.action == "set":
        subject = check_pseudonymous_id(args.subject, allow_identifying=args.allow_identifying_id)
        if args.body_mass is not None or args.height is not None or args.sex is not None:
            from bsp_ros.core.anthropometry import check_body_mass_kg, check_height_m

            if args.body_mass is not None:
                check_body_mass_kg(args.body_mass)
            if args.height is not None:
                check_height_m(args.height)
        given = (args.body_mass, args.height, args.sex, args.arm, args.affected)
        if all(value is None for value in given):
            raise InputError("nothing to set: give --body-mass, --height, --sex, --arm and/or --affected")
        with open_store(args.store) as store:
            record = store.set_subject(SubjectRecord(subject, *given))
        print(f"set {_describe(record)}")
        return 0
    with open_store(args.store, create=False) as store:
        known = store.subject_record(args.subject)
    if known is None:
        raise StoreError(f"no subject record of {args.subject}: set one with `bsp subjects set {args.subject} ...`")
    print(_describe(known))
    return 0
