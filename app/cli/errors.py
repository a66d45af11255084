"""The command line's exit statuses and the errors it reports on one line."""

from __future__ import annotations

__all__ = ["EXIT_INTERRUPTED", "EXIT_USAGE", "PROG", "REPORTED_ERRORS", "UsageError"]

PROG = "activecontour"
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class UsageError(Exception):
    """Bad input found by the command line itself (reported like the library's ValueError)."""


#: Errors reported on one line (exit status 2) rather than as a traceback; raised by one image of a
#: batch, they name it and the next image goes on.
REPORTED_ERRORS = (UsageError, FileNotFoundError, ValueError, TypeError, OSError)
