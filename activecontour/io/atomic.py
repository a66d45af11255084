"""Writing files all or nothing: each file whole or not at all, and groups of files together.

The data of a file is rendered in memory first, written to a temporary file in the destination
directory and moved into place with :func:`os.replace`: a failure (a full disk, Ctrl-C) never leaves
a half-written file, and a file that was already there is either replaced whole or left as it was.
:func:`write_group` extends this to several files: all of them or none.
"""

from __future__ import annotations

import hashlib
import os
import re
import socket
import tempfile
import time
from pathlib import Path

__all__ = ["STALE_AFTER_S", "check_protected", "sweep_temporaries", "temporary_file", "write_atomically",
           "write_group"]

#: A temporary file older than this (seconds) is swept whoever wrote it (a writer on another
#: machine of a shared file system, whose process cannot be asked after).
STALE_AFTER_S = 24 * 3600

#: The temporaries' names: ``.<file name>.<pid>-<host>.<random>.part``.
_TEMPORARY = re.compile(r"^\..+\.(?P<pid>\d+)-(?P<host>[0-9a-f]{8})\.[A-Za-z0-9_]+\.part$")


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


def check_protected(paths, protect):
    """Raise ValueError when one of ``paths`` is one of the files ``protect`` (an input that an
    output must never overwrite), compared as files where they exist, else as absolute paths."""
    for path in paths:
        if any(_same_file(path, other) for other in protect):
            raise ValueError(f"refusing to overwrite the input file {os.fspath(path)!r}")


def _same_file(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


def temporary_file(path):
    """A new empty temporary file next to ``path``, for a file too large to render in memory (a
    label stack written frame by frame): write it, then :func:`os.replace` it onto ``path``.  Named
    like every temporary here, so :func:`sweep_temporaries` removes it if its writer is killed."""
    return _temporary_copy(path, b"")


def _temporary_copy(path, data):
    """Write ``data`` to a new temporary file next to ``path``; return its name."""
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise FileNotFoundError(f"output directory does not exist: {directory!r}")
    handle, temporary = tempfile.mkstemp(
        prefix=f".{os.path.basename(path)}.{os.getpid()}-{_host()}.", suffix=".part", dir=directory
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


def sweep_temporaries(directory):
    """Remove the temporary files that writers killed mid-write left in ``directory``.

    A write that is interrupted normally removes its temporary file; one killed outright (``kill
    -9``, a power cut) cannot.  Its temporary (a hidden ``.<name>.<pid>-<host>.<random>.part``) is
    removed here when the process that wrote it, on this machine, no longer runs, or when it is
    older than :data:`STALE_AFTER_S`.  Files of other names are never touched.

    Returns
    -------
    list of pathlib.Path
        The files removed.
    """
    removed = []
    try:
        names = os.listdir(directory)
    except OSError:
        return removed
    now = time.time()
    for name in names:
        match = _TEMPORARY.match(name)
        if match is None:
            continue
        path = Path(directory) / name
        try:
            age = now - os.lstat(path).st_mtime
        except OSError:
            continue
        orphaned = match["host"] == _host() and not _running(int(match["pid"]))
        if orphaned or age > STALE_AFTER_S:
            try:
                os.remove(path)
            except OSError:
                continue
            removed.append(path)
    return removed


def _host():
    """A short tag of this machine (temporaries of writers on other machines are left alone)."""
    return hashlib.sha1(socket.gethostname().encode(errors="replace")).hexdigest()[:8]


def _running(pid):
    """Whether the process ``pid`` runs on this machine (POSIX); True where that cannot be asked."""
    if os.name != "posix":
        return True  # os.kill(pid, 0) would end the process on Windows
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True
