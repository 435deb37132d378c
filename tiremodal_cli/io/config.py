"""Reading option files (TOML or JSON) into plain dictionaries."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from tiremodal_cli.errors import DataFormatError

__all__ = ["load_mapping"]


def load_mapping(path) -> dict:
    """Load a TOML (``.toml``) or JSON (anything else) file into a dict.

    Raises DataFormatError with the file, line and reason when it does not parse.
    """
    path = Path(path)
    if not path.is_file():
        raise DataFormatError(f"{path}: no such file")
    text = path.read_text(encoding="utf-8")
    try:
        if path.suffix.lower() == ".toml":
            data = tomllib.loads(text)
        else:
            data = json.loads(text)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise DataFormatError(f"{path}: cannot parse ({exc})") from None
    if not isinstance(data, dict):
        raise DataFormatError(f"{path}: expected a table/object at the top level")
    return data
