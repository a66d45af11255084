"""Many images: worker processes on one machine, or the workers of a Dask cluster.

Each image is segmented by :func:`activecontour.segment` on its own, exactly as a serial loop would:
the same function, the same arguments, no state shared between images, so every result is
identical to the serial one whatever the number of workers or machines.  Results come back as each
image finishes, as :class:`BatchResult` records that name the image (its position and, for a file,
its path); an exception raised by one image is reported in that image's record and the others go
on.

Parts
-----
segment_many   worker processes (``concurrent.futures``) on this machine
segment_dask   the workers of a ``dask.distributed`` cluster (the ``activecontour[dask]`` extra)
map_unordered  the process pool under :func:`segment_many`, for any picklable function
find_images    the image files of folders and glob patterns, sorted
BatchResult    one image's outcome
"""

from __future__ import annotations

import contextlib
import functools
import glob
import inspect
import itertools
import os
import signal
from collections.abc import Iterable, Sized
from dataclasses import dataclass

import numpy as np

from activecontour.result import SegmentationResult
from activecontour.segment import segment

__all__ = ["INPUT_SUFFIXES", "BatchResult", "default_jobs", "find_images", "map_unordered",
           "segment_dask", "segment_many"]

#: File name suffixes taken as images when a folder is listed (compared in lower case).
INPUT_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg", ".bmp", ".gif", ".webp", ".pgm", ".ppm",
                  ".pnm")


_GLOB_CHARACTERS = frozenset("*?[")


@dataclass
class BatchResult:
    """The outcome of one image of a batch.

    Attributes
    ----------
    index : int
        The image's position in the input sequence.
    source : str or None
        The path the image was read from, None for an array.
    result : SegmentationResult or None
        The segmentation, None when it failed.
    error : BaseException or None
        What the image raised (reading or segmenting it), None when it succeeded.
    """

    index: int
    source: str | None
    result: SegmentationResult | None
    error: BaseException | None

    @property
    def ok(self):
        """True when the image was segmented."""
        return self.error is None


def segment_many(images, init=None, *, jobs=None, context=None, **segment_kwargs):
    """Segment many images in worker processes; yield each result as it finishes.

    Parameters
    ----------
    images : iterable of ndarray or path
        Images as arrays, or files (str or os.PathLike) that the workers read with
        :func:`activecontour.load_image`.  For folders and glob patterns use :func:`find_images`.
        A generator is consumed lazily: at most ``jobs`` images are in flight at a time.
    init : optional
        The initial curve of every image, anything :func:`activecontour.segment` accepts (None, a
        curve, a list of curves, a mask, ``"grid"``, ...).
    jobs : int, optional
        Worker processes; None uses every core this process may run on.  ``jobs=1`` segments the
        images one after another in this process.  Never more workers than images.
    context : {"spawn", "fork", "forkserver"} or multiprocessing context, optional
        How workers start; None takes the platform's default (:func:`multiprocessing.get_context`),
        except that a process running threads is not forked (``"forkserver"`` instead).  Every
        method gives the same results: nothing but the arguments reaches a worker.
    **segment_kwargs
        Keyword arguments of :func:`activecontour.segment` (``backend``, ``mu``, ``options``, ...),
        the same for every image.  ``callback`` is not accepted: the images run in other processes.

    Yields
    ------
    BatchResult
        In the order the images finish (use ``index`` or ``source`` to match them to the input).
        An image that raised has ``error`` set and ``result=None``; the others are unaffected.
        A worker process that dies (killed, out of memory) breaks the pool: the images in flight
        and those not yet started then fail with
        :class:`concurrent.futures.process.BrokenProcessPool` (a Python exception never does).

    Raises
    ------
    TypeError
        For ``images`` given as one string or path (not an iterable of them), an unknown keyword or
        ``callback`` (before any work starts).
    ValueError
        For a bad ``jobs`` or ``context``.

    Examples
    --------
    >>> from activecontour.batch import find_images, segment_many
    >>> for item in segment_many(find_images("micrographs/"), jobs=4, mu=0.1):  # doctest: +SKIP
    ...     print(item.source, item.result.n_iter if item.ok else item.error)
    """
    _check_images_argument(images)
    task = _segment_task(init, segment_kwargs)
    sources = {}

    def items():
        for index, item in enumerate(images):
            sources[index] = _source_of(item)
            yield item

    outcomes = map_unordered(task, _sized(items(), images), jobs=jobs, context=context)
    return (BatchResult(index, sources.pop(index), value, error) for index, (value, error) in outcomes)


def segment_dask(images, init=None, *, client=None, **segment_kwargs):
    """Segment many images on the workers of a ``dask.distributed`` cluster; yield results as they finish.

    Needs the optional extra: ``pip install "activecontour[dask]"``.

    Parameters
    ----------
    images : folder, glob pattern, sequence of paths or arrays, or dask.array
        Files are read by the workers (the paths must be readable there: a shared file system).  A
        folder or a pattern is expanded here by :func:`find_images`.  A ``dask.array`` of shape
        (n, M, N) or (n, M, N, C) is a stack of n images: each is computed on a worker straight
        from its chunks and segmented there, so the stack never has to fit on this machine.
    init : optional
        The initial curve of every image (see :func:`activecontour.segment`).
    client : distributed.Client, optional
        The cluster to use; by default the current client (``distributed.get_client()``).
    **segment_kwargs
        Keyword arguments of :func:`activecontour.segment`, the same for every image (not
        ``callback``).

    Yields
    ------
    BatchResult
        In the order the images finish, as :func:`segment_many`; ``source`` is the path for files
        and None for a stack's images (``index`` is then the position along its first axis).
        Stopping the iteration early cancels the images not yet done.

    Examples
    --------
    >>> from dask.distributed import Client, LocalCluster           # doctest: +SKIP
    >>> with LocalCluster(n_workers=4) as cluster, Client(cluster) as client:
    ...     masks = {item.source: item.result.mask for item in segment_dask("micrographs/", mu=0.1)}
    """
    try:
        import distributed
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError(
            "segment_dask needs dask.distributed: pip install \"activecontour[dask]\""
        ) from exc
    if client is None:
        try:
            client = distributed.get_client()
        except ValueError:
            raise ValueError("segment_dask needs a dask.distributed Client: create one (for example "
                             "Client(LocalCluster())) or pass client=...") from None
    task = _segment_task(init, segment_kwargs)
    if _is_dask_array(images):
        futures, sources = _submit_stack(client, task, images), None
    else:
        if isinstance(images, (str, os.PathLike)):
            images = find_images(images)
        _check_images_argument(images)
        sources = list(images)
        futures = client.map(task, sources, pure=False)
    return _gather_as_completed(client, futures, sources)


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
        As in :func:`segment_many`; ``jobs=1`` (or a single item) runs in this process.

    Yields
    ------
    (index, (value, error))
        ``index`` is the item's position; ``error`` is the exception ``function`` raised (``value``
        is then None), or None.  An ``Exception`` from one item never stops the others.
    """
    jobs = default_jobs() if jobs is None else _check_jobs(jobs)
    start_method = _start_context(context)
    if isinstance(items, Sized):
        jobs = min(jobs, max(len(items), 1))
    if jobs == 1:
        return _map_here(function, items)
    return _map_in_pool(function, items, jobs, start_method)


def _map_in_pool(function, items, jobs, start_method):
    # imported when used: a single segment() call never pays for them
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    numbered = enumerate(items)
    stop = start_method.Event()  # set when this generator ends early: queued items are skipped
    pool, pending = None, {}
    try:
        with _interrupts_held():  # the workers start with Ctrl-C held back, not in the middle of it
            pool = ProcessPoolExecutor(jobs, mp_context=start_method, initializer=_start_worker,
                                       initargs=(stop,))
            # one item per worker and none queued: an interrupt then stops every item in flight,
            # and a generator is not read ahead of the workers
            for index, item in itertools.islice(numbered, jobs):
                pending[_submit(pool, function, item)] = index
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=pending.get):
                index = pending.pop(future)
                yield index, _outcome(future)
                for next_index, item in itertools.islice(numbered, 1):
                    pending[_submit(pool, function, item)] = next_index
    except BaseException:  # Ctrl-C, or the caller closing the generator (GeneratorExit)
        stop.set()
        raise
    finally:
        for future in pending:
            future.cancel()
        if pool is not None:
            pool.shutdown(wait=True)


def find_images(*sources):
    """The image files named by paths, folders and glob patterns, in order, each once.

    Parameters
    ----------
    *sources : str or os.PathLike
        A file is taken as it is.  A folder gives the files in it (not in its sub-folders) whose
        suffix is one of :data:`INPUT_SUFFIXES`, sorted by name.  A pattern with ``*``, ``?`` or
        ``[`` that is not an existing file is expanded by :func:`glob.glob` (``**`` spans folders),
        sorted, files only.  From folders and patterns, the outputs of ``activecontour segment``
        (``<name>_mask.png`` and ``<name>_overlay.png`` next to an image ``<name>.*``) are left out,
        so that a second run over the same folder does not take them for inputs.

    Returns
    -------
    list of str

    Raises
    ------
    FileNotFoundError
        For a path that does not exist and is not a pattern.
    ValueError
        For a folder without images or a pattern that matches no file.
    """
    files = []
    for source in sources:
        text = os.fspath(source)
        if os.path.isdir(text):
            found = [os.path.join(text, name) for name in sorted(os.listdir(text))
                     if name.lower().endswith(INPUT_SUFFIXES) and os.path.isfile(os.path.join(text, name))]
            found = _without_outputs(found)
            if not found:
                raise ValueError(f"no image files ({', '.join(INPUT_SUFFIXES)}) in the folder {text!r}")
        elif os.path.exists(text) or not _GLOB_CHARACTERS.intersection(text):
            if not os.path.exists(text):
                raise FileNotFoundError(f"image file not found: {text!r}")
            found = [text]
        else:
            found = _without_outputs(sorted(p for p in glob.glob(text, recursive=True) if os.path.isfile(p)))
            if not found:
                raise ValueError(f"no file matches the pattern {text!r}")
        files.extend(found)
    return list(dict.fromkeys(files))


def default_jobs():
    """The number of cores this process may run on (its CPU affinity where the system has one)."""
    if hasattr(os, "process_cpu_count"):  # Python 3.13
        return os.process_cpu_count() or 1
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0)) or 1
    return os.cpu_count() or 1


# ----------------------------------------------------------------------------------------- helpers


def _segment_task(init, segment_kwargs):
    """The picklable one-image task, after checking the keywords against segment()'s signature."""
    if "callback" in segment_kwargs:
        raise TypeError("callback is not accepted for a batch: the images are segmented in other "
                        "processes (iterate over the results to follow progress)")
    try:
        inspect.signature(segment).bind(None, init, **segment_kwargs)
    except TypeError as exc:
        raise TypeError(f"segment_many/segment_dask: {exc}") from None
    return functools.partial(segment, init=init, **segment_kwargs)  # segment() reads a path itself


def _gather_as_completed(client, futures, sources):
    """BatchResults of Dask futures as they finish; what is left is cancelled when the caller stops."""
    import distributed

    positions = {future.key: index for index, future in enumerate(futures)}
    remaining = set(positions)
    try:
        for future in distributed.as_completed(futures):
            index = positions[future.key]
            remaining.discard(future.key)
            result, error = _outcome(future)
            source = _source_of(sources[index]) if sources is not None else None
            yield BatchResult(index, source, result, error)
    finally:
        client.cancel([f for f in futures if f.key in remaining])


def _segment_block(block, *, task):
    """Segment the one image of a (1, M, N[, C]) chunk of a stack."""
    return task(np.asarray(block)[0])


def _submit_stack(client, task, stack):
    """One future per image of a dask.array stack, computed from its chunks on the workers."""
    import dask

    if stack.ndim not in (3, 4):
        raise ValueError(f"a dask.array of images must have shape (n, M, N) or (n, M, N, C), got shape "
                         f"{stack.shape}")
    blocks = stack.rechunk({0: 1, **{axis: -1 for axis in range(1, stack.ndim)}}).to_delayed().ravel()
    run = dask.delayed(functools.partial(_segment_block, task=task), pure=True)
    return client.compute([run(block) for block in blocks])


def _is_dask_array(value):
    module = type(value).__module__
    return module.startswith("dask.array") and hasattr(value, "to_delayed")


def _check_images_argument(images):
    """Refuse one path or one array mistaken for a sequence of them."""
    if isinstance(images, (str, bytes, os.PathLike)):
        raise TypeError("images must be an iterable of arrays or paths, got a single "
                        f"{type(images).__name__} {os.fsdecode(images)!r}; for a folder or a pattern "
                        "use activecontour.batch.find_images(...)")
    if isinstance(images, np.ndarray):
        raise TypeError("images must be an iterable of arrays or paths, got one ndarray; pass a list "
                        "(or list(stack) for a stack of images)")
    if not isinstance(images, Iterable):
        raise TypeError(f"images must be an iterable of arrays or paths, got {type(images).__name__}")


class _SizedIterator:
    """An iterator that knows its length (so that map_unordered starts no more workers than items)."""

    def __init__(self, iterator, length):
        self._iterator, self._length = iterator, length

    def __iter__(self):
        return self._iterator

    def __len__(self):
        return self._length


def _sized(iterator, images):
    return _SizedIterator(iterator, len(images)) if isinstance(images, Sized) else iterator


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


def _source_of(item):
    return os.fspath(item) if isinstance(item, (str, os.PathLike)) else None


def _without_outputs(paths):
    """Leave out ``<name>_mask.png`` / ``<name>_overlay.png`` that sit next to an image ``<name>.*``."""
    from activecontour.io import output_paths

    endings = [os.fspath(path) for path in output_paths("", ())]  # "_mask.png", "_overlay.png"
    stems = {os.path.splitext(p)[0] for p in paths}
    return [p for p in paths if not any(p.endswith(e) and p[: -len(e)] in stems for e in endings)]


def _map_here(function, items):
    for index, item in enumerate(items):
        try:
            value = function(item)
        except Exception as exc:  # one image's failure is reported, the batch goes on
            yield index, (None, exc)
        else:
            yield index, (value, None)


def _check_jobs(jobs):
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1 or None (every core), got {jobs!r}")
    return int(jobs)


def _start_context(context):
    import multiprocessing
    import threading

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


#: In a worker process: the parent's "stop" event (set by :func:`_start_worker`).
_worker_stop = None


def _start_worker(stop):
    """Worker initialiser: an idle worker ignores Ctrl-C (the parent decides what stops)."""
    global _worker_stop
    _worker_stop = stop
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # one held back is dropped


def _interruptible(function, item):
    """Run one item in a worker with Ctrl-C enabled, so an interrupt stops the work at once."""
    if _worker_stop is not None and _worker_stop.is_set():
        return None  # the parent has stopped: nobody waits for this item
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        return function(item)
    finally:
        signal.signal(signal.SIGINT, previous)
