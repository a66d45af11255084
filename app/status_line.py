"""One status line on a terminal, redrawn in place: what the CLI's progress displays share."""

from __future__ import annotations

import sys


def duration(seconds):
    """``M:SS`` or ``H:MM:SS``."""
    minutes, seconds = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{seconds:02d}" if hours else f"{minutes}:{seconds:02d}"


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
