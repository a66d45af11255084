"""The ``activecontour`` command line: ``segment`` images in a batch, or ``view`` one interactively.

Usage
-----
::

    activecontour segment IMAGE|FOLDER|'GLOB' [...] [-o DIR] [--jobs N]
                          [--format json,geojson,svg,csv,npz]
                          [--backend {polygon,levelset}] [--mu MU] [--omega OMEGA]
                          [--lambda-in L] [--lambda-out L] [--max-iter N] [--tol TOL]
                          [--c-in C] [--c-out C] [--color {gray,vector}]
                          [--regions K|auto] [--fit {constant,smooth}]
                          [--init-circle ROW COL RADIUS | --init-rect ROW0 COL0 ROW1 COL1 |
                           --init-mask FILE | --init-contours FILE | --init-grid |
                           --init-checkerboard] [--option KEY=VALUE ...]
                          [--line-color COLOR] [--line-width PX] [--max-pixels N] [--quiet]
    activecontour view IMAGE [the same parameter and init options] [--max-pixels N]

``segment`` writes, for each IMAGE, ``<DIR>/<name>_mask.png`` (0/255), ``<DIR>/<name>_overlay.png``
(the contour drawn on the image, shown by its own range) and ``<DIR>/<name>_contours.<fmt>`` for
each format (and ``<DIR>/<name>_classes.png``, the region of each pixel, when ``--regions`` is
not 2), where ``<name>`` is the image's file name without its suffix, made safe
(:func:`activecontour.io.output_stem`: never outside ``DIR``).  ``DIR`` defaults to the directory
of each image and is created when the first files go into it.  A FOLDER stands for the images in it and a
quoted GLOB (``'data/**/*.tif'``) for the files it matches, both sorted, without this tool's own
outputs (:func:`activecontour.batch.find_images`).  ``--jobs N`` (default: every core) segments N
images at a time in worker processes (:mod:`app.batch`); the files are the same as with
``--jobs 1``, which segments them one after another in this process.  On a terminal a status line
on stderr shows the file (k/N), ``loading`` while it is read, then the iteration, the energy, the
elapsed time and the time left (with several jobs: the images done, the elapsed time and the time
left); one summary line per image goes to stdout as it finishes, with the reason when
``success=False`` (``--quiet`` silences both).

Errors
------
The arguments are checked before any image is read: the parameters and backend options, the
init, that every IMAGE exists, that no output would overwrite an input or another image's output,
and that the output directory can be created.  Any problem there prints one line
``activecontour: error: ...`` on stderr and exits with status 2.  Then each image is read,
checked against the init, segmented and saved; an image that fails (unreadable, init outside it,
an error while writing) gets one such line naming it, and the batch goes on with the next image;
the exit status is 2 if any image failed.  Images over ``--max-pixels`` are refused from the size
their file declares, before decoding.  Each image's files are written as a group, all or none
(:func:`activecontour.io.save_result`), so a failed or interrupted run never leaves a half-written
file, and images finished earlier keep their outputs.  Ctrl-C ends the run at once, status 130
(the image being segmented is abandoned: nothing of it is written).  A run that reaches
``--max-iter`` without converging is not an error: its summary says ``success=False`` and why.
File names in every line are escaped (a newline as ``\\n``), so each message is one line.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import inspect
import math
import os
import signal
import sys
import textwrap
import threading
import time
from pathlib import Path

from . import sequence_cli
from .status_line import StatusLine, duration

PROG = "activecontour"
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130

#: segment()'s keyword -> command-line option, for the parameters both subcommands share.
_PARAMETER_OPTIONS = {
    "backend": "--backend",
    "mu": "--mu",
    "omega": "--omega",
    "lambda_in": "--lambda-in",
    "lambda_out": "--lambda-out",
    "max_num_iter": "--max-iter",
    "tol": "--tol",
    "c_in": "--c-in",
    "c_out": "--c-out",
    "color": "--color",
    "inside": "--inside",
    "n_regions": "--regions",
    "fit": "--fit",
    "noise": "--noise",
}


class UsageError(Exception):
    """Bad input found by the command line itself (reported like the library's ValueError)."""


#: Errors reported on one line (exit status 2) rather than as a traceback; raised by one image of a
#: batch, they name it and the next image goes on.
REPORTED_ERRORS = (UsageError, FileNotFoundError, ValueError, TypeError, OSError)


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit status 2."""

    def error(self, message):
        self.exit(EXIT_USAGE, f"{PROG}: error: {message} (see '{self.prog} --help')\n")


def main(argv=None):
    """Run the command line; return the exit status (0 success, 2 bad input, 130 interrupted).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name; ``sys.argv[1:]`` by default.
    """
    try:
        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help (0) or a usage error (2), already printed
            return exc.code if isinstance(exc.code, int) else EXIT_USAGE
        return args.run(args)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except REPORTED_ERRORS as exc:
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE


def console_script():
    """The ``activecontour`` executable: :func:`main`, and after Ctrl-C an exit without the
    interpreter's teardown of SciPy and OpenCV, so that it answers at once."""
    status = main()
    if status == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    return status


def build_parser():
    """The argparse parser with the ``segment`` and ``view`` subcommands."""
    parser = _Parser(
        prog=PROG,
        description="Sub-pixel Chan-Vese active contours (The Shapes of Things, section 6.5).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    segment = commands.add_parser(
        "segment",
        help="segment images and write mask, overlay and contour files",
        description="Segment each IMAGE; write <name>_mask.png, <name>_overlay.png and "
        "<name>_contours.<fmt> into the output directory.",
        epilog=_backend_options_help(), formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    segment.add_argument(
        "images", nargs="+", metavar="IMAGE",
        help="image files (PNG, TIFF, JPEG, ...), folders (the images in them) or quoted glob "
        "patterns such as 'data/*.tif'",
    )
    segment.add_argument(
        "-o", "--output", metavar="DIR", type=Path,
        help="output directory, created if missing (default: the directory of each image)",
    )
    segment.add_argument(
        "-j", "--jobs", type=_int_at_least(1), default=None, metavar="N",
        help="segment N images at a time in worker processes; 1 runs them one after another "
        "(default: every core)",
    )
    segment.add_argument(
        "-q", "--quiet", action="store_true", help="no progress bar and no summary lines"
    )
    _add_options(segment.add_argument_group("outputs and limits"), _output_options())
    _add_parameter_options(segment)
    sequence_cli.add_options(segment)
    segment.add_argument(
        "--option", dest="options", action="append", type=_option, default=None, metavar="KEY=VALUE",
        help="a backend setting passed in segment(options=...), e.g. smoothing=10 or dt=32; "
        "repeatable (the backends' options are listed below)",
    )
    segment.set_defaults(run=_run_segment)

    view = commands.add_parser(
        "view",
        help="open the interactive viewer on one image",
        description="Watch the contour move on IMAGE; change parameters and the initial curve live.",
    )
    view.add_argument("image", metavar="IMAGE", help="an image file")
    view.add_argument(
        "--format", dest="formats", type=_formats, default=None, metavar="FMT[,FMT...]",
        help="contour file formats the viewer's Save writes (default: the viewer's)",
    )
    _add_options(view, [(flags, kwargs) for flags, kwargs in _output_options() if "--max-pixels" in flags])
    _add_parameter_options(view)
    view.set_defaults(run=_run_view)
    return parser


def _output_options():
    """The options of ``segment``'s outputs and limits, as ``(flags, add_argument keywords)``: a new
    output option is one row here (a new contour format is one entry of io.CONTOUR_FORMATS)."""
    from activecontour.io import COLORS, CONTOUR_FORMATS
    from activecontour.io.images import MAX_PIXELS

    return [
        (("--format",), {
            "dest": "formats", "type": _formats, "default": ["json"], "metavar": "FMT[,FMT...]",
            "help": f"contour file formats, a comma-separated list of {', '.join(CONTOUR_FORMATS)} "
                    "(default: json)"}),
        (("--objects",), {
            "dest": "objects", "type": _object_formats, "default": [], "metavar": "FMT[,FMT...]",
            "help": "object files, one id per object: labels (16-bit PNG label image), labels-tif, "
                    "geojson (a Feature per object with its measurements), roi (ImageJ/Fiji ROI "
                    "set .zip), csv (the measurements), classes (16-bit PNG, the region of each pixel; "
                    "written without asking when --regions is not 2) (default: none)"}),
        (("--line-color", "--overlay-color"), {
            "dest": "line_color", "default": "auto", "metavar": "COLOR",
            "help": "colour of the contour in the overlay: auto (one that stands out from the "
                    f"image: red on gray), a name ({', '.join(COLORS)}) or R,G,B in 0..255 "
                    "(default: auto)"}),
        (("--line-width",), {
            "type": _line_width, "default": "auto", "metavar": "PX",
            "help": "width of the contour in the overlay, in pixels of the overlay, or auto: 1 px "
                    "per 1024 px of its longer side (default: auto)"}),
        (("--max-pixels",), {
            "type": _int_at_least(1), "default": MAX_PIXELS, "metavar": "N",
            "help": "refuse images of more than N pixels (by the size the file declares, before "
                    "decoding it) and contour files of more than N vertices (default: "
                    "%(default)s = 2**27, about 4 GB of memory to segment)"}),
    ]


def _line_width(text):
    if text == "auto":
        return text
    return _int_at_least(1)(text)


def _add_options(parser, table):
    """Add the options of a table of ``(flags, keyword arguments of add_argument)``."""
    for flags, kwargs in table:
        parser.add_argument(*flags, **kwargs)


def _add_parameter_options(parser):
    defaults = _segment_defaults()
    group = parser.add_argument_group("parameters of the functional (6.38) and the flow")
    group.add_argument(
        "--backend", choices=("polygon", "levelset"), default=defaults["backend"],
        help="polygon: the book's sub-pixel polygon flow; levelset: the same functional on the "
        "pixel grid, free topology (default: %(default)s)",
    )
    group.add_argument("--mu", type=_mu, default=defaults["mu"],
                       help="length weight, >= 0, or 'auto': from the image's noise (default: %(default)s)")
    group.add_argument("--omega", type=float, default=defaults["omega"],
                       help="area weight: > 0 shrinks, < 0 grows the inside (default: %(default)s)")
    group.add_argument("--lambda-in", type=float, default=defaults["lambda_in"],
                       help="weight of the inside fitting term, > 0 (default: %(default)s)")
    group.add_argument("--lambda-out", type=float, default=defaults["lambda_out"],
                       help="weight of the outside fitting term, > 0 (default: %(default)s)")
    group.add_argument("--max-iter", dest="max_num_iter", type=_int_at_least(0),
                       default=defaults["max_num_iter"], metavar="N",
                       help="iteration limit (default: %(default)s)")
    group.add_argument("--tol", type=_nonnegative_float, default=defaults["tol"],
                       help="convergence tolerance (default: %(default)s)")
    group.add_argument("--c-in", type=_constant, default=None, metavar="C",
                       help="hold the inside intensity fixed: a number, or one per channel "
                       "separated by commas (default: optimised)")
    group.add_argument("--c-out", type=_constant, default=None, metavar="C",
                       help="hold the outside intensity fixed (default: optimised)")
    group.add_argument("--color", choices=("gray", "vector"), default=defaults["color"],
                       help="colour images: convert to gray or use every channel "
                       "(default: %(default)s)")
    group.add_argument("--inside", choices=_inside_choices(), default=defaults["inside"],
                       help="which region is the objects: auto (the class covering less of the "
                       "image border), bright or dark (default: %(default)s)")
    group.add_argument("--regions", dest="n_regions", type=_regions, default=defaults["n_regions"],
                       metavar="K|auto",
                       help="number of regions K >= 2 of the piecewise model, or auto: chosen in "
                       "2..6 from the image's intensities; not 2: <name>_classes.png is written "
                       "too, the region of each pixel (0 = background, the others by mean "
                       "intensity) (default: %(default)s)")
    group.add_argument("--fit", choices=_fit_choices(), default=defaults["fit"],
                       help="the regions' intensities: constant, or smooth (each region's constant "
                       "times a smooth light field shared by all, for uneven light) "
                       "(default: %(default)s)")
    group.add_argument("--noise", choices=_noise_choices(), default=defaults["noise"],
                       help="the fit term: gaussian (the squared error of 6.38) or poisson (photon "
                       "counts, for fluorescence: the cut between two regions at their "
                       "logarithmic mean) (default: %(default)s)")
    init = parser.add_argument_group(
        "initial curve",
        "default: the outlines of the two-means (6.38 without its length term) threshold of the "
        "lightly blurred image, so objects anywhere in the image are in the start "
        "(activecontour.initial.default_init)",
    ).add_mutually_exclusive_group()
    init.add_argument("--init-circle", nargs=3, type=float, metavar=("ROW", "COL", "RADIUS"),
                      help="a circle, in pixels (row, col of its centre)")
    init.add_argument("--init-rect", nargs=4, type=float, metavar=("ROW0", "COL0", "ROW1", "COL1"),
                      help="an axis-aligned rectangle with opposite corners (ROW0, COL0), (ROW1, COL1)")
    init.add_argument("--init-mask", type=Path, metavar="FILE",
                      help="a mask image of the image's size (nonzero = inside)")
    init.add_argument("--init-contours", type=Path, metavar="FILE",
                      help="a contour file written by this tool (.json, .geojson, .svg, .csv, .npz)")
    init.add_argument("--init-grid", action="store_true",
                      help="small circles all over the image, for many objects (either backend)")
    init.add_argument("--init-checkerboard", action="store_true",
                      help="a checkerboard level set (--backend levelset only)")


# --------------------------------------------------------------------------------------- segment


def _run_segment(args):
    """Check the arguments, then segment each image (``--jobs`` at a time); a failing image is
    reported and skipped."""
    from activecontour.batch import default_jobs, find_images

    settings = _settings(args)
    init, init_description = _load_init(args)
    left_out = []
    # folders and patterns expanded; a missing file stops here
    images = find_images(*args.images, left_out=left_out)
    stacks = [path for path in images if sequence_cli.is_stack(path, args.axis)]
    if args.frames is not None and not stacks:
        raise UsageError("--frames selects frames of a stack (a multi-page TIFF or a video); "
                         "no input is one")
    images = [path for path in images if path not in stacks]
    if settings["n_regions"] != 2 and "classes" not in args.objects:  # K regions: their image too
        args.objects = [*args.objects, "classes"]
    # images and stacks planned together: no two inputs may write the same file
    plans = _plan_outputs(images + stacks, args.output, args.formats, args.objects, stacks=stacks)
    stack_plans = [plan for plan in plans if plan[0] in stacks]
    plans = [plan for plan in plans if plan[0] not in stacks]
    overlay = {"color": _line_color(args.line_color), "thickness": args.line_width}
    _check_can_create(args.output)
    first_init = list(init) if isinstance(init, _ContourInit) else init  # the first frame's start
    stack_failures = (sequence_cli.run(stack_plans, args, settings, overlay, _print_line, first_init)
                      if stack_plans else 0)
    if not plans:
        return EXIT_USAGE if stack_failures else 0
    if left_out and not args.quiet:
        more = f" and {len(left_out) - 1} more" if len(left_out) > 1 else ""
        print(f"{PROG}: note: left out {_shown(left_out[0])}{more}, named like this tool's outputs "
              "next to their image; name a file on its own to segment it", file=sys.stderr)
    _sweep_temporaries(plans)
    batch = _Batch(init, init_description, settings, args.formats, overlay,
                   protect=[p for p, _ in plans], output=args.output, quiet=args.quiet,
                   max_pixels=args.max_pixels, objects=args.objects)
    jobs = min(args.jobs or default_jobs(), len(plans))
    show_progress = not args.quiet and _is_terminal(sys.stderr)
    try:
        if jobs > 1:
            failures = _segment_in_parallel(plans, batch, jobs, show_progress)
        else:
            failures = _segment_serially(plans, batch, show_progress)
    finally:
        _remove_if_empty(batch.created)
    if failures and len(plans) > 1:
        print(f"{PROG}: error: {failures} of {len(plans)} images failed; the others were written",
              file=sys.stderr)
    return EXIT_USAGE if failures or stack_failures else 0


def _print_line(line, failed):
    """A stack's summary line (stdout) or error line (stderr), as for images."""
    print(f"{PROG}: error: {_shown(line)}" if failed else _shown(line),
          file=sys.stderr if failed else sys.stdout, flush=True)


def _segment_serially(plans, batch, show_progress):
    """``--jobs 1``: the images one after another in this process; return the failures."""
    progress = _Progress(len(plans)) if show_progress else None
    failures = 0
    try:
        for number, (image_path, stem) in enumerate(plans, start=1):
            if progress is not None:
                progress.start(number, image_path)
            try:
                line = _segment_one(image_path, stem, batch, progress)
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
    """``--jobs N``: each image read, segmented and written by a worker (:mod:`app.batch`)."""
    from . import batch as parallel

    for directory in dict.fromkeys(Path(stem).parent for _, stem in plans):
        with contextlib.suppress(UsageError):  # made here, not raced for by the workers; a failure
            _make_directory(directory, batch.created)  # is each image's, reported by its worker
    return parallel.run(
        functools.partial(_segment_one, batch=batch), plans, jobs=jobs, expected=REPORTED_ERRORS,
        report_line=None if batch.quiet else functools.partial(print, flush=True),
        report_failure=functools.partial(_report_failure, None), show_progress=show_progress,
    )


def _sweep_temporaries(plans):
    """Remove the temporaries that a run killed mid-write left in the output directories."""
    from activecontour.io import sweep_temporaries

    for directory in dict.fromkeys(Path(stem).parent for _, stem in plans):
        sweep_temporaries(directory)


def _report_failure(progress, image_path, exc):
    _report(progress, f"{PROG}: error: {_naming(image_path, exc)}", sys.stderr)


class _Batch:
    """What every image of a ``segment`` run shares: the init, the settings and the outputs."""

    def __init__(self, init, init_description, settings, formats, overlay, *, protect, output, quiet,
                 max_pixels, objects=()):
        self.init = init
        self.init_description = init_description
        self.settings = settings
        self.formats = formats
        self.overlay = overlay  # keyword arguments of io.save_result: color, thickness
        #: object file formats (:data:`activecontour.io.objects.OBJECT_FORMATS`)
        self.objects = objects
        self.protect = protect
        self.output = output
        self.quiet = quiet
        self.max_pixels = max_pixels
        #: (leaf, topmost) of every output directory this run created
        self.created = []


def _segment_one(image_path, stem, batch, progress=None):
    """Load, check, segment and save one image (its files all or none); return its summary line.

    Raises the library's ValueError/TypeError/OSError or a UsageError for this image only.
    """
    import activecontour
    from activecontour import io

    with _interrupt_at_once():
        image = _load_image(image_path, batch.max_pixels)
        if progress is not None:
            progress.note(f"setting up ({' x '.join(map(str, image.shape))})")
        _check_image(image_path, batch.init, batch.settings, image=image)
        init = list(batch.init) if isinstance(batch.init, _ContourInit) else batch.init
        started = time.perf_counter()
        result = activecontour.segment(image, init, callback=progress, **batch.settings)
        elapsed = time.perf_counter() - started
    # no timing in the files: the same run writes the same bytes, whatever the jobs or the load
    metadata = {
        "image": os.fspath(image_path),
        "init": batch.init_description,
        "parameters": batch.settings,
    }
    _make_directory(Path(stem).parent, batch.created)
    written = io.save_result(result, image, stem, batch.formats, metadata=metadata,
                             protect=batch.protect, objects=batch.objects,
                             **batch.overlay)
    return _summary(Path(image_path).name, result, elapsed, written,
                    regions=batch.settings["n_regions"] != 2)


def _load_image(image_path, max_pixels):
    """The image, or a UsageError naming --max-pixels for one over the limit."""
    import activecontour
    from activecontour.io import SizeLimitError

    try:
        return activecontour.load_image(image_path, max_pixels=max_pixels)
    except SizeLimitError as exc:
        raise UsageError(_over_limit(exc)) from None


def _over_limit(exc):
    """The library's SizeLimitError with the option that raises the limit."""
    text = _one_line(exc)
    for name in ("(max_pixels)", "(max_points)"):
        text = text.replace(name, "(raise it with --max-pixels)")
    return text


@contextlib.contextmanager
def _interrupt_at_once():
    """Let Ctrl-C end the process at once while an image is read and segmented.

    Python turns SIGINT into KeyboardInterrupt only between bytecodes, and a compiled kernel
    holds the interpreter for as long as it runs (20 s in ``topology.winding_number`` on a
    speckle init).  Nothing is being written in this phase (the files of an image are written
    after it, all or none),
    so the signal's default action, ending the process, loses nothing that was finished.  Left
    alone when SIGINT is not Python's default (ignored, or the caller's).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def _naming(image_path, exc):
    """The error's one line, prefixed by the image's path unless it already names it."""
    text = _one_line(exc)
    name = _shown(image_path)
    return text if name in text or repr(os.fspath(image_path)) in text else f"{name}: {text}"


def _report(progress, line, stream):
    """Print a summary or error line, lifting the progress line out of the way first."""
    if progress is not None:
        progress.clear()
    print(line, file=stream, flush=True)


def _settings(args):
    """The keyword arguments of activecontour.segment, validated before any work is done."""
    from activecontour.models import ChanVeseParameters

    settings = {name: getattr(args, name) for name in _PARAMETER_OPTIONS}
    if getattr(args, "options", None):
        settings["options"] = dict(args.options)
        _check_option_types(settings["backend"], settings["options"])
    try:
        ChanVeseParameters(0.0 if settings["mu"] == "auto" else settings["mu"], settings["omega"],
                           settings["lambda_in"],
                           settings["lambda_out"], settings["c_in"], settings["c_out"])
    except (ValueError, TypeError) as exc:
        raise UsageError(_with_option_names(str(exc))) from None
    return settings


def _mu(text):
    if text == "auto":
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or 'auto', got {text!r}") from None


def _option(text):
    """KEY=VALUE, the value read as an int, a float, true/false, or else kept as text."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip().isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    value = value.strip()
    for convert in (int, float):
        try:
            return key.strip(), convert(value)
        except ValueError:
            pass
    return key.strip(), {"true": True, "false": False}.get(value.lower(), value)


def _check_option_types(backend, options):
    """Each ``--option KEY=VALUE`` of the kind of its field in the backend's options dataclass: a
    number for a number (or for None, a number chosen automatically), true/false for a flag, text
    for text (unknown keys are left to segment(), which lists the valid ones)."""
    from activecontour.backends import BACKENDS

    specs = {spec.name: spec for spec in BACKENDS[backend].option_specs()}
    for key, value in options.items():
        if key not in specs:
            continue
        spec = specs[key]
        if spec.kind is bool:
            expected, ok = "true or false", isinstance(value, bool)
        elif spec.kind in (int, float):
            expected, ok = "a number", isinstance(value, (int, float)) and not isinstance(value, bool)
            ok = ok and math.isfinite(value)
        else:
            expected, ok = "text", isinstance(value, str)
        if not ok:
            shown = "automatic" if spec.default is None else repr(spec.default)
            raise UsageError(f"--option {key}: expected {expected} (default {shown}), got "
                             f"{'true' if value is True else 'false' if value is False else value!r}")


def _backend_options_help():
    """The ``--option`` settings of every backend, from its options dataclass: name, default and
    the first sentence of its help."""
    from activecontour.backends import BACKENDS

    lines = ["backend options (--option KEY=VALUE):"]
    for name, backend in BACKENDS.items():
        lines.append(f"  --backend {name}:")
        for spec in backend.option_specs():
            default = "automatic" if spec.default is None else str(spec.default).lower() \
                if spec.kind is bool else spec.default
            first = spec.help.split(".  ")[0].rstrip(".")
            lines.append(textwrap.fill(first, width=79, initial_indent=f"    {spec.name}={default}: ",
                                       subsequent_indent=" " * 8))
    return "\n".join(lines)


def _with_option_names(message):
    """A library message about ``lambda_in`` etc., with the options' spelling added."""
    for name, option in _PARAMETER_OPTIONS.items():
        if message.startswith(name + " ") or message.startswith(name + ","):
            return f"{option}: {message}"
    return message


def _load_init(args):
    """The init object given to segment (None, a curve, or a mask) and its description."""
    import activecontour
    from activecontour import io

    if args.init_circle is not None:
        row, col, radius = args.init_circle
        if not all(math.isfinite(v) for v in args.init_circle):
            raise UsageError("--init-circle: ROW, COL and RADIUS must be finite numbers")
        if radius <= 0:
            raise UsageError(f"--init-circle: RADIUS must be > 0, got {radius:g}")
        return activecontour.circle((row, col), radius), f"circle {row:g} {col:g} {radius:g}"
    if args.init_rect is not None:
        row0, col0, row1, col1 = args.init_rect
        if not all(math.isfinite(v) for v in args.init_rect):
            raise UsageError("--init-rect: the corners must be finite numbers")
        if row0 == row1 or col0 == col1:
            raise UsageError("--init-rect: the rectangle has no area (ROW0 = ROW1 or COL0 = COL1)")
        return (activecontour.rectangle((row0, col0), (row1, col1)),
                f"rectangle {row0:g} {col0:g} {row1:g} {col1:g}")
    if args.init_mask is not None:
        try:
            mask = io.read_mask(args.init_mask, max_pixels=args.max_pixels)
        except io.SizeLimitError as exc:
            raise UsageError(f"--init-mask: {_over_limit(exc)}") from None
        except (FileNotFoundError, ValueError) as exc:
            raise UsageError(f"--init-mask: {_one_line(exc)}") from None
        if not mask.any():
            raise UsageError(f"--init-mask: {os.fspath(args.init_mask)!r} is empty (no nonzero pixel)")
        return mask, f"mask {os.fspath(args.init_mask)}"
    if args.init_contours is not None:
        try:
            curves = io.read_contours(args.init_contours, max_points=args.max_pixels)
            shape = io.read_metadata(args.init_contours, max_points=args.max_pixels).get("image_shape")
        except io.SizeLimitError as exc:
            raise UsageError(f"--init-contours: {_over_limit(exc)}") from None
        except (FileNotFoundError, ValueError) as exc:
            raise UsageError(f"--init-contours: {_one_line(exc)}") from None
        if not curves:
            raise UsageError(f"--init-contours: {os.fspath(args.init_contours)!r} holds no contour")
        return _ContourInit(curves, shape), f"contours {os.fspath(args.init_contours)}"
    if args.init_grid:
        return "grid", "grid"
    if args.init_checkerboard:
        if args.backend != "levelset":
            raise UsageError("--init-checkerboard needs --backend levelset (use --init-grid for the "
                             "polygon backend)")
        return "checkerboard", "checkerboard"
    return None, "default"


class _ContourInit(list):
    """Curves read from a contour file, remembering the shape of the image they were made on."""

    def __init__(self, curves, shape):
        super().__init__(curves)
        self.image_shape = tuple(shape) if shape is not None else None


def _plan_outputs(images, output, formats, objects=(), stacks=()):
    """[(image path, output stem)], after checking no output overwrites an input or another one.

    The stems come from :func:`activecontour.io.output_stem`: inside the output directory,
    whatever the images are called.  The inputs in ``stacks`` write a sequence's files
    (:func:`sequence_cli.output_paths`): two stacks with one stem (``disk.mp4``, ``disk.avi``)
    are refused as two images are.
    """
    from activecontour.io import output_paths, output_stem

    if output is not None and os.path.exists(output) and not os.path.isdir(output):
        raise UsageError(f"output path {os.fspath(output)!r} exists and is not a directory")
    plans, owners = [], {}
    inputs = {}
    for image_path in images:
        inputs.setdefault(os.path.realpath(image_path), image_path)
    for image_path in inputs.values():  # the same file named twice is segmented once
        directory = Path(output) if output is not None else Path(image_path).parent
        if directory.is_dir() and not os.access(directory, os.W_OK | os.X_OK):
            raise UsageError(f"the output directory {os.fspath(directory)!r} is not writable")
        stem = output_stem(directory, image_path)
        written = (sequence_cli.output_paths(stem) if image_path in stacks
                   else output_paths(stem, formats, objects))
        for path in written:
            key = os.path.realpath(path)
            if key in inputs:
                raise UsageError(
                    f"the output {os.fspath(path)!r} of {image_path!r} would overwrite the input "
                    f"{inputs[key]!r}; choose another --output directory"
                )
            if key in owners and owners[key] != image_path:
                raise UsageError(
                    f"{owners[key]!r} and {image_path!r} would both write {os.fspath(path)!r}; "
                    "rename one or segment them into different --output directories"
                )
            owners[key] = image_path
        plans.append((image_path, stem))
    return plans


def _check_image(image_path, init, settings, image=None):
    """Check that the image (read from ``image_path`` unless given) and the init are usable
    together (no segmentation yet)."""
    import numpy as np

    import activecontour
    from activecontour.imaging.normalize import normalize_image
    from activecontour.initial import initial_curves

    if image is None:
        image = activecontour.load_image(image_path)

    # the channel count from a corner (every axis cut to 8): normalising a huge image here would
    # cost a float64 copy of it before the run makes its own
    corner = np.asarray(image)[tuple(slice(0, 8) for _ in np.shape(image))]
    try:
        channels = normalize_image(corner, color=settings["color"]).shape[2]
    except (ValueError, TypeError) as exc:
        raise UsageError(f"{image_path}: {_one_line(exc)}") from None
    for name in ("c_in", "c_out"):
        count = len(settings[name]) if isinstance(settings[name], list) else 1
        if count not in (1, channels):
            raise UsageError(
                f"{_PARAMETER_OPTIONS[name]} has {count} values, but {image_path!r} has {channels} "
                f"channel(s) with --color {settings['color']}"
            )
    shape = image.shape[:2]
    if isinstance(init, _ContourInit) and init.image_shape is not None:
        if tuple(init.image_shape) != tuple(shape):
            raise UsageError(
                f"--init-contours were made on an image of shape {tuple(init.image_shape)}, but "
                f"{image_path!r} has shape {tuple(shape)}"
            )
    try:
        if not isinstance(init, str):  # "grid" and "checkerboard" fit any image
            initial_curves(list(init) if isinstance(init, _ContourInit) else init, shape)
    except (ValueError, TypeError) as exc:
        raise UsageError(f"{image_path}: {_one_line(exc)}") from None


def _check_can_create(output):
    """Before any work: the output directory exists, or its nearest existing parent is a writable
    directory (it is created when the first image's files are written)."""
    if output is None or os.path.isdir(output):
        return
    parent = Path(os.path.abspath(output))
    while not os.path.lexists(parent):
        parent = parent.parent
    if not os.path.isdir(parent):
        raise UsageError(f"cannot create the output directory {os.fspath(output)!r}: "
                         f"{os.fspath(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"cannot create the output directory {os.fspath(output)!r}: "
                         f"{os.fspath(parent)!r} is not writable")


def _make_directory(directory, created):
    """Create the output directory when the first files go into it, and note in ``created`` the
    topmost directory made, so that a run which ends up writing nothing leaves none behind."""
    if os.path.isdir(directory):
        return
    leaf = Path(os.path.abspath(directory))
    missing = [leaf]
    while not missing[-1].parent.exists():
        missing.append(missing[-1].parent)
    topmost = None  # the first directory this run made (another run may make some at once)
    for path in reversed(missing):
        try:
            os.mkdir(path)
        except FileExistsError:
            if not os.path.isdir(path):
                raise UsageError(f"cannot create the output directory {os.fspath(directory)!r}: "
                                 f"{_shown(path)!r} is not a directory") from None
        except OSError as exc:
            raise UsageError(f"cannot create the output directory {os.fspath(directory)!r}: "
                             f"{exc.strerror or exc}") from None
        else:
            topmost = path if topmost is None else topmost
    if topmost is not None:
        created.append((leaf, topmost))


def _remove_if_empty(created):
    """Remove the directories this run created, from the leaf up, if nothing was written in them."""
    for leaf, topmost in created:
        for directory in [leaf, *leaf.parents]:
            try:
                os.rmdir(directory)  # only succeeds on an empty directory
            except OSError:
                break
            if directory == topmost:
                break


def _line_color(text):
    """``--line-color``: "auto", a colour name or R,G,B in 0..255."""
    from activecontour.io import COLORS

    if text.lower() in ("auto", *COLORS):
        return text.lower()
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(0 <= v <= 255 for v in values):
        raise UsageError(
            f"--line-color (--overlay-color) must be auto, one of {', '.join(COLORS)} or R,G,B in "
            f"0..255, got {text!r}"
        )
    return values


def _summary(name, result, elapsed, written, regions=False):
    """One line per image; a result that did not converge says why.  ``regions``: say how many
    regions the model had (when they were asked for, or chosen)."""
    stem = os.path.commonprefix([os.fspath(p) for p in written])
    why = "" if result.success else f" ({result.message.rstrip('.')})"
    return _shown(
        f"{name}: iterations={result.n_iter} energy={result.energy:.6g} mu={result.mu:.4g} "
        f"{f'regions={result.n_regions} ' if regions else ''}"
        f"c_in={_format_constant(result.c_in)} c_out={_format_constant(result.c_out)} "
        f"time={elapsed:.2f}s success={result.success}{why} output={stem}*"
    )


def _format_constant(value):
    try:
        return f"{float(value):.4g}"
    except TypeError:
        return ",".join(f"{float(v):.4g}" for v in value)


class _Progress(StatusLine):
    """One status line on stderr, redrawn in place at most ten times a second.

    It shows the file (k/N) and its name, ``loading`` while the file is read, ``setting up`` until
    the first iteration (the image's tables and its default start), then the iteration,
    the energy, the time since the run started and an estimate of the time left: ``~`` the mean
    time of the images finished so far times the images left; for a single image, ``<=`` the time
    its remaining iterations up to ``max_num_iter`` take at the rate so far (it usually converges
    sooner); ``?`` when neither is known yet.  Used as the ``callback`` of
    :func:`activecontour.segment`.
    """

    width = 20

    def __init__(self, total, stream=None, clock=time.monotonic):
        super().__init__(stream)
        self.total = total
        self.clock = clock
        self.started = clock()
        self.finished = 0
        self.number = 0
        self.name = ""
        self.image_started = self.started
        self._rate = None  # (time, iteration) of this image's first callback, and its latest state
        self._last = -math.inf

    def start(self, number, path):
        """A new image: count the previous one as finished and show that this one is loading."""
        now = self.clock()
        if self.number:
            self.finished += 1
        self.number, self.name, self.image_started = number, _shown(Path(path).name), now
        self._rate = None
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
        first = (now, state.iteration) if self._rate is None else self._rate[0]
        self._rate = (first, (now, state.iteration, state.max_num_iter))
        if now - self._last < 0.1 and state.iteration < state.max_num_iter:
            return None
        total = max(int(state.max_num_iter), 1)
        filled = min(self.width, int(self.width * state.iteration / total))
        bar = "#" * filled + "-" * (self.width - filled)
        self._draw(f"[{bar}] {state.iteration}/{state.max_num_iter} energy {state.energy:<11.6g}", now)
        return None

    def remaining(self, now):
        """``"~M:SS"`` (an estimate), ``"<=M:SS"`` (a bound) or ``"?"``: the time left."""
        if self.finished:
            per_image = (self.image_started - self.started) / self.finished
            left = per_image * (self.total - self.number) + max(0.0, per_image - (now - self.image_started))
            return "~" + duration(left)
        if self.total == 1 and self._rate is not None:
            (start, first), (latest, iteration, max_num_iter) = self._rate
            if iteration > first:
                per_iteration = (latest - start) / (iteration - first)
                return "<=" + duration(per_iteration * (max_num_iter - iteration))
        return "?"

    def _draw(self, text, now):
        self.write(f"[{self.number}/{self.total}] {self.name}: {text} "
                   f"elapsed {duration(now - self.started)} left {self.remaining(now)}")
        self._last = now


# ------------------------------------------------------------------------------------------ view


def _run_view(args):
    from activecontour.initial import initial_curves

    settings = _settings(args)
    init, _ = _load_init(args)
    image = _load_image(args.image, args.max_pixels)
    shape = image.shape[:2]
    if isinstance(init, _ContourInit):
        init = list(init)
    if init is not None and not isinstance(init, str):  # "grid" and "checkerboard" fit any image
        try:
            initial_curves(init, shape)
        except (ValueError, TypeError) as exc:
            raise UsageError(f"{args.image}: {_one_line(exc)}") from None
    try:
        from . import viewer
    except ModuleNotFoundError as exc:
        if exc.name != f"{__package__}.viewer":
            raise
        raise UsageError(f"the interactive viewer ({__package__}.viewer) is not installed") from None
    launch = viewer.launch
    accepted = inspect.signature(launch).parameters
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in accepted.values())
    defaults = _segment_defaults()
    kwargs = {"init": init}
    for name, value in settings.items():
        if takes_any or name in accepted:
            kwargs[name] = value
        elif value != defaults.get(name):
            raise UsageError(f"the viewer does not take {_PARAMETER_OPTIONS[name]}")
    if args.formats is not None:
        if not (takes_any or "formats" in accepted):
            raise UsageError("the viewer does not take --format")
        kwargs["formats"] = tuple(args.formats)
    if takes_any or "max_pixels" in accepted:
        kwargs["max_pixels"] = args.max_pixels
    status = launch(args.image, **kwargs)
    return 0 if status is None else int(status)


# --------------------------------------------------------------------------------------- helpers


def _segment_defaults():
    """segment()'s default values, so the options and the library never disagree."""
    import importlib

    # the module, not the package attribute of the same name (the function, which may be wrapped)
    segment = importlib.import_module("activecontour._segment").segment
    parameters = inspect.signature(segment).parameters
    return {name: parameters[name].default for name in _PARAMETER_OPTIONS}


def _version():
    import activecontour

    return activecontour.__version__


def _formats(text):
    from activecontour.io import CONTOUR_FORMATS

    formats = [f.strip().lower().lstrip(".") for f in text.split(",") if f.strip()]
    if not formats:
        raise argparse.ArgumentTypeError("give at least one format")
    unknown = [f for f in formats if f not in CONTOUR_FORMATS]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown format {unknown[0]!r}; choose from {', '.join(CONTOUR_FORMATS)}"
        )
    return list(dict.fromkeys(formats))


def _object_formats(text):
    from activecontour.io.objects import OBJECT_FORMATS

    formats = [f.strip().lower() for f in text.split(",") if f.strip()]
    unknown = [f for f in formats if f not in OBJECT_FORMATS]
    if not formats or unknown:
        raise argparse.ArgumentTypeError(
            f"unknown object format {(unknown or [text])[0]!r}; choose from {', '.join(OBJECT_FORMATS)}")
    return list(dict.fromkeys(formats))


def _inside_choices():
    from activecontour._segment import INSIDE

    return INSIDE


def _noise_choices():
    from activecontour.models import NOISES

    return NOISES


def _fit_choices():
    from activecontour._segment import FITS

    return FITS


def _regions(text):
    """``--regions``: an integer >= 2 or "auto"."""
    if text == "auto":
        return text
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or value < 2:
        raise argparse.ArgumentTypeError(f"expected an integer >= 2 or 'auto', got {text!r}")
    return value


def _int_at_least(low):
    """An argparse type: an integer >= ``low``."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < low:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}")
        return value

    parse.__name__ = f"integer >= {low}"
    return parse


def _nonnegative_float(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return value


def _constant(text):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a number or comma-separated numbers, got {text!r}"
        ) from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values[0] if len(values) == 1 else values


def _one_line(exc):
    text = str(exc)
    if isinstance(exc, KeyError) and exc.args:
        text = str(exc.args[0])
    if isinstance(exc, OSError) and exc.strerror and exc.filename:
        text = f"{exc.strerror}: {exc.filename!r}"
    return _shown(" ".join(text.split()) or type(exc).__name__)


def _shown(text):
    """``text`` (a line, a path) with every character that is not printable escaped as Python
    would (a newline as ``\\n``), so a file name never splits or forges a line of output."""
    text = os.fspath(text)
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)


def _is_terminal(stream):
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
