"""bondgraph.support.progress: a bar on a terminal, plain lines otherwise, nothing when quiet or quick."""

from __future__ import annotations

import io
import threading

import pytest

from bondgraph.support.progress import Progress, _duration


class Clock:
    """A settable stand-in for time.monotonic."""

    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


@pytest.fixture
def clock(monkeypatch):
    c = Clock()
    monkeypatch.setattr("bondgraph.support.progress.time.monotonic", c)
    return c


class Tty(io.StringIO):
    def isatty(self):
        return True


def test_lines_with_percentage_count_and_time_left(clock):
    s = io.StringIO()
    p = Progress("fitting", total=8, unit="candidates", stream=s, delay=1.0, interval=5.0)
    assert p.mode == "lines"
    p.update(1)  # at once: too early to show
    clock.now += 2
    p.update(2)  # 2 of 8 after 2 s: 6 s left
    clock.now += 1
    p.update(3)  # within the interval: nothing
    clock.now += 5
    p.advance(status="creep: gain 1.8")
    p.close()
    lines = s.getvalue().splitlines()
    assert lines[0] == "fitting:  25.0 %, 2/8 candidates, 2.0 s elapsed, about 6.0 s left"
    assert lines[1] == "fitting:  50.0 %, 4/8 candidates, 8.0 s elapsed, about 8.0 s left, creep: gain 1.8"
    assert lines[2] == "fitting: done in 8.0 s; creep: gain 1.8"
    assert len(lines) == 3


def test_a_fraction_and_an_open_count(clock):
    s = io.StringIO()
    with Progress("simulating", total=1.0, stream=s, delay=0, interval=0) as p:
        p(0.5)
        clock.now += 30
        p(0.75)
    lines = s.getvalue().splitlines()
    assert lines[0] == "simulating:  50.0 %, 0.0 s elapsed"
    assert lines[1] == "simulating:  75.0 %, 30 s elapsed, about 10 s left"
    s = io.StringIO()
    with Progress("fitting", unit="simulations", stream=s, delay=0, interval=0) as p:
        clock.now += 75
        p(37)
    assert s.getvalue().splitlines()[0] == "fitting: 37 simulations, 1 min 15 s elapsed"


def test_quick_work_and_quiet_mode_print_nothing(clock):
    s = io.StringIO()
    with Progress("simulating", total=1.0, stream=s) as p:  # ends within the default 1 s delay
        p(0.5)
        p(1.0)
    assert s.getvalue() == ""
    s = io.StringIO()
    with Progress("simulating", total=1.0, stream=s, mode="quiet", delay=0) as p:
        clock.now += 10
        p(0.5)
        p.note("hello")
    assert s.getvalue() == ""


def test_bar_on_a_terminal_redraws_one_line(clock, monkeypatch):
    monkeypatch.setattr(
        "bondgraph.support.progress.shutil.get_terminal_size", lambda default: __import__("os").terminal_size((60, 20))
    )
    s = Tty()
    p = Progress("simulating", total=1.0, stream=s, delay=0)
    assert p.mode == "bar"
    p(0.25)
    clock.now += 1
    p(0.5)
    p.note("switched to radau")
    p.close()
    out = s.getvalue()
    assert "\n" not in out.split("simulating: switched to radau\n")[0].replace("\r", ""), "the bar stays on one line"
    first = out.split("\r")[1]
    assert first.startswith("simulating [#####...............]  25.0 %") and len(first) == 59
    assert "simulating: switched to radau\n" in out
    assert out.endswith("simulating: done in 1.0 s\n")


def test_environment_chooses_the_mode(monkeypatch):
    monkeypatch.setenv("BONDGRAPH_PROGRESS", "quiet")
    assert Progress("x", stream=Tty()).mode == "quiet"
    monkeypatch.setenv("BONDGRAPH_PROGRESS", "lines")
    assert Progress("x", stream=Tty()).mode == "lines"
    monkeypatch.setenv("BONDGRAPH_PROGRESS", "")
    assert Progress("x", stream=Tty()).mode == "bar"
    assert Progress("x", stream=io.StringIO(), mode="bar").mode == "bar"
    with pytest.raises(ValueError, match="one of auto, bar, lines, quiet"):
        Progress("x", mode="fancy")


def test_updates_from_threads_and_a_broken_stream(clock):
    s = io.StringIO()
    p = Progress("diagnosing", total=400, stream=s, delay=0, interval=0)
    threads = [threading.Thread(target=lambda: [p.advance() for _ in range(100)]) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert p.done == 400
    s.close()
    p.update(401)  # a closed stream never makes the work fail
    p.close()


def test_durations():
    assert [_duration(x) for x in (0.04, 9.96, 42.4, 185, 3725)] == [
        "0.0 s",
        "10.0 s",
        "42 s",
        "3 min 05 s",
        "1 h 02 min",
    ]
