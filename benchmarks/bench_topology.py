"""Topology cases: the polygon backend against the level-set backend, side by side.

Run ``python benchmarks/bench_topology.py``.  For each case (two disks from one enclosing circle, an
annulus from one circle, twelve disks of different intensities from a start that knows nothing,
a colour image whose regions have equal gray levels), both backends run from the same kind of
start; the table lists wall time, Dice against the constructed ground truth, the number of curves,
and the final energy by the common evaluator :func:`activecontour.chan_vese_energy` on each
result's contours.
"""

from __future__ import annotations

import time

import numpy as np

import activecontour as ac
from activecontour import synthetic

SIZE = (256, 256)


def cases():
    two = synthetic.union(synthetic.disk((128.3, 69.2), 38.0), synthetic.disk((127.4, 186.4), 42.0))
    image, truth = synthetic.render(two, SIZE, inside=0.75, outside=0.25)
    yield "two disks", synthetic.add_noise(image, 0.15, 1), truth, ac.circle((127.5, 127.5), 120.0), {}
    image, truth = synthetic.render(synthetic.annulus((127.5, 128.4), 28.0, 72.0), SIZE)
    yield "annulus", synthetic.add_noise(image, 0.15, 2), truth, ac.circle((127.5, 128.0), 100.0), {}
    image, truth, _ = synthetic.coins()
    yield "12 coins", image, truth, "grid", {}
    image, truth = synthetic.equal_gray_colour()
    yield "colour", image, truth, ac.circle((64.0, 64.0), 50.0), {"color": "vector"}


def warm_up():
    """Run both backends once (imports, first allocations) before timing anything."""
    image, _ = synthetic.render(synthetic.disk((20, 20), 8), (40, 40))
    for backend in ("polygon", "levelset"):
        ac.segment(image, backend=backend)


def main():
    warm_up()
    header = (f"{'case':10s} {'backend':9s} | {'time s':>7s} | {'Dice':>6s} | {'curves':>6s} | "
              f"{'energy':>10s}")
    print(header)
    print("-" * len(header))
    for name, image, truth, init, extra in cases():
        rows = {}
        for backend in ("polygon", "levelset"):
            start = init if (backend == "polygon" or not isinstance(init, str)) else "checkerboard"
            begin = time.perf_counter()
            result = ac.segment(image, start, backend=backend, **extra)
            elapsed = time.perf_counter() - begin
            energy = ac.chan_vese_energy(image, result.contours, **extra)
            rows[backend] = (elapsed, synthetic.dice(result.mask, truth), len(result.contours), energy)
            print(f"{name:10s} {backend:9s} | {elapsed:7.3f} | {rows[backend][1]:6.4f} | "
                  f"{rows[backend][2]:6d} | {energy:10.3f}")
        (tp, dp, _, ep), (tl, dl, _, el) = rows["polygon"], rows["levelset"]
        print(f"{'':10s} polygon/levelset: time {tp / tl:.2f}x, Dice {dp - dl:+.4f}, "
              f"energy {100 * (ep - el) / abs(el):+.2f}%")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
