"""Many images: worker processes on one machine, or the workers of a Dask cluster.

Each image is segmented by :func:`activecontour.segment` on its own, exactly as a serial loop would,
so every result is identical to the serial one whatever the number of workers or machines.

Parts
-----
=======================================  ========================================================
:mod:`~activecontour.batch.many`         :func:`segment_many` (worker processes on this machine)
                                         and :class:`BatchResult`, one image's outcome
:mod:`~activecontour.batch.cluster`      :func:`segment_dask`: the workers of a ``dask.distributed``
                                         cluster (the ``activecontour[dask]`` extra)
:mod:`~activecontour.batch.pool`         :func:`map_unordered`, the process pool under
                                         :func:`segment_many` (workers that die with their
                                         parent, a broken pool restarted, prompt interrupts), and
                                         :func:`default_jobs`
:mod:`~activecontour.batch.files`        :func:`find_images`: the image files of folders and
                                         glob patterns, sorted; :data:`INPUT_SUFFIXES`
=======================================  ========================================================
"""

from activecontour.batch.cluster import segment_dask
from activecontour.batch.files import INPUT_SUFFIXES, find_images
from activecontour.batch.many import BatchResult, segment_many
from activecontour.batch.pool import default_jobs, map_unordered

__all__ = ["INPUT_SUFFIXES", "BatchResult", "default_jobs", "find_images", "map_unordered",
           "segment_dask", "segment_many"]
