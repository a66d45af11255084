"""The split's cost: ``segment(image)`` (``separate=True``) over ``separate=False``, with the split of
this tree and of an earlier revision side by side, in CPU seconds, in one run.

Run ``python benchmarks/bench_splitcost.py [--before REV] [--repeat 2] [--scenes grass dsb ...]``
(``--samples``: the 25 sample images of ``benchmarks/bench_objects.py``).

Per scene, the least CPU time (``time.process_time``: the machine may be shared) over
``--repeat`` rounds of :func:`activecontour.segment` with ``separate=False``, with the defaults,
and with the defaults but :mod:`activecontour.objects.split` as it was at ``--before`` (read with
``git show`` with its stages' modules, run in place of this tree's
:func:`~activecontour.objects.split.split_touching`);
the ratios to ``separate=False``; and, on the textured images of ``benchmarks/bench_texture.py``,
scikit-image's ``chan_vese`` with its defaults.  Each round runs every variant once, in turn
first, so the machine's load falls on all alike.  Whether the objects stay the same is
``benchmarks/split_same.py``'s question.
"""

from __future__ import annotations

import argparse
import importlib
import re
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import skimage.segmentation
from bench_objects import SAMPLES
from bench_texture import IMAGES as TEXTURED
from bench_texture import gray01

import activecontour as ac
from activecontour import synthetic

SCENES = ("grass", "gravel", "hubble_deep_field", "brick", "astronaut", "coins", "dsb", "disks_0", "disks_1",
          "ellipses_0", "ellipses_1", "singles_0", "disk4096", "scale4096")


def scene(name):
    import skimage.data as data

    if name == "dsb":
        return ac.load_image(Path(__file__).resolve().parents[1] / "sample_images/nuclei.png")
    if name == "binary_blobs":
        return data.binary_blobs(rng=1)
    if name == "disk4096":
        disk = synthetic.disk_image(4096, (2048.3, 2047.6), 1500.0)[0]
        return synthetic.add_noise(disk, 0.2, seed=0)
    if name == "scale4096":  # benchmarks/bench_scale.py's 8-bit disk: its outline dips inside its hull
        from bench_scale import noisy_disk

        return ac.load_image(noisy_disk(4096, Path(tempfile.gettempdir()) / "activecontour-bench-scale")[0])
    family, _, seed = name.partition("_")
    if family in synthetic.FAMILIES and seed.isdigit():
        return synthetic.FAMILIES[family](int(seed))[0]
    return getattr(data, name)()


#: The split's modules (its stages have modules of their own since the split of split.py; before,
#: split.py held them all and the others do not exist at that revision)
SPLIT_MODULES = ("shapes", "corners", "arcs", "necks", "contrast", "split")


def split_at(revision):
    """:func:`split_touching` of ``activecontour/objects/split.py`` and its stages' modules at a git
    revision (a package of their own, importing each other, not this tree's)."""
    root = Path(__file__).resolve().parents[1]
    package = Path(tempfile.mkdtemp()) / "split_before"
    package.mkdir()
    (package / "__init__.py").write_text("")
    ours = re.compile(r"\bactivecontour\.objects\.(" + "|".join(SPLIT_MODULES) + r")\b")
    for name in SPLIT_MODULES:
        shown = subprocess.run(["git", "show", f"{revision}:activecontour/objects/{name}.py"], cwd=root,
                               capture_output=True, text=True)
        if shown.returncode == 0:
            (package / f"{name}.py").write_text(ours.sub(r"split_before.\1", shown.stdout))
    sys.path.insert(0, str(package.parent))
    return importlib.import_module("split_before.split").split_touching


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", default="main", help="git revision of the split to compare with")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--scenes", nargs="+", default=list(SCENES))
    parser.add_argument("--samples", action="store_true",
                        help="the 25 sample images of benchmarks/bench_objects.py instead of --scenes")
    args = parser.parse_args(argv)
    if args.samples:
        args.scenes = list(SAMPLES)
    measure = importlib.import_module("activecontour.objects.measure")
    ours, before = measure.split_touching, split_at(args.before)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        images = {name: scene(name) for name in args.scenes}
    ac.segment(synthetic.touching_disks(0)[0])  # imports and compiled kernels warm
    variants = ("alone", "ours", "before")
    best = {(name, variant): np.inf for name in images for variant in variants + ("chan_vese",)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for round_ in range(args.repeat):
            for name, image in images.items():
                # each round starts with another variant: the first run after another image pays
                # for the memory it takes back (a 4096^2 image: seconds of page faults)
                for variant in variants[round_ % 3:] + variants[:round_ % 3]:
                    measure.split_touching = before if variant == "before" else ours
                    start = time.process_time()
                    ac.segment(image, separate=variant != "alone")
                    best[name, variant] = min(best[name, variant], time.process_time() - start)
                measure.split_touching = ours
                if name in TEXTURED:
                    start = time.process_time()
                    skimage.segmentation.chan_vese(gray01(image))
                    best[name, "chan_vese"] = min(best[name, "chan_vese"], time.process_time() - start)
    print(f"CPU seconds, least of {args.repeat} rounds; split before = {args.before}")
    print(f"{'scene':18s} | {'sep=False':>9s} | {'ours':>7s} | {'before':>7s} | {'ratio ours':>10s} | "
          f"{'ratio before':>12s} | {'chan_vese':>9s}")
    for name in images:
        alone, now, then = (best[name, v] for v in variants)
        peer = best[name, "chan_vese"]
        print(f"{name:18s} | {alone:9.2f} | {now:7.2f} | {then:7.2f} | {now / alone:10.2f} | "
              f"{then / alone:12.2f} | {'-' if np.isinf(peer) else f'{peer:9.2f}':>9s}", flush=True)


if __name__ == "__main__":
    main()
