"""Many images on the workers of a ``dask.distributed`` cluster (the ``activecontour[dask]`` extra)."""

from __future__ import annotations

import functools
import os

import numpy as np

from activecontour.batch.files import find_images
from activecontour.batch.many import BatchResult, _check_images_argument, _segment_task, _source_of
from activecontour.batch.pool import _outcome

__all__ = ["segment_dask"]


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

