"""Many images in worker processes on this machine: :func:`segment_many` and its records.

Each image is segmented by :func:`activecontour.segment` on its own, exactly as a serial loop would:
the same function, the same arguments, no state shared between images, so every result is
identical to the serial one whatever the number of workers.  Results come back as each image
finishes, as :class:`BatchResult` records that name the image (its position and, for a file, its
path); an exception raised by one image is reported in that image's record and the others go on.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Iterable, Sized
from dataclasses import dataclass

import numpy as np

from activecontour._segment import segment
from activecontour.batch.pool import map_unordered
from activecontour.result import SegmentationResult
from activecontour.settings import Settings

__all__ = ["BatchResult", "segment_many"]


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
        :func:`activecontour.load_image`.  For folders and glob patterns use
        :func:`~activecontour.batch.find_images`.  A generator is consumed
        lazily: at most ``jobs`` images are in flight at a time.
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
        A worker process that dies (killed, out of memory) fails the images in flight at that
        moment with :class:`concurrent.futures.process.BrokenProcessPool` (a Python exception
        never does); the images after them go to a new pool.  Workers end with this process,
        even when it is killed.

    Raises
    ------
    TypeError
        For ``images`` given as one string or path (not an iterable of them), an unknown keyword,
        a keyword of the wrong type or ``callback`` (before any work starts).
    ValueError
        For a bad ``jobs`` or ``context``, or a keyword out of range (before any work starts).

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



def _segment_task(init, segment_kwargs):
    """The picklable one-image task, after checking the keywords as settings
    (:meth:`activecontour.settings.Settings.of`): a bad one is refused before any work."""
    if "callback" in segment_kwargs:
        raise TypeError("callback is not accepted for a batch: the images are segmented in other "
                        "processes (iterate over the results to follow progress)")
    try:
        Settings.of(segment_kwargs)
    except TypeError as exc:
        raise TypeError(f"segment_many/segment_dask: {exc}") from None
    return functools.partial(segment, init=init, **segment_kwargs)  # segment() reads a path itself



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



def _source_of(item):
    return os.fspath(item) if isinstance(item, (str, os.PathLike)) else None

