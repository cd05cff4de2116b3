"""Many bags at once: which paths a batch means, a folder of bags expanded to the bags inside."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from bsp_ros.bag.metadata import METADATA_FILE

# What marks a folder as a bag in itself, as `resolve_bag` sees it: its metadata, or the files of a storage it
# refuses by name (so a folder of such bags still gives each one its own row and reason). A folder of plain MCAP
# files without metadata is no bag in itself here: each file is one.
_BAG_MARKS = (METADATA_FILE, "*.db3", "*.mcap.zstd", "*.mcap.lz4", "*.bag")


def _is_one_bag(path: Path) -> bool:
    # A rosbag2 directory (its metadata names its files), or a storage the reader refuses with its reason.
    return any(next(iter(path.glob(mark)), None) is not None for mark in _BAG_MARKS)


def _mcap_files(path: Path) -> list[Path]:
    return sorted(child for child in path.glob("*.mcap") if child.is_file())


def bags_in_dir(path: Path) -> list[Path]:
    """The bags the directory ``path`` stands for: itself where it is a rosbag2 directory (``metadata.yaml``) or a
    refused storage's; else each ``.mcap`` file directly inside and each sub-directory that is a bag (a
    sub-directory of plain ``.mcap`` files: its files), sorted by name; none if it holds no bag."""
    if _is_one_bag(path):
        return [path]
    found = [*_mcap_files(path)]
    for child in sorted(p for p in path.iterdir() if p.is_dir()):
        found.extend([child] if _is_one_bag(child) else _mcap_files(child))
    return sorted(found, key=lambda p: p.name)


def expand_bags(paths: Iterable[Path]) -> list[Path]:
    """The bags meant by ``paths``, in order: a directory that is no bag itself stands for the bags inside it.

    A path that is a file, a rosbag2 directory (with ``metadata.yaml``) or does not exist is kept as given (the
    reader says what is wrong with it). Another directory is replaced by :func:`bags_in_dir`: its ``.mcap`` files,
    each a bag of its own (MCAP files without metadata are one recording each), and its sub-directories that are
    bags; one without any is kept, so its reading says it is not a bag.

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
        out.extend((bags_in_dir(path) or [path]) if path.is_dir() else [path])
    return out


def bag_name(path: Path) -> str:
    """A bag's name for its outputs: the directory's name, or an ``.mcap`` file's name without the suffix."""
    resolved = path.parent if path.name == METADATA_FILE else path
    name = resolved.name or resolved.resolve().name
    return name.removesuffix(".mcap") if resolved.suffix == ".mcap" else name
