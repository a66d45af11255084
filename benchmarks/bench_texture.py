"""Textured images: ``segment(image)`` with the defaults against scikit-image's ``chan_vese``, in CPU time.

Run ``python benchmarks/bench_texture.py [--repeat N] [--images grass gravel ...]``.

Textured images (scikit-image's grass, gravel, brick; hubble_deep_field's stars; astronaut's
detail) end as hundreds to a thousand small curves, so they measure whether many curves cost what
their vertices cost.  Per image, side by side in one process, the table lists the CPU time
(``time.process_time``: the machine may be shared) of

* ``segment(image)`` with every default (objects split apart, ``separate=True``) and with
  ``separate=False``, which leaves out the split of touching objects (its share of the run);
* scikit-image's ``chan_vese`` with its defaults on the gray image scaled to [0, 1], as
  ``benchmarks/bench_robust.py`` runs it;

each the minimum over ``--repeat`` runs, the ratio ours / chan_vese, our energy by the common
evaluator :func:`activecontour.chan_vese_energy`, the iterations and the curves.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np
import skimage.color
import skimage.data
import skimage.segmentation
from timing import least_cpu

import activecontour as ac

IMAGES = ("grass", "gravel", "hubble_deep_field", "brick", "astronaut")


def gray01(image):
    """The gray image scaled by its range to [0, 1], as scikit-image's ``chan_vese`` expects."""
    image = np.asarray(image)
    if image.ndim == 3:
        image = skimage.color.rgb2gray(image[..., :3])
    image = image.astype(np.float64)
    span = image.max() - image.min()
    return (image - image.min()) / span if span > 0 else image * 0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per image and method; the minimum counts")
    parser.add_argument("--images", nargs="+", default=list(IMAGES), choices=IMAGES)
    args = parser.parse_args(argv)
    images = {name: getattr(skimage.data, name)() for name in args.images}
    ac.segment(images[args.images[0]][:64, :64])  # imports and first allocations, not timed
    best = {name: {"ours": np.inf, "flow": np.inf, "chan_vese": np.inf} for name in images}
    results = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(args.repeat):
            for name, image in images.items():
                results[name], seconds = least_cpu(ac.segment, image)
                best[name]["ours"] = min(best[name]["ours"], seconds)
                _, seconds = least_cpu(ac.segment, image, separate=False)
                best[name]["flow"] = min(best[name]["flow"], seconds)
                gray = gray01(image)
                _, seconds = least_cpu(skimage.segmentation.chan_vese, gray)
                best[name]["chan_vese"] = min(best[name]["chan_vese"], seconds)
    header = (f"{'image':18s} | {'ours s':>7s} | {'sep=False s':>11s} | {'chan_vese s':>11s} | "
              f"{'ratio':>6s} | {'ratio sep=False':>15s} | {'energy':>12s} | {'n_iter':>6s} | {'curves':>6s}")
    print(f"CPU seconds, minimum of {args.repeat} runs")
    print(header)
    print("-" * len(header))
    for name, image in images.items():
        result, times = results[name], best[name]
        energy = ac.chan_vese_energy(image, result.contours)
        print(f"{name:18s} | {times['ours']:7.2f} | {times['flow']:11.2f} | {times['chan_vese']:11.2f} | "
              f"{times['ours'] / times['chan_vese']:6.2f} | {times['flow'] / times['chan_vese']:15.2f} | "
              f"{energy:12.6f} | {result.n_iter:6d} | {len(result.contours):6d}")


if __name__ == "__main__":
    main()
