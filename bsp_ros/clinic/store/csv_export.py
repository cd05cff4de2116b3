"""Sessions as CSV: one row per session and parameter (long format, for spreadsheets and R)."""

from __future__ import annotations

import csv
from collections.abc import Iterable
from typing import TextIO

from bsp_ros.clinic.store.records import SessionRecord, format_time

CSV_COLUMNS = (
    "subject",
    "session_time_utc",
    "session_time_ns",
    "session_source",
    "method",
    "valid",
    "n_samples",
    "condition_number",
    "warnings",
    "group",
    "part",
    "quantity",
    "value",
    "std",
    "value_source",
)


def write_sessions_csv(records: Iterable[SessionRecord], stream: TextIO) -> int:
    """Write ``records`` to ``stream`` as CSV with a header row.

    Parameters
    ----------
    records : iterable of SessionRecord
        The sessions, in the order to write.
    stream : TextIO
        Open text stream (open files with ``newline=""``).

    Returns
    -------
    int
        Number of data rows written.
    """
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for record in records:
        quality = record.quality
        head = [
            record.subject,
            format_time(record.session_time_ns),
            record.session_time_ns,
            record.source,
            record.method or "",
            int(quality.valid),
            "" if quality.n_samples is None else quality.n_samples,
            "" if quality.condition_number is None else repr(quality.condition_number),
            "; ".join(quality.warnings),
        ]
        for (group, part, quantity), q in record.parameters.items():
            writer.writerow(
                [*head, group, part, quantity, _num(q.value), _num(q.std), q.source],
            )
            rows += 1
    return rows


def _num(value: float | None) -> str:
    return "" if value is None else repr(value)
