"""``activecontour segment``: every image read, segmented and written, all of its files or none.

The arguments are turned into the run's settings, init and output plan before any image is read
(:func:`run`); then each image is segmented by :func:`segment_one`, in this process one after
another (``--jobs 1``, with a progress line per iteration) or in worker processes
(:mod:`.parallel`).  An image that fails is reported on one line naming it and the next one goes
on; stacks (multi-page TIFFs, videos) go to :mod:`.stacks`.
"""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import sys
import threading
import time
from pathlib import Path

from ..messages import one_line, shown
from . import stacks, starts
from .errors import EXIT_USAGE, PROG, REPORTED_ERRORS, UsageError
from .outputs import Directories, check_can_create, plan_outputs, sweep_temporaries
from .parser import recorded, with_option_names
from .progress import ImageProgress, is_terminal

__all__ = ["Batch", "load_image", "run", "segment_one"]


def run(args, settings):
    """Check the arguments, then segment each image (``--jobs`` at a time); a failing image is
    reported and skipped.  Returns the exit status."""
    from activecontour.batch import default_jobs, find_images
    from activecontour.io.stacks import is_stack

    init, init_description = starts.load_init(args)
    left_out = []
    # folders and patterns expanded; a missing file stops here
    images = find_images(*args.images, left_out=left_out)
    stack_paths = [path for path in images if is_stack(path, args.axis)]
    if args.frames is not None and not stack_paths:
        raise UsageError("--frames selects frames of a stack (a multi-page TIFF or a video); "
                         "no input is one")
    images = [path for path in images if path not in stack_paths]
    objects = args.objects
    if settings.n_regions != 2 and "classes" not in objects:  # K regions: their image too
        objects = [*objects, "classes"]
    # images and stacks planned together: no two inputs may write the same file
    plans = plan_outputs(images + stack_paths, args.output, args.formats, objects, stacks=stack_paths)
    stack_plans = [plan for plan in plans if plan[0] in stack_paths]
    plans = [plan for plan in plans if plan[0] not in stack_paths]
    overlay = {"color": args.line_color, "thickness": args.line_width}
    check_can_create(args.output)
    directories = Directories()
    try:
        stack_failures = (stacks.run(stack_plans, args, settings.keywords(), overlay, print_line,
                                     starts.fresh(init), directories) if stack_plans else 0)
        if not plans:
            return EXIT_USAGE if stack_failures else 0
        if left_out and not args.quiet:
            more = f" and {len(left_out) - 1} more" if len(left_out) > 1 else ""
            print(f"{PROG}: note: left out {shown(left_out[0])}{more}, named like this tool's outputs "
                  "next to their image; name a file on its own to segment it", file=sys.stderr)
        sweep_temporaries(stem for _, stem in plans)
        batch = Batch(init, init_description, settings, args.formats, overlay,
                      protect=[p for p, _ in plans], quiet=args.quiet, max_pixels=args.max_pixels,
                      objects=objects, directories=directories)
        jobs = min(args.jobs or default_jobs(), len(plans))
        show_progress = not args.quiet and is_terminal(sys.stderr)
        if jobs > 1:
            failures = _segment_in_parallel(plans, batch, jobs, show_progress)
        else:
            failures = _segment_serially(plans, batch, show_progress)
    finally:
        directories.remove_empty()
    if failures and len(plans) > 1:
        print(f"{PROG}: error: {failures} of {len(plans)} images failed; the others were written",
              file=sys.stderr)
    return EXIT_USAGE if failures or stack_failures else 0


def print_line(line, failed):
    """A stack's summary line (stdout) or error line (stderr), as for images."""
    print(f"{PROG}: error: {shown(line)}" if failed else shown(line),
          file=sys.stderr if failed else sys.stdout, flush=True)


class Batch:
    """What every image of a ``segment`` run shares: the init, the settings and the outputs
    (picklable: the workers of ``--jobs`` get a copy)."""

    def __init__(self, init, init_description, settings, formats, overlay, *, protect, quiet,
                 max_pixels, objects=(), directories=None):
        self.init = init
        self.init_description = init_description
        self.settings = settings
        self.formats = formats
        self.overlay = overlay  # keyword arguments of io.save_result: color, thickness
        #: object file formats (:data:`activecontour.io.objects.OBJECT_FORMATS`)
        self.objects = objects
        self.protect = protect
        self.quiet = quiet
        self.max_pixels = max_pixels
        self.directories = Directories() if directories is None else directories


def segment_one(image_path, stem, batch, progress=None):
    """Load, segment and save one image (its files all or none); return its summary line.

    Raises the library's ValueError/TypeError/OSError or a UsageError for this image only.
    """
    import activecontour
    from activecontour import io

    with _interrupt_at_once():
        image = load_image(image_path, batch.max_pixels)
        if progress is not None:
            progress.note(f"setting up ({' x '.join(map(str, image.shape))})")
        starts.check_shape(batch.init, image_path, image.shape[:2])
        started = time.perf_counter()
        result = activecontour.segment(image, starts.fresh(batch.init), callback=progress,
                                       **batch.settings.keywords())
        elapsed = time.perf_counter() - started
    # no timing in the files: the same run writes the same bytes, whatever the jobs or the load
    metadata = {
        "image": os.fspath(image_path),
        "init": batch.init_description,
        "parameters": recorded(batch.settings),
    }
    batch.directories.make(Path(stem).parent)
    written = io.save_result(result, image, stem, batch.formats, metadata=metadata,
                             protect=batch.protect, objects=batch.objects, **batch.overlay)
    return summary(Path(image_path).name, result, elapsed, written, regions=batch.settings.n_regions != 2)


def load_image(image_path, max_pixels):
    """The image, or a UsageError naming --max-pixels for one over the limit."""
    import activecontour
    from activecontour.io import SizeLimitError

    try:
        return activecontour.load_image(image_path, max_pixels=max_pixels)
    except SizeLimitError as exc:
        raise UsageError(starts.over_limit(exc)) from None


def _segment_serially(plans, batch, show_progress):
    """``--jobs 1``: the images one after another in this process; return the failures."""
    progress = ImageProgress(len(plans)) if show_progress else None
    failures = 0
    try:
        for number, (image_path, stem) in enumerate(plans, start=1):
            if progress is not None:
                progress.start(number, image_path)
            try:
                line = segment_one(image_path, stem, batch, progress)
            except REPORTED_ERRORS as exc:
                failures += 1
                _report_failure(progress, image_path, exc)
            else:
                if not batch.quiet:
                    _report(progress, line, sys.stdout)
    finally:
        if progress is not None:
            progress.close()
    return failures


def _segment_in_parallel(plans, batch, jobs, show_progress):
    """``--jobs N``: each image read, segmented and written by a worker (:mod:`.parallel`)."""
    from . import parallel

    for directory in dict.fromkeys(Path(stem).parent for _, stem in plans):
        with contextlib.suppress(UsageError):  # made here, not raced for by the workers; a failure
            batch.directories.make(directory)  # is each image's, reported by its worker
    return parallel.run(
        functools.partial(segment_one, batch=batch), plans, jobs=jobs, expected=REPORTED_ERRORS,
        report_line=None if batch.quiet else functools.partial(print, flush=True),
        report_failure=functools.partial(_report_failure, None), show_progress=show_progress,
    )


def _report_failure(progress, image_path, exc):
    _report(progress, f"{PROG}: error: {_naming(image_path, exc)}", sys.stderr)


def _report(progress, line, stream):
    """Print a summary or error line, lifting the progress line out of the way first."""
    if progress is not None:
        progress.clear()
    print(line, file=stream, flush=True)


def _naming(image_path, exc):
    """The error's one line (a setting named as its option), prefixed by the image's path unless
    it already names it."""
    text = with_option_names(one_line(exc))
    name = shown(image_path)
    return text if name in text or repr(os.fspath(image_path)) in text else f"{name}: {text}"


@contextlib.contextmanager
def _interrupt_at_once():
    """Let Ctrl-C end the process at once while an image is read and segmented.

    Python turns SIGINT into KeyboardInterrupt only between bytecodes, and a compiled kernel
    holds the interpreter for as long as it runs (20 s in ``topology.winding_number`` on a
    speckle init).  Nothing is being written in this phase (the files of an image are written
    after it, all or none), so the signal's default action, ending the process, loses nothing that
    was finished.  Left alone when SIGINT is not Python's default (ignored, or the caller's), and
    in a worker process of ``--jobs``: there the interrupt must come back to the parent as the
    item's KeyboardInterrupt (the pool kills a worker that does not stop), not as a worker that
    died, which the parent reports as a failed image and goes on.
    """
    processes = sys.modules.get("multiprocessing")  # a worker has it; one image need not import it
    if (threading.current_thread() is not threading.main_thread()
            or (processes is not None and processes.parent_process() is not None)
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def summary(name, result, elapsed, written, regions=False):
    """One line per image: the count of objects (``result.labels``' ids), iterations, energy, ...;
    a result that did not converge says why.  ``regions``: say how many regions the model had
    (when they were asked for, or chosen)."""
    stem = os.path.commonprefix([os.fspath(p) for p in written])
    why = "" if result.success else f" ({result.message.rstrip('.')})"
    count = 0 if result.objects is None else len(result.objects["label"])
    return shown(
        f"{name}: objects={count} iterations={result.n_iter} energy={result.energy:.6g} mu={result.mu:.4g} "
        f"{f'regions={result.n_regions} ' if regions else ''}"
        f"c_in={_format_constant(result.c_in)} c_out={_format_constant(result.c_out)} "
        f"time={elapsed:.2f}s success={result.success}{why} output={stem}*"
    )


def _format_constant(value):
    try:
        return f"{float(value):.4g}"
    except TypeError:
        return ",".join(f"{float(v):.4g}" for v in value)
