"""A result is a faithful start, and "converged" is stationary: both checks of DESIGN.md's invariants
over scikit-image's sample images, on both backends.

- **Restart.** ``segment(image, init=res, max_num_iter=0)`` returns ``res``: from the same backend the
  energy to a relative 1e-7 and the same mask; from the other backend's result the mask keeps within
  0.1 % of its area (the energies differ: each backend holds a curve its own way).
- **Stationarity.** Continuing from the result with ``tol / 100`` changes neither J nor the mask by
  0.1 % or more (the mask change counted against the mask's area).

``restart_rows`` and ``stationarity_rows`` return one dict per check (``benchmarks/promises.py``
prints them next to the claims); ``main`` prints both tables and the default runs' energies.

usage (from the project's root):
    python benchmarks/restart.py [--backends polygon,levelset] [--images camera,coins] [--skip-stationarity]
"""

from __future__ import annotations

import argparse
import inspect
import time
import warnings

import numpy as np

import activecontour as ac

#: The sample images of shared/tools/contact_sheet.py (scikit-image's data module).
SAMPLE_IMAGES = ("astronaut", "binary_blobs", "brick", "camera", "cat", "cell", "checkerboard", "chelsea",
                 "clock", "coffee", "coins", "colorwheel", "grass", "gravel", "horse", "hubble_deep_field",
                 "immunohistochemistry", "logo", "microaneurysms", "moon", "page", "retina", "rocket",
                 "shepp_logan_phantom", "text")
BACKENDS = ("polygon", "levelset")
#: DESIGN.md's thresholds.
RESTART_ENERGY = 1e-7  # same backend: relative energy change
RESTART_MASK = 1e-3  # other backend: changed pixels / mask area
STATIONARY = 1e-3  # relative energy change and changed pixels / mask area under tol / 100
DEFAULT_TOL = inspect.signature(ac.segment).parameters["tol"].default


def load(name):
    """A sample image by name (``binary_blobs`` with ``rng=1``, as the contact sheet)."""
    import skimage.data as data

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return data.binary_blobs(rng=1) if name == "binary_blobs" else getattr(data, name)()


def _named(images):
    """(name, image) pairs from names or pairs."""
    return [(item, load(item)) if isinstance(item, str) else tuple(item) for item in images]


def default_results(images, backends=BACKENDS):
    """``{(name, backend): (image, result, cpu seconds)}`` of the default run."""
    out = {}
    for name, image in _named(images):
        for backend in backends:
            start = time.process_time()
            result = ac.segment(image, backend=backend)
            out[name, backend] = (image, result, time.process_time() - start)
    return out


def _changes(before, after):
    changed = int(np.count_nonzero(before.mask != after.mask))
    area = max(int(before.mask.sum()), 1)
    return dict(energy_before=before.energy, energy_after=after.energy,
                energy_change=(after.energy - before.energy) / abs(before.energy) if before.energy else
                after.energy - before.energy,
                mask_changed=changed, mask_change=changed / area)


def restart_rows(images, backends=BACKENDS, results=None):
    """One row per image, backend and the backend whose result it starts from (``max_num_iter=0``).

    ``results``: :func:`default_results` of the same images and backends, when already run.
    """
    results = default_results(images, backends) if results is None else results
    rows = []
    for name, _ in _unique_names(results):
        for backend in backends:
            for source in backends:
                image, first, _ = results[name, source]
                again = ac.segment(image, init=first, backend=backend, max_num_iter=0)
                row = dict(image=name, backend=backend, start=source, **_changes(first, again))
                if backend == source:
                    row["ok"] = abs(row["energy_change"]) <= RESTART_ENERGY and row["mask_changed"] == 0
                else:
                    row["ok"] = row["mask_change"] <= RESTART_MASK
                rows.append(row)
    return rows


def stationarity_rows(images, backends=BACKENDS, results=None):
    """One row per image and backend: the default result continued with ``tol / 100``."""
    results = default_results(images, backends) if results is None else results
    rows = []
    for name, _ in _unique_names(results):
        for backend in backends:
            image, first, _ = results[name, backend]
            start = time.process_time()
            again = ac.segment(image, init=first, backend=backend, tol=DEFAULT_TOL / 100)
            row = dict(image=name, backend=backend, **_changes(first, again), n_iter=again.n_iter,
                       status=again.status, seconds=time.process_time() - start)
            row["ok"] = abs(row["energy_change"]) < STATIONARY and row["mask_change"] < STATIONARY
            rows.append(row)
    return rows


def _unique_names(results):
    seen = {}
    for name, backend in results:
        seen.setdefault(name, backend)
    return list(seen.items())


def _print(rows, columns):
    print(" ".join(f"{title:>{width}}" for title, _, width in columns))
    for row in rows:
        print(" ".join(f"{fmt(row):>{width}}" for _, fmt, width in columns))
    print(f"{sum(row['ok'] for row in rows)} of {len(rows)} hold")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", default=",".join(SAMPLE_IMAGES))
    parser.add_argument("--backends", default=",".join(BACKENDS))
    parser.add_argument("--skip-stationarity", action="store_true")
    args = parser.parse_args(argv)
    images, backends = args.images.split(","), tuple(args.backends.split(","))
    results = default_results(images, backends)
    print("Default runs")
    for (name, backend), (_, result, seconds) in results.items():
        print(f"{name:>22} {backend:>9} J {result.energy:14.6f} {result.n_iter:5d} it status {result.status} "
              f"{seconds:6.1f} s", flush=True)
    change = [("J before", lambda r: f"{r['energy_before']:.6f}", 14),
              ("J after", lambda r: f"{r['energy_after']:.6f}", 14),
              ("rel. change", lambda r: f"{r['energy_change']:+.2e}", 11),
              ("px", lambda r: str(r["mask_changed"]), 6),
              ("% mask", lambda r: f"{100 * r['mask_change']:.3f}", 7)]
    ok = [("ok", lambda r: "yes" if r["ok"] else "NO", 3)]
    names = [("image", lambda r: r["image"], 22), ("backend", lambda r: r["backend"], 9)]
    print("\nRestart: segment(image, init=res, max_num_iter=0)")
    _print(restart_rows(images, backends, results), names + [("from", lambda r: r["start"], 9)] + change + ok)
    if args.skip_stationarity:
        return
    print(f"\nStationarity: continued with tol = {DEFAULT_TOL / 100:g}")
    _print(stationarity_rows(images, backends, results), names + change + [
        ("it", lambda r: str(r["n_iter"]), 4), ("status", lambda r: str(r["status"]), 6),
        ("s", lambda r: f"{r['seconds']:.1f}", 6)] + ok)


if __name__ == "__main__":
    main()
