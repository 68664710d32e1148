"""Ending a command at once, cleanly, on Ctrl-C (SIGINT) or SIGTERM.

Used by the command line (``bondgraph.cli``); standard library only, so the ``bondgraph``
command installs the handlers before it imports anything else.

The command runs in a worker thread while the main thread waits for it.  Python delivers
signals to the main thread only, between two bytecodes, so a command busy in compiled code
(numba, LLVM compiling a model, a long integration, BLAS) could not see a Ctrl-C for
minutes; the waiting main thread sees it within 0.1 s.  It then

1. waits for a commit of output files that is under way (never half a set of outputs),
2. removes every temporary file of the process (:func:`bondgraph.support.atomic.remove_temporary_files`),
3. kills every child process (worker pools) and their children with SIGKILL,
4. prints one line, ``bondgraph: interrupted; no output file was changed`` (or, once the
   outputs are in place, ``...; after writing FILE``), and exits at once with status 130
   (SIGINT) or 143 (SIGTERM), skipping exit handlers that could wait for a worker.

Worker processes forked by the command inherit the handler and leave silently on the
terminal's Ctrl-C (which reaches the whole process group), so they print no traceback.
Pools started with ``spawn``/``forkserver`` should pass :func:`worker_initializer` as their
initializer (it ignores SIGINT); they are killed all the same.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

#: temporary files of this process not yet moved into place or removed (see bondgraph.support.atomic)
TEMPORARY: set[str] = set()
#: held while output files are moved into place, so an interrupt never leaves half a set
COMMIT_LOCK = threading.Lock()
#: output files already moved into place by this process (the interrupt message names them)
COMMITTED: list[str] = []

_STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}
_NAMES = {signal.SIGINT: "interrupted", signal.SIGTERM: "terminated (SIGTERM)"}
_owner = {"pid": None}


def _on_signal(signum, frame):  # noqa: ARG001 - signal handler signature
    if os.getpid() != _owner["pid"]:  # a forked worker: the parent cleans up and reports
        os._exit(_STATUS.get(signum, 1))
    for s in _STATUS:
        signal.signal(s, signal.SIG_IGN)  # a second Ctrl-C must not interrupt the clean-up
    stop(signum)


def stop(signum: int) -> None:
    """Clean up (temporary files, child processes) and exit now with one line on stderr.

    Runs inside a signal handler, possibly in the middle of an import: it imports nothing."""
    got = COMMIT_LOCK.acquire(timeout=1.5)  # let a commit under way finish (renames only)
    try:
        remove_temporary_files()
        kill_children()
        done = f"after writing {', '.join(COMMITTED)}" if COMMITTED else "no output file was changed"
        msg = f"bondgraph: {_NAMES.get(signum, 'stopped')}; {done}\n"
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        with contextlib.suppress(OSError):
            os.write(2, msg.encode())
    finally:
        if got:
            COMMIT_LOCK.release()
    os._exit(_STATUS.get(signum, 1))


@contextlib.contextmanager
def handle_signals():
    """Install the SIGINT/SIGTERM handlers for the duration of the block (main thread only;
    elsewhere the block runs without them)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _owner["pid"] = os.getpid()
    old = {s: signal.getsignal(s) for s in _STATUS}
    for s in _STATUS:
        signal.signal(s, _on_signal)
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)


def remove_temporary_files() -> int:
    """Remove every temporary file this process still holds; returns how many were removed."""
    n = 0
    for tmp in list(TEMPORARY):
        with contextlib.suppress(OSError):
            os.unlink(tmp)
            n += 1
        TEMPORARY.discard(tmp)
    return n


def run(fn, *args) -> None:
    """``fn(*args)`` in a worker thread while this (main) thread stays ready for signals;
    an exception of ``fn`` is raised here.  Outside the main thread, ``fn`` runs directly."""
    if threading.current_thread() is not threading.main_thread():
        fn(*args)
        return
    box: dict = {}

    def target():
        try:
            fn(*args)
        except BaseException as exc:  # noqa: BLE001 - handed to the main thread
            box["exc"] = exc

    worker = threading.Thread(target=target, name="bondgraph-command", daemon=True)
    worker.start()
    while worker.is_alive():
        worker.join(0.1)
    if "exc" in box:
        raise box["exc"]


def worker_initializer() -> None:
    """Pool initializer for worker processes: ignore Ctrl-C (the parent ends them)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def kill_children() -> None:
    """SIGKILL every descendant process of this one (children first found through /proc,
    else the multiprocessing children)."""
    pids = _descendants(os.getpid())
    if pids is None:  # no /proc: the children multiprocessing knows of (if it was ever imported)
        mp = sys.modules.get("multiprocessing")
        pids = [p.pid for p in mp.active_children()] if mp is not None else []
    for pid in pids:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)


def _descendants(root: int) -> list[int] | None:
    if not os.path.isdir("/proc"):
        return None
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue
        try:
            ppid = int(stat.rsplit(b")", 1)[1].split()[1])
        except (IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(entry))
    out, todo = [], [root]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out
