"""Every number README and its docs pages state, re-measured: one row per claim, claim against measured.

Each claim is found in the documents by a pattern (README.md and docs/*.md are searched, so a
claim is still found after its sentence moves to another page) and re-measured by the benchmark
functions that made it, in this run: the first command of README, the test suite's time, the cold
start next to a scikit-image process (``bench_scale``), a result as a faithful start and
"converged" as stationary (``restart``), the robustness table next to the peers (``bench_robust``),
the noisy 256² table and the cost per iteration (``bench_polygon``), the DSB split
(``bench_objects``), the drop-in (``bench_compat``) and the examples' equalities.  The documents
state no number this table does not re-measure: what the other benchmarks measure, they name.

``holds``: ``yes`` / ``NO``; a time holds when the measured one is at most 1.2x the stated one (a
shared machine's noise), a count or a bound when it is met.  README's numbers are copied from this
table's last run; the run ends with the time it took.

usage: python benchmarks/promises.py [--quick] [--only WORD ...] [--skip-tests]
  --quick       a few images per check (compat: 4 images, scikit-image's gallery call; restart and
                stationarity: 3 sample images; robustness: sizes up to 1024), no test suite
"""

from __future__ import annotations

import argparse
import contextlib
import io
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

#: The documents whose numbers are promises.
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A time claim holds up to this factor (load on a shared machine).
TIME_SLACK = 1.2
#: Sample images of the quick restart and stationarity checks.
QUICK_SAMPLES = ("camera", "coins", "horse")


@dataclass
class Claim:
    """A sentence of the documents (found by ``pattern``) and the function that re-measures it."""

    name: str
    pattern: str
    measure: object  # callable(context) -> (measured text, holds: bool or None)


CLAIMS = []


def claim(name, pattern):
    """Register ``measure(context) -> (measured, holds)`` for the sentence ``pattern`` finds."""
    def register(measure):
        CLAIMS.append(Claim(name, pattern, measure))
        return measure
    return register


def find(pattern):
    """``(document, sentence)`` of the first match of ``pattern`` in the documents, or None."""
    for path in DOCUMENTS:
        text = " ".join(path.read_text().split())
        found = re.search(pattern, text)
        if found:
            return path.relative_to(ROOT).as_posix(), found.group(0)
    return None


def number(pattern, default=None):
    """The first number the claim's sentence states after ``pattern``'s match (a float), or default."""
    located = find(pattern)
    if located is None:
        return default
    value = re.search(r"[-+]?\d+(?:\.\d+)?", located[1])
    return float(value.group(0)) if value else default


def quietly(function, *args, **kwargs):
    """Call a benchmark function that prints its own table; keep only its return value."""
    with contextlib.redirect_stdout(io.StringIO()):
        return function(*args, **kwargs)


def python_block(containing):
    """The Python example of the documents that contains ``containing``."""
    from tests.app.test_readme import python_blocks

    (block,) = [code for code in python_blocks() if containing in code]
    return block


def run_block(code):
    namespace = {"__name__": "__main__"}
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - our own documentation
    return namespace


# ------------------------------------------------------------------------------------ README.md

#: README's summary line of its first command
SUMMARY_LINE = r"disk_noisy\.png: objects=\S+ iterations=\S+ energy=\S+ mu=\S+ c_in=\S+ c_out=\S+ time=\S+"


@claim("first command", SUMMARY_LINE)
def first_command(context):
    """The summary line of ``activecontour segment sample_images/disk_noisy.png -o out``."""
    stated = find(SUMMARY_LINE)[1]
    with tempfile.TemporaryDirectory() as out:
        started = time.perf_counter()
        printed = subprocess.run([sys.executable, "-m", "app", "segment", "sample_images/disk_noisy.png",
                                  "-o", out], cwd=ROOT, capture_output=True, text=True, check=True).stdout
        wall = time.perf_counter() - started
    printed = printed.strip().split(" output=")[0]
    fields = dict(item.split("=", 1) for item in printed.split()[1:])
    said = dict(item.split("=", 1) for item in stated.split()[1:])
    same = all(fields[k] == said[k] for k in ("objects", "iterations", "energy", "mu", "c_in", "c_out"))
    seconds = float(fields["time"].rstrip("s"))
    holds = same and seconds <= TIME_SLACK * float(said["time"].rstrip("s"))
    return f"{printed} (the whole command {wall:.2f} s wall)", holds


@claim("README's Dice", r"synthetic\.dice\(res\.mask, truth\) # ~\d\.\d+")
def readme_dice(context):
    namespace = run_block(python_block("synthetic.add_noise(image, 0.25"))
    from activecontour import synthetic

    dice = synthetic.dice(namespace["res"].mask, namespace["truth"])
    return f"Dice {dice:.4f}", round(dice, 2) >= number(r"synthetic\.dice\(res\.mask, truth\) # ~\d\.\d+")


@claim("test suite", r"The second runs the test suite[^.]*\.")
def test_suite(context):
    if context["quick"] or context["skip_tests"]:
        return "not run (--quick / --skip-tests)", None
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider"], cwd=ROOT,
                          capture_output=True, text=True)
    wall = time.perf_counter() - started
    lines = done.stdout.strip().splitlines()
    tail = lines[-1] if lines else done.stderr.strip()[-200:]
    failed = [line.removeprefix("FAILED ") for line in lines if line.startswith(("FAILED", "ERROR"))]
    named = f" ({'; '.join(failed)})" if failed else ""
    return f"{wall:.0f} s wall: {tail}{named}", done.returncode == 0


# ------------------------------------------------------------------------ results and restarts

def default_results(context):
    """The default run of both backends on the sample images (shared by the checks below)."""
    if "results" not in context:
        from restart import SAMPLE_IMAGES
        from restart import default_results as run

        names = QUICK_SAMPLES if context["quick"] else SAMPLE_IMAGES
        context["results"] = run(names)
    return context["results"]


@claim("faithful start", r"or start from a curve, a mask, a result")
def faithful_start(context):
    """segment(image, init=res, max_num_iter=0) returns res (DESIGN.md, issue 22)."""
    from restart import restart_rows

    rows = restart_rows([], results=default_results(context))
    same = [r for r in rows if r["backend"] == r["start"]]
    other = [r for r in rows if r["backend"] != r["start"]]
    worst_energy = max(abs(r["energy_change"]) for r in same)
    worst_pixels = max(r["mask_changed"] for r in same)
    worst_other = max(r["mask_change"] for r in other)
    held = sum(r["ok"] for r in rows)
    text = (f"{held}/{len(rows)} starts hold; same backend: worst |dJ|/J {worst_energy:.1e}, "
            f"{worst_pixels} px; from the other: worst {100 * worst_other:.3f} % of the mask")
    return text, held == len(rows)


@claim("stationary", r"continuing with a 100× smaller `tol` changes J by < 0\.1 % and the mask by "
                     r"< 0\.1 % of its area on \d+ of the \d+ runs")
def stationary(context):
    from restart import stationarity_rows

    rows = stationarity_rows([], results=default_results(context))
    held = sum(r["ok"] for r in rows)
    stated = int(find(r"\d+ of the \d+ runs over the sample images")[1].split()[0])
    failing = ", ".join(f"{r['image']} ({r['backend']}: J {100 * r['energy_change']:+.2f} %, mask "
                        f"{100 * r['mask_change']:.2f} %)" for r in rows if not r["ok"])
    return f"{held}/{len(rows)} hold" + (f"; not: {failing}" if failing else ""), held >= stated


@claim("sample images", r"All \d+ sample images are segmented and converge on both backends; \d+ of \d+ runs "
                        r"end away from their start")
def samples_converge(context):
    import activecontour as ac

    results = default_results(context)
    converged = moved = 0
    for (_, backend), (image, result, _) in results.items():
        converged += bool(result.success)
        start = ac.segment(image, backend=backend, max_num_iter=0)
        moved += bool(np.any(start.mask != result.mask))
    n = len(results)
    stated = int(find(r"\d+ of \d+ runs end away from their start")[1].split()[0])
    return f"{converged}/{n} converge, {moved}/{n} moved from their start", converged == n and moved >= stated


# -------------------------------------------------------------------------- docs/performance.md

def robustness(context):
    """bench_robust's synthetic cases: (name, {method: Dice}, {backend: seconds})."""
    if "robust" not in context:
        import bench_robust

        from activecontour import synthetic

        rows = []
        for name, make in bench_robust.synthetic_cases(context["quick"]):
            if name.startswith("small"):
                continue
            image, truth = make()
            dice, seconds = {}, {}
            for backend in ("polygon", "levelset"):
                result, seconds[backend] = bench_robust.ours(image, backend)
                dice[backend] = synthetic.dice(result.mask, truth)
            if image.size <= 1024**2:
                for peer, (mask, _) in bench_robust.peers(image).items():
                    dice[peer] = synthetic.dice(mask, truth)
            rows.append((name, dice, seconds))
        context["robust"] = rows
    return context["robust"]


@claim("robustness",
       r"on all \d+ synthetic cases .*?the polygon's Dice is [\d.]+–[\d.]+ and at least every peer's")
def robust_polygon(context):
    return _robust("polygon", context)


@claim("robustness (level set)", r"the level set's is [\d.]+–[\d.]+ and at least every peer's[^.]*\.")
def robust_levelset(context):
    return _robust("levelset", context)


def _robust(backend, context):
    rows = robustness(context)
    ours = [dice[backend] for _, dice, _ in rows]
    behind = []
    for name, dice, _ in rows:
        peers = [value for method, value in dice.items() if method not in ("polygon", "levelset")]
        if peers and dice[backend] < max(peers):
            behind.append(f"{name} ({dice[backend]:.4f} < {max(peers):.4f})")
    text = f"{len(rows)} cases: Dice {min(ours):.4f}–{max(ours):.4f}"
    text += f"; below a peer on {', '.join(behind)}" if behind else "; at least every peer's on all"
    return text, None  # the sentence names its own exceptions: read them against this


@claim("large images",
       r"2048² in [\d.]+ s, 4096² in [\d.]+ s \(polygon\); [\d.]+ s and [\d.]+ s \(level set\)")
def large_images(context):
    if context["quick"]:
        return "not run (--quick: sizes up to 1024)", None
    times = {name: seconds for name, _, seconds in robustness(context)}
    stated = [float(x) for x in re.findall(r"[\d.]+(?= s)", find(
        r"2048² in [\d.]+ s, 4096² in [\d.]+ s \(polygon\); [\d.]+ s and [\d.]+ s \(level set\)")[1])]
    measured = [times["disk 2048 snr4"]["polygon"], times["disk 4096 snr4"]["polygon"],
                times["disk 2048 snr4"]["levelset"], times["disk 4096 snr4"]["levelset"]]
    holds = all(m <= TIME_SLACK * s for m, s in zip(measured, stated, strict=True))
    return ("polygon 2048² {:.2f} s, 4096² {:.2f} s; level set {:.2f} s, {:.2f} s (wall)".format(*measured),
            holds)


@claim("noisy 256²",
       r"Dice [\d.]+–[\d.]+ in [\d.]+–[\d.]+ s \(median [\d.]+ s\), [\d.]+–[\d.]+× faster than `chan_vese`")
def noisy_256(context):
    import bench_polygon

    quietly(bench_polygon.warm_up)
    dice, seconds, speedups = quietly(bench_polygon.accuracy_table, [1] if context["quick"] else [1, 2, 3])
    stated = find(r"Dice [\d.]+–[\d.]+ in [\d.]+–[\d.]+ s \(median [\d.]+ s\), [\d.]+–[\d.]+× faster")[1]
    low_dice = float(re.search(r"Dice ([\d.]+)", stated).group(1))
    median_time = float(re.search(r"median ([\d.]+) s", stated).group(1))
    holds = min(dice) >= low_dice and np.median(seconds) <= TIME_SLACK * median_time
    return (f"Dice {min(dice):.3f}–{max(dice):.3f} in {min(seconds):.2f}–{max(seconds):.2f} s (median "
            f"{np.median(seconds):.2f} s), {min(speedups):.1f}–{max(speedups):.1f}× faster"), holds


@claim("cost per iteration", r"An iteration costs [\d.]+–[\d.]+ ms from 256² to 2048²")
def per_iteration(context):
    import bench_polygon

    sizes = [256, 512, 1024] if context["quick"] else [256, 512, 1024, 2048]
    costs = quietly(bench_polygon.scaling_table, sizes)
    high = float(re.findall(r"[\d.]+(?= ms)", find(r"An iteration costs [\d.]+–[\d.]+ ms")[1])[0])
    return (f"{min(costs):.2f}–{max(costs):.2f} ms from 256² to {sizes[-1]}² (wall, median per run)",
            max(costs) <= TIME_SLACK * high)


@claim("cold start", r"takes [\d.]+× the\s?wall time of a fresh Python process running `chan_vese`[^)]*\)")
def cold_start(context):
    import bench_scale

    with tempfile.TemporaryDirectory() as cache:
        ours_wall, ours_cpu, theirs_wall, theirs_cpu = quietly(bench_scale.cold_start, Path(cache),
                                                               2 if context["quick"] else 5)
    stated = number(r"takes [\d.]+× the\s?wall time of a fresh Python process")
    ratio = ours_wall / theirs_wall
    return (f"{ratio:.2f}× ({ours_wall:.2f} s against {theirs_wall:.2f} s wall; CPU {ours_cpu:.2f} s against "
            f"{theirs_cpu:.2f} s)"), ratio <= TIME_SLACK * stated


# ---------------------------------------------------------------------------- docs/method.md

@claim("N regions' energy",
       r"abs\(ac\.chan_vese_energy\(image, regions=res\.class_contours[^<]*<= 1e-12 \* res\.energy")
def regions_energy(context):
    import activecontour as ac

    image = context.setdefault("coins", __import__("skimage.data", fromlist=["coins"]).coins())
    out = []
    for backend in ("polygon", "levelset"):
        res = ac.segment(image, n_regions=3, backend=backend)
        gap = abs(ac.chan_vese_energy(image, regions=res.class_contours, mu=res.mu) - res.energy) / res.energy
        out.append(gap)
    return f"relative gap {out[0]:.1e} (polygon), {out[1]:.1e} (level set)", max(out) <= 1e-12


@claim("smooth light's energy",
       r"ac\.chan_vese_energy\(image, res\.contours, mu=res\.mu, light=res\.light\) == res\.energy")
def light_energy(context):
    import activecontour as ac

    image = context.setdefault("coins", __import__("skimage.data", fromlist=["coins"]).coins())
    res = ac.segment(image, fit="smooth")
    poisson = ac.segment(image, fit="smooth", noise="poisson")
    equal = (ac.chan_vese_energy(image, res.contours, mu=res.mu, light=res.light) == res.energy,
             ac.chan_vese_energy(image, poisson.contours, mu=poisson.mu, light=poisson.light,
                                 noise="poisson") == poisson.energy)
    return f"gaussian {equal[0]}, poisson {equal[1]}", all(equal)


# ---------------------------------------------------------------------------- docs/objects.md

@claim("objects example", r"F1 [\d.]+ here at IoU >= 0\.5 \(\d+ of \d+\)")
def objects_example(context):
    namespace = run_block(python_block("match_instances(res.labels, truth)"))
    score = namespace["score"]
    stated = number(r"F1 [\d.]+ here")
    return (f"F1 {score['f1']:.3f} ({score['tp']} of {score['n_true']})",
            round(score["f1"], 2) >= stated)


@claim("DSB 2018 split", r"DSB 2018 nuclei: F1 [\d.]+")
def dsb_split(context):
    import bench_objects

    _, res, truth, score, ratio = quietly(bench_objects.dsb, 2)  # least of 2: not the first call's imports
    if truth is None:
        return "not run (StarDist's DSB mask is not installed)", None
    stated = float(find(r"DSB 2018 nuclei: F1 [\d.]+")[1].split()[-1])
    return (f"F1 {score:.3f} ({res.labels.max()} objects of {len(np.unique(truth)) - 1}; separate=True "
            f"costs {ratio:.2f}x)", round(score, 2) >= stated)


# ----------------------------------------------------------------------- docs/scikit-image.md

def compat(context):
    if "compat" not in context:
        import bench_compat

        names = bench_compat.SAMPLES[:4] if context["quick"] else bench_compat.SAMPLES
        calls = ("gallery",) if context["quick"] else tuple(bench_compat.CALLS)
        rows = list(bench_compat.compat_rows(names, calls))
        context["compat"] = (rows, bench_compat.summary(rows))
    return context["compat"]


@claim("drop-in energy", r"ours ends at a (?:lower or equal|lower) \(6\.38\) on \d+ of \d+[^.;]*")
def compat_energy(context):
    rows, total = compat(context)
    worse = ", ".join(f"{r['image']} {r['call']} {100 * (r['j_ours'] - r['j_sk']) / abs(r['j_sk']):+.2f} %"
                      for r in rows if r["j_ours"] > r["j_sk"])
    text = f"no higher on {total['lower']} of {total['n']} (images x calls)"
    return text + (f"; higher: {worse}" if worse else ""), total["lower"] == total["n"]


@claim("drop-in time", r"[Oo]ur whole call takes <= 0\.5x scikit-image's (?:CPU )?time on \d+ of \d+[^.]*")
def compat_time(context):
    rows, total = compat(context)
    slow = ", ".join(f"{r['image']} {r['call']} {r['cpu_ours'] / r['cpu_sk']:.2f}x" for r in rows
                     if r["cpu_ours"] > 0.5 * r["cpu_sk"])
    stated = int(re.search(r"time on (\d+) of", find(r"[Oo]ur whole call takes <= 0\.5x scikit-image's "
                                                        r"(?:CPU )?time on \d+ of")[1]).group(1))
    return (f"<= 0.5x on {total['faster']} of {total['n']} (median {total['median_ratio']:.2f}x)"
            + (f"; slower: {slow}" if slow else ""), total["faster"] >= stated)


# ------------------------------------------------------------------------------------- the run

def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a few images per check, no test suite")
    parser.add_argument("--only", nargs="*", help="claims whose name contains one of these words")
    parser.add_argument("--skip-tests", action="store_true", help="do not time the test suite")
    args = parser.parse_args()
    context = {"quick": args.quick, "skip_tests": args.skip_tests}
    started = time.perf_counter()
    print(f"{'claim':28s} | {'where':22s} | {'the document says':60s} | {'measured':60s} | holds")
    for item in CLAIMS:
        if args.only and not any(word in item.name for word in args.only):
            continue
        located = find(item.pattern)
        where, says = located if located else ("(not found)", "(the sentence is not in README or docs/)")
        try:
            measured, holds = item.measure(context)
        except Exception as error:  # a claim whose measurement fails says so, the others still run
            measured, holds = f"failed: {type(error).__name__}: {str(error).splitlines()[0][:120]}", False
        verdict = "-" if holds is None else ("yes" if holds else "NO")
        print(f"{item.name:28s} | {where:22s} | {says:60s} | {measured:60s} | {verdict}", flush=True)
    print(f"({time.perf_counter() - started:.0f} s{', --quick' if args.quick else ''})")


if __name__ == "__main__":
    main()
