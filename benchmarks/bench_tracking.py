"""Identities through contact: identity switches of ``segment_sequence`` on random time-lapses.

Run ``python benchmarks/bench_tracking.py [--seeds N] [--frames T]``.  Each seed draws a
time-lapse of disks with exact truth ids (:func:`scene`, rendered by
:func:`activecontour.synthetic.disk_sequence`, SNR 2, 3 or 4), 240 x 360 px, six events side by
side in cells of 120 x 120: two disks drifting into contact and staying in it; two merging
(overlap up to 1.5 times the smaller radius: no waist left) and separating again; two passing each
other on lanes 1 px apart to 2 px overlapping; a division (a mother replaced by two daughters that
move apart); a disk entering through the bottom border next to a drifting one; a disk leaving
through the right border next to a drifting one.

Identity switches (:func:`switches`): each truth object is matched per frame to the object of our
labels with which it has IoU >= 0.5; a switch is a truth object matched to another id than at its
previous match, or one of our ids matched to another truth object than at its previous match (an
id handed on).  Printed per seed: the truth tracks, frames with every truth object matched, both
kinds of switch, and the CPU seconds of the run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import activecontour as ac
from activecontour.synthetic import disk_sequence

SIZE = (240, 360)
CELL = 120.0


def _pair(rng, frames, cell, gap):
    """Two disks in ``cell`` (row, col of its corner) along a random axis, ``gap(t, r1, r2)`` px
    apart at frame t (negative: overlapping), as ``(id offset, centre, radius)`` per frame."""
    r1, r2 = rng.uniform(10, 16, size=2)
    angle = rng.uniform(0, np.pi)
    axis = np.array([np.cos(angle), np.sin(angle)])
    centre = np.array(cell) + CELL / 2 + rng.uniform(-5, 5, size=2)
    out = []
    for t in range(frames):
        distance = r1 + r2 + gap(t, r1, r2)
        out.append([(0, tuple(centre - axis * distance * r1 / (r1 + r2)), r1),
                    (1, tuple(centre + axis * distance * r2 / (r1 + r2)), r2)])
    return out


def scene(seed, frames=20):
    """The disks of every frame, ``[(truth id, (row, col), radius), ...]`` per frame (see the
    module docstring)."""
    rng = np.random.default_rng(seed)
    events = [[] for _ in range(frames)]
    next_id = [1]

    def add(per_frame):
        base = next_id[0]
        next_id[0] += 1 + max(d[0] for disks in per_frame for d in disks)
        for t, disks in enumerate(per_frame):
            events[t] += [(base + offset, centre, radius) for offset, centre, radius in disks]

    # touching: from 10 px apart at 1-2 px a frame into contact (0-3 px overlap), kept
    contact, speed = -rng.uniform(0, 3), rng.uniform(1, 2)
    add(_pair(rng, frames, (0, 0), lambda t, r1, r2: max(10 - speed * t, contact)))
    # merge then separate: from 10 px apart to an overlap of 0.5-1.5 times the smaller radius at
    # mid-sequence (beyond 1 no waist is left), and back
    depth, middle = rng.uniform(0.5, 1.5), (frames - 1) / 2
    add(_pair(rng, frames, (0, CELL), lambda t, r1, r2:
              10 - (10 + depth * min(r1, r2)) * (1 - abs(t - middle) / middle)))
    # passing: opposite directions on lanes r1 + r2 + offset apart (offset -2 .. 1 px)
    r1, r2 = rng.uniform(10, 16, size=2)
    lane, speed = r1 + r2 + rng.uniform(-2, 1), rng.uniform(2, 3)
    top, middle = CELL / 2 - lane / 2, 2.5 * CELL
    travel = speed * (frames - 1) / 2
    add([[(0, (top, middle - travel + speed * t), r1), (1, (top + lane, middle + travel - speed * t), r2)]
         for t in range(frames)])
    # division at a random frame: daughters of half the area moving apart at 1 px a frame each
    radius, birth = rng.uniform(13, 17), int(rng.integers(frames // 3, 2 * frames // 3))
    angle = rng.uniform(0, np.pi)
    axis = np.array([np.cos(angle), np.sin(angle)])
    centre = np.array([1.5 * CELL, 0.5 * CELL])
    add([[(0, tuple(centre), radius)] if t < birth else
         [(1, tuple(centre - axis * (0.6 * radius + t - birth)), radius / np.sqrt(2)),
          (2, tuple(centre + axis * (0.6 * radius + t - birth)), radius / np.sqrt(2))]
         for t in range(frames)])
    # entering through the bottom border, next to a drifting disk
    r1, r2, speed = rng.uniform(10, 16), rng.uniform(10, 16), rng.uniform(2, 3)
    drift = rng.uniform(-1, 1, size=2)
    add([[(0, (CELL + 40 + drift[0] * t, CELL + 30 + drift[1] * t), r1),
          (1, (SIZE[0] + r2 - speed * t, CELL + 85), r2)] for t in range(frames)])
    # leaving through the right border, next to a drifting disk
    r1, r2, speed = rng.uniform(10, 16), rng.uniform(10, 16), rng.uniform(2, 3)
    add([[(0, (CELL + 30 + drift[1] * t, 2 * CELL + 30 + drift[0] * t), r1),
          (1, (CELL + 80, SIZE[1] - 40 + speed * t), r2)] for t in range(frames)])
    return events


def matches(labels, truth):
    """{truth id: our id} of the pairs with IoU >= 0.5 in one frame (each side at most once)."""
    both = (labels > 0) & (truth > 0)
    pairs, counts = np.unique(np.stack([truth[both], labels[both]]), axis=1, return_counts=True)
    ours_area = np.bincount(labels.ravel())
    truth_area = np.bincount(truth.ravel())
    found = {}
    for (true, ours), common in zip(pairs.T, counts, strict=True):
        if common / (truth_area[true] + ours_area[ours] - common) >= 0.5:
            found[int(true)] = int(ours)
    return found


def switches(labels, truth):
    """(truth objects that changed id, ids handed on to another truth object, frames with every
    truth object matched) over a sequence (see the module docstring)."""
    last_ours, last_truth = {}, {}
    changed = handed = complete = 0
    for ours, true in zip(labels, truth, strict=True):
        found = matches(ours, true)
        complete += len(found) == len(np.unique(true[true > 0]))
        for true_id, our_id in found.items():
            changed += last_ours.get(true_id, our_id) != our_id
            handed += last_truth.get(our_id, true_id) != true_id
            last_ours[true_id], last_truth[our_id] = our_id, true_id
    return changed, handed, complete


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--frames", type=int, default=20)
    args = parser.parse_args()
    print(f"{'seed':>4s} {'SNR':>4s} {'tracks':>6s} {'matched':>8s} {'changed':>8s} {'handed on':>9s} "
          f"{'CPU s':>6s}", flush=True)
    totals = np.zeros(2, int)
    for seed in range(args.seeds):
        snr = (2.0, 3.0, 4.0)[seed % 3]
        images, truth = disk_sequence(SIZE, scene(seed, args.frames), inside=0.75, outside=0.25,
                                      sigma=0.5 / snr, seed=seed)
        start = time.process_time()
        seq = ac.segment_sequence(images, keep_results=False)
        seconds = time.process_time() - start
        changed, handed, complete = switches(seq.labels, truth)
        totals += (changed, handed)
        print(f"{seed:4d} {snr:4.0f} {len(np.unique(truth)) - 1:6d} {complete:4d}/{args.frames:<3d} "
              f"{changed:8d} {handed:9d} {seconds:6.1f}", flush=True)
    print(f"total: {totals[0]} truth objects changed id, {totals[1]} ids handed on, over {args.seeds} seeds "
          f"(target: 0 and 0 over at least 20 seeds)")


if __name__ == "__main__":
    main()
