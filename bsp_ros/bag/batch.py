"""Many bags at once: which paths a batch means, a folder of bags expanded to the bags inside."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from bsp_ros.bag.metadata import METADATA_FILE

# What marks a folder as a bag in itself, as `resolve_bag` sees it: its metadata, its MCAP files, or the files
# of a storage it refuses by name (so a folder of such bags still gives each one its own row and reason).
_BAG_MARKS = (METADATA_FILE, "*.mcap", "*.db3", "*.mcap.zstd", "*.mcap.lz4", "*.bag")


def looks_like_bag_dir(path: Path) -> bool:
    """Whether the directory ``path`` holds a bag of its own (``metadata.yaml``, ``.mcap`` files, or another
    storage's files that the reader names when it refuses them)."""
    return any(next(iter(path.glob(mark)), None) is not None for mark in _BAG_MARKS)


def expand_bags(paths: Iterable[Path]) -> list[Path]:
    """The bags meant by ``paths``, in order: a directory that is no bag itself stands for the bags inside it.

    A path that is a file, a bag directory or does not exist is kept as given (the reader says what is wrong
    with it). A directory that is no bag is replaced by its sub-directories that are bags, sorted by name (a
    directory with ``.mcap`` files directly inside is one bag); one without any is kept, so its reading says it
    is not a bag.

    Parameters
    ----------
    paths : iterable of Path
        Bags (rosbag2 directories or ``.mcap`` files) and folders of bags.

    Returns
    -------
    list of Path
        One entry per bag.
    """
    out: list[Path] = []
    for path in paths:
        if not path.is_dir() or looks_like_bag_dir(path):
            out.append(path)
            continue
        inside = sorted(child for child in path.iterdir() if child.is_dir() and looks_like_bag_dir(child))
        out.extend(inside or [path])
    return out


def bag_name(path: Path) -> str:
    """A bag's name for its outputs: the directory's name, or an ``.mcap`` file's name without the suffix."""
    resolved = path.parent if path.name == METADATA_FILE else path
    name = resolved.name or resolved.resolve().name
    return name.removesuffix(".mcap") if resolved.suffix == ".mcap" else name
