"""The pointed-at object: a curve drawn around one object gives that object alone (``roi="init"``).

Run ``python benchmarks/bench_pointed.py [--quick]``.  For every object of an image's default
full-image run (``ac.segment(image)``; objects that touch the image border or are smaller than
``MIN_AREA`` left out), a circle of f times the object's equivalent radius around its centroid,
and a square of the same half-side (a drawn box), is passed as ``init`` with ``roi="init"``.
Columns, per image family and f: the objects tried, the worst Dice against that object of the
full run, how many runs gave any pixel of another object of the full run (and the most such
pixels), and the largest CPU time of one run.

Families: ``coins`` (scikit-image's, 303 x 384), ``field`` (:func:`blob_field`: ~28 disks and
ellipses of radius 14-40 px a few pixels apart at 512^2, SNR 3, blurred; three seeds), ``blobs``
(``skimage.data.binary_blobs`` at 512^2 with noise: irregular shapes), ``dsb`` (the DSB 2018 nuclei
image of the stardist wheel, 512^2: :func:`bench_objects.stardist_images`).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import activecontour as ac
from activecontour import synthetic

#: Objects of the full run below this area (px^2) are not tried (a pointed-at object is one a
#: user can draw around).
MIN_AREA = 50.0
FACTORS = (1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8)


def blob_field(seed, *, size=512, count=28, radius=(14.0, 40.0), gap=(2.0, 12.0), snr=3.0, blur=1.0):
    """A dense field of disks and ellipses (aspect up to 1.5) a few pixels apart, noisy: (image,
    truth labels).  Blobs are placed at random and kept when at least ``gap[0]`` (and at most
    ``gap[1]`` from the nearest, after the first) from every other, until ``count`` or 5000 tries."""
    rng = np.random.default_rng(seed)
    shapes, placed = [], []
    for _ in range(5000):
        if len(placed) == count:
            break
        a = rng.uniform(*radius)
        b = a / rng.uniform(1.0, 1.5)
        centre = rng.uniform(a, size - 1 - a, size=2)
        distances = [np.hypot(*(centre - c)) - a - r for c, r in placed]
        if distances and (min(distances) < gap[0] or min(distances) > gap[1]):
            continue
        placed.append((centre, a))
        shapes.append(synthetic.ellipse(tuple(centre), a, b, rng.uniform(0, np.pi)))
    image, _ = synthetic.render(synthetic.union(*shapes), (size, size), inside=0.5, outside=0.0)
    truth = np.zeros((size, size), np.int32)
    for k, shape in enumerate(shapes):
        truth[synthetic.render(shape, (size, size))[1]] = k + 1
    return synthetic.add_noise(image, 0.5 / snr, seed, blur=blur), truth


def binary_blobs(seed):
    import skimage.data

    blobs = skimage.data.binary_blobs(512, blob_size_fraction=0.06, volume_fraction=0.3, rng=seed)
    return synthetic.add_noise(blobs * 0.5, 0.5 / 3, seed, blur=1.0)


def families(quick):
    import skimage.data

    yield "coins", skimage.data.coins()
    for seed in range(1 if quick else 3):
        yield "field", blob_field(seed)[0]
    for seed in range(1 if quick else 2):
        yield "blobs", binary_blobs(seed)
    from bench_objects import stardist_images

    dsb = stardist_images()
    if dsb is not None:
        yield "dsb", dsb[0]


def targets(full):
    """The ids, centroids and equivalent radii of a full run's objects that may be pointed at."""
    table = full.objects
    m, n = full.labels.shape
    inner = ((table["bbox-0"] > 0) & (table["bbox-1"] > 0) & (table["bbox-2"] < m) & (table["bbox-3"] < n)
             & (table["area"] >= MIN_AREA))
    centres = np.column_stack([table["centroid-0"], table["centroid-1"]])[inner]
    return table["label"][inner], centres, np.sqrt(table["area"][inner] / np.pi)


def drawn(shape, centre, half):
    if shape == "circle":
        return ac.circle(centre, half)
    return ac.rectangle(np.asarray(centre) - half, np.asarray(centre) + half)


def point(image, full, label, centre, half, shape):
    """(Dice against the full run's object, foreign pixels, CPU seconds) of one drawn curve."""
    start = time.process_time()
    res = ac.segment(image, drawn(shape, centre, half), roi="init")
    seconds = time.process_time() - start
    truth = full.labels == label
    dice = synthetic.dice(res.mask, truth)
    foreign = int(np.count_nonzero(res.mask & (full.labels > 0) & ~truth))
    return dice, foreign, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one image per family, f = 1.1, 1.4, 1.8")
    parser.add_argument("--shapes", default="circle,box")
    args = parser.parse_args()
    factors = (1.1, 1.4, 1.8) if args.quick else FACTORS
    print(f"{'family':8s}{'drawn':8s}{'f':>5s}{'tried':>7s}{'worst Dice':>12s}{'< 0.95':>8s}"
          f"{'foreign runs':>14s}{'max foreign':>13s}{'max s':>8s}{'median s':>10s}", flush=True)
    rows, last = {}, None
    for family, image in families(args.quick):
        if last is not None and family != last:
            report(rows, last)
        last = family
        full = ac.segment(image)
        for label, centre, radius in zip(*targets(full), strict=True):
            for shape in args.shapes.split(","):
                for f in factors:
                    dice, foreign, seconds = point(image, full, label, centre, f * radius, shape)
                    rows.setdefault((family, shape, f), []).append((dice, foreign, seconds))
    report(rows, last)


def report(rows, family):
    """Print the rows of one family (all its images pooled)."""
    for (name, shape, f), entries in rows.items():
        if name != family:
            continue
        dice, foreign, seconds = (np.array(column) for column in zip(*entries, strict=True))
        print(f"{family:8s}{shape:8s}{f:5.1f}{len(entries):7d}{dice.min():12.3f}{np.sum(dice < 0.95):8d}"
              f"{np.count_nonzero(foreign):14d}{foreign.max():13d}{seconds.max():8.2f}{np.median(seconds):10.2f}",
              flush=True)

if __name__ == "__main__":
    main()
