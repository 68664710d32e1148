"""Candidates in parallel worker processes.

Each worker is started (``fork``) with the diagnosis context, the candidates and a snapshot
of the settings as its arguments (the initializer's job: nothing is shared through module
globals); tasks carry only the chain state and a candidate index.  Workers ignore SIGINT: on
Ctrl-C (or any error) the parent kills them and waits for them, so none outlives the
diagnosis and the interruption takes effect at once.  Without ``fork`` (or with one worker)
the candidates run in the calling process.
"""

from __future__ import annotations

import multiprocessing as mp
import pickle
import queue
import signal
import threading
from typing import Callable, Iterator, Sequence

from ..support import config


def _worker(run_candidate, ctx, calibrated, candidates, settings, tasks, results) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    config.restore(settings)
    single_threaded_blas()
    while True:
        task = tasks.get()
        if task is None:
            return
        index, state, plausible, effort = task
        outcome = run_candidate(ctx, state, calibrated, candidates[index], plausible, effort)
        if not _picklable(outcome):  # e.g. a candidate class defined outside any module
            outcome = UNPICKLABLE
        results.put((index, outcome))


#: a worker's answer for a candidate whose outcome cannot be sent back (its class or law
#: terms live where a process cannot import them): the parent runs that candidate itself
UNPICKLABLE = "unpicklable"


def single_threaded_blas():
    """One BLAS thread in this process (the diagnosis' matrices are small and its workers share
    the cores: threaded BLAS only oversubscribes them, several times slower).

    Returns
    -------
    threadpoolctl.threadpool_limits
        A context manager that restores the former limits when it exits.
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


class Pool:
    """Runs candidates on a chain state, in ``workers`` processes when that helps.

    Worker processes are forked once, here, and serve every chain step; use the pool as a
    context manager (or call :meth:`close`).

    Parameters
    ----------
    run_candidate : callable
        ``run_candidate(ctx, state, calibrated, candidate, plausible, effort)`` → outcome.
    ctx : Context
        The prepared record.
    calibrated : sequence of str
        The calibrated linear parameters.
    candidates : sequence of Candidate
        Every candidate of the diagnosis (tasks refer to them by index).
    workers : int
        Processes (1: run in this process).
    """

    def __init__(self, run_candidate: Callable, ctx, calibrated: Sequence[str], candidates: Sequence, workers: int):
        self.run_candidate = run_candidate
        self.ctx, self.calibrated, self.candidates = ctx, list(calibrated), list(candidates)
        self._procs: list = []
        if workers > 1 and len(candidates) > 1 and "fork" in mp.get_all_start_methods():
            mpc = mp.get_context("fork")
            self._tasks, self._results = mpc.Queue(), mpc.Queue()
            settings = config.snapshot()
            for _ in range(min(workers, len(candidates))):
                p = mpc.Process(
                    target=_worker,
                    args=(run_candidate, ctx, self.calibrated, self.candidates, settings, self._tasks, self._results),
                    daemon=True,
                )
                p.start()
                self._procs.append(p)

    def run(self, state, indices: Sequence[int], plausible=None, effort: float = 1.0) -> Iterator[tuple[int, object]]:
        """(index, outcome) for every candidate index, as they finish (costly ones start first);
        ``plausible``: (state, bounds) of the plausible device for linear structural candidates;
        ``effort``: a factor on the candidates' optimiser budgets.

        Parameters
        ----------
        state : State
            The chain's current state.
        indices : sequence of int
            The candidates to run.
        plausible : tuple, optional
            (state, bounds) of the plausible device.
        effort : float, optional
            Factor on the optimisers' budgets.

        Yields
        ------
        tuple of (int, object)
            The candidate's index and its outcome.

        Raises
        ------
        RuntimeError
            A worker process died.
        """
        run_candidate = self.run_candidate
        order = sorted(indices, key=lambda i: -getattr(self.candidates[i], "cost", 1))
        if not self._procs or not _picklable((state, plausible)):
            for i in order:
                yield i, run_candidate(self.ctx, state, self.calibrated, self.candidates[i], plausible, effort)
            return
        for i in order:
            self._tasks.put((i, state, plausible, effort))
        for _ in order:
            while True:
                try:
                    i, outcome = self._results.get(timeout=0.2)
                except queue.Empty:
                    dead = [p for p in self._procs if not p.is_alive()]
                    if dead:
                        raise RuntimeError(f"a diagnosis worker died (exit code {dead[0].exitcode})") from None
                    continue
                if isinstance(outcome, str) and outcome == UNPICKLABLE:
                    outcome = run_candidate(self.ctx, state, self.calibrated, self.candidates[i], plausible, effort)
                yield i, outcome
                break

    def close(self, kill: bool = False) -> None:
        """Stop the worker processes (idempotent).

        Parameters
        ----------
        kill : bool, optional
            Kill them instead of letting them finish their task (after an error or Ctrl-C).
        """
        procs, self._procs = self._procs, []
        if not procs:
            return
        old = signal.signal(signal.SIGINT, signal.SIG_IGN) if _main_thread() else None
        try:
            if not kill:
                for _ in procs:
                    self._tasks.put(None)
            for p in procs:
                if kill:
                    p.kill()
                p.join(timeout=None if not kill else 5)
            for q in (self._tasks, self._results):
                q.cancel_join_thread()
                q.close()
        finally:
            if old is not None:
                signal.signal(signal.SIGINT, old)

    def __enter__(self) -> "Pool":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(kill=exc_type is not None)


def _picklable(obj) -> bool:
    """Whether ``obj`` can be sent to a worker (a queue pickles in a thread of its own, where a
    failure is lost and the worker waits for ever): a chain state holding a law term of a
    candidate defined outside any importable module cannot."""
    try:
        pickle.dumps(obj)
    except Exception:  # noqa: BLE001 - any failure to pickle means: run it here
        return False
    return True


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def fork_map(fn: Callable, items: Sequence, workers: int) -> list:
    """``[fn(x) for x in items]``, the items shared round-robin between this process and
    ``workers − 1`` forked children (``fn`` is inherited, not pickled; the results are).  Each
    result is the one the serial loop gives (the calls are independent), in the items' order.
    Serial with one worker, one item, without ``fork``, or inside a worker process (which may
    not have children).  A child's exception is raised here; on any error (Ctrl-C included)
    the children are killed and waited for.

    Parameters
    ----------
    fn : callable
        The function, called with one item.
    items : sequence
        The items.
    workers : int
        Processes, this one included.

    Returns
    -------
    list
        ``fn(item)`` per item, in order.
    """
    items = list(items)
    workers = min(int(workers), len(items))
    if workers < 2 or "fork" not in mp.get_all_start_methods() or mp.current_process().daemon:
        return [fn(x) for x in items]
    mpc = mp.get_context("fork")
    results = mpc.Queue()

    def child(share: list[int]) -> None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        for i in share:
            try:
                results.put((i, True, fn(items[i])))
            except BaseException as exc:  # noqa: BLE001 - handed to the parent, which raises it
                results.put((i, False, exc))
                return

    shares = [list(range(k, len(items), workers)) for k in range(workers)]
    procs = [mpc.Process(target=child, args=(share,), daemon=True) for share in shares[1:]]
    out: dict[int, object] = {}
    try:
        for p in procs:
            p.start()
        for i in shares[0]:
            out[i] = fn(items[i])
        while len(out) < len(items):
            try:
                i, ok, value = results.get(timeout=0.2)
            except queue.Empty:
                if any(not p.is_alive() and p.exitcode not in (0, None) for p in procs):
                    raise RuntimeError("a diagnosis worker died") from None
                continue
            if not ok:
                raise value
            out[i] = value
    finally:
        for p in procs:
            if p.is_alive():
                p.kill()
            p.join()
        results.cancel_join_thread()
        results.close()
    return [out[i] for i in range(len(items))]
