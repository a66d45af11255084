"""Objects: touching objects split, on families of scenes, next to the classic pipeline, in one run.

Run ``python benchmarks/bench_objects.py [--seeds 20] [--render DIR] [--cost] [--scale N]``.

Families (:data:`activecontour.synthetic.FAMILIES`, exact anti-aliased ground truth): touching
disks; touching ellipses (aspect 1-3, any angle, clumps of 2-8 overlapping by up to a third of
the minor axis); singles that must never be split (horse silhouette, ring, 3 px stroke, bent rod,
star, ellipse of aspect 3).  Radii 6-40 px, SNR 2-5, blur 0-1.5 px, drawn per seed.

Methods, per scene:

* ``ours``: :func:`activecontour.segment` with its defaults, ``res.labels`` (``separate=True``);
* ``cc``: the same with ``separate=False`` (connected pieces);
* ``pipeline``: the scikit-image gallery's distance-transform watershed (``plot_watershed``) on
  Otsu's threshold of the image smoothed by a Gaussian of 1 px, markers ``peak_local_max`` with
  ``min_distance=5`` (the CellProfiler-style tuning; it is the stronger of the two);
* ``gallery``: the same with the gallery's literal markers (``footprint=np.ones((3, 3))``).

Columns: F1 at IoU 0.5 (:func:`activecontour.objects.metrics.match_instances`) on the worst seed
and averaged over the seeds; for the singles, the number of extra objects the split made (objects
of ``ours`` inside one object of ``cc``); the cost ratio ``separate=True / separate=False`` (CPU
seconds of the whole :func:`activecontour.segment`, the least of two runs), largest and median.

``--scale N``: the first N seeds of each touching family rendered at 0.5x and 2x the pixel size;
F1 between the two label images, the coarse one brought to the fine grid (each pixel repeated 4x4).
``--cost``: the cost ratio on the 25 sample images of ``shared/tools/contact_sheet.py`` and on a
4096 x 4096 image with one disk.  The DSB 2018 nuclei image (``sample_images/nuclei.png``; its
truth is ``mask2d.tif`` of the ``stardist`` wheel, looked for in ``$STARDIST_DATA``, the
repository's ``../_data/stardist/data/images``, or fetched once with ``pip download --no-deps
stardist`` into ``~/.cache/activecontour``) and ``skimage.data.coins`` (object counts only) close
the table.  ``--render DIR`` writes each label image in colour (one random colour per id) next to
the image and the truth.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import warnings
import zipfile
from pathlib import Path

import numpy as np
import scipy.ndimage

import activecontour as ac
from activecontour import synthetic
from activecontour.objects.metrics import match_instances

STARDIST_FILES = ("stardist/data/images/img2d.tif", "stardist/data/images/mask2d.tif")
SAMPLES = ["astronaut", "binary_blobs", "brick", "camera", "cat", "cell", "checkerboard", "chelsea",
           "clock", "coffee", "coins", "colorwheel", "grass", "gravel", "horse", "hubble_deep_field",
           "immunohistochemistry", "logo", "microaneurysms", "moon", "page", "retina", "rocket",
           "shepp_logan_phantom", "text"]


def stardist_truth():
    """The DSB 2018 sample's true labels (``mask2d.tif`` of the stardist wheel), or None."""
    import tifffile

    here = Path(__file__).resolve().parents[1]
    candidates = [Path(os.environ["STARDIST_DATA"])] if "STARDIST_DATA" in os.environ else []
    candidates += [here.parent / "_data/stardist/data/images", here / "_data/stardist/data/images",
                   Path.home() / ".cache/activecontour/stardist/data/images"]
    for folder in candidates:
        if (folder / "mask2d.tif").exists():
            return tifffile.imread(folder / "mask2d.tif")
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
    return tifffile.imread(cache / "stardist/data/images/mask2d.tif")


def pipeline(image, *, gallery=False):
    """Otsu on the image smoothed by 1 px, then the distance-transform watershed of scikit-image's
    gallery (``plot_watershed``): markers at the peaks of the distance, ``min_distance=5`` or,
    with ``gallery``, the gallery's ``footprint=np.ones((3, 3))``."""
    from skimage.feature import peak_local_max
    from skimage.filters import threshold_otsu
    from skimage.segmentation import watershed

    smooth = scipy.ndimage.gaussian_filter(np.asarray(image, dtype=np.float64), 1.0)
    mask = smooth > threshold_otsu(smooth)
    distance = scipy.ndimage.distance_transform_edt(mask)
    markers = dict(footprint=np.ones((3, 3))) if gallery else dict(min_distance=5)
    peaks = peak_local_max(distance, labels=scipy.ndimage.label(mask)[0], exclude_border=False, **markers)
    seeds = np.zeros(mask.shape, dtype=bool)
    seeds[tuple(peaks.T)] = True
    return watershed(-distance, scipy.ndimage.label(seeds)[0], mask=mask)


def timed(image, repeat=2, **kwargs):
    """The result of ``segment(image, **kwargs)`` and its least CPU time over ``repeat`` runs."""
    best = np.inf
    for _ in range(repeat):
        start = time.process_time()
        result = ac.segment(image, **kwargs)
        best = min(best, time.process_time() - start)
    return result, best


def extra_objects(labels, pieces):
    """How many more objects ``labels`` has than ``pieces`` inside the pieces: the split's cuts."""
    owner = np.zeros(int(labels.max()) + 1, dtype=np.int64)
    inside = labels > 0
    owner[labels[inside]] = pieces[inside]
    return int(np.count_nonzero(owner[1:])) - len(np.unique(owner[owner > 0]))


def f1(labels, truth):
    return match_instances(labels, truth)["f1"]


def colour(label_image):
    """One random colour per id (0 black), boundaries white."""
    from skimage.segmentation import find_boundaries

    table = np.random.default_rng(1).uniform(60, 255, (int(label_image.max()) + 1, 3)).astype(np.uint8)
    table[0] = 0
    out = table[label_image]
    out[find_boundaries(label_image)] = 255
    return out


def render(path, image, *labels):
    import imageio.v3 as iio

    gray = np.asarray(image, dtype=np.float64)
    gray = np.round(255 * (gray - gray.min()) / max(np.ptp(gray), 1e-12)).astype(np.uint8)
    iio.imwrite(path, np.concatenate([np.dstack([gray] * 3)] + [colour(lab) for lab in labels], axis=1))


def families(seeds, folder):
    print(f"{'family':9s} | {'ours worst':>10s} {'mean':>6s} | {'pipeline worst':>14s} {'mean':>6s} | "
          f"{'gallery mean':>12s} | {'splits':>6s} | {'cost max':>8s} {'median':>6s}")
    for name, scene in synthetic.FAMILIES.items():
        ours, piped, literal, splits, ratios = [], [], [], 0, []
        for seed in range(seeds):
            image, truth = scene(seed)
            res, seconds = timed(image)
            pieces, alone = timed(image, separate=False)
            ratios.append(seconds / alone)
            ours.append(f1(res.labels, truth))
            piped.append(f1(pipeline(image), truth))
            literal.append(f1(pipeline(image, gallery=True), truth))
            splits += extra_objects(res.labels, pieces.labels)
            if folder and seed == 0:
                render(folder / f"{name}_{seed}.png", image, truth, res.labels)
        count = f"{splits:6d}" if name == "singles" else "     -"
        print(f"{name:9s} | {min(ours):10.3f} {np.mean(ours):6.3f} | {min(piped):14.3f} "
              f"{np.mean(piped):6.3f} | {np.mean(literal):12.3f} | {count} | {max(ratios):8.2f} "
              f"{np.median(ratios):6.2f}", flush=True)


def scale_consistency(seeds):
    print(f"\nscale consistency: F1 between the label images at 0.5x and 2x the pixel size ({seeds} seeds);"
          "\n'pieces': the same for separate=False (what the segmentation alone keeps)")
    for name in ("disks", "ellipses"):
        scores = {True: [], False: []}
        for seed in range(seeds):
            fine, coarse = (synthetic.FAMILIES[name](seed, pixel=pixel)[0] for pixel in (0.5, 2.0))
            for separate in (True, False):
                small = ac.segment(coarse, separate=separate).labels
                large = ac.segment(fine, separate=separate).labels
                small = np.repeat(np.repeat(small, 4, axis=0), 4, axis=1)
                m, n = min(large.shape[0], small.shape[0]), min(large.shape[1], small.shape[1])
                scores[separate].append(f1(large[:m, :n], small[:m, :n]))
        print(f"{name:9s} | worst {min(scores[True]):.3f} mean {np.mean(scores[True]):.3f} | pieces: "
              f"worst {min(scores[False]):.3f} mean {np.mean(scores[False]):.3f}", flush=True)


def dsb(repeat=2):
    """The DSB 2018 nuclei image: ``(image, result, truth or None, F1 or None, cost ratio)`` (the
    truth is StarDist's mask, when it is installed)."""
    image = ac.load_image(Path(__file__).resolve().parents[1] / "sample_images/nuclei.png")
    truth = stardist_truth()
    res, seconds = timed(image, repeat)
    alone = timed(image, repeat, separate=False)[1]
    return image, res, truth, None if truth is None else f1(res.labels, truth), seconds / alone


def real_images(folder):
    print()
    image, res, truth, score, ratio = dsb()
    scored = "(no truth found) " if truth is None else f"F1 {score:.3f}, "
    print(f"DSB 2018 nuclei: {scored}{res.labels.max()} objects / "
          f"{'-' if truth is None else len(np.unique(truth)) - 1}; cost ratio {ratio:.2f}")
    from skimage.data import coins

    coin = ac.segment(coins())
    print(f"coins: {coin.labels.max()} objects (24 coins), separate=False: "
          f"{ac.segment(coins(), separate=False).labels.max()}")
    if folder:
        render(folder / "dsb.png", image, *(() if truth is None else (truth,)), res.labels)
        render(folder / "coins.png", coins(), coin.labels)


def costs():
    import skimage.data as data

    print("\ncost ratio separate=True / separate=False (CPU s, least of 2 runs)")
    for name in SAMPLES:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            image = data.binary_blobs(rng=1) if name == "binary_blobs" else getattr(data, name)()
        res, seconds = timed(image)
        alone = timed(image, separate=False)[1]
        print(f"{name:22s} {seconds:7.2f} s / {alone:7.2f} s = {seconds / alone:5.2f}  "
              f"({res.labels.max()} objects)", flush=True)
    disk = synthetic.disk_image(4096, (2048.3, 2047.6), 1500.0)[0]
    disk = synthetic.add_noise(disk, 0.2, seed=0)
    seconds = timed(disk)[1]
    alone = timed(disk, separate=False)[1]
    print(f"{'one disk, 4096^2':22s} {seconds:7.2f} s / {alone:7.2f} s = {seconds / alone:5.2f}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds per family")
    parser.add_argument("--scale", type=int, default=0, help="seeds of the scale-consistency check")
    parser.add_argument("--cost", action="store_true", help="cost ratio on the sample images and 4096^2")
    parser.add_argument("--render", type=Path, help="write colour label images into this folder")
    args = parser.parse_args(argv)
    if args.render:
        args.render.mkdir(parents=True, exist_ok=True)
    ac.segment(synthetic.touching_disks(0)[0])  # imports and compiled kernels warm
    families(args.seeds, args.render)
    if args.scale:
        scale_consistency(args.scale)
    real_images(args.render)
    if args.cost:
        costs()


if __name__ == "__main__":
    main()
