"""Tracking: each frame's objects matched to the previous frame's by overlap.

Intersection over union with a Hungarian assignment (:func:`scipy.optimize.linear_sum_assignment`);
a split (a dividing cell) ends the parent's track and records it in napari's Tracks ``graph``.
A track without a match is kept for ``TRACK_GAP`` frames: an object without a match in the frame
before that overlaps the last outline of such a track takes its id back (two objects that merged
and separated again, an object the segmentation missed for a frame or two).

Objects that touch keep their ids because the frame before seeds this frame's split
(:func:`activecontour.objects.measure.split_by_seeds`, by :mod:`activecontour.sequence.warm`'s
start): the tracker then finds each part over its own object.
"""

from __future__ import annotations

import dataclasses

import numpy as np

#: Smallest intersection over union for two objects of consecutive frames to be one object.
MIN_IOU = 0.1
#: An object of frame t is a piece of an object of frame t-1 when at least this fraction of its
#: area lies inside that object (two or more such pieces: a split).
SPLIT_OVERLAP = 0.5
#: A track without a match keeps its id for this many frames: an object without a match in the
#: frame before that overlaps its last outline by ``MIN_IOU`` takes it back.
TRACK_GAP = 5


@dataclasses.dataclass
class _Lost:
    """A track without a match: its last outline (a bool mask on its box) and the frames it has
    been missing."""

    box: tuple
    mask: np.ndarray
    missing: int = 1


class _Tracker:
    """Track ids across frames: overlap matching, splits, births, deaths and gaps (see the module)."""

    def __init__(self):
        self.previous = None  # the last frame's labels in track ids
        self.next_id = 1
        self.lost = {}  # track id -> _Lost, for TRACK_GAP frames

    def update(self, result):
        """The result with ``labels``/``objects`` in track ids (a new result), and {child: [parent]}."""
        labels = result.labels
        count = int(labels.max(initial=0))
        ids, parents = self._assign(labels, count)
        lookup = np.concatenate([[0], ids]).astype(np.int32)
        track_ids = ids[np.asarray(result.objects["label"]) - 1]
        result = dataclasses.replace(result, labels=lookup[labels],
                                     objects=dict(result.objects, label=track_ids))
        self._remember(result.labels, ids, parents)
        self.previous = result.labels
        return result, parents

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
            self._match(iou, previous_ids, ids)
        if self.lost and (ids == 0).any():
            self._match(*self._lost_overlaps(labels, count, ids), ids)
        for k in np.flatnonzero(ids == 0):
            ids[k] = self._new()
        return ids, parents

    @staticmethod
    def _match(iou, candidates, ids):
        """Give the objects the ids of ``candidates`` by a Hungarian assignment on ``iou``
        (candidates x objects), where it is at least MIN_IOU."""
        import scipy.optimize

        rows, cols = scipy.optimize.linear_sum_assignment(iou, maximize=True)
        for row, col in zip(rows, cols, strict=True):
            if iou[row, col] >= MIN_IOU:
                ids[col] = candidates[row]

    def _lost_overlaps(self, labels, count, ids):
        """IoU of the lost tracks' last outlines (rows) with the objects still without an id, and
        the lost ids."""
        area = np.bincount(labels.ravel(), minlength=count + 1)[1:].astype(np.float64)
        lost = list(self.lost.items())
        iou = np.zeros((len(lost), count))
        for row, (_, entry) in enumerate(lost):
            r0, c0, r1, c1 = entry.box
            common = np.bincount(labels[r0:r1, c0:c1][entry.mask], minlength=count + 1)[1:]
            iou[row] = common / (entry.mask.sum() + area - common)
        iou[:, ids > 0] = 0.0
        return iou, np.array([track for track, _ in lost])

    def _remember(self, labels, ids, parents):
        """Count one more missing frame for the lost tracks, drop those found again or missing
        for more than TRACK_GAP frames; add the previous frame's tracks without a match in this
        one (not split parents)."""
        import scipy.ndimage

        now = set(ids.tolist())
        ended = set(p for parent in parents.values() for p in parent)
        for track in list(self.lost):
            self.lost[track].missing += 1
            if track in now or self.lost[track].missing > TRACK_GAP:
                del self.lost[track]
        if self.previous is None:
            return
        gone = [t for t in np.unique(self.previous[self.previous > 0]).tolist()
                if t not in now and t not in ended and t not in self.lost]
        if not gone:
            return
        boxes = scipy.ndimage.find_objects(self.previous, max_label=max(gone))
        for track in gone:
            box = boxes[track - 1]
            self.lost[track] = _Lost((box[0].start, box[1].start, box[0].stop, box[1].stop),
                                     self.previous[box] == track)

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
