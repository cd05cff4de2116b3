"""`bsp sessions`: add identified sessions to the store, list, show, erase and export them."""

from __future__ import annotations

import argparse
from typing import Any

STORE_HELP = "SQLite file or postgresql:// URL (default: $BSP_STORE, else ~/.local/share/bsp_ros/sessions.sqlite)"


def add_store_option(parser: argparse.ArgumentParser, *, sub: bool) -> None:
    """``--store`` on a command (``sub`` False) and on each of its actions: accepted before or after the action."""
    if sub:
        parser.add_argument("--store", metavar="LOCATION", default=argparse.SUPPRESS, help=STORE_HELP)
    else:
        parser.add_argument("--store", metavar="LOCATION", default=None, help=STORE_HELP)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp sessions` and its actions."""
    from bsp_ros.cli.identify_options import add_identify_arguments, add_trunk_tilt_argument

    common = argparse.ArgumentParser(add_help=False)
    add_store_option(common, sub=True)
    parser = subparsers.add_parser(
        "sessions",
        help="keep identified sessions per pseudonymous subject",
        description="Keep identified sessions per pseudonymous subject id (never a name). Sessions are numbered "
        "per subject, 1 = the first in time.",
    )
    add_store_option(parser, sub=False)
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    add = actions.add_parser(
        "add",
        parents=[common],
        help="identify a bag (with every `bsp identify` option) or take a result JSON, and store it",
        description="Store a session: a bag is identified here with the options of `bsp identify` (body data "
        "default to the subject record, see `bsp subjects set`), and its within-session repeatability is kept; "
        "a result JSON keeps the options it was made with. The same recording is stored once; a session time in "
        "the future is refused.",
    )
    add.add_argument(
        "input",
        nargs="+",
        metavar="RESULT.json|BAG",
        help="a `bsp identify --json` result, a bag, or several bags of one session identified together (one per "
        "trunk posture, with --trunk-tilt-deg)",
    )
    add.add_argument("--subject", required=True, metavar="ID", help="pseudonymous subject id [A-Za-z0-9_-]{1,64}")
    add.add_argument(
        "--time",
        metavar="TIME",
        help="session start: a date (2024-03-01), ISO 8601 (2024-03-01T09:30Z, naive = UTC) or epoch seconds; "
        "default: the recording's own stamps",
    )
    add.add_argument("--source", metavar="NAME", help="recording name, if the input lacks it (default: file name)")
    add.add_argument("--arm", choices=("left", "right"), help="the measured arm (default: the subject record's)")
    add.add_argument(
        "--retest",
        action="store_true",
        help="a retest: the same arm measured again on the same day after taking it out of the robot and "
        "re-attaching it; retests set the measurement error that changes are judged by",
    )
    add.add_argument(
        "--cell", default="", metavar="NAME", help="the robot cell (site) recorded in (retests pool per cell)"
    )
    add.add_argument(
        "--allow-identifying-id",
        action="store_true",
        help="store a subject id even though it looks like a person's name or a birth date",
    )
    identification = add.add_argument_group("identification of a bag (as `bsp identify`)")
    add_identify_arguments(identification)
    add_trunk_tilt_argument(identification)
    actions.add_parser("list", parents=[common], help="list subjects and their session counts")
    show = actions.add_parser("show", parents=[common], help="show a subject's sessions and parameters")
    show.add_argument("subject", metavar="SUBJECT")
    show.add_argument("--json", action="store_true", help="print the sessions as JSON")
    remove = actions.add_parser("remove", parents=[common], help="remove one session of a subject (by its number)")
    remove.add_argument("subject", metavar="SUBJECT")
    remove.add_argument("number", type=int, metavar="N", help="the session's number within the subject (1 = first)")
    remove.add_argument("--yes", action="store_true", help="do not ask for confirmation")
    erase = actions.add_parser(
        "erase", parents=[common], help="erase every session and the record of a subject, leaving no bytes"
    )
    erase.add_argument("subject", metavar="SUBJECT")
    erase.add_argument("--yes", action="store_true", help="do not ask for confirmation (needed when not interactive)")
    export = actions.add_parser("export", parents=[common], help="export sessions with their changes as CSV")
    export.add_argument("--csv", required=True, metavar="FILE", help="CSV file to write ('-' for stdout)")
    export.add_argument("--subject", metavar="ID", help="only this subject")
    actions.add_parser("compact", parents=[common], help="rewrite the store so deleted rows leave no bytes")
    return parser


def run(args: argparse.Namespace) -> int:
    """Run one `bsp sessions` action; return the exit code."""
    # The store's modules only where a store is used: every `bsp` command builds this parser.
    from bsp_ros.cli.session_actions import run_action

    return run_action(args)
