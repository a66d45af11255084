"""Sequences: ours warm (``segment_sequence``) vs ours cold (``segment`` per frame) vs scikit-image.

A synthetic time-lapse with exact ground truth (:func:`activecontour.synthetic.disk_sequence`):
disks drifting and breathing at SNR 2 (contrast 0.5, noise 0.25), one leaving through the border,
one entering, one dividing, two passing each other 5 px apart (:func:`scene`).  Per frame, side
by side in one run and interleaved (so the machine's
load hits all three alike): the warm frame of :func:`activecontour.iter_sequence`, a cold
:func:`activecontour.segment` of the same frame, and ``skimage.segmentation.chan_vese`` with its
defaults (``--no-skimage`` leaves it out: ~25 ms per iteration at 512^2).

The frames are made one at a time (:class:`Frames`) and the warm run streams them through
:func:`activecontour.iter_sequence`, so a run of 1000 frames holds one frame; ``--cold-every K``
segments only every K-th frame cold (and with scikit-image), the warm/cold ratio is then taken on
those frames.  Times are process CPU time (the machine is shared); ``--repeats R`` takes the least
of R runs of each cold and scikit-image frame (a warm frame depends on the one before: one run).

Reported: per-frame Dice of the foreground against the truth (mean and worst), identity switches
(a truth track whose pixels are given more than one id over its life, plus ids shared by two
truth tracks; cold results get no ids), ms per frame (median), iterations per frame (mean),
warm/cold CPU ratio, and the peak memory of the warm run (tracemalloc: numpy's allocations) at
two lengths, which is flat when the run streams (``keep_results=False``, labels to a TIFF file).

usage: python benchmarks/bench_sequence.py [--frames T] [--size N] [--no-skimage] [--cold-every K]
                                           [--repeats R] [--long T]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import tracemalloc

import numpy as np
from timing import least_cpu

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


class IdentitySwitches:
    """Truth tracks seen under more than one id, plus ids given to more than one truth track
    (each pixel of a truth object votes for the id it got; the majority id is the object's),
    counted frame by frame (:meth:`add`), so a long run need not keep its labels."""

    def __init__(self):
        self.seen, self.owners = {}, {}

    def add(self, ours, true):
        for track in np.unique(true[true > 0]):
            votes = np.bincount(ours[true == track])
            votes[0] = 0
            if votes.sum() == 0:
                continue
            label = int(votes.argmax())
            self.seen.setdefault(int(track), set()).add(label)
            self.owners.setdefault(label, set()).add(int(track))

    @property
    def count(self):
        return sum(len(ids) - 1 for ids in self.seen.values()) + sum(len(t) - 1 for t in self.owners.values())


class Frames:
    """The frames of the scene, made one at a time (frame t of :func:`disk_sequence` with noise seed
    ``seed + t``, the same image as the whole stack's frame t): a run of any length streams.
    Iterating yields the images."""

    def __init__(self, disks, size, sigma=0.25, seed=1):
        self.disks, self.size, self.sigma, self.seed = disks, size, sigma, seed

    def frame(self, t):
        """Frame t's image and ground truth."""
        images, truth = disk_sequence(self.size, self.disks[t:t + 1], sigma=self.sigma, seed=self.seed + t)
        return images[0], truth[0]

    def __iter__(self):
        return (self.frame(t)[0] for t in range(len(self.disks)))


def peak_memory(source, n_frames):
    """Peak traced memory (MB, tracemalloc: numpy's buffers included) of a streaming run over the
    first ``n_frames`` frames of ``source`` (a :class:`Frames`, made one at a time; labels to a
    temporary TIFF)."""
    frames = Frames(source.disks[:n_frames], source.size, source.sigma, source.seed)
    with tempfile.TemporaryDirectory() as folder:
        tracemalloc.start()
        ac.segment_sequence(iter(frames), keep_results=False, labels_file=os.path.join(folder, "l.tif"))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak / 2**20


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=24)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--no-skimage", action="store_true")
    parser.add_argument("--cold-every", type=int, default=1,
                        help="segment cold (and with scikit-image) only every K-th frame (a long run)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="cold and scikit-image frames: the least CPU time of this many runs")
    parser.add_argument("--long", type=int, default=0,
                        help="also stream this many frames (a generator) and report peak memory")
    args = parser.parse_args()
    source = Frames(scene(args.frames, args.size), args.size)
    ac.segment(source.frame(0)[0])  # imports and caches warm before timing
    import scipy.optimize  # noqa: F401  (the tracker's; loaded on frame 1, not timed there)

    switches = IdentitySwitches()
    seconds = {"warm": [], "cold": [], "skimage": []}
    dices = {"warm": [], "cold": [], "skimage": []}
    iterations = {"warm": [], "cold": []}
    paired = []  # (warm, cold) CPU seconds of the frames segmented both ways, frames 1..
    current = {}

    def stream():  # each frame made before its timing starts: the run reads what is there
        while True:
            yield current["image"]

    frames = ac.iter_sequence(stream())
    for t in range(args.frames):
        current["image"], truth = source.frame(t)
        frame, warm_seconds = least_cpu(next, frames)
        seconds["warm"].append(warm_seconds)
        iterations["warm"].append(frame.result.n_iter)
        dices["warm"].append(dice(frame.result.labels > 0, truth > 0))
        switches.add(frame.result.labels, truth)
        if t % args.cold_every:
            continue
        cold, cold_seconds = least_cpu(ac.segment, frame.image, repeats=args.repeats)
        seconds["cold"].append(cold_seconds)
        iterations["cold"].append(cold.n_iter)
        dices["cold"].append(dice(cold.mask, truth > 0))
        if t > 0:
            paired.append((warm_seconds, cold_seconds))
        if not args.no_skimage:
            from skimage.segmentation import chan_vese

            mask, skimage_seconds = least_cpu(chan_vese, frame.image, repeats=args.repeats)
            seconds["skimage"].append(skimage_seconds)
            # the functional does not say which class is the object: score the better reading
            dices["skimage"].append(max(dice(mask, truth > 0), dice(~mask, truth > 0)))
    print(f"{args.frames} frames of {args.size}x{args.size}, SNR 2, streamed; cold every {args.cold_every} "
          f"frame(s), least of {args.repeats}; CPU time")
    print(f"{'method':30s} {'Dice mean':>9s} {'Dice worst':>10s} {'frames':>6s} {'ms/frame':>9s} "
          f"{'iterations':>10s} {'id switches':>11s}")
    for name, label in (("warm", "ours, warm (iter_sequence)"), ("cold", "ours, cold (segment)"),
                        ("skimage", "skimage chan_vese")):
        if not seconds[name]:
            continue
        later = seconds[name][1:] if name == "warm" else seconds[name]  # frame 0 of warm is cold
        steps = f"{np.mean(iterations[name]):.1f}" if name in iterations else "-"
        print(f"{label:30s} {np.mean(dices[name]):9.4f} {np.min(dices[name]):10.4f} {len(dices[name]):6d} "
              f"{1000 * np.median(later):9.1f} {steps:>10s} {switches.count if name == 'warm' else '-':>11}")
    if paired:
        warm, cold = np.array(paired).T
        print(f"warm/cold CPU time on the {len(paired)} frames segmented both ways (1..): "
              f"{warm.sum() / cold.sum():.3f} (sums), {np.median(warm / cold):.3f} "
              f"(median of per-frame ratios)")
    if args.long:
        short, source = max(2, args.long // 10), Frames(scene(args.long, args.size), args.size)
        print(f"peak memory streaming {short} frames: {peak_memory(source, short):.1f} MB; "
              f"{args.long} frames: {peak_memory(source, args.long):.1f} MB")


if __name__ == "__main__":
    main()
