"""The split's decisions kept: the objects of ``segment(image)`` (``separate=True``) before and after
a change to :mod:`activecontour.objects.split`, compared exactly, and the split's cost.

Run ``python benchmarks/split_same.py capture DIR [--seeds 5]`` on the code before the change, then
``python benchmarks/split_same.py check DIR`` on the code after it.

``capture`` runs :func:`activecontour.segment` with its defaults on each scene (the 25 sample images
of ``benchmarks/bench_objects.py``, the DSB 2018 nuclei image, ``--seeds`` seeds of each family of
:data:`activecontour.synthetic.FAMILIES`) and stores, per scene, the arguments
:func:`activecontour.objects.measure.find_objects` was called with and the objects it returned
(label image, measurement table, curves).  ``check`` calls ``find_objects`` again on the stored
arguments (the flow is not re-run: the split is what changed) and reports every scene whose label
image or curves differ (and how far their tables' columns moved), with the CPU seconds of
``find_objects`` with ``separate=True`` and ``separate=False`` (the least of ``--repeat`` runs):
the split's share of the run.
"""

from __future__ import annotations

import argparse
import pickle
import warnings
from pathlib import Path

import numpy as np
from bench_objects import SAMPLES
from timing import least_cpu

import activecontour as ac
import activecontour._segment as segment_module
from activecontour import synthetic
from activecontour.objects.measure import find_objects


def scenes(seeds):
    """(name, image) of every scene."""
    import skimage.data as data

    for name in SAMPLES:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield name, data.binary_blobs(rng=1) if name == "binary_blobs" else getattr(data, name)()
    yield "dsb", ac.load_image(Path(__file__).resolve().parents[1] / "sample_images/nuclei.png")
    for family, scene in synthetic.FAMILIES.items():
        for seed in range(seeds):
            yield f"{family}_{seed}", scene(seed)[0]


def capture(folder, seeds):
    folder.mkdir(parents=True, exist_ok=True)
    calls = []
    original = segment_module.find_objects

    def recording(*args, **kwargs):
        found = original(*args, **kwargs)
        calls.append((args, kwargs, found))
        return found

    segment_module.find_objects = recording
    try:
        for name, image in scenes(seeds):
            calls.clear()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ac.segment(image)
            (args, kwargs, found), = calls
            with open(folder / f"{name}.pkl", "wb") as file:
                pickle.dump((args, kwargs, found), file)
            print(f"{name:22s} {len(found[0]):5d} objects", flush=True)
    finally:
        segment_module.find_objects = original


def same(before, after):
    """Whether two results of ``find_objects`` hold the same objects (curves and label image), and
    the largest relative difference of any column of their tables (a measurement's rounding may
    move with a change outside the split)."""
    (objects, labels, table), (objects2, labels2, table2) = before, after
    equal = (len(objects) == len(objects2)
             and all(len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
                     for a, b in zip(objects, objects2, strict=True))
             and np.array_equal(labels, labels2))
    if not equal or table.keys() != table2.keys():
        return False, np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        gaps = [np.nanmax(np.abs(np.asarray(table[key], float) - table2[key])
                          / np.maximum(np.abs(np.asarray(table[key], float)), 1e-300), initial=0.0)
                for key in table]
    return True, float(max(gaps, default=0.0))


def check(folder, repeat):
    changed, total, gap = [], {True: 0.0, False: 0.0}, 0.0
    print(f"{'scene':22s} | {'objects':>7s} | {'split s':>7s} | {'no split s':>10s} | same | table rel. diff")
    for path in sorted(folder.glob("*.pkl")):
        with open(path, "rb") as file:
            args, kwargs, found = pickle.load(file)
        now, seconds = least_cpu(find_objects, *args, repeats=repeat, **kwargs)
        _, alone = least_cpu(find_objects, *args, repeats=repeat, **{**kwargs, "separate": False})
        total[True] += seconds
        total[False] += alone
        equal, difference = same(found, now)
        if not equal:
            changed.append(path.stem)
        gap = max(gap, difference)
        print(f"{path.stem:22s} | {len(now[0]):7d} | {seconds:7.3f} | {alone:10.3f} | {str(equal):4s} | "
              f"{difference:.1e}", flush=True)
    print(f"total: split {total[True]:.2f} s, no split {total[False]:.2f} s; objects changed: "
          f"{changed or 'none'}; largest relative difference in a table: {gap:.1e}")
    return not changed


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=("capture", "check"))
    parser.add_argument("folder", type=Path)
    parser.add_argument("--seeds", type=int, default=5, help="seeds per family (capture)")
    parser.add_argument("--repeat", type=int, default=1, help="find_objects runs; the least counts (check)")
    args = parser.parse_args(argv)
    if args.mode == "capture":
        capture(args.folder, args.seeds)
        return 0
    return 0 if check(args.folder, args.repeat) else 1


if __name__ == "__main__":
    raise SystemExit(main())
