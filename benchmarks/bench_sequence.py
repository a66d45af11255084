"""Sequences: ours warm (``segment_sequence``) vs ours cold (``segment`` per frame) vs scikit-image.

A synthetic time-lapse with exact ground truth (:func:`activecontour.synthetic.disk_sequence`):
disks drifting and breathing at SNR 2 (contrast 0.5, noise 0.25), one leaving through the border,
one entering, one dividing, two passing each other 5 px apart (:func:`scene`).  Per frame, side
by side in one run and interleaved (so the machine's
load hits all three alike): the warm frame of :func:`activecontour.iter_sequence`, a cold
:func:`activecontour.segment` of the same frame, and ``skimage.segmentation.chan_vese`` with its
defaults (``--no-skimage`` leaves it out: ~25 ms per iteration at 512^2).

Reported: per-frame Dice of the foreground against the truth (mean and worst), identity switches
(a truth track whose pixels are given more than one id over its life, plus ids shared by two
truth tracks; cold results get no ids), ms per frame (median), warm/cold ratio, and the peak
memory of the warm run (tracemalloc: numpy's allocations) at two lengths, which is flat when the
run streams (``keep_results=False``, labels to a TIFF file).

usage: python benchmarks/bench_sequence.py [--frames T] [--size N] [--no-skimage] [--long T]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import tracemalloc

import numpy as np

import activecontour as ac
from activecontour.synthetic import dice, disk_sequence


def scene(n_frames, size):
    """Disks (id, centre, radius) per frame, each in its own lane: 1 drifts, 2 breathes, 3 leaves
    through the top border, 4 enters from the left, 5 divides at mid-sequence (two daughters of
    half its area moving apart: ids 8 and 9), 6 and 7 pass each other 1 % of the size apart."""
    r, half = 0.06 * size, n_frames // 2
    frames = []
    for t in range(n_frames):
        s = t / max(n_frames - 1, 1)  # 0 .. 1 over the sequence
        disks = [(1, (0.14 * size, 0.16 * size + 0.1 * size * s), r),
                 (2, (0.5 * size, 0.15 * size), r * (1 + 0.15 * np.sin(2 * np.pi * t / 12))),
                 (3, (0.25 * size - (0.25 * size + 1.2 * r) * s / 0.7, 0.6 * size), r),
                 (6, (0.66 * size, 0.2 * size + 0.6 * size * s), r),
                 (7, (0.66 * size + 2 * r + 0.01 * size, 0.8 * size - 0.6 * size * s), r)]
        if t >= n_frames // 4:
            disks.append((4, (0.92 * size, -1.2 * r + 0.35 * size * (t - n_frames // 4) / n_frames), r))
        if t < half:
            disks.append((5, (0.42 * size, 0.82 * size), r))
        else:
            offset = 0.6 * r + 0.005 * size * (t - half)
            disks += [(8, (0.42 * size - offset, 0.82 * size), 0.72 * r),
                      (9, (0.42 * size + offset, 0.82 * size), 0.72 * r)]
        frames.append(disks)
    return frames


def identity_switches(labels, truth):
    """Truth tracks seen under more than one id, plus ids given to more than one truth track
    (each pixel of a truth object votes for the id it got; the majority id is the object's)."""
    seen, owners = {}, {}
    for ours, true in zip(labels, truth, strict=True):
        for track in np.unique(true[true > 0]):
            votes = np.bincount(ours[true == track])
            votes[0] = 0
            if votes.sum() == 0:
                continue
            label = int(votes.argmax())
            seen.setdefault(int(track), set()).add(label)
            owners.setdefault(label, set()).add(int(track))
    return sum(len(ids) - 1 for ids in seen.values()) + sum(len(t) - 1 for t in owners.values())


def peak_memory(images, n_frames):
    """Peak traced memory (MB, tracemalloc: numpy's buffers included) of a streaming run over
    ``n_frames`` frames drawn from ``images`` by a generator (labels to a temporary TIFF)."""
    frames = (images[t % len(images)] for t in range(n_frames))
    with tempfile.TemporaryDirectory() as folder:
        tracemalloc.start()
        ac.segment_sequence(frames, keep_results=False, labels_file=os.path.join(folder, "l.tif"))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak / 2**20


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--no-skimage", action="store_true")
    parser.add_argument("--long", type=int, default=0,
                        help="also stream this many frames (a generator) and report peak memory")
    args = parser.parse_args()
    images, truth = disk_sequence(args.size, scene(args.frames, args.size), sigma=0.25, seed=1)
    ac.segment(images[0])  # imports and caches warm before timing
    warm_labels, times = [], {"warm": [], "cold": [], "skimage": []}
    dices = {"warm": [], "cold": [], "skimage": []}
    frames = ac.iter_sequence(images)
    for t in range(args.frames):
        start = time.perf_counter()
        frame = next(frames)
        times["warm"].append(time.perf_counter() - start)
        warm_labels.append(frame.result.labels)
        dices["warm"].append(dice(frame.result.labels > 0, truth[t] > 0))
        start = time.perf_counter()
        cold = ac.segment(images[t])
        times["cold"].append(time.perf_counter() - start)
        dices["cold"].append(dice(cold.mask, truth[t] > 0))
        if not args.no_skimage:
            from skimage.segmentation import chan_vese

            start = time.perf_counter()
            mask = chan_vese(images[t])
            times["skimage"].append(time.perf_counter() - start)
            # the functional does not say which class is the object: score the better reading
            dices["skimage"].append(max(dice(mask, truth[t] > 0), dice(~mask, truth[t] > 0)))
    switches = identity_switches(np.stack(warm_labels), truth)
    print(f"{args.frames} frames of {args.size}x{args.size}, SNR 2, {len(np.unique(truth)) - 1} tracks "
          f"(drift, breathing, leaving, entering, one division, two passing close by)")
    print(f"{'method':28s} {'Dice mean':>9s} {'Dice worst':>10s} {'ms/frame':>9s} {'id switches':>11s}")
    for name, label in (("warm", "ours, warm (segment_sequence)"), ("cold", "ours, cold (segment)"),
                        ("skimage", "skimage chan_vese")):
        if not times[name]:
            continue
        later = times[name][1:] if name == "warm" else times[name]  # frame 0 of warm is cold
        print(f"{label:28s} {np.mean(dices[name]):9.4f} {np.min(dices[name]):10.4f} "
              f"{1000 * np.median(later):9.1f} {switches if name == 'warm' else '-':>11}")
    ratio = np.median(np.array(times["warm"][1:]) / np.array(times["cold"][1:]))
    print(f"warm/cold per frame (median of per-frame ratios, frames 1..): {ratio:.3f}")
    if args.long:
        short = max(2, args.long // 10)
        print(f"peak memory streaming {short} frames: {peak_memory(images, short):.1f} MB; "
              f"{args.long} frames: {peak_memory(images, args.long):.1f} MB")


if __name__ == "__main__":
    main()
