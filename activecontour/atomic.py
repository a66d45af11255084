"""Writing files all or nothing: each file whole or not at all, and groups of files together.

The data of a file is rendered in memory first, written to a temporary file in the destination
directory and moved into place with :func:`os.replace`: a failure (a full disk, Ctrl-C) never leaves
a half-written file, and a file that was already there is either replaced whole or left as it was.
:func:`write_group` extends this to several files: all of them or none.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["write_atomically", "write_group"]


def write_atomically(path, data):
    """Write the bytes ``data`` to ``path`` whole, or leave ``path`` as it was."""
    write_group([(Path(path), data)])


def write_group(items):
    """Write several files all or nothing: temporary files first, then one rename each; on a
    failure the renamed ones are removed and the files they replaced are restored."""
    for path, _ in items:
        if os.path.isdir(path):
            raise IsADirectoryError(f"output path is a directory: {os.fspath(path)!r}")
    temporaries, backups, placed = [], [], []
    try:
        for path, data in items:
            temporaries.append(_temporary_copy(path, data))
        for (path, _), temporary in zip(items, temporaries, strict=True):
            if os.path.lexists(path):
                backup = _temporary_copy(path, b"")
                os.replace(path, backup)
                backups.append((path, backup))
            os.replace(temporary, path)
            placed.append(path)
    except BaseException:
        for path in placed:
            _remove_quietly(path)
        for path, backup in backups:
            try:
                os.replace(backup, path)
            except OSError:
                pass
        for temporary in temporaries:
            _remove_quietly(temporary)
        raise
    for _, backup in backups:
        _remove_quietly(backup)


def _temporary_copy(path, data):
    """Write ``data`` to a new temporary file next to ``path``; return its name."""
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise FileNotFoundError(f"output directory does not exist: {directory!r}")
    handle, temporary = tempfile.mkstemp(
        prefix=f".{os.path.basename(path)}.", suffix=".part", dir=directory
    )
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        # mkstemp creates the file 0600; give it the permissions an ordinary new file would get
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
    except BaseException:
        _remove_quietly(temporary)
        raise
    return temporary


def _remove_quietly(path):
    try:
        os.remove(path)
    except OSError:
        pass
