"""Batches: ``activecontour segment --jobs 1`` against ``--jobs 2``, and the Dask path on a LocalCluster.

Run ``python benchmarks/bench_batch.py [--images 16] [--size 512] [--repeat 2]``.

The images are noisy anti-aliased shapes (:mod:`activecontour.synthetic`: disks and stars of
different sizes and places, noise 0.2 on a 0.3/0.7 contrast), written as PNG files into a
temporary folder.  The script measures, on the same files in the same run:

1. the command line end to end, a fresh process each time (``python -m app segment FOLDER -o DIR
   --jobs J --quiet``), J = 1 and 2, the best of ``--repeat`` interleaved runs; the speed-up, and
   whether the two runs wrote byte-identical masks and identical contours;
2. :func:`activecontour.segment_many` over the files in this (warm) process, jobs 1 and 2: the
   batch alone, without the start of a process;
3. :func:`activecontour.batch.segment_dask` over the files on a ``LocalCluster`` of 2 worker
   processes with 1 thread each (the cluster's start-up reported apart), and its throughput against
   ``segment_many(jobs=2)``; its masks against the serial ones.

The machine's load (``os.getloadavg``) is printed before and after: the cores may be shared.  Next
to each wall time is the CPU time of the processes that did the work (``resource.getrusage``, the
workers included) and their ratio, the cores the run really had: on a busy machine a speed-up
below the number of jobs shows there as fewer cores, not as a slower program.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

import activecontour as ac
from activecontour import io, synthetic
from activecontour.batch import segment_many

ROOT = Path(__file__).resolve().parents[1]


def make_images(folder, count, size):
    """``count`` noisy shapes as 8-bit PNGs in ``folder``; returns the ground truths by file name."""
    rng = np.random.default_rng(2024)
    truths = {}
    for k in range(count):
        center = (size / 2 + rng.uniform(-0.12, 0.12) * size, size / 2 + rng.uniform(-0.12, 0.12) * size)
        radius = rng.uniform(0.15, 0.28) * size
        shape = synthetic.disk(center, radius) if k % 2 == 0 else synthetic.star(center, radius)
        image, truth = synthetic.render(shape, (size, size), inside=0.7, outside=0.3, supersample=2)
        image = synthetic.add_noise(image, 0.2, seed=k)
        name = f"shape{k:03d}.png"
        cv2.imwrite(str(folder / name), np.round(np.clip(image, 0, 1) * 255).astype(np.uint8))
        truths[name] = truth
    return truths


def cpu_seconds():
    """User + system time of this process and of its children that have finished (workers too)."""
    return sum(resource.getrusage(who).ru_utime + resource.getrusage(who).ru_stime
               for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))


def timed(function, *args):
    """(wall seconds, CPU seconds, value) of ``function(*args)``."""
    cpu, started = cpu_seconds(), time.perf_counter()
    value = function(*args)
    return time.perf_counter() - started, cpu_seconds() - cpu, value


def run_cli(folder, out, jobs):
    subprocess.run([sys.executable, "-m", "app", "segment", str(folder), "-o", str(out), "--jobs", str(jobs),
                    "--quiet"], cwd=ROOT, check=True)


def describe(wall, cpu):
    return f"{wall:6.2f} s (CPU {cpu:6.2f} s, {cpu / wall:.2f} cores)"


def same_outputs(first, second):
    """Masks byte-identical and contours equal, for every file of two output folders."""
    names = sorted(os.listdir(first))
    if names != sorted(os.listdir(second)):
        return False
    for name in names:
        if name.endswith("_mask.png") and (first / name).read_bytes() != (second / name).read_bytes():
            return False
        if name.endswith("_contours.json"):
            a, b = io.read_contours(first / name), io.read_contours(second / name)
            if len(a) != len(b) or not all(np.array_equal(p, q) for p, q in zip(a, b, strict=True)):
                return False
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=16)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args()
    print(f"load before: {' '.join(f'{v:.2f}' for v in os.getloadavg())}  (cores: {os.cpu_count()})")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        folder = tmp / "images"
        folder.mkdir()
        truths = make_images(folder, args.images, args.size)
        paths = [str(folder / name) for name in sorted(truths)]
        n = len(paths)

        # 1. the command line, fresh processes, interleaved
        runs = {1: [], 2: []}
        for attempt in range(args.repeat):
            for jobs in (1, 2):
                wall, cpu, _ = timed(run_cli, folder, tmp / f"cli{jobs}_{attempt}", jobs)
                runs[jobs].append((wall, cpu))
        (cli1, cpu1), (cli2, cpu2) = min(runs[1]), min(runs[2])
        identical = all(same_outputs(tmp / f"cli1_{a}", tmp / f"cli2_{b}")
                        for a in range(args.repeat) for b in range(args.repeat))
        dice = {name: synthetic.dice(io.read_mask(tmp / "cli2_0" / name.replace(".png", "_mask.png")), truth)
                for name, truth in truths.items()}
        worst = min(dice, key=dice.get)
        print(f"\n{n} images of {args.size}^2, command line end to end (best of {args.repeat}):")
        print(f"  --jobs 1: {describe(cli1, cpu1)}   --jobs 2: {describe(cli2, cpu2)}")
        print(f"  speed-up {cli1 / cli2:.2f}   identical masks and contours: {identical}   "
              f"Dice median {np.median(list(dice.values())):.4f}, lowest {dice[worst]:.4f} ({worst})")
        print(f"  all runs (wall s): jobs 1 {' '.join(f'{w:.2f}' for w, _ in runs[1])}, "
              f"jobs 2 {' '.join(f'{w:.2f}' for w, _ in runs[2])}")
        # what 2 free cores would give: the start of the command (imports, kernels, one tiny image)
        # is serial, the rest of --jobs 2's CPU time splits over the two workers
        tiny = tmp / "tiny"
        tiny.mkdir()
        cv2.imwrite(str(tiny / "tiny.png"), cv2.imread(paths[0], cv2.IMREAD_GRAYSCALE)[:32, :32])
        start_cpu = min(timed(run_cli, tiny, tmp / f"tiny_out{k}", 1)[1] for k in range(args.repeat))
        ideal = cpu1 / (start_cpu + (cpu2 - start_cpu) / 2)
        print(f"  start of the command alone (one 32^2 image): CPU {start_cpu:.2f} s; --jobs 2 spends "
              f"{cpu2 / cpu1:.2f}x the CPU of --jobs 1; on 2 free cores that is a speed-up of ~{ideal:.2f}")

        # 2. the library in this process (warm: kernels loaded, no process start)
        ac.segment(ac.load_image(paths[0]))
        serial_time, serial_cpu, serial = timed(lambda: list(segment_many(paths, jobs=1)))
        pool_time, pool_cpu, pooled = timed(lambda: list(segment_many(paths, jobs=2)))
        reference = {item.index: item.result for item in serial}
        equal = all(np.array_equal(item.result.mask, reference[item.index].mask)
                    and item.result.energy == reference[item.index].energy for item in pooled)
        print("\nsegment_many over the files, in a warm process (the batch alone):")
        print(f"  jobs 1: {describe(serial_time, serial_cpu)} {n / serial_time:.2f} images/s")
        print(f"  jobs 2: {describe(pool_time, pool_cpu)} {n / pool_time:.2f} images/s   "
              f"speed-up {serial_time / pool_time:.2f}   identical: {equal}")
        print(f"  jobs 2 spends {pool_cpu / serial_cpu:.2f}x the CPU of jobs 1; on 2 free cores that is a "
              f"speed-up of ~{2 * serial_cpu / pool_cpu:.2f}")

        # 3. Dask
        if not args.no_dask:
            bench_dask(paths, reference, pool_time, cli2)
    print(f"\nload after: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")


def bench_dask(paths, reference, pool_time, cli2):
    try:
        import dask
        from distributed import Client, LocalCluster
    except ModuleNotFoundError:
        print("\nDask: not installed (pip install 'activecontour[dask]'), skipped")
        return
    from activecontour.batch import segment_dask

    n = len(paths)
    print("\nsegment_dask over the files on LocalCluster(n_workers=2, threads_per_worker=1):")
    # Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536 (to hand memory back); measured
    # with it unset (glibc's default, as in segment_many's workers), then with it.  The nannies of a
    # LocalCluster live in this process and leave the variable in os.environ: hence this order.
    for label, trim in (("MALLOC_TRIM_THRESHOLD_ unset", {TRIM_KEY: None}),
                        ("Dask's default environment", {})):
        started = time.perf_counter()
        cluster_options = {"n_workers": 2, "threads_per_worker": 1, "processes": True,
                           "dashboard_address": None}
        with dask.config.set(trim), LocalCluster(**cluster_options) as cluster, Client(cluster) as client:
            start_up = time.perf_counter() - started
            warm_started = time.perf_counter()
            client.run(warm_up)  # every worker loads the compiled kernels once
            warm = time.perf_counter() - warm_started
            dask_time, _, items = timed(lambda client=client: list(segment_dask(paths, client=client)))
            equal = all(item.ok and np.array_equal(item.result.mask, reference[item.index].mask)
                        and item.result.energy == reference[item.index].energy for item in items)
        print(f"  {label}: cluster start {start_up:.2f} s, kernels loading on the workers {warm:.2f} s")
        print(f"    batch {dask_time:6.2f} s ({n / dask_time:.2f} images/s) = {pool_time / dask_time:.2f}x "
              f"the throughput of segment_many(jobs=2); with the start and warm-up "
              f"{start_up + warm + dask_time:.2f} s (command line --jobs 2: {cli2:.2f} s); "
              f"identical: {equal}")


TRIM_KEY = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"


def warm_up():
    ac.segment(synthetic.render(synthetic.disk((20, 20), 8), (40, 40))[0])


if __name__ == "__main__":
    main()
