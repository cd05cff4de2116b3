"""Where a bag's MCAP files are, and which layouts are refused (other storage, whole-file compression)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from bsp_ros.bag.compression import check_message_format, normalized
from bsp_ros.bag.errors import BagCorruptError, BagNotFoundError, NotABagError, UnsupportedBagError
from bsp_ros.bag.mcap_scan import check_mcap_magic
from bsp_ros.bag.metadata import METADATA_FILE, BagMetadata, read_metadata

#: File name endings of rosbag2 layouts this reader refuses, with what they are.
_FOREIGN_FILES = (
    ("*.db3", "rosbag2 sqlite3 storage"),
    ("*.mcap.zstd", "rosbag2 file compression (zstd)"),
    ("*.mcap.lz4", "file compression (lz4)"),
    ("*.bag", "ROS 1 bags"),
)


@dataclass
class BagLayout:
    """The parts of a bag a reader opens.

    Attributes
    ----------
    files : the MCAP files, in order.
    metadata : the parsed ``metadata.yaml``, None without one.
    metadata_path : its path, None without one.
    message_compression : ``""``, or the format (``zstd``, ``lz4``) each message is compressed with.
    warnings, damage : what locating the files noticed (no metadata.yaml; a listed file missing).
    """

    files: list[Path]
    metadata: BagMetadata | None = None
    metadata_path: Path | None = None
    message_compression: str = ""
    warnings: list[str] = field(default_factory=list)
    damage: list[str] = field(default_factory=list)


def resolve_bag(path: str | Path) -> BagLayout:
    """The MCAP files of a bag directory, its ``metadata.yaml`` or a single ``.mcap`` file.

    Raises
    ------
    BagNotFoundError
        ``path`` does not exist.
    NotABagError
        Neither a rosbag2 directory nor an MCAP file.
    UnsupportedBagError
        Another storage (sqlite3 ``.db3``, a ROS 1 bag), whole-file compression (``compression_mode:
        file``, ``.mcap.zstd``) or a per-message compression format other than zstd and lz4.
    BagCorruptError
        ``metadata.yaml`` lists files of which none exists.
    """
    root = Path(path)
    if not root.exists():
        raise BagNotFoundError(str(root))
    if root.is_file():
        if root.name == METADATA_FILE:
            return resolve_bag(root.parent)
        check_mcap_magic(root)  # names sqlite3, ROS 1 and compressed files as unsupported
        return BagLayout([root])
    meta_path = root / METADATA_FILE
    if not meta_path.is_file():
        return _without_metadata(root)
    metadata = read_metadata(meta_path)
    storage = normalized(metadata.storage_identifier)
    if storage not in ("mcap", ""):
        raise UnsupportedBagError(
            f"{root} uses storage {metadata.storage_identifier!r}; only mcap is read "
            "(convert it with `ros2 bag convert` or `rosbags-convert --dst-storage mcap`)"
        )
    mode = normalized(metadata.compression_mode)
    if mode == "file":
        raise UnsupportedBagError(
            f"{root} is file-compressed ({metadata.compression_format or 'unknown format'}); "
            "decompress it first (`ros2 bag decompress`)"
        )
    if mode not in ("", "message"):
        raise UnsupportedBagError(f"{root}: unknown compression_mode {metadata.compression_mode!r}")
    layout = BagLayout([], metadata, meta_path)
    if mode == "message":
        layout.message_compression = check_message_format(metadata.compression_format, str(root))
    for name in metadata.relative_file_paths:
        file = root / name
        if file.is_file():
            check_mcap_magic(file)
            layout.files.append(file)
        else:
            layout.damage.append(f"{name}: listed in {METADATA_FILE} but missing")
    if not layout.files and metadata.relative_file_paths:
        raise BagCorruptError(f"{root}: none of its files {list(metadata.relative_file_paths)} exists")
    return layout


def _without_metadata(root: Path) -> BagLayout:
    files = sorted(root.glob("*.mcap"))
    if files:
        return BagLayout(files, warnings=[f"{root} has no {METADATA_FILE}: expected counts come from the MCAP summary"])
    for pattern, what in _FOREIGN_FILES:
        found = sorted(root.glob(pattern))
        if found:
            raise UnsupportedBagError(
                f"{root} holds {what} ({found[0].name}) and no {METADATA_FILE}; only rosbag2 mcap storage is read "
                "(convert it with `ros2 bag convert` or `rosbags-convert --dst-storage mcap`; decompress first)"
            )
    raise NotABagError(f"{root} is not a bag: it has neither {METADATA_FILE} nor an .mcap file")
