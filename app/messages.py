"""Messages on one line, shared by the command line and the viewer."""

from __future__ import annotations

import os

__all__ = ["one_line", "shown"]


def one_line(exc):
    """An exception's message on one line (some third-party messages span several); a KeyError
    without its quotes, an OSError as ``reason: 'file'``."""
    text = str(exc)
    if isinstance(exc, KeyError) and exc.args:
        text = str(exc.args[0])
    if isinstance(exc, OSError) and exc.strerror and exc.filename:
        text = f"{exc.strerror}: {exc.filename!r}"
    return shown(" ".join(text.split()) or type(exc).__name__)


def shown(text):
    """``text`` (a line, a path) with every character that is not printable escaped as Python
    would (a newline as ``\\n``), so a file name never splits or forges a line of output."""
    text = os.fspath(text)
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)
