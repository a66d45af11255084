"""Stacks on the command line: ``activecontour segment movie.tif`` segments a sequence.

An input that holds several frames (a multi-page TIFF, a video: :func:`activecontour.io.stacks.is_stack`)
is not one image: ``segment`` hands it to :func:`activecontour.segment_sequence` and writes its
files with :func:`activecontour.io.save_sequence` (the label stack, tracks, objects, contours and a
contact sheet: all of them or none).  ``--frames`` picks frames (``0:100:2`` or ``3,5,8``),
``--axis`` names the frame axis of a TIFF stack (z-stacks stored with the slices on another axis).
"""

from __future__ import annotations

import time
from pathlib import Path

__all__ = ["add_options", "parse_frames", "run"]


def add_options(parser):
    """``--frames`` and ``--axis`` on the ``segment`` subcommand (or one of its groups)."""
    parser.add_argument(
        "--frames", type=parse_frames, default=None, metavar="SELECTION",
        help="the frames of a stack (multi-page TIFF, video) to segment: START:STOP[:STEP] or a "
        "comma-separated list of indices, counted from 0 (default: all)")
    parser.add_argument(
        "--axis", type=int, default=0, metavar="N",
        help="the axis of a TIFF stack that runs over frames, time or z (default: 0)")


def parse_frames(text):
    """``--frames``: a slice ``START:STOP[:STEP]`` or a list ``I,J,K`` of frame indices."""
    import argparse

    try:
        if ":" in text:
            parts = [int(p) if p.strip() else None for p in text.split(":")]
            if len(parts) > 3 or parts[-1] == 0 and len(parts) == 3:
                raise ValueError
            return slice(*parts)
        return [int(p) for p in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"invalid frame selection {text!r}: use START:STOP[:STEP] or a list like 0,5,9") from None


def segment_stack(path, stem, settings, *, frames=None, axis=0, overlay=None, init=None, status=None,
                  directories=None):
    """Segment one stack and write its files (all or none); return its summary line.

    ``init`` starts the first frame (the others start from their predecessor); ``status`` (a
    :class:`~.progress.StatusLine`) shows the frame being done and the time left; ``directories``
    (:class:`~.outputs.Directories`) makes the output directory once the frames are known good.
    """
    import numpy as np

    import activecontour as ac
    from activecontour import io
    from activecontour.io.stacks import read_frames

    from .progress import duration

    _, count = read_frames(path, axis=axis, select=frames)  # checks --frames before any work
    if directories is not None:
        directories.make(Path(stem).parent)
    started = time.perf_counter()
    try:
        with io.save_sequence(stem, source=path, n_frames=count, protect=[path], **(overlay or {})) as writer:
            def collect(frame):
                writer.add(frame)
                if status is not None:
                    elapsed = time.perf_counter() - started
                    done = frame.position + 1
                    left = f" left ~{duration(elapsed / done * (count - done))}" if count else ""
                    status.write(f"{Path(path).name}: frame {done}/{count or '?'}, "
                                 f"{len(frame.result.objects['label'])} objects, "
                                 f"elapsed {duration(elapsed)}{left}")

            seq = ac.segment_sequence(path, init, axis=axis, select=frames, callback=collect,
                                      keep_results=False, labels_file=writer.labels_file, **settings)
            written = writer.finish(seq)
    finally:
        if status is not None:
            status.clear()
    elapsed = time.perf_counter() - started
    n_tracks = len(np.unique(seq.tracks[:, 0]))
    divisions = len({parent for parents in seq.graph.values() for parent in parents})
    return (f"{Path(path).name}: {seq.n_frames} frames, {n_tracks} tracks, {divisions} divisions, "
            f"{elapsed:.1f}s -> {written[0].name} and {len(written) - 1} more")


def run(plans, args, settings, overlay, report, init=None, directories=None):
    """Segment the stacks named on the command line, one after another; return the failures.

    ``plans`` are (stack path, output stem) pairs, checked for colliding outputs with the images
    (:func:`.outputs.plan_outputs`); ``report(line, failed)`` prints a summary or an error line
    (the command line's own printer); ``init`` (the ``--init-*`` options) is the first frame's
    start.
    """
    import sys

    from ..messages import one_line
    from .errors import REPORTED_ERRORS
    from .progress import StatusLine, is_terminal

    status = StatusLine() if not args.quiet and is_terminal(sys.stderr) else None
    failures = 0
    for path, stem in plans:
        try:
            line = segment_stack(path, stem, settings, frames=args.frames, axis=args.axis, overlay=overlay,
                                 init=init, status=status, directories=directories)
        except REPORTED_ERRORS as exc:
            failures += 1
            report(f"{path}: {one_line(exc)}", True)
            continue
        if not args.quiet:
            report(line, False)
    return failures
