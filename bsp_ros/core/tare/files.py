"""The tare file: YAML of schema ``bsp_ros/core/tare/1``."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from bsp_ros.core.tare.model import Tare
from bsp_ros.errors import InputError


def write_tare_file(path: str | Path, tare: Tare) -> Path:
    """Write ``tare`` as YAML (schema ``bsp_ros/core/tare/1``); refuse to overwrite."""
    import yaml

    out = Path(path)
    if out.exists():
        raise InputError(f"{out} exists already: refusing to overwrite a tare (choose another --out)")
    out.parent.mkdir(parents=True, exist_ok=True)
    text = "# bsp_ros tare: F/T sensor offset and handle payload (README, Tare)\n"
    text += yaml.safe_dump(tare.to_dict(), sort_keys=False, default_flow_style=None, width=120)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(text, "utf-8")
    tmp.replace(out)
    return out


def read_tare_file(path: str | Path) -> Tare:
    """Read a tare file written by :func:`write_tare_file`.

    Raises
    ------
    InputError
        The file is missing, not YAML, or not a ``bsp_ros/core/tare/1`` document.
    """
    import yaml

    file = Path(path)
    if not file.is_file():
        raise InputError(f"tare file {file} does not exist")
    try:
        data = yaml.safe_load(file.read_text("utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise InputError(f"tare file {file} is not YAML: {error}") from None
    return dataclasses.replace(Tare.from_dict(data), file=file.name)
