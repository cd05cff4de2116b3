"""The judged sessions as CSV: one row per session and parameter, with its changes and the MDC95 used."""

from __future__ import annotations

import csv
from collections.abc import Iterable
from typing import TextIO

from bsp_ros.clinic.report.analysis import MDC_SOURCES, Analysis, Change
from bsp_ros.clinic.store.csv_export import JOIN_COLUMNS, join_cells
from bsp_ros.clinic.store.records import format_time

CSV_COLUMNS = (
    "subject",
    "arm",
    "session_number",
    "session_label",
    "session_time_utc",
    "retest",
    "valid",
    "group",
    "part",
    "quantity",
    "unit",
    "value",
    "std",
    "value_source",
    "change_from_previous",
    "change_from_first",
    "mdc95",
    "mdc95_source",
    "mdc95_pairs",
    "flag_limit",
    "flagged",
    *JOIN_COLUMNS,
    # After the join columns, so every column before keeps its position.
    "session_source",
)


def _num(value: float | None) -> str:
    return "" if value is None else repr(float(value))


def _mdc95_source(step: Change | None, judged: bool) -> str:
    # A step's MDC95 may be the two sessions' own uncertainty (larger than the retest pairs'): say which.
    if step is not None:
        return step.mdc95_source
    return MDC_SOURCES[0] if judged else MDC_SOURCES[2]


def write_analysis_csv(analyses: Iterable[Analysis], stream: TextIO) -> int:
    """Write every session and parameter of ``analyses`` to ``stream``; return the number of data rows.

    ``change_from_previous`` and ``change_from_first`` compare a usable session with the usable session before
    it and with the arm's first usable one (empty for retests, invalid sessions and the first); ``mdc95`` is the
    change it would need to be flagged (empty when unknown: ``mdc95_source`` ``none``) and ``mdc95_source`` says
    what it is: ``retest pairs``, or ``session uncertainty`` where the two sessions' own uncertainty is the larger;
    ``flag_limit`` is the report's limit (:attr:`Change.limit`, set for the number of confirmations it judges) and
    ``flagged`` is 1 for a change from the previous session beyond it that the next session confirmed.
    ``session_number`` is the store's number
    (``bsp sessions show``), ``session_label`` the report's (``3``, ``3a`` for the retest of session 3). The join
    columns (:data:`~bsp_ros.clinic.store.csv_export.JOIN_COLUMNS`) and ``session_source``, the recording's name
    (a bag's directory or file name: the last part of the ``bag`` column of `bsp identify --each --summary`), lead
    a row back to its bag and its summary row.
    """
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for analysis in analyses:
        by_key = {(s.arm, s.key): s for s in analysis.series}
        for record in analysis.sessions:
            joined = join_cells(record)
            for key, quantity in record.parameters.items():
                series = by_key.get((record.arm, key))
                step: Change | None = None
                first: Change | None = None
                if series is not None and not record.retest:
                    step = next((c for c in series.steps if c.after.session_id == record.id), None)
                    usable = [p for p in series.points if p.usable]
                    if usable and step is not None:
                        first_point = usable[0]
                        first = Change(key, first_point, step.after, step.after.value - first_point.value, series.error)  # type: ignore[operator]
                error = series.error if series is not None else None
                judged = series is not None and series.judged and error is not None and error.known
                writer.writerow(
                    [
                        record.subject,
                        record.arm or "",
                        record.number or "",
                        analysis.label_of(record),
                        format_time(record.session_time_ns),
                        int(record.retest),
                        int(record.quality.valid),
                        *key,
                        series.unit if series is not None else "",
                        _num(quantity.value),
                        _num(quantity.std),
                        quantity.source,
                        _num(step.delta if step is not None else None),
                        _num(first.delta if first is not None else None),
                        _num(
                            step.mdc95
                            if step is not None and judged
                            else (error.mdc95_at(quantity.value) if judged and error else None)
                        ),
                        _mdc95_source(step if judged else None, judged),
                        error.n_pairs if error is not None else 0,
                        _num(step.limit if step is not None and judged else None),
                        int(step is not None and judged and step.flagged),
                        *joined,
                        record.source,
                    ]
                )
                rows += 1
    return rows
