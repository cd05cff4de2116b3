"""Sessions as CSV: one row per session and parameter (long format, for spreadsheets and R).

The last columns (:data:`JOIN_COLUMNS`) join a row back to the recording and the run it came from: the
recording's content hash is the `content_sha256` column of `bsp identify --each --summary`.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable
from typing import TextIO

from bsp_ros.clinic.store.records import SessionRecord, format_time

_SESSION_COLUMNS = (
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
#: Last, so a reader that takes the columns by position finds the others where they were.
JOIN_COLUMNS = (
    "content_sha256",
    "passive_model_configured",
    "tare_applied",
    "tare_file",
    "estimate_schema",
    "bsp_ros_version",
    "passive_model",
)
CSV_COLUMNS = (*_SESSION_COLUMNS, *JOIN_COLUMNS)


def join_cells(record: SessionRecord) -> list[str]:
    """The :data:`JOIN_COLUMNS` cells of ``record``: what joins its rows back to the recording and the run.

    ``content_sha256`` is the recording's fingerprint (a bag's, or its estimate's for a result JSON without one);
    ``passive_model_configured`` the passive model the identification was configured with (``coulomb`` for the
    default, which falls back to an elastic model where the data reject it); ``tare_applied`` 1 or 0;
    ``estimate_schema`` the estimate's schema tag; ``bsp_ros_version`` the version that made the estimate;
    ``passive_model`` the model it used (``auto``'s or the fallback's choice; the ``passive_model`` column of
    `bsp identify --each --summary`). The last two are empty for a session stored before they were kept.
    """
    passive = record.config.get("passive")
    return [
        record.content_sha256 or "",
        "" if passive is None else str(passive),
        str(int(record.quality.tare_applied)),
        record.quality.tare_file or "",
        record.estimate_schema,
        str(record.config.get("bsp_ros_version", "")),
        record.passive_model or "",
    ]


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
        joined = join_cells(record)
        for (group, part, quantity), q in record.parameters.items():
            writer.writerow(
                [*head, group, part, quantity, _num(q.value), _num(q.std), q.source, *joined],
            )
            rows += 1
    return rows


def _num(value: float | None) -> str:
    return "" if value is None else repr(value)
