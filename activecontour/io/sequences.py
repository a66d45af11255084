"""A segmented sequence written as files: labels, tracks, objects, contours and a contact sheet.

:func:`save_sequence` writes what :func:`activecontour.segment_sequence` finds in a stack (a
multi-page TIFF, a video, a folder of frames), all of the files or none:

* ``<stem>_labels.tif``: the label stack, one int32 page per frame, an object's id the same in
  every frame (streamed to disk frame by frame: a long movie is not held in memory);
* ``<stem>_tracks.csv``: napari's Tracks data, ``track_id, t, row, col`` (the centroids), and the
  parents of the tracks born by a division in ``<stem>_tracks.json`` (napari's ``graph``);
* ``<stem>_objects.csv``: one row per object per frame (frame, index, label, area, centroid, ...);
* ``<stem>_contours.json``: every frame's objects' contours, with the frame and the id;
* ``<stem>_overlay.png``: a contact sheet of up to :data:`SHEET_FRAMES` frames with their contours.

The label stack and the contours go to temporary files while the frames come; everything is moved
into place at the end (:mod:`activecontour.io.atomic`), or removed if the run fails.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from activecontour.io.atomic import check_protected, temporary_file, write_group
from activecontour.io.objects import encode_table
from activecontour.io.pictures import encode_picture, render_overlay

__all__ = ["SEQUENCE_SUFFIXES", "SHEET_FRAMES", "SHEET_TILE", "SequenceWriter", "save_sequence",
           "sequence_paths"]

#: Frames shown on the contact sheet at most, and the longer side of each tile (pixels).
SHEET_FRAMES = 16
SHEET_TILE = 384

#: What :func:`save_sequence` appends to the stem, in the order :func:`sequence_paths` lists them.
SEQUENCE_SUFFIXES = ("_labels.tif", "_tracks.csv", "_tracks.json", "_objects.csv", "_contours.json",
                     "_overlay.png")


def sequence_paths(output_stem):
    """The files :func:`save_sequence` writes for a stem, in the order of :data:`SEQUENCE_SUFFIXES`."""
    stem = os.fspath(output_stem)
    return [Path(f"{stem}{suffix}") for suffix in SEQUENCE_SUFFIXES]


def save_sequence(output_stem, *, source=None, n_frames=None, color="auto", thickness="auto",
                  protect=()):
    """Write a sequence's files as :func:`activecontour.segment_sequence` finds its frames: all of
    them, or none.

    Use the returned :class:`SequenceWriter` as a context manager around the run: give its
    :meth:`~SequenceWriter.add` as the run's callback (or call it from yours) and its
    :attr:`~SequenceWriter.labels_file` as the run's ``labels_file``, then pass the run's
    :class:`~activecontour.sequence.SequenceResult` to :meth:`~SequenceWriter.finish`::

        with io.save_sequence(stem, source=path, n_frames=count) as writer:
            seq = ac.segment_sequence(path, callback=writer.add, keep_results=False,
                                      labels_file=writer.labels_file)
            paths = writer.finish(seq)

    Leaving the block without :meth:`~SequenceWriter.finish` (an error, Ctrl-C) writes nothing.

    Parameters
    ----------
    output_stem : str or os.PathLike
        The files are ``<stem>_labels.tif`` and the others of :data:`SEQUENCE_SUFFIXES`; the
        directory must exist.
    source : str or os.PathLike, optional
        The sequence's path, recorded in the contours file.
    n_frames : int, optional
        How many frames will come, when known: the contact sheet shows up to
        :data:`SHEET_FRAMES` of them, evenly spaced (without it: the first ones).
    color, thickness
        Of the contact sheet's contour lines (see :func:`activecontour.io.write_overlay`).
    protect : sequence of path
        Files that must not be overwritten (the input): ValueError if an output is one.

    Returns
    -------
    SequenceWriter
    """
    return SequenceWriter(output_stem, source=source, n_frames=n_frames, color=color,
                          thickness=thickness, protect=protect)


class SequenceWriter:
    """The files of one sequence, written as its frames come (see :func:`save_sequence`).

    Attributes
    ----------
    paths : list of pathlib.Path
        The files written by :meth:`finish` (:func:`sequence_paths`).
    labels_file : str
        The temporary file that the label stack streams into (``labels_file`` of
        :func:`activecontour.segment_sequence`); set on entering the ``with`` block.
    """

    def __init__(self, output_stem, *, source=None, n_frames=None, color="auto", thickness="auto",
                 protect=()):
        self.paths = sequence_paths(output_stem)
        check_protected(self.paths, protect)
        self.source = source
        self.color, self.thickness = color, thickness
        if n_frames:  # evenly spaced over the sequence; a video that does not say its length: the first
            self.shown = set(np.linspace(0, n_frames - 1, min(n_frames, SHEET_FRAMES)).round().astype(int))
        else:
            self.shown = set(range(SHEET_FRAMES))
        self.labels_file = None
        self._contours_file = None
        self._contours = None
        self._tiles = []
        self._finished = False

    def __enter__(self):
        labels_path, contours_path = self.paths[0], self.paths[4]
        try:
            self.labels_file = temporary_file(labels_path)
            self._contours_file = temporary_file(contours_path)
            self._contours = open(self._contours_file, "w")  # closed by finish or __exit__
        except BaseException:
            self._remove_temporaries()
            raise
        source = None if self.source is None else os.fspath(self.source)
        self._contours.write(f'{{"source": {json.dumps(source)}, "frames": [')
        return self

    def add(self, frame):
        """One frame done (a :class:`~activecontour.sequence.SequenceFrame`): its objects'
        contours, and its tile of the contact sheet when it is one of those shown."""
        result = frame.result
        entry = {"frame": frame.position, "index": frame.index, "objects": [
            {"label": int(label), "contours": [np.round(c, 4).tolist() for c in curves]}
            for label, curves in zip(result.objects["label"], result.object_contours, strict=True)]}
        self._contours.write(("," if frame.position else "") + json.dumps(entry))
        if frame.position in self.shown:
            self._tiles.append(render_overlay(frame.image, result.contours, self.color, self.thickness,
                                              max_side=SHEET_TILE))

    def finish(self, sequence):
        """Write the files of ``sequence`` (the run's :class:`~activecontour.sequence.SequenceResult`,
        whose labels went to :attr:`labels_file`) as a group; return their paths."""
        self._contours.write("]}")
        self._contours.close()
        tracks = {"track_id": sequence.tracks[:, 0].astype(int), "t": sequence.tracks[:, 1].astype(int),
                  "row": sequence.tracks[:, 2], "col": sequence.tracks[:, 3]}
        graph = {str(child): parents for child, parents in sequence.graph.items()}
        labels_path, tracks_path, graph_path, objects_path, contours_path, sheet_path = self.paths
        files = [
            (tracks_path, encode_table(tracks)),
            (graph_path, json.dumps({"graph": graph}, indent=1).encode()),
            (objects_path, encode_table(sequence.objects)),
            (sheet_path, encode_picture(sheet_path, contact_sheet(self._tiles))),
        ]
        write_group(files)
        try:
            os.replace(self.labels_file, labels_path)
            os.replace(self._contours_file, contours_path)
        except BaseException:
            for written in [p for p, _ in files] + [labels_path, contours_path]:
                written.unlink(missing_ok=True)
            raise
        self._finished = True
        return list(self.paths)

    def __exit__(self, *_exc):
        if self._contours is not None:
            self._contours.close()
        if not self._finished:
            self._remove_temporaries()
        return False

    def _remove_temporaries(self):
        for temporary in (self.labels_file, self._contours_file):
            if temporary is not None:
                Path(temporary).unlink(missing_ok=True)


def contact_sheet(tiles):
    """The tiles (RGB arrays, the first one's size or smaller) on a grid, row by row."""
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
