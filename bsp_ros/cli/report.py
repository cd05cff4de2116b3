"""`bsp report SUBJECT`: a therapist-readable HTML or PDF report of a subject's sessions, plus PNG and CSV exports."""

from __future__ import annotations

import argparse
from typing import Any

from bsp_ros.errors import InputError


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp report`."""
    parser = subparsers.add_parser(
        "report",
        help="write a subject's report (HTML page, PDF, PNG plots, CSV)",
        description="A plain-language summary first (per joint: passive moment trend and changes beyond the "
        "minimal detectable change), then the arm weight and the support it implies, trends with uncertainty "
        "and anthropometric reference bands, session quality and detail.",
    )
    parser.add_argument("subject", metavar="SUBJECT", help="pseudonymous subject id")
    parser.add_argument("--out", metavar="FILE", help="self-contained HTML report to write")
    parser.add_argument("--pdf", metavar="FILE", help="PDF report to write (for the patient file)")
    parser.add_argument("--png", metavar="DIR", help="also write one PNG plot per parameter into DIR")
    parser.add_argument(
        "--baseline",
        type=int,
        default=0,
        metavar="N",
        help="the first N (>= 2) valid sessions are test-retest baseline sessions: their spread also sets the "
        "standard error of measurement (default 0: within-session cycles only)",
    )
    parser.add_argument("--csv", metavar="FILE", help="also write the plotted numbers as CSV")
    parser.add_argument(
        "--store",
        metavar="LOCATION",
        help="SQLite file or postgresql:// URL (default: $BSP_STORE, else ~/.local/share/bsp_ros/sessions.sqlite)",
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Write the requested outputs; return the exit code."""
    from bsp_ros.clinic.report import analyse, write_csv, write_html, write_pdf, write_pngs  # matplotlib: only when run
    from bsp_ros.clinic.store import open_store

    if not (args.out or args.pdf or args.png or args.csv):
        raise InputError("nothing to write: give --out FILE, --pdf FILE, --png DIR and/or --csv FILE")
    from bsp_ros.validation import check_output_dir, check_output_file

    # Before opening the store and plotting: every output must be writable.
    for option, path in (("--out", args.out), ("--pdf", args.pdf), ("--csv", args.csv)):
        if path:
            check_output_file(option, path)
    if args.png:
        check_output_dir("--png", args.png)
    with open_store(args.store) as store:
        analysis = analyse(args.subject, store.sessions(args.subject), baseline_sessions=args.baseline)
    if args.out:
        print(f"wrote {write_html(analysis, args.out)}")
    if args.pdf:
        print(f"wrote {write_pdf(analysis, args.pdf)}")
    if args.png:
        print(f"wrote {len(write_pngs(analysis, args.png))} plots to {args.png}")
    if args.csv:
        print(f"wrote {write_csv(analysis, args.csv)}")
    changes = analysis.latest_changes
    print(
        f"{len(analysis.sessions)} session(s); the latest valid session changed beyond the MDC95 in "
        f"{len(changes)} comparison(s) (since the previous and since the first session)"
    )
    return 0
