"""Identities through contact (issue 23, item 6): the frame before seeds the split, lost tracks
keep their ids for a few frames."""

import numpy as np
import pytest

import activecontour as ac
from activecontour.objects.measure import find_objects, split_by_seeds
from activecontour.result import SegmentationResult
from activecontour.sequence.tracking import TRACK_GAP, _Tracker
from activecontour.synthetic import disk, disk_sequence, render

SIZE = (120, 160)


def matched_ids(labels, truth):
    """Per truth track, our id in each frame where the two overlap with IoU >= 0.5 (None where
    none does: a blob on top of another, whose visible part is a cap, is no match)."""
    seen = {}
    for ours, true in zip(labels, truth, strict=True):
        for track in np.unique(true[true > 0]):
            mine = true == track
            votes = np.bincount(ours[mine])
            votes[0] = 0
            best = int(votes.argmax())
            iou = votes[best] / np.count_nonzero(mine | (ours == best)) if votes.sum() else 0.0
            seen.setdefault(int(track), []).append(best if iou >= 0.5 else None)
    return seen


def assert_no_switch(labels, truth):
    """Every truth track has one id wherever it is matched, and no id is matched to two tracks."""
    seen = matched_ids(labels, truth)
    owners = {}
    for track, ids in seen.items():
        assert len(set(ids) - {None}) == 1, f"track {track}: ids {ids}"
        owners.setdefault(next(i for i in ids if i is not None), []).append(track)
    assert all(len(tracks) == 1 for tracks in owners.values()), f"an id handed on: {seen}"
    return seen


def test_three_drifting_blobs_keep_their_ids_through_contact():
    """The issue's case: blob 2 (radius 10) drifts into blob 1 (radius 18) until they overlap by
    12 px, no waist left, and stays there; blob 3 drifts alone.  Blob 2 keeps an object of its
    own (the part beyond the chord between the two outlines' crossings)."""
    spec = []
    for t in range(10):
        gap = max(10.0 - 3.0 * t, -12.0)
        spec.append([(1, (60.0, 50.0 + 0.5 * t), 18.0), (2, (60.0, 78.0 + gap + 0.5 * t), 10.0),
                     (3, (25.0 + t, 135.0), 12.0)])
    images, truth = disk_sequence(SIZE, spec, sigma=0.5 / 3, seed=4)
    seq = ac.segment_sequence(images)
    seen = assert_no_switch(seq.labels, truth)
    assert None not in seen[1] + seen[3]
    assert all(len(np.unique(seq.labels[t])) == 4 for t in range(10))
    assert seq.graph == {}


@pytest.mark.parametrize("depth", [0.6, 1.2])
def test_two_blobs_that_merge_and_separate_keep_their_ids(depth):
    """Blobs of radius 15 and 12 overlap up to ``depth`` times the smaller radius (1.2: no waist
    left, one blob by its outline) for a few frames and move apart again."""
    spec = []
    for t in range(12):
        gap = 10.0 - (10.0 + depth * 12.0) * (1 - abs(t - 5.5) / 5.5)
        spec.append([(1, (60.0, 70.0 - gap / 2), 15.0), (2, (60.0, 97.0 + gap / 2), 12.0)])
    images, truth = disk_sequence(SIZE, spec, sigma=0.5 / 3, seed=6)
    seq = ac.segment_sequence(images)
    seen = assert_no_switch(seq.labels, truth)
    assert seen[2][0] is not None and seen[2][-1] is not None  # before and after the merge
    # while they overlap, each still has its own object
    assert all(len(np.unique(seq.labels[t])) == 3 for t in range(12))


def test_split_by_seeds_cuts_an_object_without_a_waist_between_its_seeds():
    """Two disks overlapping by 1.2 times the smaller radius: no neck, one object for
    split_touching; with the disks of a pixel before as seeds, two, each nearly its disk."""
    big, small = disk((40.0, 40.0), 15.0), disk((40.0, 40.0 + 15.0 + 12.0 - 14.4), 12.0)
    image, union = render(lambda r, c: big(r, c) | small(r, c), (80, 80))
    res = ac.segment(image)
    assert res.labels.max() == 1
    seeds = np.zeros((80, 80), np.int32)
    seeds[render(disk((40.0, 41.0), 15.0), (80, 80))[1]] = 5
    seeds[render(disk((40.0, 41.0 + 12.6), 12.0), (80, 80))[1]] = 7  # drawn last: the overlap is 7's
    objects = [[c for c in res.contours]]
    parts = split_by_seeds(objects, res.labels, seeds)
    assert len(parts) == 2
    _, labels, table = find_objects(res.contours, (80, 80), seeds=seeds)
    assert labels.max() == 2
    np.testing.assert_allclose(table["area"].sum(), sum(np.sum([_area(c) for c in part]) for part in parts))
    # each part is its seed's share of the object, where the object is now: the big disk less the
    # small one, and the small one
    small_now = render(small, (80, 80))[1]
    expected = [render(big, (80, 80))[1] & ~small_now, small_now]
    for k in (1, 2):
        iou = max(np.sum((labels == k) & t) / np.sum((labels == k) | t) for t in expected)
        assert iou > 0.85
    # an object holding one seed is split as without seeds
    one_seed = (seeds == 5).astype(np.int32)
    np.testing.assert_array_equal(find_objects(res.contours, (80, 80), seeds=one_seed)[1], res.labels)


def _area(curve):
    r, c = curve[:, 0], curve[:, 1]
    return 0.5 * np.sum(r * np.roll(c, -1) - np.roll(r, -1) * c)


def _frame(labels):
    """A result carrying ``labels`` (ids 1..n) as the tracker reads it."""
    count = int(labels.max())
    return SegmentationResult(mask=labels > 0, contours=[], c_in=1.0, c_out=0.0, energy=0.0, energies=[0.0],
                              n_iter=0, status=0, backend="polygon", labels=labels,
                              objects={"label": np.arange(1, count + 1, dtype=np.int32)})


def _square(top, left, side=10, shape=(40, 80)):
    labels = np.zeros(shape, np.int32)
    labels[top:top + side, left:left + side] = 1
    return labels


@pytest.mark.parametrize("missing", [1, TRACK_GAP, TRACK_GAP + 1])
def test_a_track_lost_for_a_few_frames_takes_its_id_back(missing):
    """A square seen, then missed for ``missing`` frames while another object goes on: it takes
    its id back within TRACK_GAP frames, a new one after."""
    tracker = _Tracker()
    other = _square(25, 60)
    ids = []
    for t in range(3 + missing):
        labels = other.copy()
        if t < 2 or t == 2 + missing:
            labels[_square(5, 5 + t) > 0] = 2
        result, _ = tracker.update(_frame(labels))
        ids.append(np.unique(result.labels[5:15, 5 + t:15 + t]).tolist() if labels[5, 5 + t] else None)
    first, last = ids[0], ids[-1]
    assert (last == first) == (missing <= TRACK_GAP)
    assert ids[1] == first
