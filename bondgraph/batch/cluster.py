"""Where batch jobs run: a Dask cluster (``dask.distributed``), embedded or existing.

* ``scheduler=None``: an embedded ``LocalCluster`` of ``workers`` processes (default: one per
  CPU core), one thread each, started for the call and shut down after it.
* ``scheduler="tcp://host:8786"``: the existing cluster of that scheduler (same code path);
  its workers need ``bondgraph`` installed and must see the model and data files at the
  same paths (a shared file system).
* ``scheduler=client``: a ``distributed.Client`` you already hold (left open).

Jobs are submitted as tasks; a task that fails on its worker (or whose worker dies) becomes
an error for its jobs, never stopping the others.  Ctrl-C (``KeyboardInterrupt``) cancels
every task, shuts the embedded cluster down and propagates.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
from typing import Any, Callable, Iterator, Sequence

from ..support import config
from ..support.errors import UsageError

#: the one-line fix when Dask is missing
INSTALL_HINT = "pip install -e '.[dask]' (or pip install 'dask[distributed]')"


def require_dask():
    """The ``distributed`` module, or a UsageError naming the extra to install.

    Returns
    -------
    module
        ``distributed``.

    Raises
    ------
    UsageError
        Dask is not installed.
    """
    try:
        import distributed
    except ImportError:
        raise UsageError(f"batch runs need Dask (dask.distributed): {INSTALL_HINT}") from None
    return distributed


def default_workers() -> int:
    """One worker per CPU core this process may use.

    Returns
    -------
    int
        The number of cores in this process's affinity set (at least 1).
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def connect(
    scheduler: Any = None, workers: int | None = None, say: Callable[[str], None] | None = None
) -> Iterator[Any]:
    """A ``distributed.Client`` for the duration of a ``with`` block (see the module docstring);
    ``say`` receives one line on where the jobs run and the dashboard address, if any.

    Parameters
    ----------
    scheduler : str or distributed.Client, optional
        Where the jobs run: None for an embedded ``LocalCluster`` (closed at the end of the
        block), a scheduler address (``tcp://head:8786``), or a client to use as it is.
    workers : int, optional
        Worker processes of the embedded cluster (default: the setting's worker count); only
        without ``scheduler``.
    say : callable, optional
        ``say(line)`` receives one line on where the jobs run.

    Yields
    ------
    distributed.Client
        The client the jobs are submitted to.

    Raises
    ------
    UsageError
        dask is not installed, ``workers`` with a scheduler or client, fewer than one worker,
        or a scheduler that cannot be reached.
    """
    distributed = require_dask()
    say = say or (lambda s: None)
    if isinstance(scheduler, distributed.Client):
        if workers is not None:
            raise UsageError("workers= sizes an embedded cluster; a given client's cluster has its own workers")
        yield scheduler
        return
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            n = default_workers() if workers is None else int(workers)
            if n < 1:
                raise UsageError(f"--workers must be at least 1, got {workers}")
            cluster = stack.enter_context(
                distributed.LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=_dashboard_address(),
                    silence_logs=logging.CRITICAL,
                )
            )
            client = stack.enter_context(distributed.Client(cluster))
            client.run(ignore_interrupts)  # Ctrl-C is the client's to handle: it cancels, then closes
            where = f"a local Dask cluster of {n} worker process{'es' if n != 1 else ''}"
        else:
            if workers is not None:
                raise UsageError(
                    "--workers sizes the local cluster; with --scheduler the cluster's own workers "
                    "run the jobs (drop --workers)"
                )
            try:
                client = stack.enter_context(
                    distributed.Client(str(scheduler), timeout=f"{config.get('batch.connect_timeout')}s")
                )
            except (OSError, TimeoutError, ValueError) as exc:
                raise UsageError(
                    f"cannot reach the Dask scheduler at {scheduler} ({exc}); start one with "
                    f"'dask scheduler' and 'dask worker ADDRESS', or check the address"
                ) from None
            n = len(client.scheduler_info()["workers"])
            where = f"the Dask cluster at {scheduler} ({n} worker{'s' if n != 1 else ''} now)"
        link = dashboard(client)
        say(f"running on {where}" + (f"; dashboard: {link}" if link else ""))
        yield client


def ignore_interrupts() -> None:
    """Run on each worker of the embedded cluster: the terminal's Ctrl-C reaches the worker
    processes too (one process group); they ignore it and leave it to the client (which cancels
    and closes, or, under the command line, :mod:`bondgraph.support.interrupt` ends them)."""
    import threading

    from ..support import interrupt

    if threading.current_thread() is threading.main_thread():
        interrupt.worker_initializer()


def _dashboard_address() -> str | None:
    """A free port for the embedded cluster's dashboard when bokeh is installed, else none."""
    try:
        import bokeh  # noqa: F401 - Dask's dashboard needs it
    except ImportError:
        return None
    return ":0"


def dashboard(client) -> str | None:
    """The dashboard address of the client's scheduler, if it serves one.

    Parameters
    ----------
    client : distributed.Client
        The client.

    Returns
    -------
    str or None
        The dashboard's URL, or None.
    """
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # noqa: BLE001 - a missing dashboard is no error
        return None
    return client.dashboard_link if "dashboard" in services else None


def worker_count(client) -> int:
    """Number of workers the client's scheduler has now.

    Parameters
    ----------
    client : distributed.Client
        The client.

    Returns
    -------
    int
        At least 1.
    """
    return max(1, len(client.scheduler_info()["workers"]))


def run_tasks(
    client,
    fn: Callable,
    chunks: Sequence[list],
    kwargs: dict | None = None,
    on_result: Callable[[int, list], None] | None = None,
    failed: Callable[[list, BaseException], list] | None = None,
) -> list[list]:
    """Run ``fn(chunk, **kwargs)`` for every chunk on the cluster; the results in chunk order.

    ``on_result(index, result)`` is called as each task completes.  A task that raises on its
    worker (or whose worker dies) gives ``failed(chunk, exception)`` instead.  On any exception
    here, Ctrl-C included, every task is cancelled before it propagates.

    Parameters
    ----------
    client : distributed.Client
        The client.
    fn : callable
        ``fn(chunk, **kwargs)`` → a list, run on a worker.
    chunks : sequence of list
        The chunks of jobs.
    kwargs : dict, optional
        Further keyword arguments of ``fn``.
    on_result : callable, optional
        ``on_result(index, result)`` as each task completes.
    failed : callable, optional
        ``failed(chunk, exception)`` → the result of a task that failed (default: raise).

    Returns
    -------
    list of list
        Each chunk's result, in chunk order.
    """
    distributed = require_dask()
    futures = client.map(fn, list(chunks), pure=False, **(kwargs or {}))
    index = {f.key: i for i, f in enumerate(futures)}
    results: list = [None] * len(futures)
    try:
        for fut in distributed.as_completed(futures):
            i = index[fut.key]
            if fut.status == "finished":
                results[i] = fut.result()
            else:
                exc = _task_exception(fut)
                if failed is None:
                    raise exc
                results[i] = failed(chunks[i], exc)
            if on_result is not None:
                on_result(i, results[i])
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(futures, force=True)
        raise
    return results


def _task_exception(fut) -> BaseException:
    try:
        return fut.exception()
    except BaseException as exc:  # noqa: BLE001 - a cancelled task has no exception of its own
        return exc


def chunked(items: Sequence, size: int) -> list[list]:
    """``items`` in consecutive chunks of ``size`` (the last one shorter).

    Parameters
    ----------
    items : sequence
        The items.
    size : int
        Items per chunk (at least 1).

    Returns
    -------
    list of list
        The chunks, in order.
    """
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def chunk_size(n_jobs: int, n_workers: int) -> int:
    """Jobs per task for many short jobs: about ``batch.tasks_per_worker`` tasks per worker (load
    balance, progress) and at most ``batch.max_jobs_per_task`` jobs per task (a prompt Ctrl-C).

    Parameters
    ----------
    n_jobs : int
        Number of jobs.
    n_workers : int
        Number of workers.

    Returns
    -------
    int
        Jobs per task, at least 1.
    """
    per_worker, largest = config.get("batch.tasks_per_worker"), config.get("batch.max_jobs_per_task")
    return max(1, min(largest, math.ceil(n_jobs / (per_worker * n_workers))))
