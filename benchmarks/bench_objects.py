"""Objects: instance segmentation of touching objects, next to the classic pipelines, in one run.

Run ``python benchmarks/bench_objects.py [--render DIR]``.  Methods:

* ``polygon``, ``levelset``: :func:`activecontour.segment` with its defaults (``separate=True``:
  touching objects split along their necks), ``res.labels``;
* ``polygon cc``: the same segmentation, ``separate=False`` (connected pieces);
* ``otsu cc``: Gaussian blur (1 px), Otsu's threshold, connected components;
* ``otsu ws``: the same mask split by the watershed of its distance transform from the peaks
  ``peak_local_max(min_distance=5)`` (the scikit-image gallery / CellProfiler pipeline);
* ``morph cv``: ``skimage.segmentation.morphological_chan_vese`` (checkerboard start, 150
  iterations, smoothing 1; inside = the class covering less of the border), connected components.

Scenes: :func:`activecontour.synthetic.touching_clumps` (elongated ellipses, aspect up to 2.5,
overlapping by up to a third of the minor axis, SNR 3; seeds 0-3 pooled), the DSB 2018 nuclei
image shipped in the ``stardist`` wheel (BSD-3; looked for in ``$STARDIST_DATA``, the repository's
``../_data/stardist/data/images``, or fetched once with ``pip download --no-deps stardist`` into
``~/.cache/activecontour``), and ``skimage.data.coins`` (24 coins, no instance truth: object
counts only).  Columns: F1 and accuracy TP / (TP + FP + FN) at IoU >= 0.5
(:func:`activecontour.objects.metrics.match_instances`), objects found / true, wall time.  ``--render``
writes each label image in colour (one colour per id) next to the truth.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
import scipy.ndimage

import activecontour as ac
from activecontour import synthetic
from activecontour.objects.metrics import match_instances

STARDIST_FILES = ("stardist/data/images/img2d.tif", "stardist/data/images/mask2d.tif")


def stardist_images():
    """(image, labels) of the DSB 2018 sample in the stardist wheel, or None when unavailable."""
    import tifffile

    here = Path(__file__).resolve().parents[1]
    candidates = [Path(os.environ["STARDIST_DATA"])] if "STARDIST_DATA" in os.environ else []
    candidates += [here.parent / "_data/stardist/data/images", here / "_data/stardist/data/images",
                   Path.home() / ".cache/activecontour/stardist/data/images"]
    for folder in candidates:
        if (folder / "img2d.tif").exists() and (folder / "mask2d.tif").exists():
            return tifffile.imread(folder / "img2d.tif"), tifffile.imread(folder / "mask2d.tif")
    cache = Path.home() / ".cache/activecontour"
    with tempfile.TemporaryDirectory() as tmp:
        fetched = subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "--quiet",
                                  "-d", tmp, "stardist"], capture_output=True)
        wheels = list(Path(tmp).glob("stardist-*.whl"))
        if fetched.returncode != 0 or not wheels:
            return None
        with zipfile.ZipFile(wheels[0]) as wheel:
            for name in STARDIST_FILES:
                wheel.extract(name, cache)
    folder = cache / "stardist/data/images"
    return tifffile.imread(folder / "img2d.tif"), tifffile.imread(folder / "mask2d.tif")


def otsu_mask(image):
    from skimage.filters import threshold_otsu

    smooth = scipy.ndimage.gaussian_filter(np.asarray(image, dtype=np.float64), 1.0)
    return smooth > threshold_otsu(smooth)


def otsu_components(image):
    return scipy.ndimage.label(otsu_mask(image))[0]


def otsu_watershed(image):
    from skimage.feature import peak_local_max
    from skimage.segmentation import watershed

    mask = otsu_mask(image)
    distance = scipy.ndimage.distance_transform_edt(mask)
    peaks = peak_local_max(distance, min_distance=5, labels=scipy.ndimage.label(mask)[0],
                           exclude_border=False)
    markers = np.zeros(mask.shape, dtype=np.int32)
    markers[tuple(peaks.T)] = np.arange(1, len(peaks) + 1)
    return watershed(-distance, markers, mask=mask)


def morphological_components(image):
    from skimage.segmentation import morphological_chan_vese

    values = np.asarray(image, dtype=np.float64)
    values = (values - values.min()) / max(np.ptp(values), 1e-12)
    mask = morphological_chan_vese(values, 150, init_level_set="checkerboard", smoothing=1) > 0
    border = np.concatenate([mask[0], mask[-1], mask[:, 0], mask[:, -1]])
    if border.mean() > 0.5:
        mask = ~mask
    return scipy.ndimage.label(mask)[0]


METHODS = {
    "polygon": lambda image: ac.segment(image).labels,
    "levelset": lambda image: ac.segment(image, backend="levelset").labels,
    "polygon cc": lambda image: ac.segment(image, separate=False).labels,
    "otsu cc": otsu_components,
    "otsu ws": otsu_watershed,
    "morph cv": morphological_components,
}


def scenes():
    clumps = [synthetic.touching_clumps(seed=seed) for seed in range(4)]
    yield "clumps x4", clumps
    dsb = stardist_images()
    if dsb is not None:
        yield "DSB 2018", [dsb]
    else:
        print("(DSB 2018 image not found and stardist could not be downloaded: skipped)")
    from skimage.data import coins

    yield "coins", [(coins(), None)]


def render(labels, truth, image, path):
    """The image, the truth and the labels side by side, one random colour per id."""
    import cv2
    from skimage.segmentation import find_boundaries

    def colour(label_image):
        rng = np.random.default_rng(1)
        table = rng.uniform(60, 255, (int(label_image.max()) + 1, 3)).astype(np.uint8)
        table[0] = 0
        out = table[label_image]
        out[find_boundaries(label_image)] = 255
        return out

    gray = np.asarray(image, dtype=np.float64)
    gray = np.round(255 * (gray - gray.min()) / max(np.ptp(gray), 1e-12)).astype(np.uint8)
    panels = [np.dstack([gray] * 3)] + ([colour(truth)] if truth is not None else []) + [colour(labels)]
    cv2.imwrite(str(path), np.concatenate(panels, axis=1)[:, :, ::-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--render", type=Path, help="write colour label images into this folder")
    args = parser.parse_args(argv)
    if args.render:
        args.render.mkdir(parents=True, exist_ok=True)
    warm = synthetic.touching_clumps(size=(64, 64), n_clumps=1, seed=9)[0]
    for method in METHODS.values():
        method(warm)
    header = (f"{'scene':10s} {'method':11s} | {'F1':>5s} | {'accuracy':>8s} | {'objects':>9s} | "
              f"{'time s':>6s}")
    print(header)
    print("-" * len(header))
    for scene, images in scenes():
        for name, method in METHODS.items():
            counts, found, true, elapsed = np.zeros(3, int), 0, 0, 0.0
            for k, (image, truth) in enumerate(images):
                started = time.perf_counter()
                labels = method(image)
                elapsed += time.perf_counter() - started
                found += len(np.unique(labels)) - 1
                if truth is not None:
                    score = match_instances(labels, truth)
                    counts += [score["tp"], score["fp"], score["fn"]]
                    true += score["n_true"]
                if args.render and k == 0:
                    slug = f"{scene.split()[0].lower()}_{name.replace(' ', '_')}.png"
                    render(labels, truth, image, args.render / slug)
            tp, fp, fn = counts
            f1 = f"{2 * tp / max(2 * tp + fp + fn, 1):5.3f}" if true else "    -"
            accuracy = f"{tp / max(tp + fp + fn, 1):8.3f}" if true else "       -"
            print(f"{scene:10s} {name:11s} | {f1} | {accuracy} | {found:4d}/{true if true else '-':>4} | "
                  f"{elapsed:6.2f}", flush=True)


if __name__ == "__main__":
    main()
