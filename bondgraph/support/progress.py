"""Progress reports on stderr for work that takes more than a moment.

    from bondgraph.support.progress import Progress

    with Progress("simulating", total=1.0) as p:           # a known amount of work ...
        sim.run(t, inputs, progress=p)                      # p(0.25) -> "25 %", with an ETA
    with Progress("fitting", unit="simulations") as p:      # ... or a count with no known end
        ident.fit(specs, progress=p)                        # p(37) -> "37 simulations"
    with Progress("diagnosing", total=8, unit="candidates") as p:
        for c in candidates:
            ...
            p.advance(status=f"{c.name}: gain {g:.2f}")    # one more done, with a status text
            p.note(f"{c.name} rejected: ...")               # a line of its own

    with waiting("compiling the integrator"):              # one blocking call (no updates of
        from . import integrators                           # its own): elapsed time, from a timer

Modes: ``bar`` (one line redrawn in place, with the estimated time left; chosen when the
stream is a terminal), ``lines`` (a plain line at most every ``interval`` seconds, 10 s by
default; chosen otherwise, e.g. for a log file or CI), ``quiet`` (nothing).  ``auto``, the
default, picks ``bar`` or ``lines``; the environment variable ``BONDGRAPH_PROGRESS`` (bar,
lines or quiet) overrides ``auto``.  Nothing is shown for work that ends within ``delay``
seconds (1 s by default), so quick commands stay silent.  Notes are shown at once (not in
quiet mode).  When something was shown, :meth:`close` ends with a line saying how long the
work took.  Updates are cheap (a clock read when nothing is due) and thread-safe.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import threading
import time
from typing import IO

__all__ = ["Progress", "MODES", "waiting"]

MODES = ("auto", "bar", "lines", "quiet")
#: the mode of :class:`waiting` reports that are not given one (compilations started deep
#: inside the framework): ``bondgraph --quiet`` makes it quiet for its run
default_mode = "auto"


class Progress:
    """A progress reporter; call it (or :meth:`update`) with the amount done so far.

    ``total``: the amount of the whole work (``None``: unknown, a count is shown);
    ``unit``: what is counted (``"simulations"``), shown after the numbers; ``mode``: see the
    module docstring; ``stream``: where to write (default ``sys.stderr`` at each write).
    """

    def __init__(
        self,
        label: str,
        total: float | None = None,
        *,
        unit: str = "",
        mode: str = "auto",
        stream: IO | None = None,
        delay: float = 1.0,
        interval: float | None = None,
    ):
        if mode not in MODES:
            raise ValueError(f"progress mode must be one of {', '.join(MODES)}, not {mode!r}")
        self.label, self.total, self.unit = label, total, unit
        self._stream = stream
        if mode == "auto":
            env = os.environ.get("BONDGRAPH_PROGRESS", "").strip().lower()
            mode = env if env in ("bar", "lines", "quiet") else ("bar" if self._isatty() else "lines")
        self.mode = mode
        self.delay = delay
        self.interval = interval if interval is not None else (0.2 if mode == "bar" else 10.0)
        self.done: float = 0.0
        self.status = ""
        self.t0 = time.monotonic()
        self._last = -1.0  # time of the last line written (-1: nothing shown yet)
        self._bar_open = False  # a bar line is on screen without its newline
        self._closed = False
        self._lock = threading.Lock()

    # ---- reporting -------------------------------------------------------------------------
    def update(self, done: float | None = None, status: str | None = None) -> None:
        """Set the amount done (in units of ``total``) and optionally a short status text."""
        with self._lock:
            if done is not None:
                self.done = float(done)
            if status is not None:
                self.status = status
            self._maybe_show()

    __call__ = update

    def advance(self, amount: float = 1.0, status: str | None = None) -> None:
        """Add ``amount`` to the amount done."""
        self.update(self.done + amount, status)

    def note(self, text: str) -> None:
        """Write ``text`` as a line of its own now (the bar, if any, is redrawn below it)."""
        if self.mode == "quiet":
            return
        with self._lock:
            self._clear_bar()
            self._write(f"{self.label}: {text}\n")
            if self._last >= 0:
                self._maybe_show(force=self.mode == "bar")

    def close(self, status: str | None = None) -> None:
        """End the report: a final line with the time taken, if anything was shown."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            if status is not None:
                self.status = status
            if self.mode == "quiet" or self._last < 0:
                return
            self._clear_bar()
            elapsed = time.monotonic() - self.t0
            tail = f"; {self.status}" if self.status else ""
            self._write(f"{self.label}: done in {_duration(elapsed)}{tail}\n")

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:  # interrupted or failed: end the bar line so an error message starts cleanly
            with self._lock:
                self._closed = True
                self._clear_bar()

    # ---- text ------------------------------------------------------------------------------
    def text(self) -> str:
        """The current report as one line (without the bar drawing)."""
        elapsed = time.monotonic() - self.t0
        unit = f" {self.unit}" if self.unit else ""
        if self.total:
            frac = min(max(self.done / self.total, 0.0), 1.0)
            parts = [f"{100 * frac:5.1f} %"]
            if self.total != 1.0:
                parts.append(f"{_count(self.done)}/{_count(self.total)}{unit}")
            parts.append(f"{_duration(elapsed)} elapsed")
            if 0 < frac < 1 and elapsed > 0:
                parts.append(f"about {_duration(elapsed * (1 - frac) / frac)} left")
        else:
            parts = [f"{_count(self.done)}{unit}", f"{_duration(elapsed)} elapsed"]
        if self.status:
            parts.append(self.status)
        return ", ".join(parts)

    def _maybe_show(self, force: bool = False) -> None:
        if self.mode == "quiet" or self._closed:
            return
        now = time.monotonic()
        if not force and (now - self.t0 < self.delay or (self._last >= 0 and now - self._last < self.interval)):
            return
        self._last = now
        if self.mode == "bar":
            self._draw_bar()
        else:
            self._write(f"{self.label}: {self.text()}\n")

    def _draw_bar(self) -> None:
        width = shutil.get_terminal_size((80, 20)).columns - 1
        text = self.text()
        if self.total:
            frac = min(max(self.done / self.total, 0.0), 1.0)
            cells = 20
            filled = int(round(frac * cells))
            bar = "[" + "#" * filled + "." * (cells - filled) + "] "
        else:
            bar = ""
        line = f"{self.label} {bar}{text}"[:width]
        self._write("\r" + line.ljust(width))
        self._bar_open = True

    def _clear_bar(self) -> None:
        if self._bar_open:
            width = shutil.get_terminal_size((80, 20)).columns - 1
            self._write("\r" + " " * width + "\r")
            self._bar_open = False

    def _write(self, s: str) -> None:
        stream = self._stream or sys.stderr
        try:
            stream.write(s)
            stream.flush()
        except (OSError, ValueError):  # closed or broken stream: progress is never worth a failure
            pass

    def _isatty(self) -> bool:
        try:
            return (self._stream or sys.stderr).isatty()
        except (AttributeError, ValueError):
            return False


def _count(v: float) -> str:
    return f"{int(v)}" if float(v).is_integer() else f"{v:.3g}"


def _duration(seconds: float) -> str:
    """1.2 s, 42 s, 3 min 05 s, 1 h 02 min."""
    if seconds < 10:
        return f"{seconds:.1f} s"
    if seconds < 60:
        return f"{seconds:.0f} s"
    m, s = divmod(int(round(seconds)), 60)
    if m < 60:
        return f"{m} min {s:02d} s"
    h, m = divmod(m, 60)
    return f"{h} h {m:02d} min"


#: seconds a :class:`waiting` block runs before a report in a log (``lines`` mode)
LOG_DELAY = 10.0


class waiting:
    """A :class:`Progress` with no amount, kept alive by a timer thread while one blocking call
    runs (a compilation, an import): it shows the label and the time elapsed once the call has
    taken more than ``delay`` seconds (default: 1 s on a terminal, :data:`LOG_DELAY` in a log
    or a pipe, where every report stays as a line), and the time it took at the end.  ``mode`` as for
    :class:`Progress`; the environment variable ``BONDGRAPH_PROGRESS`` applies.  Usable as a
    context manager only; ``seconds`` holds the time the block took when it ends.  ``mode``
    defaults to :data:`default_mode` (a command's ``--quiet`` sets it to quiet while it runs).
    """

    def __init__(self, label: str, *, status: str = "", mode: str | None = None, stream: IO | None = None, delay=None):
        self.progress = Progress(label, mode=mode or default_mode, stream=stream)
        # a terminal redraws one line: shown after a second; a log keeps every line: only a
        # wait that a reader would wonder about (a first compilation of tens of seconds)
        self.progress.delay = delay if delay is not None else (1.0 if self.progress.mode == "bar" else LOG_DELAY)
        self.progress.status = status
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.seconds = 0.0

    def _tick(self) -> None:
        while not self._stop.wait(0.2):
            self.progress.update()

    def __enter__(self) -> "waiting":
        self.t0 = time.monotonic()
        if self.progress.mode != "quiet":
            self._thread = threading.Thread(target=self._tick, name="bondgraph-waiting", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        self.seconds = time.monotonic() - self.t0
        self.progress.status = ""
        self.progress.__exit__(exc_type, exc, tb)


@contextlib.contextmanager
def quiet_if(quiet: bool):
    """Within the block, :data:`default_mode` is quiet when ``quiet`` (restored after)."""
    global default_mode
    before = default_mode
    default_mode = "quiet" if quiet else before
    try:
        yield
    finally:
        default_mode = before
