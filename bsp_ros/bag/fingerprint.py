"""A recording's content fingerprint: the SHA-256 of its data files, the same whichever name or copy it has."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path

BAG_SUFFIXES = (".mcap", ".db3", ".bag")


def content_sha256(path: str | Path) -> str:
    """SHA-256 of a recording's content: the file's bytes, or a directory's data files in name order.

    Written into an estimate's ``session`` block by :func:`bsp_ros.bag.offline.identify_bag`, so the session
    store knows a result JSON and its bag for the same recording (one is refused once the other is stored).
    """
    path = Path(path)
    digest = hashlib.sha256()
    files = sorted(f for f in path.iterdir() if f.suffix.lower() in BAG_SUFFIXES) if path.is_dir() else [path]
    for file in files:
        with file.open("rb") as stream:
            for block in iter(lambda: stream.read(1 << 20), b""):
                digest.update(block)
    return digest.hexdigest()


def recordings_sha256(paths: Sequence[str | Path]) -> tuple[str, list[str]]:
    """The fingerprint of several recordings identified together (their hashes hashed in order), and each one's."""
    hashes = [content_sha256(path) for path in paths]
    return hashlib.sha256("".join(hashes).encode()).hexdigest(), hashes
