"""``activecontour.compat.chan_vese`` next to ``skimage.segmentation.chan_vese``, side by side.

Both are called with the same arguments (scikit-image's defaults unless ``--mu``/``--init`` say
otherwise) on scikit-image's sample images (colour ones converted to gray with ``rgb2gray``), in one
run.  Every result is scored by the common evaluator of (6.38),
:func:`activecontour.chan_vese_energy`, with the mapped parameters (``mu``, ``lambda_in=lambda1``,
``lambda_out=lambda2``, intensities rescaled by the image's range as both functions do):

* ``E sk``: scikit-image's result as a curve, the lower of the energies of its sub-pixel zero level
  set of ``phi`` and of its mask's outline (the generous choice for scikit-image);
* ``E ours``: ours as a curve, the last of the returned ``energies`` (by construction the common
  evaluator's value of the final contours, the invariant every result obeys);
* ``mask sk`` / ``mask ours``: both returned masks outlined the same way (marching squares at 1/2,
  :func:`activecontour.geometry.raster.mask_to_curves`) and scored: what a user holding only the masks sees.

``dE`` is ``(E ours - E sk) / |E sk|`` (negative: ours lower); ``t ratio`` is the time of our call
over scikit-image's, ``cpu rat`` the same for this process's CPU time (what a loaded machine does
not distort).  Where scikit-image's ``tol`` stops it after ~50 iterations, long before its
contour settles, our converged call may take longer than that; ``t reach`` is the time at which the
same run (``activecontour.segment`` with the mapped arguments and a callback) first reaches
scikit-image's final energy, and ``reach ratio`` that time over scikit-image's.

usage: python benchmarks/bench_compat.py [--quick] [--mu MU] [--init checkerboard|disk|small disk]
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import activecontour as ac
from activecontour.compat import _segment_arguments, chan_vese
from activecontour.geometry.raster import level_curves, mask_to_curves
from activecontour.synthetic import dice

#: scikit-image sample images that load without a download (``--quick``: the first four)
SAMPLES = ("camera", "coins", "astronaut", "moon", "page", "text", "horse", "coffee", "chelsea",
           "rocket", "immunohistochemistry", "brick", "grass", "gravel", "cell", "clock",
           "microaneurysms", "binary_blobs", "shepp_logan_phantom", "hubble_deep_field")


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


def time_to_reach(image, target, mu, init_level_set):
    """Seconds until our flow, with :func:`chan_vese`'s mapped arguments, first has energy <= target."""
    init, arguments = _segment_arguments(image.shape, mu, 1.0, 1.0, 1e-3, 500, init_level_set)
    start = time.perf_counter()
    reached = []

    def callback(state):
        if state.energy <= target and not reached:
            reached.append(time.perf_counter() - start)

    ac.segment(image, init, callback=callback, **arguments)
    return reached[0] if reached else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the first four images only")
    parser.add_argument("--mu", type=float, default=0.25)
    parser.add_argument("--init", default="checkerboard", choices=("checkerboard", "disk", "small disk"))
    args = parser.parse_args()
    from skimage.segmentation import chan_vese as skimage_chan_vese

    kwargs = dict(mu=args.mu, init_level_set=args.init, extended_output=True)
    print(f"mu={args.mu} init_level_set={args.init!r}, other arguments scikit-image's defaults")
    header = (f"{'image':22s} {'size':>9s} {'E sk':>10s} {'E ours':>10s} {'dE':>7s} "
              f"{'mask sk':>10s} {'mask ours':>10s} {'it sk':>5s} {'it ours':>7s} "
              f"{'t sk s':>7s} {'t ours s':>8s} {'t ratio':>7s} {'cpu rat':>7s} {'t reach':>7s} "
              f"{'reach ratio':>11s} {'Dice':>6s}")
    print(header)
    ratios, cpu_ratios, reach_ratios, gains, mask_gains = [], [], [], [], []
    for name in SAMPLES[:4] if args.quick else SAMPLES:
        image = load_gray(name)

        def energy(curves, image=image):
            return ac.chan_vese_energy(image, curves, mu=args.mu)

        start, cpu = time.perf_counter(), time.process_time()
        seg_sk, phi_sk, energies_sk = skimage_chan_vese(image, **kwargs)
        t_sk, cpu_sk = time.perf_counter() - start, time.process_time() - cpu
        start, cpu = time.perf_counter(), time.process_time()
        seg, _, energies = chan_vese(image, **kwargs)
        t_ours, cpu_ours = time.perf_counter() - start, time.process_time() - cpu
        e_sk = min(energy(zero_level_set(phi_sk)), energy(mask_to_curves(seg_sk)))
        e_ours = energies[-1]
        mask_sk, mask_ours = energy(mask_to_curves(seg_sk)), energy(mask_to_curves(seg))
        gain = (e_ours - e_sk) / abs(e_sk)
        t_reach = time_to_reach(image, e_sk, args.mu, args.init)
        ratios.append(t_ours / t_sk)
        cpu_ratios.append(cpu_ours / cpu_sk)
        reach_ratios.append(t_reach / t_sk)
        gains.append(gain)
        mask_gains.append((mask_ours - mask_sk) / abs(mask_sk))
        size = f"{image.shape[0]}x{image.shape[1]}"
        print(f"{name:22s} {size:>9s} {e_sk:10.2f} {e_ours:10.2f} {100 * gain:6.2f}% "
              f"{mask_sk:10.2f} {mask_ours:10.2f} {len(energies_sk):5d} {len(energies) - 1:7d} "
              f"{t_sk:7.2f} {t_ours:8.3f} {t_ours / t_sk:7.3f} {cpu_ours / cpu_sk:7.3f} {t_reach:7.3f} "
              f"{t_reach / t_sk:11.3f} {dice(seg, seg_sk):6.3f}",
              flush=True)
    print(f"energy: ours lower or equal on {sum(g <= 0 for g in gains)}/{len(gains)} images "
          f"(worst dE {100 * max(gains):+.2f}%); masks outlined alike: ours lower or equal on "
          f"{sum(g <= 0 for g in mask_gains)}/{len(mask_gains)} (worst {100 * max(mask_gains):+.2f}%)")
    print(f"time ratio ours/scikit-image: median {np.median(ratios):.3f}, worst {max(ratios):.3f}, "
          f"<= 0.5 on {sum(r <= 0.5 for r in ratios)}/{len(ratios)}; CPU time ratio: median "
          f"{np.median(cpu_ratios):.3f}, worst {max(cpu_ratios):.3f}, <= 0.5 on "
          f"{sum(r <= 0.5 for r in cpu_ratios)}/{len(cpu_ratios)}")
    reached = [r for r in reach_ratios if np.isfinite(r)]
    print(f"time to reach scikit-image's energy / its time: reached on {len(reached)}/{len(reach_ratios)}, "
          f"median {np.median(reached):.3f}, worst {max(reached):.3f}, "
          f"<= 0.5 on {sum(r <= 0.5 for r in reached)}/{len(reach_ratios)}")


if __name__ == "__main__":
    main()
