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
        description="A first page that stands alone: who, when, what changed beyond the measurement error "
        "(from same-day retests: `bsp sessions add ... --retest`), the passive-moment trends and the sessions "
        "that need attention; then the detail (static moments, masses, weight support, quality). The PDF is A4; "
        "the HTML prints the same way.",
    )
    parser.add_argument("subject", metavar="SUBJECT", help="pseudonymous subject id")
    parser.add_argument("--out", metavar="FILE", help="self-contained HTML report to write")
    parser.add_argument("--pdf", metavar="FILE", help="PDF report to write (for the patient file)")
    parser.add_argument("--png", metavar="DIR", help="also write one PNG plot per parameter into DIR")
    parser.add_argument("--csv", metavar="FILE", help="also write the plotted numbers as CSV")
    from bsp_ros.cli.sessions import add_store_option

    add_store_option(parser, sub=False)
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
    with open_store(args.store, create=False) as store:
        analysis = analyse(
            args.subject,
            store.sessions(args.subject),
            pool=store.sessions(),
            subject_record=store.subject_record(args.subject),
        )
    if args.out:
        print(f"wrote {write_html(analysis, args.out)}")
    if args.pdf:
        print(f"wrote {write_pdf(analysis, args.pdf)}")
    if args.png:
        print(f"wrote {len(write_pngs(analysis, args.png))} plots to {args.png}")
    if args.csv:
        print(f"wrote {write_csv(analysis, args.csv)}")
    from bsp_ros.clinic.report.summary import headline

    for arm in analysis.arms:
        for sentence in headline(analysis, arm):
            print(sentence)
    return 0
