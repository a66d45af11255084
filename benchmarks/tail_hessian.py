"""What the polygon flow's tail is made of: the Hessian of (6.38) at a converged result, split into
the vertices' normal and tangential parts.

Issue 24 item 6 asks for a faster tail (a warm frame at 0.5x a cold one).  This script measures
where the energy left after "converged" lies.  At the default run's result on an image, the Hessian
of the reduced energy ``min_c J`` over the vertex positions is taken by central differences of the
exact load (6.41) (``activecontour.energy.evaluate``; the load is J's exact gradient, so the
differences are exact up to rounding and the Hessian's kinks where an edge crosses a grid line),
and written in each vertex's frame (normal nu, tangent tau: the bisector of its edges).

Columns:

- ``K``: vertices; ``normal``, ``tangent``: the eigenvalue range of the Hessian's normal-normal and
  tangent-tangent blocks, and ``neg``: how many of the tangential block's eigenvalues are negative;
  ``coupling``: the Frobenius norm of the normal-tangent block over the normal block's.
- ``f_n``, ``f_t``: the root-mean-square normal and tangential load (what is left of the gradient).
- ``dJ_n``: the normal Newton decrement ``0.5 f_n H_nn^-1 f_n`` (what a Newton step along the normals
  would still gain); ``dJ_t``: the tangential one with the block's eigenvalues' moduli floored at
  ``FLOOR`` (the block is indefinite: a bound of what re-spacing the vertices still gains).
- ``dJ 300``: what ``MORE`` further iterations with ``tol=0`` actually gain; ``it``: the default
  run's iterations.

What it showed when written (the scene of ``bench_sequence``, 512^2 at SNR 2, frames 1 and 2, and
four sample images with at most ``MAX_VERTICES`` vertices), per row ``dJ_n``, ``dJ_t``, ``dJ 300``:
scene frames 8e-5, 1.2e-2, 1.3e-2 and 3e-4, 1.1e-2, 1.3e-2; shepp_logan_phantom 1e-3, 0.10, 0.17;
cell 4e-6, 3e-5, 1.3e-4.  The normal block is positive definite and well conditioned on those (0.01
.. 2.4), the tangential block two orders smaller and indefinite (a tenth to a quarter of its
eigenvalues negative): the normal part has converged, and what further iterations gain is the
vertices re-spaced along the boundary, which moves its chords by a fraction of a pixel (the stop
rule's measure and the area between the polygons at the start and end of a block agree, about
2e-3 .. 4e-4 px per iteration in the tail of a warm frame).  moon is the exception: a normal mode
with curvature 2e-5 (a faint stretch of boundary) makes the quadratic model's normal decrement
meaningless (23 against 0.01 gained).  Weighing the tangential part of the velocity less (a
metric ``a(V.nu, Y.nu) + 0.1 a(V.tau, Y.tau)``) cut the iterations by a quarter but stopped some
runs at a higher J, and on text let vertices cluster until an edge vanished (see the branch tail5's
history and its report).

usage (from the project's root):
    python benchmarks/tail_hessian.py [--frames 1,2] [--images cell,moon]
"""

from __future__ import annotations

import argparse

import numpy as np
from bench_sequence import Frames, scene
from restart import load

import activecontour as ac
from activecontour.energy import evaluate
from activecontour.geometry.curve import stack_curves
from activecontour.problem import prepare
from activecontour.settings import Settings

STEP = 1e-5  # px: the central differences' step
FLOOR = 1e-4  # the tangential eigenvalues' moduli are floored here for its decrement
MORE = 300  # iterations of the continuation with tol = 0
MAX_VERTICES = 3000  # the Hessian is dense: (2K)^2 numbers, 4K evaluations


def hessian(model, params, points, next_index):
    """The symmetrised Hessian (2K x 2K, coordinates interleaved as ``points.ravel()``) and the load."""
    x = points.ravel()
    columns = []
    for j in range(len(x)):
        loads = []
        for sign in (1.0, -1.0):
            moved = x.copy()
            moved[j] += sign * STEP
            trial = evaluate(model, moved.reshape(-1, 2), next_index, params, gradient=True)
            loads.append(trial.load.ravel())
        columns.append((loads[0] - loads[1]) / (2 * STEP))
    h = np.array(columns).T
    return 0.5 * (h + h.T), evaluate(model, points, next_index, params, gradient=True).load


def vertex_tangents(points, next_index):
    """The unit bisector of every vertex's two edge directions (stacked curves)."""
    previous = np.empty_like(next_index)
    previous[next_index] = np.arange(len(next_index))
    d = points[next_index] - points
    unit = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    tangents = unit + unit[previous]
    return tangents / np.hypot(tangents[:, 0], tangents[:, 1])[:, None]


def row(name, image):
    result = ac.segment(image)
    problem = prepare(image, Settings.of({}))
    model, params = problem.model()[0], problem.working
    points, next_index, _ = stack_curves(result.contours)
    k = len(points)
    if k > MAX_VERTICES:
        return dict(image=name, k=k)
    own = evaluate(model, points, next_index, params).energy
    units = result.energy / own  # the result's energy units over the working frame's
    h, load = hessian(model, params, points, next_index)
    tangents = vertex_tangents(points, next_index)
    normals = np.column_stack([tangents[:, 1], -tangents[:, 0]])
    frame = np.zeros((2 * k, 2 * k))  # columns: the normals, then the tangents
    frame[0::2, :k], frame[1::2, :k] = np.diag(normals[:, 0]), np.diag(normals[:, 1])
    frame[0::2, k:], frame[1::2, k:] = np.diag(tangents[:, 0]), np.diag(tangents[:, 1])
    rotated = frame.T @ h @ frame
    nn, tt, nt = rotated[:k, :k], rotated[k:, k:], rotated[:k, k:]
    normal, tangent = np.linalg.eigvalsh(nn), np.linalg.eigh(tt)
    f_n, f_t = np.einsum("ij,ij->i", load, normals), np.einsum("ij,ij->i", load, tangents)
    along = tangent.eigenvectors.T @ f_t
    again = ac.segment(image, init=result, tol=0.0, max_num_iter=MORE)
    return dict(image=name, k=k, it=result.n_iter, normal=(normal.min(), normal.max()),
                tangent=(tangent.eigenvalues.min(), tangent.eigenvalues.max()),
                negative=int(np.count_nonzero(tangent.eigenvalues < 0)),
                coupling=np.linalg.norm(nt) / np.linalg.norm(nn),
                f=(np.sqrt(np.mean(f_n**2)), np.sqrt(np.mean(f_t**2))),
                decrement=(units * 0.5 * f_n @ np.linalg.solve(nn, f_n) if normal.min() > 0 else np.nan,
                           units * 0.5 * np.sum(along**2 / np.maximum(np.abs(tangent.eigenvalues), FLOOR))),
                gained=result.energy - again.energy)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", default="1,2", help="frames of bench_sequence's scene (30 frames, 512^2)")
    parser.add_argument("--images", default="", help="sample images (at most MAX_VERTICES vertices)")
    args = parser.parse_args(argv)
    cases = []
    if args.frames:
        source = Frames(scene(30, 512), 512)
        cases += [(f"scene frame {t}", source.frame(int(t))[0]) for t in args.frames.split(",")]
    cases += [(name, load(name)) for name in args.images.split(",") if name]
    print(f"{'image':>16} {'K':>5} {'it':>4} {'normal':>17} {'tangent':>19} {'neg':>4} {'coupling':>8} "
          f"{'f_n':>8} {'f_t':>8} {'dJ_n':>8} {'dJ_t':>8} {'dJ ' + str(MORE):>8}")
    for name, image in cases:
        r = row(name, image)
        if "it" not in r:
            print(f"{name:>16} {r['k']:5d}  (more than {MAX_VERTICES} vertices: skipped)")
            continue
        print(f"{name:>16} {r['k']:5d} {r['it']:4d} {r['normal'][0]:8.1e}..{r['normal'][1]:7.1e} "
              f"{r['tangent'][0]:+9.1e}..{r['tangent'][1]:8.1e} {r['negative']:4d} {r['coupling']:8.3f} "
              f"{r['f'][0]:8.1e} {r['f'][1]:8.1e} {r['decrement'][0]:8.1e} {r['decrement'][1]:8.1e} "
              f"{r['gained']:8.1e}", flush=True)


if __name__ == "__main__":
    main()
