"""One way to write an output file: all of it, or nothing (floor-1 leaf).

Every file mvtk writes (report page and tables, netCDF, UFF, TOML, PDF, the stage
cache) goes through :func:`atomic_path`: the content is written to a temporary file in
the target's own folder, flushed and ``fsync``-ed, and renamed over the target in one
step (``os.replace``, atomic on POSIX and Windows within one file system), the rule
SQLite and git follow. When anything fails (disk full, file-size limit, permission, an
exception in the writer, Ctrl-C) the temporary file is removed and the previous file,
if there was one, is left byte-identical; the error names the file and the cause.

:func:`same_file` and :func:`refuse_input` implement the other half of "nothing lost":
an output path that resolves to one of the command's input files (symlinks and hard
links followed, by device and inode) is refused before any work.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import stat
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import OutputError

__all__ = ["atomic_path", "write_bytes", "write_text", "write_error", "refuse_input",
           "same_file", "check_room", "special_file", "TEMP_SUFFIX"]

#: Suffix of the temporary files (``.<name>.<random>.tmp``), so an interrupted run's
#: leftovers can be recognised and removed.
TEMP_SUFFIX = ".tmp"

_CAUSES = {
    errno.ENOSPC: "disk full (no space left on the device)",
    errno.EDQUOT: "disk quota exceeded",
    errno.EFBIG: "file-size limit exceeded (ulimit -f) or file too large",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EROFS: "read-only file system",
    errno.ENOENT: "the folder does not exist",
    errno.ENOTDIR: "a part of the path is not a folder",
    errno.EISDIR: "the path is a folder",
    errno.EIO: "input/output error of the device",
}


def _cause(err: BaseException) -> str:
    """The plain-words cause of ``err`` (an OSError found in its chain, if any)."""
    seen = 0
    e: BaseException | None = err
    while e is not None and seen < 10:
        if isinstance(e, OSError) and e.errno in _CAUSES:
            return _CAUSES[e.errno]
        if isinstance(e, OSError) and e.strerror:
            return e.strerror
        e = e.__cause__ or e.__context__
        seen += 1
    text = " ".join(str(err).split())
    # h5py / pyuff wrap the OS error in their own text; recognise the common ones
    low = text.lower()
    for key, what in (("file too large", _CAUSES[errno.EFBIG]),
                      ("no space left", _CAUSES[errno.ENOSPC]),
                      ("permission denied", _CAUSES[errno.EACCES]),
                      ("read-only file system", _CAUSES[errno.EROFS])):
        if key in low:
            return what
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def write_error(path: str | os.PathLike, err: BaseException) -> OutputError:
    """The :class:`~mvtk.errors.OutputError` naming ``path`` and the cause of ``err``."""
    return OutputError(f"{path}: could not be written: {_cause(err)}; the previous file "
                       "(if any) is unchanged")


def _chain(err: BaseException) -> Iterator[BaseException]:
    e: BaseException | None = err
    for _ in range(10):
        if e is None:
            return
        yield e
        e = e.__cause__ or e.__context__


def _new_mode(target: Path) -> int:
    """Permissions of the file to write: those of the file replaced, else 0666 & ~umask."""
    try:
        return stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        pass
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _fsync_dir(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Context manager giving a temporary path to write instead of ``path``.

    The caller (or a library it hands the path to: h5netcdf, pyuff, Chromium) writes the
    whole file to the yielded path; on a normal exit the file is fsync-ed and renamed
    over ``path``. On any exception the temporary file is removed, ``path`` is left as
    it was, and an OSError or a failure of the writer is raised again as
    :class:`~mvtk.errors.OutputError` naming ``path`` and the cause.

    Parameters
    ----------
    path : path-like
        The output file. Its folder must exist.

    Yields
    ------
    pathlib.Path
        A fresh temporary path in the same folder (``.<name>.<random>.tmp``); it does not
        exist yet, so writers that refuse to overwrite work too.

    Raises
    ------
    OutputError
        The file could not be written; the previous file is unchanged.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise OutputError(f"{target}: is a folder, expected a file name")
    try:
        fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=TEMP_SUFFIX,
                                    dir=folder)
    except OSError as err:
        raise write_error(target, err) from err
    os.close(fd)
    tmp = Path(name)
    tmp.unlink()  # the writer creates it (some refuse an existing file)
    try:
        yield tmp
        if not tmp.exists():
            raise OutputError(f"{target}: could not be written: the writer produced no "
                              "file; the previous file (if any) is unchanged")
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, _new_mode(target))
        os.replace(tmp, target)
    except BaseException as err:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(err, OutputError):
            raise
        if isinstance(err, KeyboardInterrupt | SystemExit | GeneratorExit):
            raise
        if isinstance(err, OSError) or any(isinstance(e, OSError) for e in _chain(err)) \
                or "file too large" in str(err).lower() or "no space" in str(err).lower():
            raise write_error(target, err) from err
        raise
    _fsync_dir(folder)


def check_room(path: str | os.PathLike, nbytes: int) -> None:
    """Refuse, before writing, a file of about ``nbytes`` that cannot fit.

    Checks the process's file-size limit (``ulimit -f``, ``RLIMIT_FSIZE``) and the free
    space of the target's file system. Used ahead of writers (HDF5) whose failure in
    the middle of a file is not recoverable in-process.

    Raises
    ------
    OutputError
        Naming the file, the size needed and the limit or free space found.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        unlimited = soft == resource.RLIM_INFINITY
    except (ImportError, OSError, ValueError, AttributeError):  # not POSIX
        soft, unlimited = -1, True
    if not unlimited and nbytes > soft:
        raise OutputError(f"{target}: could not be written: about {nbytes / 1e6:.3g} MB "
                          f"needed but the file-size limit (ulimit -f) is {soft / 1e6:.3g} "
                          "MB; the previous file (if any) is unchanged")
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return
    if nbytes > free:
        raise OutputError(f"{target}: could not be written: disk full (about "
                          f"{nbytes / 1e6:.3g} MB needed, {free / 1e6:.3g} MB free); the "
                          "previous file (if any) is unchanged")


def write_bytes(path: str | os.PathLike, data: bytes | memoryview) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`); return the path."""
    target = Path(path)
    with atomic_path(target) as tmp, open(tmp, "xb") as fh:
        fh.write(data)
        fh.flush()
    return target


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`); return the path."""
    return write_bytes(path, text.encode(encoding))


def special_file(path: str | os.PathLike) -> str | None:
    """What ``path`` is when it exists but is not a regular file or folder, else None.

    A FIFO, socket or device never ends (or blocks until a writer comes): readers refuse
    it before opening it.
    """
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    for test, name in ((stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device")):
        if test(mode):
            return name
    return "a special file"


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """True when ``a`` and ``b`` are one file (symlinks and hard links followed).

    Compares device and inode of the existing files; a path that does not exist is
    the same as another only when both resolve to the same absolute path.
    """
    try:
        sa, sb = os.stat(a), os.stat(b)
    except OSError:
        return Path(a).resolve() == Path(b).resolve()
    return (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino)


def refuse_input(output: str | os.PathLike, inputs: Iterable[str | os.PathLike],
                 option: str = "output") -> None:
    """Refuse an output path that is one of the input files.

    Parameters
    ----------
    output : path-like
        The output file (it may not exist yet).
    inputs : iterable of path-like
        Every file the command reads.
    option : str
        How the output was given (``"--out"``, ``"-o"``), for the message.

    Raises
    ------
    OutputError
        ``output`` resolves to one of ``inputs`` (same device and inode, or the same
        absolute path); ``--force`` does not lift this.
    """
    for src in inputs:
        if src is None:
            continue
        if same_file(output, src):
            raise OutputError(
                f"{option} {str(output)!r} is the input file {str(src)!r}: refusing to "
                "overwrite an input (give another output path)")
