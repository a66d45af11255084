"""The models on scenes with ground truth: N regions, smooth light, both backends, next to the peers.

Scenes: three nested classes at SNR 3 (384^2); scikit-image's Shepp-Logan phantom (400^2, six
levels, two of them under 250 px) with noise 0.02; three colour regions of one gray level; 20
faint blobs (contrast 0.15) under a gradient and a vignette of amplitude 0.5 (384^2); real nuclei of
different brightness (DSB 2018 from the stardist wheel, if ``--nuclei DIR`` holds img2d.tif and
mask2d.tif).  Every method runs on every scene it applies to, in one run: ours with
``n_regions=K`` on both backends, ``fit="constant"`` and ``"smooth"`` (for two regions also with
``noise="poisson"``); scikit-image's ``threshold_multiotsu`` (on the image smoothed by a Gaussian
of 1 px, K classes), ``threshold_local`` (block 35), ``chan_vese`` and ``morphological_chan_vese``
(35 iterations) with their defaults.  Dice: for two regions the object's, strict (the inside must be
the objects; thresholds take the bright side); for K regions the mean per-class Dice after the best
matching of found to true classes (scipy's linear_sum_assignment), with the per-class values.
Ours run with ``separate=False``: the times are the segmentation's, not the objects' split.

Then ``n_regions="auto"`` (:func:`activecontour.models.modes.choose_regions`, by
:attr:`activecontour.problem.Problem.n_regions`) on the scenes, on
pure noise, two flat regions at SNR 3, a ramp, and scikit-image's coins, camera, page, text and
clock: the K chosen, the time of the choice, of ``segment(n_regions="auto")`` and of a two-region
level-set run (``--no-auto`` skips it).

Then ``fit="smooth"`` against ``"constant"`` on every synthetic case of bench_robust.py (the quick
set), both backends: Dice and time ratio.  ``--sheets DIR`` writes contact sheets of skimage's
coins, clock, page and text with the models.

usage: PYTHONPATH=. python benchmarks/bench_models.py [--nuclei DIR] [--no-auto] [--no-robust]
       [--no-scenes] [--sheets DIR] [--repeat N] [--only WORD ...]
       PYTHONPATH=. python benchmarks/bench_models.py --backends [--repeat N] [--only WORD ...]
                                                                  # N regions, both backends
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np

import activecontour as ac

sys.path.insert(0, os.path.dirname(__file__))


def nested_scene(size=384, snr=3.0, seed=0):
    rows, cols = np.mgrid[:size, :size]
    radius = np.hypot(rows - size / 2, cols - size / 2)
    truth = (radius < 0.39 * size).astype(int) + (radius < 0.21 * size)
    return truth / 2.0 + np.random.default_rng(seed).normal(0, 0.5 / snr, truth.shape), truth


def phantom_scene(noise=0.02, seed=1):
    import skimage.data

    phantom = skimage.data.shepp_logan_phantom()
    truth = np.argmin(np.abs(phantom[..., None] - np.array([0.0, 0.098, 0.2, 0.298, 0.4, 1.0])), axis=-1)
    return phantom + np.random.default_rng(seed).normal(0, noise, phantom.shape), truth


def colour_scene(seed=2):
    rgb = np.array([[0.2, 0.5, 0.9], [0.6, 0.45, 0.3], [0.35, 0.5, 0.2]])
    gray = rgb @ np.array([0.2125, 0.7154, 0.0721])
    rgb[1:] *= (gray[0] / gray[1:])[:, None]
    truth = np.zeros((240, 320), dtype=int)
    truth[40:200, 30:150] = 1
    rows, cols = np.mgrid[:240, :320]
    truth[np.hypot(rows - 120, cols - 235) < 70] = 2
    return rgb[truth] + np.random.default_rng(seed).normal(0, 0.08, truth.shape + (3,)), truth


def blobs_scene(size=384, n=20, contrast=0.15, amplitude=0.5, noise=0.01, seed=3):
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[:size, :size].astype(float)
    truth = np.zeros((size, size), dtype=bool)
    for _ in range(n):
        r, c, radius = rng.uniform(20, size - 20, 2).tolist() + [rng.uniform(6, 14)]
        truth |= (rows - r) ** 2 + (cols - c) ** 2 < radius**2
    vignette = 1 - amplitude * ((rows - size / 2) ** 2 + (cols - size / 2) ** 2) / (size**2 / 2)
    gradient = 1 - amplitude / 2 + amplitude * cols / size
    image = 0.5 * (1 + contrast * truth) * vignette * gradient + rng.normal(0, noise, truth.shape)
    return image, truth.astype(int)


def nuclei_scene(folder):
    import tifffile

    image = tifffile.imread(os.path.join(folder, "img2d.tif"))
    truth = (tifffile.imread(os.path.join(folder, "mask2d.tif")) > 0).astype(int)
    return image, truth


def _gray(image):
    image = np.asarray(image, dtype=np.float64)
    if image.ndim == 3:
        image = image @ np.array([0.2125, 0.7154, 0.0721])
    span = image.max() - image.min()
    return (image - image.min()) / span


def class_dice(found, truth, n_classes):
    """Per-class Dice after the best one-to-one matching of found to true classes."""
    from scipy.optimize import linear_sum_assignment

    overlap = np.zeros((n_classes, n_classes))
    np.add.at(overlap, (found.ravel(), truth.ravel()), 1)
    sizes_found, sizes_true = overlap.sum(axis=1), overlap.sum(axis=0)
    dice = 2 * overlap / np.maximum(sizes_found[:, None] + sizes_true[None, :], 1)
    rows, cols = linear_sum_assignment(-dice)
    per_class = np.zeros(n_classes)
    per_class[cols] = dice[rows, cols]
    return per_class


def object_dice(mask, truth):
    truth = truth > 0
    return 2 * np.sum(mask & truth) / max(mask.sum() + truth.sum(), 1)


def methods(n_classes, colour):
    """(name, function image -> labels or mask) of every method that applies."""
    import cv2
    import skimage.filters
    import skimage.segmentation as seg

    color = {"color": "vector"} if colour else {}
    out = []
    noises = ["gaussian"] if n_classes > 2 else ["gaussian", "poisson"]
    for backend in ("polygon", "levelset"):
        for noise in noises:
            for fit in ("constant", "smooth"):
                def ours(image, backend=backend, fit=fit, noise=noise):
                    res = ac.segment(image, backend=backend, fit=fit, noise=noise, n_regions=n_classes,
                                     separate=False, **color)
                    return res.classes if n_classes > 2 else res.mask
                out.append((f"ours {backend} {fit}" + (" poisson" if noise == "poisson" else ""), ours))

    def multiotsu(image):
        smooth = cv2.GaussianBlur(_gray(image).astype(np.float32), (0, 0), 1.0)
        labels = np.digitize(smooth, skimage.filters.threshold_multiotsu(smooth, classes=n_classes))
        return labels if n_classes > 2 else labels > 0
    out.append(("multiotsu (smoothed)", multiotsu))
    if n_classes == 2:
        out.append(("threshold_local 35",
                    lambda image: _gray(image) > skimage.filters.threshold_local(_gray(image), 35)))
        out.append(("chan_vese", lambda image: seg.chan_vese(_gray(image)) > 0))
        out.append(("morph_cv 35", lambda image: seg.morphological_chan_vese(_gray(image), 35) > 0))
    return out


def scenes_table(nuclei):
    scenes = [("nested 3, SNR 3, 384^2", nested_scene, 3, False),
              ("Shepp-Logan 6 levels, noise 0.02", phantom_scene, 6, False),
              ("colour 3 regions, one gray", colour_scene, 3, True),
              ("20 faint blobs, light 0.5", blobs_scene, 2, False)]
    if nuclei and os.path.exists(os.path.join(nuclei, "img2d.tif")):
        scenes.append(("nuclei DSB2018 512^2", lambda: nuclei_scene(nuclei), 2, False))
    print("scene | method | Dice | per-class Dice | s")
    for name, make, n_classes, colour in scenes:
        image, truth = make()
        for label, run in methods(n_classes, colour):
            t = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                found = run(image)
            elapsed = time.perf_counter() - t
            if n_classes > 2:
                per_class = class_dice(np.asarray(found, dtype=np.intp), truth, n_classes)
                print(f"{name} | {label} | {per_class.mean():.4f} | {np.round(per_class, 3).tolist()} | "
                      f"{elapsed:.2f}", flush=True)
            else:
                print(f"{name} | {label} | {object_dice(np.asarray(found, bool), truth):.4f} | - | "
                      f"{elapsed:.2f}", flush=True)
        if name.startswith("nuclei"):
            t = time.perf_counter()
            res = ac.segment(image, backend="levelset", n_regions=3, fit="smooth", separate=False)
            print(f"{name} | ours levelset smooth, 3 regions, inside = not background | "
                  f"{object_dice(res.mask, truth):.4f} | - | {time.perf_counter() - t:.2f}", flush=True)


def auto_table():
    import skimage.data

    from activecontour.problem import prepare
    from activecontour.settings import Settings

    rng = np.random.default_rng(4)
    halves = np.zeros((256, 256), dtype=int)
    halves[:, 128:] = 1
    scenes = [("nested 3, SNR 3, 384^2", *nested_scene(), "gray"),
              ("Shepp-Logan 6 levels, noise 0.02", *phantom_scene(), "gray"),
              ("colour 3 regions, one gray (vector)", *colour_scene(), "vector"),
              ("20 faint blobs, light 0.5", *blobs_scene(), "gray"),
              ("pure noise 256^2", rng.normal(0.5, 0.1, (256, 256)), None, "gray"),
              ("two flat halves, SNR 3", halves + rng.normal(0, 1 / 3, halves.shape), halves, "gray"),
              ("ramp 0..1, 256^2", np.tile(np.linspace(0, 1, 256), (256, 1)), None, "gray")]
    scenes += [(f"skimage {name}", getattr(skimage.data, name)(), None, "gray")
               for name in ("coins", "camera", "page", "text", "clock")]
    print("\nscene | true K | K chosen | choice ms | auto: levelset s, Dice | auto: polygon s, Dice | "
          "K=2 levelset s | choice / K=2 run")
    for name, image, truth, color in scenes:
        n_true = "-" if truth is None else int(truth.max()) + 1
        t = time.perf_counter()
        chosen = prepare(image, Settings(color=color, n_regions="auto")).n_regions
        choice = time.perf_counter() - t
        cells = []
        for backend in ("levelset", "polygon"):
            t = time.perf_counter()
            try:
                res = ac.segment(image, n_regions="auto", backend=backend, color=color, separate=False)
            except (RuntimeError, ValueError) as exc:  # a failing backend is a row of the table
                cells.append(f"{type(exc).__name__}: {exc}")
                continue
            elapsed = time.perf_counter() - t
            assert res.n_regions == chosen
            dice = (class_dice(res.classes, truth, chosen).mean()
                    if truth is not None and chosen == n_true else None)
            cells.append(f"{elapsed:.2f}, {'-' if dice is None else f'{dice:.4f}'}")
        t = time.perf_counter()
        ac.segment(image, n_regions=2, backend="levelset", color=color, separate=False)
        two = time.perf_counter() - t
        print(f"{name} | {n_true} | {chosen} | {1000 * choice:.1f} | {cells[0]} | {cells[1]} | "
              f"{two:.2f} | {choice / two:.3f}", flush=True)


def robust_comparison(repeat=1, only=None):
    """smooth vs constant on bench_robust's quick set; times the minimum of ``repeat`` runs of
    each, interleaved (the machine's load moves single runs by 2x)."""
    from bench_robust import synthetic_cases

    from activecontour import synthetic

    print(f"\ncase | backend | constant Dice | smooth Dice | difference | time smooth / constant "
          f"(min of {repeat})")
    for name, make in synthetic_cases(quick=True):
        if only and not any(word in name for word in only):
            continue
        image, truth = make()
        for backend in ("polygon", "levelset"):
            dice, seconds = {}, {"constant": [], "smooth": []}
            for _ in range(repeat):
                for fit in ("constant", "smooth"):
                    t = time.perf_counter()
                    res = ac.segment(image, backend=backend, fit=fit, separate=False)
                    seconds[fit].append(time.perf_counter() - t)
                    dice[fit] = synthetic.dice(res.mask, truth)
            ratio = min(seconds["smooth"]) / min(seconds["constant"])
            print(f"{name} | {backend} | {dice['constant']:.4f} | {dice['smooth']:.4f} | "
                  f"{dice['smooth'] - dice['constant']:+.4f} | {ratio:.2f}", flush=True)


def contact_sheets(folder):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import skimage.data

    os.makedirs(folder, exist_ok=True)
    runs = [("constant (polygon)", {}), ("smooth (polygon)", {"fit": "smooth"}),
            ("3 regions (polygon)", {"n_regions": 3}),
            ("3 regions, smooth (polygon)", {"n_regions": 3, "fit": "smooth"})]
    for name in ("coins", "clock", "page", "text"):
        image = getattr(skimage.data, name)()
        figure, axes = plt.subplots(1, len(runs) + 1, figsize=(4 * (len(runs) + 1), 4.4))
        axes[0].imshow(image, cmap="gray")
        axes[0].set_title(name)
        for axis, (title, kwargs) in zip(axes[1:], runs, strict=True):
            t = time.perf_counter()
            res = ac.segment(image, separate=False, **kwargs)
            elapsed = time.perf_counter() - t
            axis.imshow(image, cmap="gray")
            # each region's boundary in its own colour (two regions: the contours in red)
            regions = res.class_contours[1:] if res.class_contours is not None else [res.contours]
            for curves, colour in zip(regions, ("r", "c", "y", "m", "g"), strict=False):
                for contour in curves:
                    axis.plot(contour[:, 1], contour[:, 0], "-", color=colour, lw=0.8)
            axis.set_title(f"{title}\n{elapsed:.2f} s")
        for axis in axes:
            axis.set_axis_off()
        figure.tight_layout()
        path = os.path.join(folder, f"models_{name}.png")
        figure.savefig(path, dpi=80)
        plt.close(figure)
        print("wrote", path)


def backends_table(repeat=3, only=None):
    """N regions on both backends, side by side in one run: the energy by the common evaluator
    (:func:`activecontour.chan_vese_energy` of each one's sub-pixel partition), per-class Dice
    where the truth is known, the CPU time (the best of ``repeat``, both backends alternating), and
    the ratios polygon (the network) / level set (the label field)."""
    import skimage.data

    scenes = [("nested 3, SNR 3, 384^2", *nested_scene(), 3, "gray"),
              ("Shepp-Logan 6 levels, noise 0.02", *phantom_scene(), 6, "gray"),
              ("colour 3 regions, one gray", *colour_scene(), 3, "vector")]
    scenes += [(f"skimage {name}", getattr(skimage.data, name)(), None, 3, "gray")
               for name in ("coins", "page", "camera", "text")]
    print(f"\nscene | K | polygon: J, Dice, CPU s (best of {repeat}) | levelset: J, Dice, CPU s | "
          "time polygon / levelset | J polygon / levelset")
    for name, image, truth, n_regions, color in scenes:
        if only and not any(word in name for word in only):
            continue
        best, results = {"polygon": np.inf, "levelset": np.inf}, {}
        for _ in range(repeat):
            for backend in best:
                t = time.process_time()
                results[backend] = ac.segment(image, n_regions=n_regions, backend=backend, color=color,
                                              separate=False)
                best[backend] = min(best[backend], time.process_time() - t)
        cells, energies = [], []
        for backend, res in results.items():
            energy = ac.chan_vese_energy(image, regions=res.class_contours, mu=res.mu, color=color)
            dice = "-" if truth is None else f"{class_dice(res.classes, truth, n_regions).mean():.4f}"
            cells.append(f"{energy:.6f}, {dice}, {best[backend]:.2f}")
            energies.append(energy)
        print(f"{name} | {n_regions} | {cells[0]} | {cells[1]} | {best['polygon'] / best['levelset']:.2f} | "
              f"{energies[0] / energies[1]:.4f}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nuclei", default=os.environ.get("NUCLEI_DIR", ""),
                        help="folder with img2d.tif and mask2d.tif (the stardist wheel's data/images)")
    parser.add_argument("--no-auto", action="store_true", help="skip the n_regions='auto' table")
    parser.add_argument("--no-robust", action="store_true")
    parser.add_argument("--no-scenes", action="store_true", help="skip the scenes' table")
    parser.add_argument("--repeat", type=int, default=1,
                        help="time each fit on the bench_robust cases this many times (the minimum)")
    parser.add_argument("--only", nargs="*", help="bench_robust cases whose names contain these words")
    parser.add_argument("--sheets", help="write contact sheets of coins, clock, page, text here")
    parser.add_argument("--backends", action="store_true",
                        help="only the N-region table of both backends (energy, Dice, best of --repeat)")
    args = parser.parse_args()
    ac.segment(np.random.default_rng(0).random((64, 64)))  # load the compiled kernels
    if args.backends:
        backends_table(max(args.repeat, 1), args.only)
        return
    if not args.no_scenes:
        scenes_table(args.nuclei)
    if not args.no_auto:
        auto_table()
    if not args.no_robust:
        robust_comparison(args.repeat, args.only)
    if args.sheets:
        contact_sheets(args.sheets)


if __name__ == "__main__":
    main()
