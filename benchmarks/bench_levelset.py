"""Benchmark the level-set backend against scikit-image's Chan-Vese implementations.

On synthetic 512 x 512 images with exact ground truth (:mod:`activecontour.synthetic`): a noisy
disk, a star, two disks inside one initial circle (the contour must split) and an annulus whose
hole lies inside the initial circle (a hole must open).  Every method starts from the same init,
``--start circle`` (the default circle of radius 3/8 of the side), ``--start checkerboard``
(squares of 16 x 16 pixels, the start chan_vese is designed for) or ``--start both``, and is
scored the same way:

* wall time of the call (best of ``--repeat``; every method is run once on a small image first,
  so that imports and first-call set-up are not timed);
* Dice of the mask against the ground truth;
* the final energy (6.38) by the common evaluator :func:`activecontour.chan_vese_energy`
  (exact on the bilinear image), on each method's contours: the zero level set of phi by
  marching squares for the level-set methods, the pixel boundary of the mask
  (:func:`activecontour.geometry.raster.mask_to_curves`) for the morphological one.

The methods:

``levelset``
    ``activecontour.segment(image, init, backend="levelset", mu=MU)``.
``chan_vese``
    ``skimage.segmentation.chan_vese`` with its defaults (dt=0.5, tol=1e-3, max_num_iter=500)
    except: the same start, as phi0 = signed distance / radius (the scaling of its own "disk"
    start) or the checkerboard scaled to [-1, 1] (as its own), and mu = MU / range^2 with
    range = max - min of the image, because chan_vese rescales the image to [0, 1], which
    multiplies its fitting terms by 1 / range^2 (its curvature term is in 1/pixels, as ours).
    From the circle its tol=1e-3 stops it after one iteration (the rms change of phi is below
    1e-3 at once), so there tol=1e-5 is passed and it runs up to max_num_iter.
``morph_cv``
    ``skimage.segmentation.morphological_chan_vese`` from the same mask, ``smoothing=3`` (the
    most robust to the noise of its 1, 2, 3) and ``num_iter=250`` (it has no convergence test;
    250 one-pixel moves cross these images), lambda1 = lambda2 = 1.
``polygon`` (with ``--polygon``)
    ``activecontour.segment(..., backend="polygon")`` for reference.

From the checkerboard the functional does not say which phase is the object: as the level-set
backend does, every method's result is given the phase whose inside covers less of the image
border before scoring.

The ratios printed per case are the wall time of ``chan_vese`` (and ``morph_cv``) over that of
``levelset``, the Dice differences and the energy ratios (< 1: the level set is lower).

``--defaults`` runs every method with its own defaults and its own start instead: ours
``segment(image, backend=...)`` (init=None, mu="auto"), ``chan_vese(image)``,
``morphological_chan_vese(image, 250)`` (num_iter has no default); the energies are still scored
with mu = MU.

Run ``python benchmarks/bench_levelset.py`` (about a minute per case, mostly ``chan_vese``), or
``--quick`` for 256 x 256 images.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

import activecontour as ac
from activecontour import synthetic as sy
from activecontour.backends.levelset import checkerboard_level_set, curves_level_set, level_set_contours
from activecontour.geometry.raster import mask_to_curves, rasterize
from activecontour.initial import default_init

MU = 0.2
INSIDE, OUTSIDE = 0.75, 0.25
NOISE, BLUR = 0.15, 1.0
MORPH_ITER = 250  # no convergence test in morphological_chan_vese: enough to cross the images
PERIOD = 16  # checkerboard squares, pixels


def make_cases(size):
    """name -> (image, truth), the shapes scaled with the image size."""
    s = size / 512.0
    shapes = {
        "noisy disk": sy.disk((250 * s, 262 * s), 110 * s),
        "star": sy.star((256 * s, 256 * s), 130 * s),
        "two disks": sy.union(sy.disk((256 * s, 150 * s), 80 * s), sy.disk((256 * s, 370 * s), 70 * s)),
        "annulus": sy.annulus((256 * s, 256 * s), 90 * s, 220 * s),
    }
    cases = {}
    for seed, (name, shape) in enumerate(shapes.items()):
        image, truth = sy.render(shape, (size, size), inside=INSIDE, outside=OUTSIDE)
        cases[name] = (sy.add_noise(image, NOISE, seed, blur=BLUR), truth)
    return cases


def run_levelset(image, start):
    init = "checkerboard" if start == "checkerboard" else start
    result = ac.segment(image, init, backend="levelset", mu=MU, options={"checkerboard_period": PERIOD})
    return result.mask, result.contours, result.n_iter


def run_polygon(image, start):
    init = "grid" if start == "checkerboard" else start  # the polygon's start all over the image
    result = ac.segment(image, init, backend="polygon", mu=MU)
    return result.mask, result.contours, result.n_iter


def run_chan_vese(image, start):
    from skimage.segmentation import chan_vese

    if start == "checkerboard":
        phi0, tol = checkerboard_level_set(image.shape, PERIOD) / (PERIOD / np.pi), 1e-3
    else:
        phi0, tol = curves_level_set(start, image.shape) / circle_radius(start), 1e-5
    scale = float(image.max() - image.min())
    _, phi, energies = chan_vese(image, mu=MU / scale**2, init_level_set=phi0, tol=tol,
                                 extended_output=True)
    phi = _object_phase(phi)
    return phi > 0, level_set_contours(phi), len(energies)


def run_morphological(image, start):
    from skimage.segmentation import morphological_chan_vese

    if start == "checkerboard":
        mask0 = checkerboard_level_set(image.shape, PERIOD) > 0
    else:
        mask0 = rasterize(start, image.shape)
    mask = morphological_chan_vese(image, MORPH_ITER, init_level_set=mask0, smoothing=3).astype(bool)
    mask = _object_phase(np.where(mask, 1.0, -1.0)) > 0
    return mask, mask_to_curves(mask), MORPH_ITER


def _object_phase(phi):
    """phi or -phi: the one whose inside covers less than half of the image border."""
    border = np.concatenate([phi[0], phi[-1], phi[1:-1, 0], phi[1:-1, -1]])
    return -phi if np.count_nonzero(border > 0) > border.size / 2 else phi


def circle_radius(curves):
    points = np.concatenate(curves)
    return float(np.max(np.hypot(*(points - points.mean(axis=0)).T)))


def run_levelset_defaults(image, start):
    result = ac.segment(image, backend="levelset")
    return result.mask, result.contours, result.n_iter


def run_polygon_defaults(image, start):
    result = ac.segment(image, backend="polygon")
    return result.mask, result.contours, result.n_iter


def run_chan_vese_defaults(image, start):
    from skimage.segmentation import chan_vese

    _, phi, energies = chan_vese(image, extended_output=True)
    phi = _object_phase(phi)
    return phi > 0, level_set_contours(phi), len(energies)


def run_morphological_defaults(image, start):
    from skimage.segmentation import morphological_chan_vese

    # num_iter has no default; the rest (checkerboard start, smoothing=1) are its own
    mask = morphological_chan_vese(image, MORPH_ITER).astype(bool)
    mask = _object_phase(np.where(mask, 1.0, -1.0)) > 0
    return mask, mask_to_curves(mask), MORPH_ITER


METHODS = {
    "levelset": run_levelset,
    "chan_vese": run_chan_vese,
    "morph_cv": run_morphological,
    "polygon": run_polygon,
}

#: ``--defaults``: every method with its own defaults and start (mu, init, tolerances)
DEFAULT_METHODS = {
    "levelset": run_levelset_defaults,
    "chan_vese": run_chan_vese_defaults,
    "morph_cv": run_morphological_defaults,
    "polygon": run_polygon_defaults,
}


def measure(method, image, truth, start, repeat):
    best = np.inf
    for _ in range(repeat):
        clock = time.perf_counter()
        mask, contours, n_iter = METHODS[method](image, start)
        best = min(best, time.perf_counter() - clock)
    energy = ac.chan_vese_energy(image, contours, mu=MU) if contours else np.inf
    return {"time": best, "iter": n_iter, "dice": sy.dice(mask, truth), "energy": energy}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="256 x 256 images")
    parser.add_argument("--size", type=int, default=None, help="image side (default 512)")
    parser.add_argument("--repeat", type=int, default=1, help="timing: best of this many runs")
    parser.add_argument("--polygon", action="store_true", help="also run the polygon backend")
    parser.add_argument("--case", action="append", help="run only this case (repeatable)")
    parser.add_argument("--start", choices=("circle", "checkerboard", "both"), default="circle",
                        help="the common start (default: circle)")
    parser.add_argument("--defaults", action="store_true",
                        help="every method with its own defaults and start (no common init, "
                             "our mu='auto'); energies still by mu=MU")
    args = parser.parse_args(argv)
    if args.defaults:
        METHODS.update(DEFAULT_METHODS)
        args.start = "circle"  # ignored by the default runners
    size = args.size or (256 if args.quick else 512)
    methods = ["levelset", "chan_vese", "morph_cv"] + (["polygon"] if args.polygon else [])
    cases = make_cases(size)
    if args.case:
        unknown = sorted(set(args.case) - set(cases))
        if unknown:
            parser.error(f"unknown case(s) {unknown}; choose from {sorted(cases)}")
        cases = {name: cases[name] for name in args.case}
    circle = default_init((size, size))
    starts = {"circle": circle, "checkerboard": "checkerboard"}
    if args.start != "both":
        starts = {args.start: starts[args.start]}
    print(f"{size} x {size}, mu={MU}, contrast {INSIDE}/{OUTSIDE}, noise sigma {NOISE}, blur {BLUR}; "
          f"circle radius {circle_radius(circle):.0f}, checkerboard squares {PERIOD} px")
    header = (f"{'start':<12} {'case':<11} {'method':<10} {'time [s]':>9} {'iter':>5} {'Dice':>8} "
              f"{'energy':>11}")
    print(header)
    print("-" * len(header))
    # warm up: imports and first-call set-up are not part of any method's time
    warm_image, _ = sy.render(sy.disk((16.0, 16.0), 8.0), (32, 32))
    for method in methods:
        for start in (default_init((32, 32)), "checkerboard"):
            METHODS[method](warm_image, start)
    summary = []
    for start_name, start in starts.items():
        for name, (image, truth) in cases.items():
            rows = {}
            for method in methods:
                rows[method] = row = measure(method, image, truth, start, args.repeat)
                print(f"{start_name:<12} {name:<11} {method:<10} {row['time']:9.2f} {row['iter']:5d} "
                      f"{row['dice']:8.4f} {row['energy']:11.2f}", flush=True)
            summary.append((start_name, name, rows))
    print()
    print("ratios (levelset vs the others): time_other / time_levelset, Dice_levelset - Dice_other, "
          "E_levelset / E_other")
    for start_name, name, rows in summary:
        ours = rows["levelset"]
        parts = []
        for other in methods[1:]:
            theirs = rows[other]
            parts.append(f"{other}: x{theirs['time'] / ours['time']:.1f}, "
                         f"dDice {ours['dice'] - theirs['dice']:+.4f}, "
                         f"E {ours['energy'] / theirs['energy']:.4f}")
        print(f"{start_name:<12} {name:<11} " + " | ".join(parts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
