"""Where the session store lives: `$BSP_STORE`, else a per-user SQLite file in the XDG data directory."""

from __future__ import annotations

import os
import re
from pathlib import Path

ENV_VAR = "BSP_STORE"
FILE_NAME = "sessions.sqlite"
_URL_SCHEMES = ("postgresql://", "postgres://")


def default_location() -> str:
    """The store location used when none is given.

    Returns
    -------
    str
        ``$BSP_STORE`` if set and not empty, else ``$XDG_DATA_HOME/bsp_ros/sessions.sqlite``
        (``~/.local/share/bsp_ros/sessions.sqlite`` when ``XDG_DATA_HOME`` is unset).
    """
    configured = os.environ.get(ENV_VAR, "").strip()
    if configured:
        return configured
    data_home = os.environ.get("XDG_DATA_HOME", "").strip()
    base = Path(data_home) if data_home and os.path.isabs(data_home) else Path.home() / ".local" / "share"
    return str(base / "bsp_ros" / FILE_NAME)


def is_database_url(location: str) -> bool:
    """Whether ``location`` names a PostgreSQL server (``postgresql://...``) rather than a SQLite file."""
    return location.strip().lower().startswith(_URL_SCHEMES)


def redact(location: str) -> str:
    """``location`` with any password in a database URL replaced by ``***`` (for messages)."""
    return re.sub(r"(://[^:/@]*:)[^@]*@", r"\1***@", location)
