"""Sequences and stacks: every frame segmented from the previous frame's result, objects tracked.

A time-lapse, a z-stack, a multi-page TIFF, a folder of numbered frames or a video is segmented
frame by frame with :func:`activecontour.segment`.  Frame 0 starts from ``init``.  Frame t starts
from frame t-1's contours plus the pieces of its threshold split (the default start's, with frame
t-1's constants) that frame t-1's inside does not touch, so that objects entering the field or
appearing are found too; or, where that is lower in (6.38), from the threshold split alone (objects
that moved further than the flow travels in a few iterations): see :func:`_warm_start`.

Objects keep their identity: each frame's objects (``result.labels``, touching objects apart) are
matched to the previous frame's by overlap (intersection over union, Hungarian assignment by
:func:`scipy.optimize.linear_sum_assignment`).  An object without a match in the next frame ends
its track; one without a match in the previous frame starts a new one; an object that splits
(two or more objects of frame t lying mostly inside one object of frame t-1, e.g. a dividing cell)
ends its track and its pieces start new ones, with the parent recorded in ``graph`` (napari's
Tracks ``graph``: child id -> [parent id]).  Ids are never reused.

:func:`iter_sequence` is the generator underneath: it holds one frame and one result at a time, so
a movie of any length streams at constant memory; :func:`segment_sequence` collects what it
yields (the label stack optionally streamed to a TIFF file).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

import numpy as np

__all__ = ["SequenceFrame", "SequenceResult", "iter_sequence", "read_frames", "segment_sequence",
           "tiff_frame_count"]

#: Smallest intersection over union for two objects of consecutive frames to be one object.
MIN_IOU = 0.1
#: An object of frame t is a piece of an object of frame t-1 when at least this fraction of its
#: area lies inside that object (two or more such pieces: a split).
SPLIT_OVERLAP = 0.5
#: File name endings read as videos (OpenCV); other files are images or (multi-page) TIFFs.
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".wmv", ".mpg", ".mpeg", ".webm", ".ogv")
#: Frame files a folder may hold (read by :func:`activecontour.image.load_image`).
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg", ".bmp", ".webp", ".jp2", ".pgm", ".ppm")


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
    and the previous frame's labels, whatever the length of the sequence.
    """
    from activecontour.segment import segment

    if callback is not None and not callable(callback):
        raise TypeError("callback must be callable or None")
    source, n_frames = read_frames(frames, axis=axis, select=select)
    tracker = _Tracker()
    previous = None
    warm_kwargs = _warm_kwargs(segment_kwargs)
    for position, (index, image) in enumerate(source):
        if previous is None:
            result = segment(image, init, **segment_kwargs)
            # n_regions="auto" chooses K on the first frame; every frame keeps it (a class means
            # the same region in every frame)
            segment_kwargs = {**segment_kwargs, "n_regions": result.n_regions}
            warm_kwargs = _warm_kwargs(segment_kwargs)
        elif previous.n_regions > 2:  # K regions: the previous frame's classes are the start
            result = segment(image, previous, **segment_kwargs)
        else:
            start = _warm_start(previous, image, segment_kwargs)
            result = segment(image, start, **(segment_kwargs if start is None else warm_kwargs))
        parents = tracker.update(result)
        frame = SequenceFrame(index, position, n_frames, image, result, parents)
        previous = result
        yield frame
        if callback is not None and callback(frame):
            return


def _warm_kwargs(segment_kwargs):
    """The keywords of a warm frame: the polygon flow starts at its finest smoothing length (the
    contours already lie on the boundaries: nothing to move as a whole) and does not search for
    new components by nucleation (the threshold split's new pieces are in the start already).
    Both only save iterations; options the caller gives win."""
    if segment_kwargs.get("backend", "polygon") != "polygon" or segment_kwargs.get("n_regions", 2) != 2:
        return segment_kwargs
    from activecontour.backends.polygon import PolygonOptions

    given = dict(segment_kwargs.get("options") or {})
    finest = given.get("min_smoothing", PolygonOptions().min_smoothing)
    return {**segment_kwargs, "options": {"smoothing": finest, "nucleate": False, **given}}


def _warm_start(previous, image, segment_kwargs):
    """The start of a frame after the first: the lower in (6.38), on this frame, of

    * the previous frame's contours plus the new pieces of this frame's threshold split (objects
      entering the field or appearing), and
    * the pieces of this frame's threshold split alone (where objects moved by more than the
      flow travels in a few iterations, their new outline is the nearer start).

    The threshold split is the default start's (:func:`activecontour.initial.default_init`):
    the image smoothed by ``DEFAULT_INIT_BLUR`` px, thresholded half-way between the previous
    result's region constants (along their difference, for a vector image), pieces under
    :func:`activecontour.initial.speck_area` dropped; new pieces are its connected components
    that do not touch the previous result's inside.  Its constants are the previous frame's, not
    a new global scan (a third of a frame's time on 512^2; they barely move between frames).
    """
    import cv2

    from activecontour.energy import evaluate, stack_curves
    from activecontour.image import ImageModel, intensity_scale, normalize_image
    from activecontour.initial import DEFAULT_INIT_BLUR, speck_area
    from activecontour.models import ChanVeseParameters
    from activecontour.raster import mask_to_curves

    if not previous.contours:
        return None  # nothing to follow: the default start, as at frame 0
    normalize = segment_kwargs.get("normalize", "range")
    values = normalize_image(image, color=segment_kwargs.get("color", "gray"), normalize=normalize)
    offset, scale = intensity_scale(image, normalize)
    c_in = (np.atleast_1d(previous.c_in_image) - offset) / scale
    c_out = (np.atleast_1d(previous.c_out_image) - offset) / scale
    difference = c_in - c_out
    projected = np.zeros(values.shape[:2], dtype=np.float32)
    for channel in range(values.shape[2]):
        smooth = cv2.GaussianBlur(values[:, :, channel].astype(np.float32), (0, 0), DEFAULT_INIT_BLUR,
                                  borderType=cv2.BORDER_REFLECT)
        projected += difference[channel] * (smooth - 0.5 * (c_in[channel] + c_out[channel]))
    candidate = projected > 0
    count, pieces = cv2.connectedComponents(candidate.astype(np.uint8), connectivity=8)
    followed = np.zeros(count, dtype=bool)
    followed[np.unique(pieces[previous.mask])] = True
    speck = speck_area(previous.mu, float(np.mean(difference**2)))
    new = mask_to_curves(candidate & ~followed[pieces], min_area=speck)
    starts = [list(previous.contours) + new, mask_to_curves(candidate, min_area=speck)]
    model = ImageModel(values)
    params = ChanVeseParameters(previous.mu, segment_kwargs.get("omega", 0.0),
                                segment_kwargs.get("lambda_in", 1.0), segment_kwargs.get("lambda_out", 1.0))
    energies = [evaluate(model, *stack_curves(curves)[:2], params).energy if curves else np.inf
                for curves in starts]
    curves = starts[int(np.argmin(energies))]
    return _Start(contours=curves, mask=previous.mask) if curves else None


@dataclass
class _Start:
    """A previous result's contours (with new pieces) as an ``init``: taken as already oriented,
    and, like a result, started with the small smoothing length of a start on the boundaries."""

    contours: list
    mask: np.ndarray


class _Tracker:
    """Track ids across frames: overlap matching, splits, births and deaths (see the module)."""

    def __init__(self):
        self.previous = None  # the last frame's labels in track ids
        self.next_id = 1

    def update(self, result):
        """Relabel ``result.labels``/``objects`` with track ids; return {child: [parent]}."""
        labels = result.labels
        count = int(labels.max(initial=0))
        ids, parents = self._assign(labels, count)
        lookup = np.concatenate([[0], ids]).astype(np.int32)
        result.labels = lookup[labels]
        result.objects = dict(result.objects, label=ids[np.asarray(result.objects["label"]) - 1])
        self.previous = result.labels
        return parents

    def _assign(self, labels, count):
        ids = np.zeros(count, dtype=np.int64)
        parents = {}
        if self.previous is not None and count and self.previous.any():
            previous_ids, overlap, area_previous, area = _overlaps(self.previous, labels, count)
            # splits: pieces lying mostly inside one previous object
            dominant = overlap.argmax(axis=0)
            piece = overlap[dominant, np.arange(count)] >= SPLIT_OVERLAP * area
            split_parents = set()
            for parent in np.unique(dominant[piece]):
                children = np.flatnonzero(piece & (dominant == parent))
                if len(children) >= 2:
                    split_parents.add(parent)
                    for child in children:
                        ids[child] = self._new()
                        parents[int(ids[child])] = [int(previous_ids[parent])]
            iou = overlap / (area_previous[:, None] + area[None, :] - overlap)
            iou[list(split_parents), :] = 0.0
            iou[:, ids > 0] = 0.0
            import scipy.optimize

            rows, cols = scipy.optimize.linear_sum_assignment(iou, maximize=True)
            for row, col in zip(rows, cols, strict=True):
                if iou[row, col] >= MIN_IOU:
                    ids[col] = previous_ids[row]
        for k in np.flatnonzero(ids == 0):
            ids[k] = self._new()
        return ids, parents

    def _new(self):
        self.next_id += 1
        return self.next_id - 1


def _overlaps(previous, labels, count):
    """The previous frame's object ids, the pixel counts of their intersections with this frame's
    objects 1..count, and both frames' object areas: ``ids (P,), overlap (P, count), areas of
    the previous objects (P,), areas of this frame's (count,)``."""
    both = (previous > 0) | (labels > 0)
    previous_ids, previous_index = np.unique(previous[both], return_inverse=True)
    pairs = previous_index.astype(np.int64) * (count + 1) + labels[both]
    table = np.bincount(pairs, minlength=len(previous_ids) * (count + 1)).reshape(-1, count + 1)
    table = table.astype(np.float64)
    keep = previous_ids > 0  # row 0 (when present): this frame's pixels over the old background
    return (previous_ids[keep], table[keep][:, 1:], table[keep].sum(axis=1), table[:, 1:].sum(axis=0))


def _concatenate(rows):
    """One long table (dict of 1-D arrays) from per-frame tables with the same columns."""
    if not rows:
        return {"frame": np.zeros(0, int), "index": np.zeros(0, int), "label": np.zeros(0, np.int32)}
    return {name: np.concatenate([row[name] for row in rows]) for name in rows[0]}


# ------------------------------------------------------------------------------------- reading


def read_frames(frames, *, axis=0, select=None):
    """The frames of a sequence, read lazily: ``(iterator of (index, image), count or None)``.

    Parameters
    ----------
    frames : ndarray, sequence of arrays, iterable, or path
        * an array whose axis ``axis`` runs over frames: (T, M, N) or (T, M, N, C) for axis 0;
        * a list or tuple of 2-D images (M, N) or (M, N, C), or any iterable of them (read once);
        * the path of a multi-page TIFF (one frame per page along ``axis`` of its first series),
          of a folder of numbered frames (image files sorted by the numbers in their names:
          ``frame2.png`` before ``frame10.png``), or of a video (:data:`VIDEO_SUFFIXES`, read by
          OpenCV in RGB order).
    axis : int
        The frame axis of an array or a TIFF stack.
    select : slice, range or sequence of int, optional
        Source indices of the frames to keep, in the order given.

    Raises
    ------
    ValueError
        For a path that does not exist or holds no frames, an array with fewer than 3 dimensions,
        an ``axis`` out of range, or a ``select`` index out of range.
    """
    if isinstance(frames, (str, os.PathLike)):
        return _read_path(os.fspath(frames), axis, select)
    if isinstance(frames, np.ndarray) or hasattr(frames, "__array__") and hasattr(frames, "shape"):
        stack = np.asarray(frames) if not isinstance(frames, np.ndarray) else frames
        if stack.ndim < 3:
            raise ValueError(f"frames must be a stack (T, M, N) or (T, M, N, C), got shape {stack.shape}; "
                             "segment a single image with activecontour.segment")
        if not -stack.ndim <= axis < stack.ndim:
            raise ValueError(f"axis {axis} is out of range for frames of shape {stack.shape}")
        stack = np.moveaxis(stack, axis, 0)
        return _indexed(lambda i: stack[i], len(stack), select)
    if isinstance(frames, (list, tuple)):
        return _indexed(lambda i: np.asarray(frames[i]), len(frames), select)
    if hasattr(frames, "__iter__"):
        chosen = _selection(select, None)
        wanted = set(chosen or ())
        iterator = ((i, np.asarray(image)) for i, image in enumerate(frames)
                    if chosen is None or i in wanted)
        return iterator, (len(chosen) if chosen is not None else None)
    raise TypeError(f"frames must be an array, a list of images, an iterable or a path, "
                    f"got {type(frames).__name__}")


def _selection(select, count):
    """``select`` as a list of indices (checked against ``count`` when known), or None for all."""
    if select is None:
        return None
    if isinstance(select, slice):
        if count is None:
            raise ValueError("select as a slice needs a source of known length; pass a list of indices")
        return list(range(count)[select])
    chosen = [int(i) for i in select]
    if count is not None:
        bad = [i for i in chosen if not -count <= i < count]
        if bad:
            raise ValueError(f"select has frame index {bad[0]} but the sequence has {count} frames "
                             f"(0..{count - 1})")
        chosen = [i % count for i in chosen]
    return chosen


def _indexed(get, count, select):
    chosen = _selection(select, count)
    order = range(count) if chosen is None else chosen
    return ((i, get(i)) for i in order), len(order)


def _read_path(path, axis, select):
    if not os.path.exists(path):
        raise FileNotFoundError(f"frames not found: {path!r}")
    if os.path.isdir(path):
        names = [name for name in os.listdir(path) if name.lower().endswith(IMAGE_SUFFIXES)]
        if not names:
            raise ValueError(f"folder {path!r} holds no image files ({', '.join(IMAGE_SUFFIXES)})")
        names.sort(key=_natural_key)
        files = [os.path.join(path, name) for name in names]
        from activecontour.image import load_image

        return _indexed(lambda i: load_image(files[i]), len(files), select)
    if path.lower().endswith(VIDEO_SUFFIXES):
        return _read_video(path, select)
    if path.lower().endswith((".tif", ".tiff")):
        return _read_tiff(path, axis, select)
    from activecontour.image import load_image

    return _indexed(lambda i: load_image(path), 1, select)


def _natural_key(name):
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def tiff_frame_count(path, axis=0):
    """Frames in a TIFF's first series along ``axis``: with ``axis=0``, 1 for a single 2-D or
    colour image; another axis is the caller's word that the file is a stack along it."""
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        shape, axes = series.shape, series.axes
    if axis == 0 and _tiff_is_single_image(shape, axes):
        return 1
    if not -len(shape) <= axis < len(shape):
        raise ValueError(f"axis {axis} is out of range for the TIFF {path!r} of shape {shape}")
    return shape[axis]


def _tiff_is_single_image(shape, axes):
    """A 2-D page, or one colour image (samples "S" chunky or planar), not a stack."""
    return len(shape) == 2 or (len(shape) == 3 and "S" in axes)


def _read_tiff(path, axis, select):
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        shape, axes, pages = series.shape, series.axes, len(series.pages)
    if axis == 0 and _tiff_is_single_image(shape, axes):
        from activecontour.image import load_image

        return _indexed(lambda i: load_image(path), 1, select)
    if axis == 0 and pages == shape[0]:  # one page per frame: read each when it is needed

        def page(i):
            with tifffile.TiffFile(path) as tif:
                return tif.series[0].asarray(key=i)

        return _indexed(page, pages, select)
    stack = np.moveaxis(tifffile.imread(path, series=0), axis, 0)  # frames across pages: read it all
    return _indexed(lambda i: stack[i], len(stack), select)


def _read_video(path, select):
    import cv2

    capture = cv2.VideoCapture(path)
    if not capture.isOpened():
        capture.release()
        raise ValueError(f"cannot read video {path!r}")
    count = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) or None
    chosen = _selection(select, count)
    chosen = None if chosen is None else sorted(set(chosen))  # a video is read forward only

    wanted = set(chosen or ())

    def frames():
        try:
            index = 0
            while True:
                ok, image = capture.read()
                if not ok:
                    return
                if chosen is None or index in wanted:
                    yield index, cv2.cvtColor(image, cv2.COLOR_BGR2RGB) if image.ndim == 3 else image
                index += 1
        finally:
            capture.release()

    return frames(), (len(chosen) if chosen is not None else count)

