"""The batch loop of ``activecontour segment``: each image read, segmented and written by a worker.

The images run in ``--jobs`` worker processes (:func:`activecontour.batch.map_unordered`); each
worker reads its image, segments it and writes its files as a group
(:func:`activecontour.io.save_result`), so the files are the same bytes whatever the number of
jobs, and an image that fails leaves no file and does not stop the others.  The parent process
only reports: a summary line per image as it finishes, and one progress display for the batch
(images done out of all, elapsed time, an estimate of the time left).
"""

from __future__ import annotations

import functools
import os
import sys
import time
from dataclasses import dataclass

__all__ = ["BatchProgress", "SaveTask", "check_all", "run"]


@dataclass(frozen=True)
class SaveTask:
    """Segment one image file and write its outputs: what each worker runs (picklable).

    Attributes
    ----------
    init : object
        The init given to :func:`activecontour.segment` (the same for every image).
    settings : dict
        segment()'s keyword arguments.
    formats : tuple of str
        Contour formats.
    color : str or tuple
        Overlay colour.
    init_description : str
        How the init was given, for the contour files' metadata.
    protect : tuple of str
        The input images, which no output may overwrite.
    """

    init: object
    settings: dict
    formats: tuple
    color: object
    init_description: str
    protect: tuple

    def __call__(self, plan, callback=None):
        """Segment ``plan = (image path, output stem)``; return (result, seconds, written paths)."""
        import activecontour
        from activecontour import io

        image_path, stem = plan
        image = activecontour.load_image(image_path)
        started = time.perf_counter()
        result = activecontour.segment(image, self.init, callback=callback, **self.settings)
        elapsed = time.perf_counter() - started
        metadata = {
            "image": os.fspath(image_path),
            "init": self.init_description,
            "parameters": self.settings,
            "wall_time_s": elapsed,
        }
        written = io.save_result(result, image, stem, list(self.formats), metadata=metadata,
                                 color=self.color, protect=list(self.protect))
        return result, elapsed, written


def check_all(check, image_paths, *, jobs):
    """Run ``check(image_path)`` on every image, ``jobs`` at a time; raise the first failure.

    Checking reads every image, so a batch of many files is checked in parallel too.  Of several
    bad inputs, the first in the input order is raised, as a serial loop would.
    """
    from activecontour.batch import map_unordered

    failures = [(index, error) for index, (_, error) in map_unordered(check, image_paths, jobs=jobs)
                if error is not None]
    if failures:
        raise min(failures, key=lambda failure: failure[0])[1]


def run(task, plans, *, jobs, summary, report_error, quiet=False, show_progress=False,
        image_progress=None, stream=None):
    """Run ``task`` on every plan in ``jobs`` processes; report each image; return the failures.

    Parameters
    ----------
    task : SaveTask
    plans : list of (image path, output stem)
    jobs : int
        Worker processes (capped at the number of images); 1 runs in this process.
    summary : callable
        ``summary(name, result, elapsed, written) -> str``, the line printed for a finished image.
    report_error : callable
        ``report_error(image_path, exception)``, called for an image that failed.
    quiet : bool
        No summary lines and no progress display.
    show_progress : bool
        Draw the progress display (on a terminal).
    image_progress : callable, optional
        ``image_progress(name)`` gives the per-iteration callback of a batch of one image (with
        ``close()``); a batch of several images gets :class:`BatchProgress` instead.
    stream : file, optional
        Where the progress display goes; ``sys.stderr`` by default.

    Returns
    -------
    int
        The number of images that failed.
    """
    from activecontour.batch import map_unordered

    show_progress = show_progress and not quiet
    one_bar = None
    if len(plans) == 1 and show_progress and image_progress is not None:
        one_bar = image_progress(os.path.basename(plans[0][0]))
        task = functools.partial(task, callback=one_bar)
    bar = BatchProgress(len(plans), jobs=min(jobs, len(plans)), stream=stream) \
        if show_progress and one_bar is None else None
    failures = 0
    try:
        for index, (value, error) in map_unordered(task, plans, jobs=jobs):
            if one_bar is not None:
                one_bar.close()
                one_bar = None
            line = None
            if error is not None:
                failures += 1
            elif not quiet:
                line = summary(os.path.basename(plans[index][0]), *value)
            if bar is not None:
                bar.clear()
            if error is not None:
                report_error(plans[index][0], error)
            elif line is not None:
                print(line, flush=True)
            if bar is not None:
                bar.advance()
    finally:
        for display in (one_bar, bar):
            if display is not None:
                display.close()
    return failures


class BatchProgress:
    """One line on a terminal: images done out of all, elapsed time, estimated time left.

    Parameters
    ----------
    total : int
        Images in the batch.
    jobs : int
        Worker processes (shown).
    stream : file, optional
        ``sys.stderr`` by default.
    """

    width = 30

    def __init__(self, total, *, jobs=1, stream=None):
        self.total = total
        self.jobs = jobs
        self.done = 0
        self.stream = stream if stream is not None else sys.stderr
        self.started = time.monotonic()
        self._drawn = False
        self.draw()

    def advance(self):
        """One more image finished: redraw."""
        self.done += 1
        self.draw()

    def draw(self):
        elapsed = time.monotonic() - self.started
        filled = self.width * self.done // max(self.total, 1)
        left = f"~{_clock(elapsed * (self.total - self.done) / self.done)} left" if self.done else "? left"
        self.stream.write(
            f"\r[{'#' * filled}{'-' * (self.width - filled)}] {self.done}/{self.total} images  "
            f"{_clock(elapsed)} elapsed  {left}  ({self.jobs} job{'s' if self.jobs != 1 else ''})"
        )
        self.stream.flush()
        self._drawn = True

    def clear(self):
        """Erase the line (before a summary line is printed)."""
        if self._drawn:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self._drawn = False

    close = clear


def _clock(seconds):
    seconds = int(round(seconds))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"
