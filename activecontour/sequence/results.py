"""Sequences and stacks: every frame segmented from the previous frame's result, objects tracked.

A time-lapse, a z-stack, a multi-page TIFF, a folder of numbered frames or a video is segmented
frame by frame with :func:`activecontour.segment` (read by :mod:`activecontour.io.stacks`).
Frame 0 starts from ``init``.  Frame t starts
from frame t-1's contours plus the pieces of its threshold split (the default start's, with frame
t-1's constants) that frame t-1's inside does not touch, so that objects entering the field or
appearing are found too; or, where that is lower in (6.38), from the threshold split alone (objects
that moved further than the flow travels in a few iterations): see
:func:`~activecontour.sequence.warm._warm_start`.

Objects keep their identity: each frame's objects (``result.labels``, touching objects apart) are
matched to the previous frame's by overlap (intersection over union, Hungarian assignment by
:func:`scipy.optimize.linear_sum_assignment`).  The previous frame's objects seed this frame's
split (:func:`activecontour.objects.measure.split_by_seeds`): objects that touch, or overlap with
no waist left between them, stay apart and keep their ids.  An object without a match in the next
frame ends its track, but for ``TRACK_GAP`` (5) frames an object without a match that overlaps the
track's last outline takes its id back (two objects that merged and separated again, an object
missed for a frame or two); one without a match in the previous frame (or a gap) starts a new one;
an object that splits (two or more objects of frame t lying mostly inside one object of frame t-1,
e.g. a dividing cell) ends its track and its pieces start new ones, with the parent recorded in
``graph`` (napari's Tracks ``graph``: child id -> [parent id]).  Ids are never reused
(:mod:`activecontour.sequence.tracking`).

:func:`iter_sequence` is the generator underneath: it holds one frame and one result at a time, so
a movie of any length streams at constant memory; :func:`segment_sequence` collects what it
yields (the label stack optionally streamed to a TIFF file).
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field

import numpy as np

from activecontour.io.stacks import read_frames
from activecontour.sequence.tracking import _concatenate, _Tracker
from activecontour.sequence.warm import _warm_settings, _warm_start
from activecontour.settings import Settings

__all__ = ["SequenceFrame", "SequenceResult", "iter_sequence", "segment_sequence"]

@dataclass(frozen=True)
class SequenceFrame:
    """One frame's outcome, as :func:`iter_sequence` yields it.

    Attributes
    ----------
    index : int
        The frame's index in the source (before any ``select``).
    position : int
        Its position among the frames segmented (0, 1, 2, ...).
    n_frames : int or None
        How many frames will be segmented, when the source says (a progress bar's total).
    image : ndarray
        The frame as read (for overlays).
    result : SegmentationResult
        The frame's segmentation; ``result.labels`` and ``result.objects["label"]`` hold the track
        ids (an object keeps its id in every frame it is in).
    parents : dict of int to list of int
        The tracks born at this frame by a split: child id -> [parent id].
    """

    index: int
    position: int
    n_frames: int | None
    image: np.ndarray
    result: object
    parents: dict


@dataclass
class SequenceResult:
    """What :func:`segment_sequence` collects.

    Attributes
    ----------
    results : list of SegmentationResult, or None
        One per frame (None with ``keep_results=False``).
    labels : int32 ndarray (T, M, N)
        Track ids, 0 = background (a read-only memory map of the TIFF file when ``labels_file`` was
        given).
    tracks : float ndarray (n, 4)
        ``track_id, t, row, col``: each object's centroid in each frame it is in, sorted by track
        then frame (napari's Tracks layer data); t is the position in the sequence.
    graph : dict of int to list of int
        child track id -> [parent track id] for the tracks born by a split (napari's ``graph``).
    objects : dict of str to ndarray
        The long table: one row per object per frame, ``frame`` (the position t), ``index`` (the
        frame's index in the source), then the per-object measurements of ``result.objects``
        (``label`` = track id, ``area``, ``centroid-0``, ``centroid-1``, ...).
    frame_indices : ndarray of int
        The source index of every segmented frame.
    """

    results: list | None
    labels: np.ndarray
    tracks: np.ndarray
    graph: dict
    objects: dict
    frame_indices: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def n_frames(self):
        return len(self.frame_indices)


def segment_sequence(frames, init=None, *, axis=0, select=None, callback=None, keep_results=True,
                     labels_file=None, **segment_kwargs):
    """Segment a time-lapse or z-stack, each frame from the previous one's result, tracking objects.

    Parameters
    ----------
    frames : ndarray (T, M, N) or (T, M, N, C), sequence of 2-D images, iterable, or path
        The frames (see :func:`read_frames`): an array, a list of arrays, a multi-page TIFF, a
        folder of numbered frames, or a video file.
    init : optional
        The start of the first frame, anything :func:`activecontour.segment` accepts (None: the
        default start).
    axis : int
        The axis of an array or TIFF stack that runs over frames (time or z); the others are the
        image's (M, N[, C]).
    select : slice, range or sequence of int, optional
        The frames to segment, by their index in the source (e.g. ``slice(0, 100, 2)``).
    callback : callable, optional
        ``callback(frame)`` with the :class:`SequenceFrame` once per frame, in order (for
        progress: ``frame.position``, ``frame.n_frames``); return True to stop after that frame.
    keep_results : bool
        Keep every frame's :class:`~activecontour.result.SegmentationResult` in ``results``.
        False keeps only the labels, tracks and table: constant memory for long movies (with
        ``labels_file``).
    labels_file : str or os.PathLike, optional
        Stream the label stack to this TIFF file (int32, one uncompressed page per frame) instead
        of holding it in memory; the returned ``labels`` is a read-only memory map of the file.
    **segment_kwargs
        Passed to :func:`activecontour.segment` for every frame (``backend``, ``mu``, ...).

    Returns
    -------
    SequenceResult
    """
    results, rows, tracks, graph, indices = [], [], [], {}, []
    writer, stack = None, []
    try:
        if labels_file is not None:
            import tifffile

            writer = tifffile.TiffWriter(os.fspath(labels_file), bigtiff=True)
        for frame in iter_sequence(frames, init, axis=axis, select=select, callback=callback,
                                   **segment_kwargs):
            result = frame.result
            graph.update(frame.parents)
            indices.append(frame.index)
            shape = result.labels.shape
            table = result.objects
            count = len(table["label"])
            rows.append({"frame": np.full(count, frame.position), "index": np.full(count, frame.index),
                         **table})
            tracks.append(np.column_stack([table["label"], np.full(count, frame.position),
                                           table["centroid-0"], table["centroid-1"]]))
            if writer is not None:
                writer.write(result.labels, contiguous=True, photometric="minisblack")
            else:
                stack.append(result.labels)
            if keep_results:
                results.append(result)
    finally:
        if writer is not None:
            writer.close()
    if not indices:
        labels = np.zeros((0, 0, 0), np.int32)
    elif writer is not None:
        import tifffile

        labels = tifffile.memmap(os.fspath(labels_file), mode="r").reshape(len(indices), *shape)
    else:
        labels = np.stack(stack)
    tracks = np.concatenate(tracks) if tracks else np.zeros((0, 4))
    tracks = tracks[np.lexsort((tracks[:, 1], tracks[:, 0]))].astype(np.float64)
    return SequenceResult(results=results if keep_results else None, labels=labels, tracks=tracks,
                          graph=graph, objects=_concatenate(rows), frame_indices=np.array(indices, int))


def iter_sequence(frames, init=None, *, axis=0, select=None, callback=None, **segment_kwargs):
    """Segment frames one after the other, yielding each frame's :class:`SequenceFrame` as it is done.

    The generator under :func:`segment_sequence` (same parameters): it holds one frame, one result
    and the previous frame's image and labels, whatever the length of the sequence.  A frame equal
    to the one before (a repeated frame of a video) is not segmented again: the frame before's
    result, when it converged, is stationary on it.
    """
    from activecontour._segment import segment, solve_problem
    from activecontour.problem import prepare

    if callback is not None and not callable(callback):
        raise TypeError("callback must be callable or None")
    settings = Settings.of(segment_kwargs)
    source, n_frames = read_frames(frames, axis=axis, select=select)
    tracker = _Tracker()
    previous = warm = found = previous_image = None
    for position, (index, image) in enumerate(source):
        if previous is not None and found.success and np.array_equal(image, previous_image):
            # the frame before again: its result converged on this very image, it is stationary here
            result = found
        elif previous is None:
            result = segment(image, init, **settings.keywords())
            # n_regions="auto" chooses K on the first frame; every frame keeps it (a class means
            # the same region in every frame)
            settings = dataclasses.replace(settings, n_regions=result.n_regions)
            warm = _warm_settings(settings)
        elif previous.n_regions > 2:  # K regions: the previous frame's classes are the start
            result = segment(image, previous, **settings.keywords())
        else:
            problem = prepare(image, warm)
            start = _warm_start(previous, problem)
            result = (segment(image, None, **settings.keywords()) if start is None
                      else solve_problem(problem, start))
            del problem  # (not held while the frame is out)
        found = result  # (in the frame's own ids: the tracker's input)
        result, parents = tracker.update(result)
        frame = SequenceFrame(index, position, n_frames, image, result, parents)
        previous, previous_image = result, image
        yield frame
        if callback is not None and callback(frame):
            return

