"""Atomic file output: a file either appears complete at its final path or not at all.

Every file the framework writes (simulation CSV, JSON reports, PNG plots) goes through
:func:`atomic_write`.  The content is written to a temporary file in the *same directory*
as the target, flushed and ``fsync``-ed, and only then moved over the target with
:func:`os.replace` (atomic on POSIX and Windows when both are on one file system).  If the
``with`` body raises -- any exception, including :class:`KeyboardInterrupt` -- the temporary
file is removed and an existing file at the target path is left untouched.

Examples::

    with atomic_write("out.csv") as f:             # text, UTF-8
        f.write("t,V,x\\n")
    with atomic_write("report.json") as f:
        json.dump(result, f, indent=2)
    with atomic_write("fit.png", "wb") as f:       # binary, e.g. matplotlib
        fig.savefig(f, format="png")
"""
from __future__ import annotations

import contextlib
import os
import secrets
import stat
from typing import IO, Iterator

__all__ = ["atomic_write"]

_MODES = {"w", "wt", "wb"}


def _create_temp(directory: str, base: str) -> tuple[int, str]:
    """Create a new, empty, exclusively-owned temp file next to the target.

    ``os.open(..., 0o666)`` lets the kernel apply the process umask, so the final file
    gets the same permissions an ordinary ``open(path, "w")`` would give it (unlike
    :func:`tempfile.mkstemp`, which always uses 0o600).
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        tmp = os.path.join(directory, f".{base[:100]}.{secrets.token_hex(4)}.tmp")
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(f"could not create a temporary file in {directory!r}")


def _fsync_directory(directory: str) -> None:
    """Best effort: make the rename itself durable (POSIX only)."""
    if os.name != "posix":
        return
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike,
    mode: str = "w",
    encoding: str | None = "utf-8",
    newline: str | None = None,
) -> Iterator[IO]:
    """Open ``path`` for writing so that it is replaced atomically when the block succeeds.

    Parameters
    ----------
    path:
        Final file path.  If it is a symbolic link, the file it points to is replaced.
    mode:
        ``"w"``/``"wt"`` (text) or ``"wb"`` (binary).  Appending or reading is not supported.
    encoding, newline:
        As for :func:`open`, text mode only (``encoding`` defaults to UTF-8 and is ignored in
        binary mode).

    Yields the open file object.  On normal exit the data is flushed, fsync-ed and the temp
    file renamed over ``path`` (keeping the permission bits of a file already there).  On any
    exception (``BaseException``, so Ctrl-C too) the temp file is deleted, ``path`` is not
    touched, and the exception propagates.  Errors opening the temp file (missing directory,
    no permission) propagate as :class:`OSError` before the block runs.
    """
    if mode not in _MODES:
        raise ValueError(f"atomic_write: mode must be one of {sorted(_MODES)}, not {mode!r}")
    binary = "b" in mode
    target = os.path.realpath(os.fspath(path))
    directory, base = os.path.split(target)
    fd, tmp = _create_temp(directory, base)
    try:
        try:
            if binary:
                f = os.fdopen(fd, "wb")
            else:
                f = os.fdopen(fd, "w", encoding=encoding, newline=newline)
        except BaseException:
            os.close(fd)
            raise
        with f:
            yield f
            still_open = not f.closed
            if still_open:
                f.flush()
                os.fsync(f.fileno())
        if not still_open:  # the block closed the file itself: sync through a new descriptor
            sync_fd = os.open(tmp, os.O_RDWR)
            try:
                os.fsync(sync_fd)
            finally:
                os.close(sync_fd)
        try:
            os.chmod(tmp, stat.S_IMODE(os.stat(target).st_mode))
        except OSError:
            pass  # no previous file (or not ours to inspect): keep umask-derived mode
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_directory(directory)
