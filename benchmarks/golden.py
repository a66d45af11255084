#!/usr/bin/env python3
"""Golden check: sha256 hashes of the outputs of a fixed corpus, so that a change that should not
change any number (moving files, issue 21) can be proven byte-identical.

The corpus (one *case* per line of ``--list``):

* ``segment/<image>/<backend>/K<k>``: :func:`activecontour.segment` with its defaults on each of the
  25 scikit-image samples of ``../shared/tools/contact_sheet.py`` (loaded the same way:
  ``binary_blobs(rng=1)``, the others as ``skimage.data`` gives them), on ``backend="polygon"`` and
  ``"levelset"``, with ``n_regions=2`` and ``3`` (100 cases).  Hashed: every field of the result
  (mask, classes, labels, contours as float64, energy, energies, c_in, c_out, n_iter, message, the
  objects table, ...) and the energy of its contours by :func:`activecontour.chan_vese_energy`.
* ``sequence/disks``: :func:`activecontour.segment_sequence` of a short synthetic time-lapse
  (:func:`activecontour.synthetic.disk_sequence`: 4 frames of 96^2, a drift, a breathing disk and
  a division): labels, tracks, graph, objects table, and every frame's result.
* ``files/coins/<backend>/K<k>``: one result written in every contour format and every object
  format (:func:`activecontour.io.save_result`, and :func:`activecontour.io.write_contours` of the
  bare curves): the bytes of each file.

Only public entry points are used (``activecontour``, ``activecontour.io``,
``activecontour.synthetic``), so the script runs unchanged after a move.

Canonical forms (what is hashed, and why):

* an array: its dtype (little-endian), its shape and its C-order bytes; a float: its IEEE-754 bytes
  (``-0.0`` and ``0.0`` differ, every NaN payload is one NaN); lists and dicts item by item, in
  their order (a table's column order is part of its CSV), except ``SequenceResult.graph`` whose
  keys are sorted (an unordered map of child -> parents).
* a ZIP file (``_rois.zip``, ``_contours.npz``): its members' names, compression and contents,
  not its raw bytes, because the ROI archive's entries carry the wall-clock time they were written
  (``zipfile.ZipFile.writestr`` of a name stamps ``time.localtime()``).  No other output holds a
  time or a date: results have no timing field, PNGs are written by OpenCV without tIME chunks,
  TIFFs by tifffile without a DateTime tag, and the NPZ's entries have a fixed 1980 stamp.
* BLAS and OpenCV run with one thread (set before numpy is imported, in this process and in its
  workers): ``-j`` workers then do not oversubscribe the cores, and a case's CPU time is its own.
  It is not needed for the hashes: 23 cases run with two BLAS and two OpenCV threads in one process
  hashed the same.
* The same bytes on every x86-64 machine with AVX2 (:data:`PINNED`, set before numpy is imported):
  OpenBLAS picks its kernels by the processor, and numpy and OpenCV dispatch some loops to AVX-512
  where it exists; each gives results that differ in the last bits (a dot product summed in another
  order, ``exp`` by another polynomial). Stored on one machine, 76 of the 103 cases hashed
  differently on an AMD EPYC with AVX-512 (whose environment sets ``OPENBLAS_CORETYPE=Haswell``),
  the library unchanged; with OpenBLAS's SkylakeX kernels forced there, the cheap cell case hashed
  as stored again. So the
  corpus runs with OpenBLAS's Haswell kernels and numpy and OpenCV kept to AVX2: any machine with
  AVX2 runs the same instructions. These three are set whatever the environment says (a machine may
  set its own ``OPENBLAS_CORETYPE``, as this one does); the thread counts only where unset.

usage:
    python3 benchmarks/golden.py --write         # compute every case and store benchmarks/golden.json
    python3 benchmarks/golden.py                 # recompute, one line per case: same / CHANGED
    python3 benchmarks/golden.py --only coins    # the cases whose name contains a pattern (fnmatch
                                                 # when it has * ? [)
    python3 benchmarks/golden.py -j 2            # worker processes (default 2)
    python3 benchmarks/golden.py --list          # the case names
Check mode exits 1 when a case changed (it names the parts that did) or is not stored, 2 when one
failed to run.
"""

from __future__ import annotations

import os

#: Set before numpy is imported (see the docstring): one BLAS thread where unset, and the same
#: kernels on every x86-64 machine with AVX2 always.
THREADS = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
PINNED = {"OPENBLAS_CORETYPE": "Haswell",
          "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
          "OPENCV_CPU_DISABLE": "AVX512-SKX,AVX512-CLX,AVX512-CNL,AVX512-ICL,AVX512-COMMON,AVX_VNNI"}
if __name__ == "__main__":  # the script and its -j workers (spawned: they inherit the environment);
    for _name, _value in THREADS.items():  # an importer (the tests) keeps its own environment, or
        os.environ.setdefault(_name, _value)  # its children would run other kernels than it does
    os.environ.update(PINNED)

import argparse  # noqa: E402
import fnmatch  # noqa: E402
import hashlib  # noqa: E402
import io as _stdio  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import struct  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
import zipfile  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

GOLDEN = Path(__file__).with_name("golden.json")

#: The scikit-image samples of ../shared/tools/contact_sheet.py, in its order.
SAMPLES = ["astronaut", "binary_blobs", "brick", "camera", "cat", "cell", "checkerboard", "chelsea",
           "clock", "coffee", "coins", "colorwheel", "grass", "gravel", "horse", "hubble_deep_field",
           "immunohistochemistry", "logo", "microaneurysms", "moon", "page", "retina", "rocket",
           "shepp_logan_phantom", "text"]
BACKENDS = ("polygon", "levelset")
REGIONS = (2, 3)
#: The result written in every format: (image, backend, K).
FILE_CASES = [("coins", "polygon", 2), ("coins", "polygon", 3)]

#: The fields of a result that are hashed (a field missing after a change is reported, not skipped).
RESULT_FIELDS = ["mask", "contours", "c_in", "c_out", "energy", "energies", "n_iter", "success", "status",
                 "message", "backend", "phi", "mu", "c_in_image", "c_out_image", "labels", "objects",
                 "object_contours", "classes", "constants", "light", "roi", "n_regions", "class_contours"]
SEQUENCE_FIELDS = ["labels", "tracks", "graph", "objects", "frame_indices"]


# ---------------------------------------------------------------- the corpus


def case_names():
    names = [f"segment/{image}/{backend}/K{k}" for image in SAMPLES for backend in BACKENDS for k in REGIONS]
    names.append("sequence/disks")
    names += [f"files/{image}/{backend}/K{k}" for image, backend, k in FILE_CASES]
    return names


def load_sample(name):
    """A scikit-image sample, loaded as contact_sheet.py loads it."""
    import skimage.data as data

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return data.binary_blobs(rng=1) if name == "binary_blobs" else getattr(data, name)()


def sequence_frames():
    """4 frames of 96^2 at SNR 5: disk 1 drifts, disk 2 breathes, disk 3 divides into 4 and 5."""
    from activecontour import synthetic

    frames = []
    for t in range(4):
        disks = [(1, (24 + 3 * t, 24), 12), (2, (70, 26), 10 + t)]
        if t < 2:
            disks.append((3, (48, 70), 13))
        else:
            disks += [(4, (34 - 4 * t, 70), 9), (5, (62 + 4 * t, 70), 9)]
        frames.append(disks)
    images, _ = synthetic.disk_sequence(96, frames, sigma=0.1, seed=0)
    return images


# ---------------------------------------------------------------- canonical bytes


def canonical(value):
    """Bytes that stand for ``value``: equal bytes if and only if equal outputs (type included)."""
    out = _stdio.BytesIO()
    _encode(value, out)
    return out.getvalue()


def _encode(value, out):
    if value is None:
        out.write(b"N")
    elif isinstance(value, (bool, np.bool_)):
        out.write(b"T" if value else b"F")
    elif isinstance(value, (int, np.integer)):
        text = str(int(value)).encode()
        out.write(b"i" + struct.pack("<Q", len(text)) + text)
    elif isinstance(value, (float, np.floating)):
        value = float(value)
        out.write(b"f" + (struct.pack("<d", math.nan) if math.isnan(value) else struct.pack("<d", value)))
    elif isinstance(value, str):
        text = value.encode()
        out.write(b"s" + struct.pack("<Q", len(text)) + text)
    elif isinstance(value, bytes):
        out.write(b"b" + struct.pack("<Q", len(value)) + value)
    elif isinstance(value, np.ndarray):
        array = np.ascontiguousarray(value)
        if array.dtype == object:
            _encode(array.tolist(), out)
            return
        array = array.astype(array.dtype.newbyteorder("<"), copy=False)
        if array.dtype.kind == "f":  # one NaN
            array = np.where(np.isnan(array), np.nan, array).astype(array.dtype)
        head = f"{array.dtype.str}{array.shape}".encode()
        out.write(b"a" + struct.pack("<Q", len(head)) + head)
        data = array.tobytes()
        out.write(struct.pack("<Q", len(data)) + data)
    elif isinstance(value, (list, tuple)):
        out.write(b"l" + struct.pack("<Q", len(value)))
        for item in value:
            _encode(item, out)
    elif isinstance(value, dict):
        out.write(b"d" + struct.pack("<Q", len(value)))
        for key, item in value.items():
            _encode(key, out)
            _encode(item, out)
    else:
        raise TypeError(f"no canonical form for {type(value).__name__}")


def digest(value):
    return hashlib.sha256(canonical(value)).hexdigest()


def file_digest(path):
    """sha256 of a file's bytes; of its members (name, compression, contents) for a ZIP archive,
    whose entries may carry the time they were written (see the module docstring)."""
    data = Path(path).read_bytes()
    if data[:4] == b"PK\x03\x04":
        with zipfile.ZipFile(_stdio.BytesIO(data)) as archive:
            data = canonical([[info.filename, info.compress_type, archive.read(info)]
                              for info in archive.infolist()])
    return hashlib.sha256(data).hexdigest()


def curves64(curves):
    """Curves (or lists of curves) as float64 arrays."""
    if curves is None:
        return None
    if isinstance(curves, np.ndarray):
        return np.asarray(curves, dtype=np.float64)
    return [curves64(c) for c in curves]


def result_parts(res):
    """field -> hash of one SegmentationResult."""
    parts = {}
    for name in RESULT_FIELDS:
        if not hasattr(res, name):
            parts[name] = "missing"
            continue
        value = getattr(res, name)
        if name in ("contours", "object_contours", "class_contours"):
            value = curves64(value)
        parts[name] = digest(value)
    return parts


def result_summary(res):
    return {"energy": float(res.energy), "n_iter": int(res.n_iter), "status": int(res.status),
            "contours": len(res.contours), "objects": 0 if res.labels is None else int(res.labels.max())}


# ---------------------------------------------------------------- the cases


def _segment(image_name, backend, k):
    import activecontour as ac

    image = load_sample(image_name)
    return image, ac.segment(image, backend=backend, n_regions=k)


def run_segment(image_name, backend, k):
    import activecontour as ac

    image, res = _segment(image_name, backend, k)
    parts = result_parts(res)
    if k == 2:
        evaluated = ac.chan_vese_energy(image, res.contours, mu=res.mu)
    else:
        evaluated = ac.chan_vese_energy(image, regions=res.class_contours, mu=res.mu)
    parts["chan_vese_energy"] = digest(float(evaluated))
    return parts, result_summary(res)


def run_sequence():
    import activecontour as ac

    seq = ac.segment_sequence(sequence_frames())
    parts = {}
    for name in SEQUENCE_FIELDS:
        value = getattr(seq, name, "missing")
        if name == "graph" and isinstance(value, dict):  # an unordered map: sort its keys
            value = {int(key): sorted(int(v) for v in value[key]) for key in sorted(value)}
        parts[name] = "missing" if isinstance(value, str) else digest(value)
    for t, res in enumerate(seq.results):
        parts.update({f"frame{t}.{name}": h for name, h in result_parts(res).items()})
    summary = {"frames": len(seq.results), "tracks": len(np.unique(seq.tracks[:, 0])),
               "energies": [round(float(r.energy), 9) for r in seq.results]}
    return parts, summary


def run_files(image_name, backend, k):
    from activecontour import io

    image, res = _segment(image_name, backend, k)
    formats = list(io.CONTOUR_FORMATS)
    objects = list(io.OBJECT_FORMATS)
    parts = {}
    with tempfile.TemporaryDirectory() as tmp:
        stem = Path(tmp) / "result"
        for path in io.save_result(res, image, stem, formats, objects=objects):
            parts[path.name] = file_digest(path)
        for fmt in formats:  # the bare curves, with the image's shape and a metadata entry
            path = Path(tmp) / f"curves.{fmt}"
            io.write_contours(path, res.contours, metadata={"case": "golden"}, image_shape=res.mask.shape)
            parts[path.name] = file_digest(path)
    return parts, {"files": len(parts), "energy": float(res.energy)}


def run_case(name):
    """(name, parts, summary, seconds, error) of one case; seconds of CPU time (this process's:
    BLAS has one thread), which a loaded machine changes less than the wall time."""
    start = time.process_time()
    try:
        kind, *rest = name.split("/")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if kind == "segment":
                parts, summary = run_segment(rest[0], rest[1], int(rest[2][1:]))
            elif kind == "files":
                parts, summary = run_files(rest[0], rest[1], int(rest[2][1:]))
            elif kind == "sequence":
                parts, summary = run_sequence()
            else:
                raise ValueError(f"unknown case {name!r}")
    except Exception as exc:  # reported per case; the others still run
        return name, None, None, time.process_time() - start, f"{type(exc).__name__}: {exc}"
    if caught:  # the library's warnings, for people (not hashed)
        summary["warnings"] = sorted({f"{w.category.__name__}: {w.message} "
                                      f"({Path(w.filename).name}:{w.lineno})" for w in caught})
    return name, parts, summary, time.process_time() - start, None


def case_hash(parts):
    return hashlib.sha256(canonical(sorted(parts.items()))).hexdigest()


def entry(parts, summary, seconds):
    """What golden.json holds for a case: its hash, each part's (16 hex digits, to name what
    changed), a summary for people and its CPU seconds (not hashed: they order the next run)."""
    return {"hash": case_hash(parts), "summary": summary, "cpu_s": round(seconds, 1),
            "parts": {name: h[:16] for name, h in sorted(parts.items())}}


# ---------------------------------------------------------------- running


def _start_worker():
    import cv2

    cv2.setNumThreads(1)


def select(names, patterns):
    if not patterns:
        return names
    chosen = []
    for name in names:
        for pattern in patterns:
            if any(ch in pattern for ch in "*?[") and fnmatch.fnmatchcase(name, pattern) or pattern in name:
                chosen.append(name)
                break
    return chosen


def run_cases(names, jobs=2, stored=None, report=None):
    """Run ``names`` in ``jobs`` worker processes (in this one when jobs is 1), the longest first
    (by the stored CPU times, else in the corpus order); call
    ``report(name, parts, summary, seconds, error)`` as each finishes.  Returns
    {name: (parts, summary, seconds, error)}."""
    stored = stored or {}
    order = sorted(names, key=lambda n: -stored.get(n, {}).get("cpu_s", 0.0))
    results = {}

    def done(item):
        name, *rest = item
        results[name] = tuple(rest)
        if report is not None:
            report(*item)

    if jobs <= 1 or len(order) <= 1:
        _start_worker()
        for name in order:
            done(run_case(name))
        return results
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    context = multiprocessing.get_context("spawn")  # a fresh interpreter: nothing inherited
    with ProcessPoolExecutor(jobs, mp_context=context, initializer=_start_worker) as pool:
        for item in _unordered(pool, order):
            done(item)
    return results


def _unordered(pool, names):
    from concurrent.futures import as_completed

    futures = [pool.submit(run_case, name) for name in names]
    for future in as_completed(futures):
        yield future.result()


def load_golden(path=GOLDEN):
    if not Path(path).exists():
        return {}
    return json.loads(Path(path).read_text())["cases"]


def compare(name, parts, stored):
    """'same', 'new' or 'CHANGED: part, part, ...' of a computed case against its stored entry."""
    if stored is None:
        return "new"
    if case_hash(parts) == stored["hash"]:
        return "same"
    old = stored.get("parts", {})
    changed = sorted(p for p in set(parts) | set(old) if parts.get(p, "absent")[:16] != old.get(p, "absent"))
    return "CHANGED: " + ", ".join(changed)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="store the hashes in golden.json")
    ap.add_argument("--only", action="append", default=[], metavar="PATTERN",
                    help="the cases whose name contains PATTERN (or matches it, with * ? [); repeatable")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--list", action="store_true", help="print the case names and exit")
    ap.add_argument("--golden", type=Path, default=GOLDEN, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    names = select(case_names(), args.only)
    if args.list:
        print("\n".join(names))
        return 0
    if not names:
        print(f"no case matches {args.only}", file=sys.stderr)
        return 2
    golden = load_golden(args.golden)
    if not args.write and not golden:
        print(f"{args.golden} does not exist: run with --write first", file=sys.stderr)
        return 2
    width = max(map(len, names))
    verdicts = {}

    def report(name, parts, summary, seconds, error):
        if error is not None:
            verdicts[name] = f"FAILED: {error}"
        else:
            verdicts[name] = "written" if args.write else compare(name, parts, golden.get(name))
        print(f"{name:{width}s} {seconds:6.1f} s cpu  {verdicts[name]}", flush=True)

    start = time.perf_counter()
    results = run_cases(names, args.jobs, golden, report)
    wall = time.perf_counter() - start
    failed = sorted(n for n, v in verdicts.items() if v.startswith("FAILED"))
    changed = sorted(n for n, v in verdicts.items() if v.startswith("CHANGED") or v == "new")
    if args.write:
        if failed:
            print(f"not written: {len(failed)} case(s) failed", file=sys.stderr)
            return 2
        cases = dict(golden)
        cases.update({n: entry(*results[n][:3]) for n in names})
        cases = {n: cases[n] for n in case_names() if n in cases}
        document = {"about": "sha256 of the outputs of a fixed corpus: python3 benchmarks/golden.py",
                    "cases": cases}
        args.golden.write_text(json.dumps(document, indent=1) + "\n")
        print(f"wrote {len(names)} case(s) to {args.golden}")
    else:
        same = sum(v == "same" for v in verdicts.values())
        print(f"{same} same, {len(changed)} changed, {len(failed)} failed, "
              f"{sum(v == 'new' for v in verdicts.values())} not stored, of {len(names)}")
    print(f"total {wall:.1f} s wall ({args.jobs} worker(s))")
    if failed:
        return 2
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
