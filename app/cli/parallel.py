"""The parallel loop of ``activecontour segment --jobs N``: whole images in worker processes.

Each worker runs the command line's own per-image step (:func:`.segment.segment_one`: read,
segment, write the files all or none), so the files are the same bytes whatever the number of jobs,
and an image that fails leaves no file and does not stop the others.  The workers come from
:func:`activecontour.batch.map_unordered`.  This process only reports: each image's summary or error
line as it finishes, and one status line for the batch (images done of all, elapsed time, an
estimate of the time left).
"""

from __future__ import annotations

import functools

from .progress import BatchProgress

__all__ = ["run"]


def run(segment_one, plans, *, jobs, expected, report_line, report_failure, show_progress=False,
        stream=None):
    """Run ``segment_one(image_path, stem)`` for every plan in ``jobs`` worker processes.

    Parameters
    ----------
    segment_one : callable
        Picklable; returns the summary line of the image.
    plans : list of (image path, output stem)
    jobs : int
    expected : tuple of exception types
        What an image may raise and the batch survives: passed to ``report_failure``.  Anything
        else is raised here, as the serial loop would.  A worker that dies (killed, out of memory)
        is the failure of the images in flight at that moment; the others go to new workers.
    report_line : callable or None
        ``report_line(line)`` for a finished image; None prints nothing (``--quiet``).
    report_failure : callable
        ``report_failure(image_path, exception)``.
    show_progress : bool
        Draw :class:`BatchProgress` on ``stream`` (``sys.stderr`` by default).

    Returns
    -------
    int
        The number of images that failed.
    """
    from concurrent.futures.process import BrokenProcessPool

    from activecontour.batch import map_unordered

    expected = (*expected, BrokenProcessPool)
    bar = BatchProgress(len(plans), jobs=jobs, stream=stream) if show_progress else None
    failures = 0
    try:
        task = functools.partial(_run_plan, segment_one=segment_one)
        for index, (line, error) in map_unordered(task, plans, jobs=jobs):
            if error is not None and not isinstance(error, expected):
                raise error
            if bar is not None:
                bar.clear()
            if isinstance(error, BrokenProcessPool):  # say what happened, not the pool's words
                error = BrokenProcessPool("a worker process died (killed, or out of memory) while "
                                          "this image was being segmented; the others went on")
            if error is not None:
                failures += 1
                report_failure(plans[index][0], error)
            elif report_line is not None:
                report_line(line)
            if bar is not None:
                bar.advance()
    finally:
        if bar is not None:
            bar.close()
    return failures


def _run_plan(plan, *, segment_one):
    image_path, stem = plan
    return segment_one(image_path, stem)
