"""Worker processes on this machine: the pool under :func:`~activecontour.batch.segment_many`.

What a batch of independent items needs from a process pool, beyond ``concurrent.futures``:

* at most one item per worker in flight and none queued, so a generator is not read ahead of the
  workers and an interrupt has nothing queued to wait for;
* a worker that dies (killed, out of memory) fails the items in flight with it, and the rest go to
  a fresh pool;
* Ctrl-C, or the caller closing the iteration early, stops the items in flight at once (the workers
  are interrupted, then killed if they do not stop), whether the signal reached the whole process
  group or this process alone;
* a worker never outlives this process: killed with ``kill -9``, its workers follow within a second
  (:func:`_die_with_parent`), so nothing keeps its stdout and stderr open.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import sys
import threading
from collections.abc import Sized

import numpy as np

__all__ = ["default_jobs", "map_unordered"]

#: Seconds an interrupted worker gets to stop on its own (it may be removing a temporary file)
#: before it is killed.
STOP_GRACE_S = 1.0

#: Seconds between two looks of a worker's watcher thread at its parent.
PARENT_POLL_S = 0.5


def map_unordered(function, items, *, jobs=None, context=None):
    """Call ``function(item)`` for every item in worker processes; yield the outcomes as they finish.

    Parameters
    ----------
    function : callable
        Picklable (a module-level function, or a :func:`functools.partial` of one) when it runs in
        other processes.
    items : iterable
        Picklable arguments; a generator is consumed lazily, at most ``jobs`` in flight.
    jobs, context
        As in :func:`activecontour.batch.segment_many`; ``jobs=1`` (or a single item) runs in this
        process.

    Yields
    ------
    (index, (value, error))
        ``index`` is the item's position; ``error`` is the exception ``function`` raised (``value``
        is then None), or None.  An ``Exception`` from one item never stops the others.  A worker
        that dies fails the items in flight at that moment with
        :class:`concurrent.futures.process.BrokenProcessPool`; the items after them run in a new
        pool.
    """
    jobs = default_jobs() if jobs is None else _check_jobs(jobs)
    start_method = _start_context(context)
    if isinstance(items, Sized):
        jobs = min(jobs, max(len(items), 1))
    if jobs == 1:
        return _map_here(function, items)
    return _map_in_pool(function, items, jobs, start_method)


def default_jobs():
    """The number of cores this process may run on (its CPU affinity where the system has one)."""
    if hasattr(os, "process_cpu_count"):  # Python 3.13
        return os.process_cpu_count() or 1
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0)) or 1
    return os.cpu_count() or 1


def _map_in_pool(function, items, jobs, start_method):
    # imported when used: a single segment() call never pays for them
    from concurrent.futures import FIRST_COMPLETED, wait
    from concurrent.futures.process import BrokenProcessPool

    numbered = enumerate(items)
    stop = start_method.Event()  # set when this generator ends early: queued items are skipped
    pool, pending = None, {}
    try:
        while True:
            if pool is None:
                pool = _new_pool(jobs, start_method, stop)
            # one item per worker and none queued: an interrupt then stops every item in flight,
            # and a generator is not read ahead of the workers
            for index, item in itertools.islice(numbered, jobs - len(pending)):
                pending[_submit(pool, function, item)] = index
            if not pending:
                break
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            broken = False
            for future in sorted(done, key=pending.get):
                index = pending.pop(future)
                value, error = _outcome(future)
                broken = broken or isinstance(error, BrokenProcessPool)
                yield index, (value, error)
            if broken:  # the other items in flight fail with the pool; the rest get a new one
                for future in sorted(wait(pending).done, key=pending.get):
                    yield pending.pop(future), _outcome(future)
                pool.shutdown(wait=True)
                pool = None
    except BaseException:  # Ctrl-C, or the caller closing the generator (GeneratorExit)
        stop.set()
        if pool is not None:
            _stop_workers(pool)
        raise
    finally:
        for future in pending:
            future.cancel()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _new_pool(jobs, start_method, stop):
    from concurrent.futures import ProcessPoolExecutor

    with _interrupts_held():  # the workers start with Ctrl-C held back, not in the middle of it
        return ProcessPoolExecutor(jobs, mp_context=start_method, initializer=_start_worker,
                                   initargs=(stop, os.getpid()))


def _stop_workers(pool):
    """Interrupt the workers of an abandoned pool, and kill those still running after a grace time.

    A Ctrl-C at the terminal reaches the workers too, and they stop by themselves; SIGINT sent to
    this process alone, or the caller closing the iteration, reaches only this process.
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        process.join(0.2 / max(len(processes), 1))
    for process in processes:
        if process.is_alive():
            with contextlib.suppress(OSError):
                os.kill(process.pid, signal.SIGINT)
    for process in processes:
        process.join(STOP_GRACE_S)
        if process.is_alive():
            process.kill()
            process.join()


def _map_here(function, items):
    for index, item in enumerate(items):
        try:
            value = function(item)
        except Exception as exc:  # one image's failure is reported, the batch goes on
            yield index, (None, exc)
        else:
            yield index, (value, None)


def _outcome(future):
    """(value, None) or (None, the exception) of a finished future."""
    try:
        return future.result(), None
    except Exception as exc:
        return None, exc


def _submit(pool, function, item):
    """Submit one item; a pool broken by a dead worker gives a future holding that error."""
    from concurrent.futures import Future
    from concurrent.futures.process import BrokenProcessPool

    try:
        return pool.submit(_interruptible, function, item)
    except BrokenProcessPool as exc:
        failed = Future()
        failed.set_exception(exc)
        return failed


def _check_jobs(jobs):
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1 or None (every core), got {jobs!r}")
    return int(jobs)


def _start_context(context):
    import multiprocessing

    if context is None:
        default = multiprocessing.get_context()
        if (default.get_start_method() == "fork" and threading.active_count() > 1
                and "forkserver" in multiprocessing.get_all_start_methods()):
            return multiprocessing.get_context("forkserver")  # forking a threaded process can deadlock
        return default
    if isinstance(context, str):
        methods = multiprocessing.get_all_start_methods()
        if context not in methods:
            raise ValueError(f"context must be one of {tuple(methods)} or a multiprocessing context, "
                             f"got {context!r}")
        return multiprocessing.get_context(context)
    if not hasattr(context, "Process"):
        raise ValueError(f"context must be a start method name or a multiprocessing context, got "
                         f"{context!r}")
    return context


@contextlib.contextmanager
def _interrupts_held():
    """Block SIGINT in this thread (it stays pending); workers started meanwhile inherit the block."""
    if not hasattr(signal, "pthread_sigmask"):  # Windows
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


# ----------------------------------------------------------------------------- in a worker process

#: In a worker process: the parent's "stop" event (set by :func:`_start_worker`).
_worker_stop = None


def _start_worker(stop, parent_pid):
    """Worker initialiser: die with the parent; an idle worker ignores Ctrl-C (the parent decides
    what stops)."""
    global _worker_stop
    _worker_stop = stop
    _die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # one held back is dropped


def _die_with_parent(parent_pid):
    """End this worker when the process that started the pool dies, even by ``kill -9``.

    On Linux the kernel sends SIGKILL when the worker's parent ends (``prctl(PR_SET_PDEATHSIG)``),
    which works while a compiled kernel holds the interpreter.  Everywhere, a daemon thread looks
    every :data:`PARENT_POLL_S` seconds whether the worker's parent changed (it was re-parented)
    or ``parent_pid`` ended, and ends the process if so.  (With the ``forkserver`` start method the
    worker's parent is the fork server, which ends with the process that started it.)
    """
    parent_at_start = os.getppid()
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            pr_set_pdeathsig = 1
            libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
    if not _alive(parent_pid) or os.getppid() != parent_at_start:
        os._exit(1)  # the parent died before the request above took effect

    def watch():
        while os.getppid() == parent_at_start and _alive(parent_pid):
            threading.Event().wait(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="activecontour-parent-watch", daemon=True).start()


def _alive(pid):
    """True while the process ``pid`` exists (POSIX); always True where that cannot be asked."""
    if os.name != "posix":
        return True  # os.kill(pid, 0) would end the process on Windows
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # exists, owned by someone else
    return True


def _interruptible(function, item):
    """Run one item in a worker with Ctrl-C enabled, so an interrupt stops the work at once."""
    if _worker_stop is not None and _worker_stop.is_set():
        return None  # the parent has stopped: nobody waits for this item
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return function(item)
    finally:
        signal.signal(signal.SIGINT, previous)
