"""The ``activecontour`` command line: ``segment`` images in a batch, or ``view`` one interactively.

Usage
-----
::

    activecontour segment IMAGE|FOLDER|'GLOB' [...] [-o DIR] [-j N] [--format FMT,...] [options]
    activecontour view IMAGE [options]

``segment`` writes, for each IMAGE, ``<DIR>/<name>_mask.png`` (0/255), ``<DIR>/<name>_overlay.png``
(the contour drawn on the image, shown by its own range) and ``<DIR>/<name>_contours.<fmt>`` for
each format (and ``<DIR>/<name>_classes.png``, the region of each pixel, when ``--regions`` is
not 2), where ``<name>`` is the image's file name without its suffix, made safe
(:func:`activecontour.io.output_stem`: never outside ``DIR``).  ``DIR`` defaults to the directory
of each image and is created when the first files go into it.  A FOLDER stands for the images in
it and a quoted GLOB (``'data/**/*.tif'``) for the files it matches, both sorted, without this
tool's own outputs (:func:`activecontour.batch.find_images`).  ``--jobs N`` (default: every core)
segments N images at a time in worker processes (:mod:`.parallel`); the files are the same as with
``--jobs 1``, which segments them one after another in this process.  On a terminal a status line
on stderr shows the file (k/N), ``loading`` while it is read, then the iteration, the energy, the
elapsed time and the time left (with several jobs: the images done, the elapsed time and the time
left); one summary line per image goes to stdout as it finishes, with the reason when
``success=False`` (``--quiet`` silences both).  A multi-page TIFF or a video is a sequence
(:mod:`.stacks`).

Errors
------
The arguments are checked before any image is read: the settings (by the library:
:func:`.parser.settings_from`), the init, that every IMAGE exists, that no output would overwrite
an input or another image's output, and that the output directory can be created.  Any problem
there prints one line ``activecontour: error: ...`` on stderr and exits with status 2.  Then each
image is read, segmented and saved; an image that fails (unreadable, init outside it, an error
while writing) gets one such line naming it, and the batch goes on with the next image; the exit
status is 2 if any image failed.  Images over ``--max-pixels`` are refused from the size their
file declares, before decoding.  Each image's files are written as a group, all or none
(:func:`activecontour.io.save_result`), so a failed or interrupted run never leaves a half-written
file, and images finished earlier keep their outputs.  Ctrl-C ends the run at once, status 130
(the image being segmented is abandoned: nothing of it is written).  A run that reaches
``--max-iter`` without converging is not an error: its summary says ``success=False`` and why.
File names in every line are escaped (a newline as ``\\n``), so each message is one line.

Parts
-----
parser    the options, from the library's settings and registries; text to settings
segment   the images of a run: read, segment, write, report
parallel  ``--jobs N``: whole images in worker processes
stacks    multi-page TIFFs and videos, segmented as sequences
starts    the ``--init-*`` options
outputs   output stems and directories
progress  the status line on a terminal
view      ``activecontour view``: the viewer with these settings
errors    exit statuses and the errors reported on one line
"""

from __future__ import annotations

import os
import sys

from ..messages import one_line
from .errors import EXIT_INTERRUPTED, EXIT_USAGE, PROG, REPORTED_ERRORS

__all__ = ["EXIT_INTERRUPTED", "EXIT_USAGE", "console_script", "main", "reuse_freed_memory"]


def main(argv=None):
    """Run the command line; return the exit status (0 success, 2 bad input, 130 interrupted).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name; ``sys.argv[1:]`` by default.
    """
    from .parser import build_parser, settings_from

    try:
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:  # --help (0) or a usage error (2), already printed
            return exc.code if isinstance(exc.code, int) else EXIT_USAGE
        settings = settings_from(args)
        if args.run == "view":
            from . import view as command
        else:
            from . import segment as command
        return command.run(args, settings)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except REPORTED_ERRORS as exc:
        from .parser import with_option_names

        print(f"{PROG}: error: {with_option_names(one_line(exc))}", file=sys.stderr)
        return EXIT_USAGE


#: The environment the executable sets for numpy where the caller's does not say: no transparent
#: huge pages.  numpy asks for them on every large array (``madvise``); where the kernel's THP
#: ``defrag`` is ``madvise``, each first touch may compact memory synchronously, which on the
#: 2-core machine cost a 4096^2 run 4.60 s CPU instead of 3.80 (and the read-plus-cumsum floor
#: 1.33 s instead of 0.33: ``benchmarks/bench_scale.py --no-hugepages``).  The same numbers.
NUMPY_ENVIRONMENT = {"NUMPY_MADVISE_HUGEPAGE": "0"}


#: glibc's ``mallopt`` parameters (``malloc.h``) that :func:`reuse_freed_memory` sets.
_M_TRIM_THRESHOLD, _M_MMAP_MAX = -1, -4


def reuse_freed_memory():
    """Have glibc's malloc keep the memory of freed arrays for the next ones (Linux; elsewhere
    nothing happens).

    By default every array over 32 MB is a fresh ``mmap`` returned to the kernel when freed, so
    the next one faults in zeroed pages again: a run at 8192^2 allocates several GB so, one
    image-sized temporary after another, and spent 2-3 s of system time in page faults against
    4 s of its own work (1.2-1.9 s with this).  From the heap, without trimming it, a freed
    array's pages serve the next allocation.  The peak memory is the same (+2 % at 8192^2: the
    heap's holes); the process keeps it until it ends (a ``--jobs`` worker until the pool ends).
    Numbers are unchanged: only where they are stored.
    """
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc's C library
        return
    mallopt(_M_MMAP_MAX, 0)
    mallopt(_M_TRIM_THRESHOLD, 2**31 - 1)


def console_script():
    """The ``activecontour`` executable: :func:`main` (with :data:`NUMPY_ENVIRONMENT`, set before
    numpy is imported, and :func:`reuse_freed_memory`), and after Ctrl-C an exit without the
    interpreter's teardown of SciPy and OpenCV, so that it answers at once."""
    for name, value in NUMPY_ENVIRONMENT.items():
        os.environ.setdefault(name, value)
    reuse_freed_memory()
    status = main()
    if status == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status
