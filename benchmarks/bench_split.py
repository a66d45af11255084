"""The cost of splitting touching objects on speckled objects, against their size.

Run ``python benchmarks/bench_split.py``.  Each object is the largest connected piece of smoothed
uniform noise (Gaussian, sigma 2 px) above its 45 % quantile: a sponge-like outline whose distance
to the boundary has a local maximum every few pixels, so the watershed of
:func:`activecontour.objects.split.split_touching` makes hundreds to thousands of parts.  The table
lists the object's pixels, the watershed's parts, the objects after the split, the wall time and
the time per pixel, which stays about constant if the split is about linear in the pixels.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.ndimage
import skimage.morphology

from activecontour.geometry.raster import mask_to_curves
from activecontour.geometry.regions import group_curves
from activecontour.objects.measure import label_image
from activecontour.objects.split import split_touching

SIDES = (192, 384, 768, 1100)


def speckled_object(side, seed=0):
    """The largest 4-connected piece of smoothed noise above its 45 % quantile, 2 px from the edge."""
    field = scipy.ndimage.gaussian_filter(np.random.default_rng(seed).random((side, side)), 2.0)
    mask = field > np.quantile(field, 0.45)
    mask[:2], mask[-2:], mask[:, :2], mask[:, -2:] = False, False, False, False
    pieces, _ = scipy.ndimage.label(mask)
    return pieces == 1 + np.argmax(np.bincount(pieces.ravel())[1:])


def main():
    print(f"{'side':>5} | {'pixels':>8} | {'parts':>6} | {'objects':>7} | {'time s':>7} | {'us/px':>6}")
    print("-" * 55)
    for side in SIDES:
        mask = speckled_object(side)
        distance = scipy.ndimage.distance_transform_edt(mask)
        parts = scipy.ndimage.label(skimage.morphology.local_maxima(distance) & mask)[1]
        objects = group_curves(mask_to_curves(mask))
        labels = label_image(objects, mask.shape)
        start = time.perf_counter()
        split = split_touching(objects, labels)
        elapsed = time.perf_counter() - start
        pixels = int(mask.sum())
        print(f"{side:>5} | {pixels:>8} | {parts:>6} | {len(split):>7} | {elapsed:>7.2f} | "
              f"{1e6 * elapsed / pixels:>6.2f}")


if __name__ == "__main__":
    main()
