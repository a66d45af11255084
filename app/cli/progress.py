"""The command line's progress on a terminal: one status line on stderr, redrawn in place.

:class:`ImageProgress` follows the images of a serial run (``--jobs 1``) iteration by iteration,
:class:`BatchProgress` the images of a parallel one; a stack's frames use :class:`StatusLine`
itself (:mod:`.stacks`).
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

from ..messages import shown

__all__ = ["BatchProgress", "ImageProgress", "StatusLine", "duration", "is_terminal"]


def duration(seconds):
    """``M:SS`` or ``H:MM:SS``."""
    minutes, seconds = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{seconds:02d}" if hours else f"{minutes}:{seconds:02d}"


def is_terminal(stream):
    """Whether ``stream`` is a terminal (a progress line is drawn only there)."""
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


class StatusLine:
    """A line on ``stream`` (stderr by default) that :meth:`write` replaces and :meth:`clear` erases."""

    def __init__(self, stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self._drawn = False

    def write(self, text):
        self.stream.write(f"\r\033[K{text}")
        self.stream.flush()
        self._drawn = True

    def clear(self):
        """Erase the line (before a summary or error line is printed)."""
        if self._drawn:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self._drawn = False

    close = clear


class ImageProgress(StatusLine):
    """One status line on stderr, redrawn in place at most ten times a second.

    It shows the file (k/N) and its name, ``loading`` while the file is read, ``setting up`` until
    the first iteration (the image's tables and its default start), then the iteration, the
    energy, the time since the run started and an estimate of the time left: ``~`` the mean time
    of the images finished so far times the images left, ``?`` before one has finished.  A single
    image shows no time left and no bar: a run stops when its contour moves less than ``tol``
    pixels per iteration, usually long before ``max_num_iter``, and nothing seen so far says when
    (a bar and a bound scaled to ``max_num_iter`` said "left 8:43" at iteration 2 of a run that
    ended after 8 s).  Used as the ``callback`` of :func:`activecontour.segment`.
    """

    def __init__(self, total, stream=None, clock=time.monotonic):
        super().__init__(stream)
        self.total = total
        self.clock = clock
        self.started = clock()
        self.finished = 0
        self.number = 0
        self.name = ""
        self.image_started = self.started
        self._last = -math.inf

    def start(self, number, path):
        """A new image: count the previous one as finished and show that this one is loading."""
        now = self.clock()
        if self.number:
            self.finished += 1
        self.number, self.name, self.image_started = number, shown(Path(path).name), now
        try:
            size = f" ({os.path.getsize(path) / 1e6:.1f} MB)"
        except OSError:
            size = ""
        self._draw(f"loading{size}", now)

    def note(self, text):
        """Show what the current image is doing before its first iteration (``setting up``)."""
        self._draw(text, self.clock())

    def __call__(self, state):
        now = self.clock()
        if now - self._last < 0.1 and state.iteration < state.max_num_iter:
            return None
        self._draw(f"iteration {state.iteration} energy {state.energy:<11.6g}", now)
        return None

    def remaining(self, now):
        """``"~M:SS"`` (an estimate from the images finished), ``"?"`` before one has finished,
        or None for a single image (no estimate is shown)."""
        if self.finished:
            per_image = (self.image_started - self.started) / self.finished
            left = per_image * (self.total - self.number) + max(0.0, per_image - (now - self.image_started))
            return "~" + duration(left)
        return None if self.total == 1 else "?"

    def _draw(self, text, now):
        left = self.remaining(now)
        self.write(f"[{self.number}/{self.total}] {self.name}: {text} elapsed {duration(now - self.started)}"
                   + ("" if left is None else f" left {left}"))
        self._last = now


class BatchProgress(StatusLine):
    """One status line on a terminal: images done of all, elapsed time, estimated time left.

    The time left is the elapsed time per finished image times the images left (``?`` before the
    first one finishes).

    Parameters
    ----------
    total : int
        Images in the batch.
    jobs : int
        Worker processes (shown).
    stream : file, optional
        ``sys.stderr`` by default.
    clock : callable
        Seconds, monotonic.
    """

    width = 20

    def __init__(self, total, *, jobs=1, stream=None, clock=time.monotonic):
        super().__init__(stream)
        self.total = total
        self.jobs = jobs
        self.done = 0
        self.clock = clock
        self.started = clock()
        self.draw()

    def advance(self):
        """One more image finished: redraw."""
        self.done += 1
        self.draw()

    def remaining(self, now):
        """Seconds left for the whole batch, or None before an image has finished."""
        if not self.done:
            return None
        return (now - self.started) / self.done * (self.total - self.done)

    def draw(self):
        now = self.clock()
        filled = self.width * self.done // max(self.total, 1)
        left = self.remaining(now)
        self.write(
            f"[{self.done}/{self.total}] images done, {self.jobs} jobs: "
            f"[{'#' * filled}{'-' * (self.width - filled)}] elapsed {duration(now - self.started)} "
            f"left {'?' if left is None else '~' + duration(left)}"
        )
