"""Scale: cold start of the command line, and images from 1024^2 to 8192^2 through the polygon backend.

Run ``python benchmarks/bench_scale.py`` from the repository root, after ``pip install -e .``
(``--huge`` adds 8192^2: ~30 s to make the image once, ~1 GB of cache; ``--max-iter`` fixes the
iteration count so that the sizes compare; ``--importtime`` prints the import profile).  On a
shared two-core machine OpenBLAS's threads in the flow's long vector products have cost up to 10x
per iteration: compare a run under ``OPENBLAS_NUM_THREADS=1``.  Every
measurement runs in a fresh process, so peak RSS (``os.wait4``) is that run's alone.  The machine's
load average is printed with the timings: compare ratios taken in the same run.

The floor is one large fresh allocation, and first touches of fresh memory can dominate it: numpy
asks the kernel for transparent huge pages (``madvise``), and where the kernel's THP ``defrag`` is
``madvise`` and memory is fragmented, each fault compacts memory synchronously.  Measured at 4096^2
on the 2-core machine (same run, idle otherwise): floor 1.33 s CPU with huge pages, 0.33 s without;
our command line 4.60 s and 3.80 s, so 3.5x or 11.6x the floor.  ``--no-hugepages`` runs every
child with ``NUMPY_MADVISE_HUGEPAGE=0``: report both.

1. Cold start: wall time of ``python -m app segment disk.png -o DIR -q`` on a 256^2 noisy disk, and
   of a fresh process that reads the same PNG and runs ``skimage.segmentation.chan_vese`` with its
   defaults; interleaved, min of ``--repeat`` runs each.
2. Sizes: a disk of radius 0.3 size (contrast 0.4, noise sigma 0.2, 8-bit PNG).  The floor is reading
   the PNG plus one float64 cumulative sum along its rows (in-process time).  Then the command line
   with ``--max-iter`` (wall, peak RSS, iterations, Dice of its mask against the synthetic truth);
   the library in one process: preparation (normalising and the tables), the default start
   (:func:`activecontour.initial.threshold_starts`), time per iteration, the rest after the last
   iteration (the final mask and the objects), the objects' pass alone
   (:func:`activecontour.objects.measure.find_objects`) and the whole ``segment`` call (CPU s).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent

SKIMAGE = """
import sys, skimage.io, skimage.segmentation
skimage.segmentation.chan_vese(skimage.io.imread(sys.argv[1]))
"""

FLOOR = """
import sys, time, cv2, numpy as np
start, cpu = time.perf_counter(), time.process_time()
image = cv2.imread(sys.argv[1], cv2.IMREAD_UNCHANGED)
np.cumsum(image, axis=1, dtype=np.float64)
print(time.perf_counter() - start, time.process_time() - cpu)
"""

LIBRARY = """
import sys, time, numpy as np
import activecontour as ac
import activecontour._segment as segment_module
import activecontour.initial as initial
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
image = ac.load_image(sys.argv[1])
start = time.process_time()
ImageModel(normalize_image(image))
prepare = time.process_time() - start
spent = {"start": 0.0, "objects": 0.0}

def timed(function, key):
    def run(*args, **kwargs):
        begin = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            spent[key] += time.process_time() - begin
    return run

initial.threshold_starts = timed(initial.threshold_starts, "start")  # the default start
segment_module.find_objects = timed(segment_module.find_objects, "objects")
stamps = []
start = time.process_time()
result = ac.segment(image, max_num_iter=int(sys.argv[2]),
                    callback=lambda s: stamps.append(time.process_time()))
end = time.process_time()
steps = np.diff([start] + stamps)
per_iteration = float(np.median(steps[1:])) if len(steps) > 1 else float("nan")
print(prepare, per_iteration, end - stamps[-1], result.n_iter, spent["start"], spent["objects"], end - start)
"""


#: Runs the command given after the path of a file where it writes the command's own wall s, peak
#: RSS MB and CPU s (see :func:`run_measured`).
LAUNCHER = """
import os, subprocess, sys, time
start = time.perf_counter()
process = subprocess.Popen(sys.argv[2:])
_, status, usage = os.wait4(process.pid, 0)
wall = time.perf_counter() - start
cpu = usage.ru_utime + usage.ru_stime
with open(sys.argv[1], "w") as out:
    print(wall, usage.ru_maxrss / 1024, cpu, os.waitstatus_to_exitcode(status), file=out)
"""


def run_measured(command):
    """Run a command in the repository root; return wall s, peak RSS MB and CPU s (user + system) of
    exactly this child, and its stdout.

    The child is started by a small launcher process, which reports its figures: a child that this
    process started directly would report this process's peak RSS as its own where that is larger
    (Python starts children by ``vfork``, and Linux records the peak of the memory a process leaves
    at ``exec`` as the new program's: the 8192^2 image made here, 3.7 GB, was once reported as the
    command line's peak, 1.6 GB).  The child runs with bytecode caching on, as where the package
    is installed (pip compiles an install's modules; Python writes an editable checkout's
    ``__pycache__`` on its first run): under ``PYTHONDONTWRITEBYTECODE`` every child would compile
    all of our modules afresh (~0.25 s on the 2-core machine) while scikit-image's, installed,
    come compiled."""
    caching = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
    with (tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err,
          tempfile.NamedTemporaryFile("r") as figures):
        launcher = [sys.executable, "-c", LAUNCHER, figures.name, *map(str, command)]
        code = subprocess.run(launcher, stdout=out, stderr=err, text=True, cwd=ROOT, env=caching).returncode
        out.seek(0)
        err.seek(0)
        wall, rss, cpu, status = map(float, figures.read().split() or [0, 0, 0, code or 1])
        if code or status:
            raise RuntimeError(f"{' '.join(map(str, command))} failed: {err.read().strip()}")
        return wall, rss, cpu, out.read()


def noisy_disk(size, cache):
    """Write (once) the 8-bit noisy disk of this size and its truth; return their paths."""
    import cv2

    from activecontour import synthetic

    image_path, truth_path = cache / f"disk{size}.png", cache / f"disk{size}_truth.npy"
    if not (image_path.exists() and truth_path.exists()):
        center = (0.5 * size + 0.3, 0.47 * size - 0.2)
        image, truth = synthetic.render(synthetic.disk(center, 0.3 * size), (size, size), inside=0.7,
                                        outside=0.3, supersample=2)
        image = synthetic.add_noise(image, 0.2, seed=size)
        cv2.imwrite(str(image_path), np.clip(np.rint(image * 255), 0, 255).astype(np.uint8))
        np.save(truth_path, truth)
    return image_path, truth_path


def load():
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def cold_start(cache, repeat):
    """Print and return (ours wall, ours CPU, scikit-image's wall, its CPU), seconds, min of ``repeat``."""
    image, _ = noisy_disk(256, cache)
    out = cache / "cold-out"
    ours = [sys.executable, "-m", "app", "segment", str(image), "-o", str(out), "-q"]
    theirs = [sys.executable, "-c", SKIMAGE, str(image)]
    run_measured(ours)  # the first run after an install writes the bytecode caches (run_measured)
    times = {"ours": [], "skimage": []}
    for _ in range(repeat):  # interleaved: both see the same load
        times["ours"].append(run_measured(ours)[::2])
        times["skimage"].append(run_measured(theirs)[::2])
    (ours_wall, ours_cpu), (theirs_wall, theirs_cpu) = (np.min(times[k], axis=0) for k in ("ours", "skimage"))
    print(f"Cold start, 256x256 noisy disk, min of {repeat} fresh processes ({load()})")
    print(f"  activecontour segment: {ours_wall:.3f} s wall, {ours_cpu:.3f} s CPU   skimage chan_vese: "
          f"{theirs_wall:.3f} s wall, {theirs_cpu:.3f} s CPU   ratio {ours_wall / theirs_wall:.2f} wall, "
          f"{ours_cpu / theirs_cpu:.2f} CPU")
    return ours_wall, ours_cpu, theirs_wall, theirs_cpu


def import_profile(cache, top=12):
    image, _ = noisy_disk(256, cache)
    command = [sys.executable, "-X", "importtime", "-m", "app", "segment", str(image), "-o",
               str(cache / "cold-out"), "-q"]
    rows = []
    for line in subprocess.run(command, capture_output=True, text=True, cwd=ROOT).stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            _, cumulative, name = line.split("|")
            if cumulative.strip().isdigit() and not name.startswith("    "):
                rows.append((int(cumulative), name.rstrip()))
    print("Import profile of the segment command (cumulative ms, top-level modules)")
    for cumulative, name in sorted(rows, reverse=True)[:top]:
        print(f"  {cumulative / 1000:8.1f}  {name}")


def sizes(cache, sizes, max_iter):
    from activecontour import synthetic
    from activecontour.io.images import load_image

    pages = "off" if os.environ.get("NUMPY_MADVISE_HUGEPAGE") == "0" else "on"
    print(f"\nNoisy disk through the polygon backend, --max-iter {max_iter}, numpy's huge pages {pages} "
          f"({load()})")
    print("floor: read + one float64 cumulative sum (in-process wall / CPU); CLI: whole process; library")
    print("x floor compares CPU seconds with the floor's CPU")
    header = (f"{'size':>6s} | {'floor s':>9s} | {'CLI s':>11s} {'x floor':>7s} {'RSS MB':>6s} {'iters':>5s} "
              f"{'Dice':>6s} | {'prepare':>7s} {'start':>5s} {'ms/iter':>7s} {'final':>5s} {'objects':>7s} "
              f"{'segment':>7s}")
    print(header)
    print("-" * len(header))
    for size in sizes:
        image, truth = noisy_disk(size, cache)
        floor_wall, floor = map(float, run_measured([sys.executable, "-c", FLOOR, str(image)])[3].split())
        out = cache / f"out{size}"
        wall, rss, cpu, stdout = run_measured([sys.executable, "-m", "app", "segment", str(image), "-o",
                                               str(out), "--max-iter", str(max_iter)])
        iterations = int(stdout.split("iterations=")[1].split()[0])
        mask = load_image(out / f"disk{size}_mask.png") != 0
        dice = synthetic.dice(mask, np.load(truth))
        prepare, per_iter, final, _, start, objects, whole = map(
            float, run_measured([sys.executable, "-c", LIBRARY, str(image), str(max_iter)])[3].split())
        print(f"{size:6d} | {floor_wall:4.2f}/{floor:4.2f} | {wall:5.2f}/{cpu:5.2f} {cpu / floor:7.1f} "
              f"{rss:6.0f} {iterations:5d} {dice:6.4f} | {prepare:7.2f} {start:5.2f} {per_iter * 1e3:7.1f} "
              f"{final:5.2f} {objects:7.2f} {whole:7.2f}", flush=True)
    print(f"({load()})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--huge", action="store_true", help="also 8192 x 8192")
    parser.add_argument("--max-iter", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--skip-cold", action="store_true")
    parser.add_argument("--skip-sizes", action="store_true")
    parser.add_argument("--sizes", type=int, nargs="+", default=[1024, 2048, 4096],
                        help="the image sizes (default 1024 2048 4096; --huge adds 8192)")
    parser.add_argument("--importtime", action="store_true")
    parser.add_argument("--no-hugepages", action="store_true",
                        help="run every child with NUMPY_MADVISE_HUGEPAGE=0 (see the module's docstring)")
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "activecontour-bench-scale")
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    if args.no_hugepages:
        os.environ["NUMPY_MADVISE_HUGEPAGE"] = "0"
    if args.importtime:
        import_profile(args.cache)
    if not args.skip_cold:
        cold_start(args.cache, args.repeat)
    if not args.skip_sizes:
        huge = [8192] if args.huge and 8192 not in args.sizes else []
        sizes(args.cache, args.sizes + huge, args.max_iter)


if __name__ == "__main__":
    main()
