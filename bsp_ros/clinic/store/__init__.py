"""The session store: identified sessions per pseudonymous subject, in SQLite (default) or PostgreSQL."""

from bsp_ros.clinic.store.csv_export import CSV_COLUMNS, write_sessions_csv
from bsp_ros.clinic.store.estimate import (
    ESTIMATE_SCHEMA,
    WALL_CLOCK_START_NS,
    load_estimate_file,
    parse_estimate,
    parse_time_ns,
)
from bsp_ros.clinic.store.location import default_location, is_database_url
from bsp_ros.clinic.store.records import (
    ParamKey,
    Quality,
    Quantity,
    SessionRecord,
    SubjectRecord,
    SubjectSummary,
    format_time,
)
from bsp_ros.clinic.store.schema import SCHEMA_VERSION
from bsp_ros.clinic.store.store import Store, open_store
from bsp_ros.clinic.store.subject import check_subject_id

__all__ = [
    "CSV_COLUMNS",
    "ESTIMATE_SCHEMA",
    "SCHEMA_VERSION",
    "WALL_CLOCK_START_NS",
    "ParamKey",
    "Quality",
    "Quantity",
    "SessionRecord",
    "Store",
    "SubjectRecord",
    "SubjectSummary",
    "check_subject_id",
    "default_location",
    "format_time",
    "is_database_url",
    "load_estimate_file",
    "open_store",
    "parse_estimate",
    "parse_time_ns",
    "write_sessions_csv",
]
