"""`bsp report SUBJECT`: a therapist-readable HTML report of a subject's sessions, plus PNG and CSV exports."""

from __future__ import annotations

import argparse
from typing import Any

from bsp_ros.errors import InputError


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp report`."""
    parser = subparsers.add_parser(
        "report",
        help="write a subject's report (HTML page, PNG plots, CSV)",
        description="Trends of every parameter across a subject's sessions, with uncertainty bands, "
        "anthropometric reference bands, flagged changes and session quality.",
    )
    parser.add_argument("subject", metavar="SUBJECT", help="pseudonymous subject id")
    parser.add_argument("--out", metavar="FILE", help="self-contained HTML report to write")
    parser.add_argument("--png", metavar="DIR", help="also write one PNG plot per parameter into DIR")
    parser.add_argument("--csv", metavar="FILE", help="also write the plotted numbers as CSV")
    parser.add_argument(
        "--store",
        metavar="LOCATION",
        help="SQLite file or postgresql:// URL (default: $BSP_STORE, else ~/.local/share/bsp_ros/sessions.sqlite)",
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Write the requested outputs; return the exit code."""
    from bsp_ros.report import analyse, write_csv, write_html, write_pngs  # matplotlib: only when run
    from bsp_ros.store import open_store

    if not (args.out or args.png or args.csv):
        raise InputError("nothing to write: give --out FILE, --png DIR and/or --csv FILE")
    from bsp_ros.validation import check_output_dir, check_output_file

    # Before opening the store and plotting: every output must be writable.
    for option, path in (("--out", args.out), ("--csv", args.csv)):
        if path:
            check_output_file(option, path)
    if args.png:
        check_output_dir("--png", args.png)
    with open_store(args.store) as store:
        analysis = analyse(args.subject, store.sessions(args.subject))
    if args.out:
        print(f"wrote {write_html(analysis, args.out)}")
    if args.png:
        print(f"wrote {len(write_pngs(analysis, args.png))} plots to {args.png}")
    if args.csv:
        print(f"wrote {write_csv(analysis, args.csv)}")
    changes = analysis.changes
    print(f"{len(analysis.sessions)} session(s), {len(changes)} change(s) beyond the uncertainty flagged")
    return 0
