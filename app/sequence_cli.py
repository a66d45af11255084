"""Stacks on the command line: ``activecontour segment movie.tif`` segments a sequence.

An input that holds several frames (a multi-page TIFF, a video: :func:`is_stack`) is not one image:
``segment`` hands it to :func:`activecontour.segment_sequence` and writes, next to the other outputs,

* ``<name>_labels.tif``: the label stack, one int32 page per frame, an object's id the same in
  every frame (streamed to disk frame by frame: a long movie is not held in memory);
* ``<name>_tracks.csv``: napari's Tracks data, ``track_id, t, row, col`` (the centroids), and the
  parents of the tracks born by a division in ``<name>_tracks.json`` (napari's ``graph``);
* ``<name>_objects.csv``: one row per object per frame (frame, index, label, area, centroid, ...);
* ``<name>_contours.json``: every frame's objects' contours, with the frame and the id;
* ``<name>_overlay.png``: a contact sheet of up to 16 frames with their contours.

All of them or none: the label stack goes to a temporary file that is renamed with the others at
the end.  ``--frames`` picks frames (``0:100:2`` or ``3,5,8``), ``--axis`` names the frame axis of a
TIFF stack (z-stacks stored with the slices on another axis).
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

#: Frames shown on the contact sheet at most, and the longer side of each tile (pixels).
SHEET_FRAMES = 16
SHEET_TILE = 384

OUTPUT_SUFFIXES = ("_labels.tif", "_tracks.csv", "_tracks.json", "_objects.csv", "_contours.json",
                   "_overlay.png")


def add_options(parser):
    """``--frames`` and ``--axis`` on the ``segment`` subcommand."""
    group = parser.add_argument_group("stacks (multi-page TIFF, video): segmented as a sequence")
    group.add_argument(
        "--frames", type=parse_frames, default=None, metavar="SELECTION",
        help="the frames of a stack to segment: START:STOP[:STEP] or a comma-separated list of "
        "indices, counted from 0 (default: all)")
    group.add_argument(
        "--axis", type=int, default=0, metavar="N",
        help="the axis of a TIFF stack that runs over frames (time or z) (default: 0)")


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


def is_stack(path, axis=0):
    """Whether ``path`` holds a sequence of frames: a video, or a TIFF with more than one frame."""
    from activecontour.io.images import tiff_frame_count
    from activecontour.io.stacks import VIDEO_SUFFIXES

    lower = os.fspath(path).lower()
    if lower.endswith(VIDEO_SUFFIXES):
        return True
    if lower.endswith((".tif", ".tiff")):
        try:
            return tiff_frame_count(path, axis) > 1
        except Exception:  # not a readable TIFF: the image reader says why, in one line
            return False
    return False


def output_paths(stem):
    return [Path(f"{stem}{suffix}") for suffix in OUTPUT_SUFFIXES]


def segment_stack(path, stem, settings, *, frames=None, axis=0, overlay=None, init=None, status=None):
    """Segment one stack and write its files (all or none); return its summary line.  ``init``
    starts the first frame (the others start from their predecessor); ``status`` (a
    :class:`~app.status_line.StatusLine`) shows the frame being done and the time left.

    The label stack and the contours are streamed to temporary files frame by frame (constant
    memory, however long the movie); everything is renamed into place at the end.
    """
    import numpy as np

    import activecontour as ac
    from activecontour.io.atomic import temporary_file, write_group
    from activecontour.io.objects import encode_table
    from activecontour.io.pictures import render_overlay
    from activecontour.io.stacks import read_frames

    from .status_line import duration

    overlay = overlay or {}
    _, count = read_frames(path, axis=axis, select=frames)  # checks --frames before any work
    if count:  # evenly spaced over the sequence; a video that does not say its length: the first
        shown = set(np.linspace(0, count - 1, min(count, SHEET_FRAMES)).round().astype(int))
    else:
        shown = set(range(SHEET_FRAMES))
    tiles = []
    labels_path, contours_path = Path(f"{stem}_labels.tif"), Path(f"{stem}_contours.json")
    created = not labels_path.parent.exists()
    labels_path.parent.mkdir(parents=True, exist_ok=True)
    temporaries = []
    started = time.perf_counter()
    try:
        temporaries = [temporary_file(labels_path), temporary_file(contours_path)]
        with open(temporaries[1], "w") as contours:
            contours.write(f'{{"source": {json.dumps(os.fspath(path))}, "frames": [')

            def collect(frame):
                result = frame.result
                if status is not None:
                    elapsed = time.perf_counter() - started
                    done = frame.position + 1
                    left = f" left ~{duration(elapsed / done * (count - done))}" if count else ""
                    status.write(f"{Path(path).name}: frame {done}/{count or '?'}, "
                                 f"{len(result.objects['label'])} objects, elapsed {duration(elapsed)}{left}")
                entry = {"frame": frame.position, "index": frame.index, "objects": [
                    {"label": int(label), "contours": [np.round(c, 4).tolist() for c in curves]}
                    for label, curves in zip(result.objects["label"], result.object_contours, strict=True)]}
                contours.write(("," if frame.position else "") + json.dumps(entry))
                if frame.position in shown:
                    tiles.append(render_overlay(frame.image, result.contours, overlay.get("color", "auto"),
                                                overlay.get("thickness", "auto"), max_side=SHEET_TILE))

            seq = ac.segment_sequence(path, init, axis=axis, select=frames, callback=collect,
                                      keep_results=False, labels_file=temporaries[0], **settings)
            contours.write("]}")
        tracks = {"track_id": seq.tracks[:, 0].astype(int), "t": seq.tracks[:, 1].astype(int),
                  "row": seq.tracks[:, 2], "col": seq.tracks[:, 3]}
        graph = {str(child): parents for child, parents in seq.graph.items()}
        files = [
            (Path(f"{stem}_tracks.csv"), encode_table(tracks)),
            (Path(f"{stem}_tracks.json"), json.dumps({"graph": graph}, indent=1).encode()),
            (Path(f"{stem}_objects.csv"), encode_table(seq.objects)),
            (Path(f"{stem}_overlay.png"), _encode_png(_contact_sheet(tiles))),
        ]
        write_group(files)
        try:
            for temporary, final in zip(temporaries, (labels_path, contours_path), strict=True):
                os.replace(temporary, final)
        except BaseException:
            for written in [p for p, _ in files] + [labels_path, contours_path]:
                written.unlink(missing_ok=True)
            raise
    except BaseException:
        for temporary in temporaries:
            Path(temporary).unlink(missing_ok=True)
        _remove_if_empty(labels_path.parent, created)
        raise
    finally:
        if status is not None:
            status.clear()
    elapsed = time.perf_counter() - started
    n_tracks = len(np.unique(seq.tracks[:, 0]))
    divisions = len({parent for parents in seq.graph.values() for parent in parents})
    return (f"{Path(path).name}: {seq.n_frames} frames, {n_tracks} tracks, {divisions} divisions, "
            f"{elapsed:.1f}s -> {labels_path.name} and {len(files) + 1} more")


def _remove_if_empty(directory, created):
    """Remove a directory this run created for a stack whose files were not written."""
    if created:
        try:
            directory.rmdir()
        except OSError:
            pass


def _contact_sheet(tiles):
    """The tiles (RGB arrays, the first one's size or smaller) on a grid, row by row."""
    import numpy as np

    if not tiles:
        return np.zeros((16, 16, 3), np.uint8)
    columns = math.ceil(math.sqrt(len(tiles)))
    rows = math.ceil(len(tiles) / columns)
    height = max(t.shape[0] for t in tiles)
    width = max(t.shape[1] for t in tiles)
    sheet = np.zeros((rows * height, columns * width, 3), np.uint8)
    for k, tile in enumerate(tiles):
        r, c = divmod(k, columns)
        sheet[r * height: r * height + tile.shape[0], c * width: c * width + tile.shape[1]] = tile
    return sheet


def _encode_png(rgb):
    import cv2

    ok, data = cv2.imencode(".png", rgb[:, :, ::-1])
    if not ok:
        raise OSError("cannot encode the contact sheet as PNG")
    return data.tobytes()


def run(plans, args, settings, overlay, report, init=None):
    """Segment the stacks named on the command line, one after another; return the failures.

    ``plans`` are (stack path, output stem) pairs, checked by the command line for outputs that
    would collide; ``report(line, failed)`` prints a summary or an error line (the command line's
    own printer); ``init`` (the ``--init-*`` options) is the first frame's start.
    """
    import sys

    from .status_line import StatusLine

    status = StatusLine() if not args.quiet and sys.stderr.isatty() else None
    failures = 0
    for path, stem in plans:
        try:
            line = segment_stack(path, stem, settings, frames=args.frames, axis=args.axis, overlay=overlay,
                                 init=init, status=status)
        except (ValueError, TypeError, OSError) as exc:
            failures += 1
            report(f"{path}: {str(exc).strip().splitlines()[0]}", True)
            continue
        if not args.quiet:
            report(line, False)
    return failures
