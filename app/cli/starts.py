"""The ``--init-*`` options: the initial curve given to :func:`activecontour.segment`.

Each option is read once, before any image: the library makes the curve (:func:`activecontour.circle`,
:func:`activecontour.rectangle`) or reads the file (:func:`activecontour.io.read_mask`,
:func:`activecontour.io.read_contours`), and its refusal is reported naming the option.
"""

from __future__ import annotations

import os

from ..messages import one_line
from .errors import UsageError

__all__ = ["ContourInit", "add_options", "load_init"]

#: The default start, as the help says it (:func:`activecontour.initial.default_init`).
DEFAULT_START = ("the outlines of what is brighter or darker than the two-means threshold of the "
                 "lightly blurred image, so objects anywhere in the image are in the start "
                 "(activecontour.initial.default_init)")


def add_options(parser):
    """The mutually exclusive ``--init-*`` options, in their own group of ``parser``."""
    from pathlib import Path

    group = parser.add_argument_group(
        "initial curve", f"default: {DEFAULT_START}").add_mutually_exclusive_group()
    group.add_argument("--init-circle", nargs=3, type=float, metavar=("ROW", "COL", "RADIUS"),
                       help="a circle, in pixels (row, col of its centre)")
    group.add_argument("--init-rect", nargs=4, type=float, metavar=("ROW0", "COL0", "ROW1", "COL1"),
                       help="a rectangle with opposite corners (ROW0, COL0), (ROW1, COL1)")
    group.add_argument("--init-mask", type=Path, metavar="FILE",
                       help="a mask image of the image's size (nonzero = inside)")
    group.add_argument("--init-contours", type=Path, metavar="FILE",
                       help="a contour file written by this tool (.json, .geojson, .svg, .csv, .npz)")
    group.add_argument("--init-grid", action="store_true",
                       help="small circles all over the image, for many objects")
    group.add_argument("--init-checkerboard", action="store_true",
                       help="a checkerboard level set (--backend levelset only)")


class ContourInit(list):
    """Curves read from a contour file, remembering the shape of the image they were made on."""

    def __init__(self, curves, shape):
        super().__init__(curves)
        self.image_shape = tuple(shape) if shape is not None else None


def load_init(args):
    """``(init, description)``: what the ``--init-*`` options give :func:`activecontour.segment`
    (None for the default start), and its words for the contour files' metadata."""
    if args.init_circle is not None:
        row, col, radius = args.init_circle
        return _made("--init-circle", "circle", (row, col), radius), f"circle {row:g} {col:g} {radius:g}"
    if args.init_rect is not None:
        row0, col0, row1, col1 = args.init_rect
        return (_made("--init-rect", "rectangle", (row0, col0), (row1, col1)),
                f"rectangle {row0:g} {col0:g} {row1:g} {col1:g}")
    if args.init_mask is not None:
        return _mask(args.init_mask, args.max_pixels), f"mask {os.fspath(args.init_mask)}"
    if args.init_contours is not None:
        return _contours(args.init_contours, args.max_pixels), f"contours {os.fspath(args.init_contours)}"
    if args.init_grid:
        return "grid", "grid"
    if args.init_checkerboard:
        _check_named("checkerboard", args.backend)
        return "checkerboard", "checkerboard"
    return None, "default"


def _check_named(name, backend):
    """A named start that the backend's solver does not take (the registry says which do)."""
    from activecontour.backends import BACKENDS

    if name not in BACKENDS[backend].inits:
        takers = [other for other, solver in BACKENDS.items() if name in solver.inits]
        raise UsageError(f"--init-{name} needs --backend {' or '.join(takers)} (the {backend} backend "
                         "does not take it)")


def fresh(init):
    """The init for one run: a contour file's curves as a new list (a run may keep its init)."""
    return list(init) if isinstance(init, ContourInit) else init


def check_shape(init, image_path, shape):
    """A contour file made on an image of another shape is no start for this one."""
    if isinstance(init, ContourInit) and init.image_shape is not None and init.image_shape != tuple(shape):
        raise UsageError(f"--init-contours were made on an image of shape {init.image_shape}, but "
                         f"{os.fspath(image_path)!r} has shape {tuple(shape)}")


def _made(option, maker, *arguments):
    import activecontour

    try:
        return getattr(activecontour, maker)(*arguments)
    except (ValueError, TypeError) as exc:
        raise UsageError(f"{option}: {one_line(exc)}") from None


def _mask(path, max_pixels):
    from activecontour import io
    from activecontour.initial import initial_curves

    try:
        mask = io.read_mask(path, max_pixels=max_pixels)
        initial_curves(mask, mask.shape)  # an empty mask is no start for any image
    except io.SizeLimitError as exc:
        raise UsageError(f"--init-mask: {over_limit(exc)}") from None
    except (FileNotFoundError, ValueError) as exc:
        raise UsageError(f"--init-mask: {os.fspath(path)!r}: {one_line(exc)}") from None
    return mask


def _contours(path, max_points):
    from activecontour import io

    try:
        curves = io.read_contours(path, max_points=max_points)
        shape = io.read_metadata(path, max_points=max_points).get("image_shape")
    except io.SizeLimitError as exc:
        raise UsageError(f"--init-contours: {over_limit(exc)}") from None
    except (FileNotFoundError, ValueError) as exc:
        raise UsageError(f"--init-contours: {one_line(exc)}") from None
    if not curves:
        raise UsageError(f"--init-contours: {os.fspath(path)!r} holds no contour")
    return ContourInit(curves, shape)


def over_limit(exc):
    """The library's SizeLimitError with the option that raises the limit."""
    text = one_line(exc)
    for name in ("(max_pixels)", "(max_points)"):
        text = text.replace(name, "(raise it with --max-pixels)")
    return text
