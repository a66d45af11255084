"""Polygon backend: accuracy and speed against scikit-image, and cost per iteration vs image size.

Run ``python benchmarks/bench_polygon.py`` (``--quick`` for fewer images).  Two tables:

1. Noisy synthetic images (256 x 256, contrast 0.4, Gaussian noise sigma 0.25, fixed seeds):
   Dice against the constructed ground truth and wall time, for ``activecontour.segment`` with its
   defaults and for ``skimage.segmentation.chan_vese`` with its defaults, in the same run, with the
   ratio of times.
2. The same object (a disk of radius 60 px) in images from 256^2 to 2048^2: one-time preparation
   (normalising, cumulative tables) and time per iteration, which must not grow with the pixel count.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import skimage.segmentation

import activecontour as ac
from activecontour import synthetic
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel

CONTRAST_IMAGES = {
    "disk": lambda c: synthetic.disk(c, 60.0),
    "square": lambda c: synthetic.rectangle((c[0] - 55.3, c[1] - 50.6), (c[0] + 50.2, c[1] + 54.7)),
    "star": lambda c: synthetic.star(c, 70.0, amplitude=0.3, arms=5),
}


def noisy_image(name, seed, size=256):
    center = ((size - 1) / 2.0 + 0.3, (size - 1) / 2.0 - 0.2)
    if size < 160:
        return synthetic.add_noise(synthetic.render(synthetic.disk(center, size / 4), (size, size))[0],
                                   0.25, seed), None
    image, truth = synthetic.render(CONTRAST_IMAGES[name](center), (size, size), inside=0.7, outside=0.3)
    return synthetic.add_noise(image, 0.25, seed), truth


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    out = function(*args, **kwargs)
    return out, time.perf_counter() - start


def accuracy_table(seeds):
    """Print the table; return ours' Dice, ours' times and the speed-ups over chan_vese, per image."""
    print("Noisy 256x256 images, contrast 0.4, noise sigma 0.25 (defaults of both libraries)")
    header = f"{'image':10s} {'seed':>4s} | {'ours s':>7s} {'Dice':>6s} {'iters':>5s} | " \
             f"{'skimage s':>9s} {'Dice':>6s} | {'speed-up':>8s}"
    print(header)
    print("-" * len(header))
    ratios, ours_dice, ours_time = [], [], []
    for name in CONTRAST_IMAGES:
        for seed in seeds:
            image, truth = noisy_image(name, seed)
            result, t_ours = timed(ac.segment, image)
            theirs, t_theirs = timed(skimage.segmentation.chan_vese, image)
            # skimage's mask marks the region of its own phi > 0, whichever intensity it got
            dice_theirs = max(synthetic.dice(theirs, truth), synthetic.dice(~theirs, truth))
            dice_ours = synthetic.dice(result.mask, truth)
            ratios.append(t_theirs / t_ours)
            ours_dice.append(dice_ours)
            ours_time.append(t_ours)
            print(f"{name:10s} {seed:4d} | {t_ours:7.3f} {dice_ours:6.4f} {result.n_iter:5d} | "
                  f"{t_theirs:9.3f} {dice_theirs:6.4f} | {t_theirs / t_ours:7.1f}x")
    print(f"ours: min Dice {min(ours_dice):.4f}, max time {max(ours_time):.3f} s, "
          f"median time {np.median(ours_time):.3f} s; speed-up over skimage.chan_vese: "
          f"median {np.median(ratios):.1f}x, min {min(ratios):.1f}x")
    # skimage's default tol stops early; run it to convergence from our initial circle once
    image, truth = noisy_image("disk", 1)
    rows, cols = np.mgrid[: image.shape[0], : image.shape[1]]
    center = (np.array(image.shape) - 1) / 2.0
    phi = 0.375 * min(image.shape) - np.hypot(rows - center[0], cols - center[1])
    result, t_ours = timed(ac.segment, image)
    theirs, t_theirs = timed(skimage.segmentation.chan_vese, image, init_level_set=phi, tol=1e-5,
                             max_num_iter=2000)
    dice_theirs = max(synthetic.dice(theirs, truth), synthetic.dice(~theirs, truth))
    print(f"disk seed 1 from the same circle, skimage to tol 1e-5: skimage {t_theirs:.2f} s Dice "
          f"{dice_theirs:.4f}; ours {t_ours:.3f} s Dice {synthetic.dice(result.mask, truth):.4f}: "
          f"{t_theirs / t_ours:.0f}x\n")
    return ours_dice, ours_time, ratios


def scaling_table(sizes):
    """Print the table; return the milliseconds per iteration, per size."""
    print("Same disk (radius 60 px) in larger images: cost per iteration vs pixel count")
    header = f"{'image':>11s} | {'prepare s':>9s} | {'iters':>5s} | {'ms / iter':>9s} | {'Dice':>6s}"
    print(header)
    print("-" * len(header))
    costs = []
    for size in sizes:
        center = ((size - 1) / 2.0 + 0.3, (size - 1) / 2.0 - 0.2)
        image, truth = synthetic.render(synthetic.disk(center, 60.0), (size, size), inside=0.7,
                                        outside=0.3, supersample=2)
        image = synthetic.add_noise(image, 0.1, 1)
        _, t_prepare = timed(ImageModel, normalize_image(image))
        stamps = []
        result, _ = timed(ac.segment, image, ac.circle(center, 100.0),
                          callback=lambda state, stamps=stamps: stamps.append(time.perf_counter()))
        per_iteration = np.median(np.diff(stamps)) * 1e3
        costs.append(per_iteration)
        print(f"{size:>5d}x{size:<5d} | {t_prepare:9.3f} | {result.n_iter:5d} | {per_iteration:9.2f} | "
              f"{synthetic.dice(result.mask, truth):6.4f}")
    return costs


def warm_up():
    """Run every code path once (imports, first allocations) before timing anything."""
    image, _ = noisy_image("disk", 0, size=64)
    ac.segment(image)
    skimage.segmentation.chan_vese(image, max_num_iter=2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one seed, sizes up to 1024")
    args = parser.parse_args()
    warm_up()
    accuracy_table([1] if args.quick else [1, 2, 3])
    scaling_table([256, 512, 1024] if args.quick else [256, 512, 1024, 2048])


if __name__ == "__main__":
    main()
