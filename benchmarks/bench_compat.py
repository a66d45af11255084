"""``activecontour.compat.chan_vese`` next to ``skimage.segmentation.chan_vese``, side by side.

Both are called with the same arguments on 20 of scikit-image's sample images (colour ones
converted to gray with ``rgb2gray``), in one run, in two calls:

* ``gallery``: scikit-image's documented call (its Chan-Vese gallery example),
  ``chan_vese(image, mu=0.25, lambda1=1, lambda2=1, tol=1e-3, max_num_iter=200, dt=0.5,
  init_level_set="checkerboard", extended_output=True)``;
* ``default``: its defaults (``max_num_iter=500``), with ``extended_output=True``.

Every result is scored by the common evaluator of (6.38), :func:`activecontour.chan_vese_energy`,
with the mapped parameters (``mu``, ``lambda_in=lambda1``, ``lambda_out=lambda2``, intensities
rescaled by the image's range as both functions do):

* ``J sk``: scikit-image's result as curves, the lower of the energies of its sub-pixel zero level
  set of ``phi`` and of its mask's outline (the generous choice for scikit-image);
* ``J ours``: the last of the returned ``energies`` (by construction the common evaluator's
  value of the final contours, the invariant every result obeys).

``dJ`` is ``(J ours - J sk) / |J sk|`` (negative: ours lower).  Times are CPU seconds of this
process (``time.process_time``; the machine is shared), the minimum over ``--repeat`` runs of
each call, scikit-image's and ours alternating; ``ratio`` is ours over scikit-image's.  The
promise (README, issue 22): ``J ours <= J sk`` and ``ratio <= 0.5`` on every image and call.

usage: python benchmarks/bench_compat.py [--quick] [--repeat N] [--calls gallery,default]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import activecontour as ac
from activecontour.compat import chan_vese
from activecontour.geometry.raster import level_curves, mask_to_curves

#: scikit-image sample images that load without a download (``--quick``: the first four)
SAMPLES = ("camera", "coins", "astronaut", "moon", "page", "text", "horse", "coffee", "chelsea",
           "rocket", "immunohistochemistry", "brick", "grass", "gravel", "cell", "clock",
           "microaneurysms", "binary_blobs", "shepp_logan_phantom", "hubble_deep_field")
#: the two calls: scikit-image's gallery example and its defaults (both with extended_output)
CALLS = {
    "gallery": dict(mu=0.25, lambda1=1, lambda2=1, tol=1e-3, max_num_iter=200, dt=0.5,
                    init_level_set="checkerboard", extended_output=True),
    "default": dict(extended_output=True),
}


def load_gray(name):
    import skimage.color
    import skimage.data

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # binary_blobs draws new blobs on every call unless seeded
        image = skimage.data.binary_blobs(rng=0) if name == "binary_blobs" else getattr(skimage.data, name)()
    if image.ndim == 3:
        image = skimage.color.rgb2gray(image[..., :3])
    return image


def zero_level_set(phi):
    """The sub-pixel zero level set of phi (inside phi > 0) as closed curves in the image domain.

    The padding ring takes ``-|phi|`` of its neighbour, so a curve leaving the image runs along the
    domain's border (half-way between the pixel and its mirror), never outside it.
    """
    padded = np.pad(phi.astype(np.float64), 1, mode="edge")
    ring = np.ones(padded.shape, bool)
    ring[1:-1, 1:-1] = False
    padded[ring] = -np.abs(padded[ring])
    low, high = (-0.5, -0.5), (phi.shape[0] - 0.5, phi.shape[1] - 0.5)
    return [np.clip(c, low, high) for c in level_curves(padded, 0.0)]


def _timed(function, image, kwargs, repeat):
    """The output of the first call and the least CPU time over ``repeat`` calls."""
    best, out = np.inf, None
    for _ in range(repeat):
        cpu = time.process_time()
        result = function(image, **kwargs)
        best = min(best, time.process_time() - cpu)
        out = result if out is None else out
    return out, best


def compat_rows(names=SAMPLES, calls=tuple(CALLS), repeat=1):
    """One row per image and call: a dict with image, call, J sk, J ours, iterations, CPU times.

    Yields the rows as they are measured (a long run shows its progress)."""
    from skimage.segmentation import chan_vese as skimage_chan_vese

    for name in names:
        image = load_gray(name)
        for call in calls:
            kwargs = CALLS[call]
            mu = kwargs.get("mu", 0.25)
            (seg_sk, phi_sk, energies_sk), cpu_sk = _timed(skimage_chan_vese, image, kwargs, repeat)
            (_, _, energies), cpu_ours = _timed(chan_vese, image, kwargs, repeat)
            j_sk = min(ac.chan_vese_energy(image, curves, mu=mu)
                       for curves in (zero_level_set(phi_sk), mask_to_curves(seg_sk)))
            yield dict(image=name, size=f"{image.shape[0]}x{image.shape[1]}", call=call, j_sk=j_sk,
                       j_ours=float(energies[-1]), it_sk=len(energies_sk), it_ours=len(energies) - 1,
                       cpu_sk=cpu_sk, cpu_ours=cpu_ours)


def summary(rows):
    """The promise, counted: (images and calls, energy no higher, time <= 0.5x, worst dJ, worst ratio)."""
    gains = [(r["j_ours"] - r["j_sk"]) / abs(r["j_sk"]) for r in rows]
    ratios = [r["cpu_ours"] / r["cpu_sk"] for r in rows]
    return dict(n=len(rows), lower=sum(g <= 0 for g in gains), faster=sum(r <= 0.5 for r in ratios),
                worst_gain=max(gains), worst_ratio=max(ratios), median_ratio=float(np.median(ratios)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the first four images, one run each")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each call; the least CPU time counts")
    parser.add_argument("--calls", default="gallery,default", help="comma-separated: gallery, default")
    args = parser.parse_args()
    names = SAMPLES[:4] if args.quick else SAMPLES
    repeat = 1 if args.quick else args.repeat
    print(f"{'image':22s} {'size':>9s} {'call':8s} {'J sk':>10s} {'J ours':>10s} {'dJ':>8s} "
          f"{'it sk':>5s} {'it ours':>7s} {'cpu sk s':>8s} {'cpu ours':>8s} {'ratio':>6s}")
    rows = []
    for row in compat_rows(names, args.calls.split(","), repeat):
        rows.append(row)
        gain = (row["j_ours"] - row["j_sk"]) / abs(row["j_sk"])
        print(f"{row['image']:22s} {row['size']:>9s} {row['call']:8s} {row['j_sk']:10.2f} "
              f"{row['j_ours']:10.2f} "
              f"{100 * gain:+7.2f}% {row['it_sk']:5d} {row['it_ours']:7d} {row['cpu_sk']:8.3f} "
              f"{row['cpu_ours']:8.3f} {row['cpu_ours'] / row['cpu_sk']:6.3f}", flush=True)
    total = summary(rows)
    print(f"energy no higher than scikit-image's on {total['lower']}/{total['n']} (worst dJ "
          f"{100 * total['worst_gain']:+.2f}%); CPU time <= 0.5x on {total['faster']}/{total['n']} "
          f"(median {total['median_ratio']:.3f}x, worst {total['worst_ratio']:.3f}x)")


if __name__ == "__main__":
    main()
