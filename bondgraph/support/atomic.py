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

A run that writes several files uses :class:`Outputs`: every path is checked before the work
starts (the directory exists and is writable, the name is not a directory, not an input of
the run, not given twice), each file is written to its temporary file, and all of them are
moved into place together only when the whole run succeeded::

    with Outputs(inputs=[model_path, data_path]) as out:
        csv = out.add(args.out, "--out")             # checked now, before any work
        png = out.add(args.plot, "--plot", suffixes=(".png", ".pdf", ".svg"))
        ...                                          # the work
        with out.path(csv) as tmp:                   # any writer that takes a path
            write_csv(tmp, t, columns)
        with out.open(png, "wb") as fh:              # or a file object
            fig.savefig(fh, format="png")
    # leaving the block without an exception commits; with one, nothing is replaced

Every temporary file lives next to its target and is listed in
:data:`bondgraph.support.interrupt.TEMPORARY`, so the interrupt handler removes them all
(:func:`remove_temporary_files`) before the process exits.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from typing import IO, Iterable, Iterator

from .errors import BondGraphError, UsageError
from .interrupt import COMMIT_LOCK, COMMITTED, TEMPORARY, remove_temporary_files

__all__ = ["atomic_write", "Outputs", "remove_temporary_files", "COMMIT_LOCK"]

_MODES = {"w", "wt", "wb"}


def _create_temp(directory: str, base: str, suffix: str = "") -> tuple[int, str]:
    """Create a new, empty, exclusively-owned temp file next to the target.

    ``os.open(..., 0o666)`` lets the kernel apply the process umask, so the final file
    gets the same permissions an ordinary ``open(path, "w")`` would give it (unlike
    :func:`tempfile.mkstemp`, which always uses 0o600).
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        tmp = os.path.join(directory, f".{base[:100]}.{secrets.token_hex(4)}.tmp{suffix}")
        try:
            fd = os.open(tmp, flags, 0o666)
        except FileExistsError:
            continue
        TEMPORARY.add(tmp)
        return fd, tmp
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
            _fsync_file(tmp)
        _replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        TEMPORARY.discard(tmp)
        raise
    _fsync_directory(directory)


def _fsync_file(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _replace(tmp: str, target: str) -> None:
    """Move ``tmp`` over ``target``, keeping the permission bits of a file already there."""
    try:
        os.chmod(tmp, stat.S_IMODE(os.stat(target).st_mode))
    except OSError:
        pass  # no previous file (or not ours to inspect): keep umask-derived mode
    os.replace(tmp, target)
    TEMPORARY.discard(tmp)


class Outputs:
    """The output files of one run: checked before the work, committed together after it.

    ``inputs``: files the run reads (an output must not overwrite one of them).  Use as a
    context manager: leaving the block normally commits every file added, an exception
    discards them all (existing files stay untouched).
    """

    def __init__(self, inputs: Iterable[str | os.PathLike | None] = ()):
        self._inputs = {os.path.realpath(os.fspath(p)): os.fspath(p) for p in inputs if p}
        self._temps: dict[str, str] = {}  # target (real path) -> temporary file
        self._names: dict[str, str] = {}  # target (real path) -> option that named it
        self._written: set[str] = set()  # targets whose content was written
        self._shown: dict[str, str] = {}  # target (real path) -> the name the user gave

    def add(
        self, path: str | os.PathLike | None, option: str = "--out", suffixes: Iterable[str] | None = None
    ) -> str | None:
        """Check that ``path`` can be written and reserve its temporary file; returns the
        path (``None`` passes through).  Problems are :class:`UsageError` naming ``option``."""
        if path is None:
            return None
        name = os.fspath(path)
        where = f"{option} {name}"
        if not name.strip():
            raise UsageError(f"{option}: empty file name")
        if suffixes is not None:
            suffixes = tuple(suffixes)
            suffix = os.path.splitext(name)[1].lower()
            if suffix not in suffixes:
                raise UsageError(
                    f"{where}: unknown file type {suffix or '(none)'!r}; "
                    f"use {', '.join(suffixes[:-1])} or {suffixes[-1]}"
                    if len(suffixes) > 1
                    else f"{where}: the file name must end in {suffixes[0]}"
                )
        target = os.path.realpath(name)
        directory, base = os.path.split(target)
        if os.path.isdir(target):
            raise UsageError(f"{where}: is a directory; give a file name")
        if not os.path.isdir(directory):
            shown = os.path.dirname(name) or "."
            raise UsageError(f"{where}: directory {shown} does not exist; create it first or choose another path")
        if not os.access(directory, os.W_OK | os.X_OK):
            shown = os.path.dirname(name) or "."
            raise UsageError(f"{where}: cannot write in directory {shown} (permission denied); choose another path")
        if target in self._inputs:
            raise UsageError(f"{where}: would overwrite the input file {self._inputs[target]}; choose another name")
        if target in self._names:
            raise UsageError(
                f"{where}: the same file is already the output of {self._names[target]}; give each output its own name"
            )
        try:
            fd, tmp = _create_temp(directory, base, os.path.splitext(base)[1])
        except OSError as exc:
            raise UsageError(f"{where}: cannot create a file there ({exc.strerror or exc})") from None
        os.close(fd)
        self._temps[target] = tmp
        self._names[target] = option
        self._shown[target] = name
        return name

    def _temp(self, path: str | os.PathLike) -> str:
        target = os.path.realpath(os.fspath(path))
        if target not in self._temps:
            raise ValueError(f"{path} was not added to these outputs")
        return self._temps[target]

    @contextlib.contextmanager
    def path(self, path: str | os.PathLike) -> Iterator[str]:
        """The temporary file to write ``path``'s content to (same suffix, same directory).
        Errors naming the temporary file are re-raised naming ``path``."""
        tmp = self._temp(path)
        try:
            yield tmp
            self._written.add(os.path.realpath(os.fspath(path)))
        except (BondGraphError, OSError) as exc:
            text = str(exc).replace(tmp, os.fspath(path))
            if text == str(exc):
                raise
            raise type(exc)(text) from None if isinstance(exc, BondGraphError) else exc

    @contextlib.contextmanager
    def open(self, path: str | os.PathLike, mode: str = "w", encoding: str | None = "utf-8") -> Iterator[IO]:
        """``path``'s temporary file opened for writing (``"w"`` text or ``"wb"`` binary)."""
        if mode not in _MODES:
            raise ValueError(f"Outputs.open: mode must be one of {sorted(_MODES)}, not {mode!r}")
        with self.path(path) as tmp:
            with open(tmp, mode, **({} if "b" in mode else {"encoding": encoding})) as fh:
                yield fh

    def commit(self) -> None:
        """Move every written temporary file over its target (fsync-ed first); the others
        are removed by :meth:`discard`."""
        with COMMIT_LOCK:
            for target, tmp in list(self._temps.items()):
                if target not in self._written:
                    continue
                _fsync_file(tmp)
                _replace(tmp, target)
                _fsync_directory(os.path.dirname(target))
                COMMITTED.append(self._shown[target])
                del self._temps[target]

    def discard(self) -> None:
        """Remove every temporary file; no target is touched."""
        for tmp in self._temps.values():
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            TEMPORARY.discard(tmp)
        self._temps.clear()

    def __enter__(self) -> "Outputs":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            try:
                self.commit()
            finally:
                self.discard()
        else:
            self.discard()
