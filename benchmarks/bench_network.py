"""Where the N-region polygon (the network, ``backends/network/``) spends its CPU, next to the
level set (the label field) in the same run: scikit-image's coins, page, camera and text with
``n_regions=3`` (issue 24.5: the polygon at most 1.5x the level set).

Per scene, the least CPU of ``--repeat`` runs (both backends alternating, ``separate=False``) of:
the label field's descent (the start both backends share), the network's flow after it, the
polygon's whole call, the level set's whole call, and the ratio polygon / level set; with the
energies and the polygon's status.  ``--profile`` adds the flow's CPU per network method (the
best run's calls and milliseconds).

usage: PYTHONPATH=. python benchmarks/bench_network.py [--repeat N] [--only WORD ...] [--profile]
"""

from __future__ import annotations

import argparse
import time

import skimage.data

import activecontour as ac
from activecontour.backends import labelfield
from activecontour.backends.network import flow, graph, h1

_SCENES = ("coins", "page", "camera", "text")
# each looked up when called: the flow's methods, its module's Steps, the H^1 system's functions
_METHODS = {flow._Flow: ("run", "evaluate", "drop_islands", "resolve", "remesh"), flow: ("Steps",),
            h1: ("nodal_force", "factorised", "velocity", "normal_part"),
            graph.Network: ("simple", "faces", "closed_loops", "closed_areas", "meeting_pairs", "meet_among")}


def _timed(owner, name, spent):
    """``owner.name`` (a method, or a module's function or class) wrapped to add its calls and CPU
    seconds to ``spent[name]``."""
    method = getattr(owner, name)

    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return method(*args, **kwargs)
        finally:
            calls, seconds = spent.get(name, (0, 0.0))
            spent[name] = (calls + 1, seconds + time.process_time() - start)

    setattr(owner, name, wrapper)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--only", nargs="*", help="scenes whose name contains one of these words")
    parser.add_argument("--profile", action="store_true", help="the flow's CPU per network method")
    args = parser.parse_args()
    spent = {}
    _timed(labelfield, "descend_labels", spent)  # looked up when called, by both backends
    for owner, names in _METHODS.items():
        for name in names:
            _timed(owner, name, spent)
    print(f"scene | label field s | flow s | polygon s | level set s | polygon / level set | J polygon | "
          f"J level set | status (best of {args.repeat})")
    for name in _SCENES:
        if args.only and not any(word in name for word in args.only):
            continue
        image = getattr(skimage.data, name)()
        best = {"polygon": (float("inf"), {}), "levelset": (float("inf"), {})}
        results = {}
        for _ in range(max(args.repeat, 1)):
            for backend in best:
                spent.clear()
                start = time.process_time()
                results[backend] = ac.segment(image, n_regions=3, backend=backend, separate=False)
                total = time.process_time() - start
                if total < best[backend][0]:
                    best[backend] = (total, dict(spent))
        (polygon, stages), (levelset, _) = best["polygon"], best["levelset"]
        print(f"{name} | {stages['descend_labels'][1]:.3f} | {stages['run'][1]:.3f} | {polygon:.3f} | "
              f"{levelset:.3f} | {polygon / levelset:.2f} | {results['polygon'].energy:.6f} | "
              f"{results['levelset'].energy:.6f} | {results['polygon'].status}", flush=True)
        if args.profile:
            for method, (calls, seconds) in sorted(stages.items(), key=lambda item: -item[1][1]):
                print(f"    {method}: {calls} calls, {1000 * seconds:.1f} ms")


if __name__ == "__main__":
    main()
