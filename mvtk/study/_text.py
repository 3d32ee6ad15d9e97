"""Reading the text files of a study (study and structure TOML) with encoding detection."""

from __future__ import annotations

import codecs
import tomllib
from pathlib import Path

from .._atomic import special_file
from ..errors import ConfigError

__all__ = ["read_text", "read_toml"]

_BOMS = ((codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"),
         (codecs.BOM_UTF16_BE, "utf-16"))


def read_text(path: str | Path, what: str = "file") -> str:
    """Text of ``path``: UTF-8, UTF-8 with a BOM, or UTF-16 with a BOM.

    Raises
    ------
    ConfigError
        Missing file, a directory, or bytes that are not text in these encodings (the
        message names the byte, its offset, line and column).
    OSError
        Other operating-system errors (permissions, symlink loops); ``filename`` is set.
    """
    p = Path(path)
    kind = special_file(p)
    if kind is not None:
        raise ConfigError(f"{what} {str(p)!r} is {kind}, expected a TOML file")
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{what} {str(p)!r} not found") from None
    except IsADirectoryError:
        raise ConfigError(f"{what} {str(p)!r} is a directory, expected a TOML file") from None
    encoding = "utf-8"
    for bom, enc in _BOMS:
        if data.startswith(bom):
            encoding = enc
            break
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as err:
        head = data[: err.start]
        line = head.count(b"\n") + 1
        col = err.start - (head.rfind(b"\n") + 1) + 1
        raise ConfigError(
            f"{p}: not {encoding.upper()} text: byte 0x{data[err.start]:02x} at offset "
            f"{err.start} (line {line}, column {col}); save the file as UTF-8"
        ) from None
    if "\x00" in text:
        off = text.index("\x00")
        raise ConfigError(f"{p}: NUL character at offset {off}; expected a text file "
                          "(UTF-16 without a byte-order mark is not supported: save as UTF-8)")
    return text


def read_toml(path: str | Path, what: str = "file") -> dict:
    """Parse a TOML file read by :func:`read_text`; ConfigError names the file and line."""
    text = read_text(path, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{path}: invalid TOML: {err}") from err
