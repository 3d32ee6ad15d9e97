"""Copies of the example study for tests that run it from a temporary folder."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"

_FILE_NAME = re.compile(r'"([^"\s]+\.(?:toml|csv|uff|unv|lvm|mat|nc|h5|hdf5|msh|bdf))"')


def with_absolute_paths(text: str, base: Path = STUDY.parent) -> str:
    """``text`` (a study or structure TOML) with every quoted relative file name that
    exists under ``base`` replaced by its absolute POSIX path, so that a copy of the
    file reads the same files from any folder."""
    def absolute(match: re.Match) -> str:
        path = base / match.group(1)
        return f'"{path.resolve().as_posix()}"' if path.is_file() else match.group(0)

    return _FILE_NAME.sub(absolute, text)
