"""The polygon backend: the time-discrete gradient flow (6.30)-(6.31) of the Chan-Vese functional.

Per iteration k, on the polygon(s) Gamma^k:

1. c_in, c_out by (6.42) (unless fixed), and the load f_j = delta J(Gamma^k; phi_j e_d) of (6.41),
   both from one exact pass along the edges (:func:`activecontour.energy.evaluate`).
2. The velocity: ``b(V, Y) = -delta J(Y)`` (6.30)/(6.40), i.e. ``(M + l^2 K) V = -f`` for the H^1
   form (6.39) or ``M V = -f`` for the L^2 form (6.25).  Both components at once, O(K) per curve
   (:func:`fem.cyclic_solve`).  Then ``delta J(V) = -b(V, V) < 0`` (6.27): V is a descent direction.
   The length l (pixels) runs coarse to fine: it starts at ``smoothing``, which moves the curve as a
   whole, and is divided by 4 each time the flow stalls, down to ``min_smoothing`` (1 px: the
   book's form), which resolves corners and fine detail.
3. ``X^{k+1} = X^k + dt V^k`` (6.31), vertices kept inside the image domain, with dt chosen by
   backtracking until the Armijo condition ``J(X^{k+1}) <= J(X^k) + 1e-4 f . (X^{k+1} - X^k)`` holds.
   The first trial is twice the last accepted dt, at most the dt that moves the vertices by
   ``max_step`` pixels root-mean-square: the bulk of the curve sets the scale (the fastest vertex
   of a noisy image is an outlier, often 20x the median), so a step is scale-free (it does not
   depend on the image contrast) and a 300 px travel takes tens of iterations.
4. Mesh health: when an edge is shorter than half or longer than twice ``spacing``, the curve
   is resampled at equal arc length; the resampled curve is kept only if its energy is not above
   the previous iterate's, so the recorded energy sequence never increases.

The flow stalls when the contour stops getting anywhere: its mean normal displacement (the area it
sweeps over its length, in pixels) between the start and the end of a block of five iterations,
per iteration, falls below ``tol`` (see :class:`_Movement`).  No energy scale enters, so the test
means the same on every image: a relative energy decrease would stop earlier the larger or noisier
the image, as J holds the noise energy sigma^2 |D|.  A coarse l gives way to the next at 10 tol; a
stall at the finest l is convergence; the run also stops at ``max_num_iter``.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from activecontour import fem, topology
from activecontour.curve import edge_lengths, resample
from activecontour.energy import evaluate, stack_curves
from activecontour.initial import circle, initial_curves
from activecontour.raster import rasterize
from activecontour.result import FlowState, build_result

__all__ = ["segment_polygon"]

_VELOCITIES = ("h1", "l2")
_ARMIJO = 1e-4
_MAX_HALVINGS = 40
_WINDOW = 5  # iterations over which the movement is averaged for the stopping test
_SMOOTHING_FACTOR = 4.0
_STAGE_TOL = 10.0  # a coarse stage ends at 10 tol: the finer metric then makes faster progress
_MIN_EDGE = 1e-9
_RELATIVE_SMOOTHING = 0.5
_NUCLEATION_RADIUS = 4.0
_NUCLEATION_ROUNDS = 4
_NUCLEATION_TRIALS = 30
_REMESH_COOLDOWN = 10


def segment_polygon(model, init, params, *, max_num_iter, tol, callback, velocity="h1", spacing=1.0,
                    max_step=8.0, smoothing=30.0, min_smoothing=1.0, min_area=4.0, nucleate=True):
    """Minimise (6.38) by the H^1 gradient flow of a polygon (``backend="polygon"``).

    Called by :func:`activecontour.segment`; the keywords after ``callback`` are its ``options``.

    Parameters
    ----------
    model : ImageModel
    init : see :func:`activecontour.initial.initial_curves`
    params : ChanVeseParameters
    max_num_iter : int
    tol : float
    callback : callable or None
    velocity : {"h1", "l2"}
        The bilinear form b: H^1 (6.39), the default, or L^2 (6.25).
    spacing : float
        Target distance between vertices, in pixels (> 0).  About one vertex per pixel resolves
        everything the image resolves; the cost of an iteration grows with the curve's length in
        pixels either way.
    max_step : float
        Largest root-mean-square vertex displacement of a trial step, in pixels (> 0).  Steps
        double while they are accepted, up to this; backtracking halves them.
    smoothing, min_smoothing : float
        First and last length l in ``b(V, Y) = int V.Y + l^2 int grad V : grad Y``, in pixels
        (``smoothing >= min_smoothing >= 0``).  The book's (6.39) is l = 1 in its units.  In pixel
        units l = 1 barely smooths: on noisy images the fastest (noise-driven) vertex then caps the
        step and the bulk of the curve crawls; a large l alone spreads every local force over l
        pixels and fills corners slowly.  Coarse to fine gets both: the curve reaches the object
        in a few tens of iterations and then settles into its details.

    min_area : float
        Curves enclosing less than this many square pixels are removed (when that does not raise
        the energy), e.g. circles of a grid start that shrink away on the background.
    nucleate : bool
        When the flow has converged, look for holes and new components that lower the energy
        (the topological derivative, :func:`activecontour.topology.nucleation_sites`), insert
        small circles there and continue; repeated at most a few times.  This is how a single
        initial curve finds a hole or a second object it cannot reach by deformation.

    Returns
    -------
    SegmentationResult
    """
    if velocity not in _VELOCITIES:
        raise ValueError(f"velocity must be one of {_VELOCITIES}, got {velocity!r}")
    for name, value, low in (("spacing", spacing, 0.0), ("max_step", max_step, 0.0)):
        if not (np.isfinite(value) and value > low):
            raise ValueError(f"{name} must be a positive number of pixels, got {value!r}")
    if not (np.isfinite(min_smoothing) and np.isfinite(smoothing) and smoothing >= min_smoothing >= 0):
        raise ValueError(
            f"smoothing and min_smoothing must be pixel lengths with smoothing >= min_smoothing >= 0, "
            f"got {smoothing!r} and {min_smoothing!r}"
        )
    if not (np.isfinite(min_area) and min_area >= 0):
        raise ValueError(f"min_area must be a number of square pixels >= 0, got {min_area!r}")
    shape = model.shape
    # a curve whose vertices are already about ``spacing`` apart (a previous result) is kept
    # exactly: resampling it would cut its corners and move it off its minimum
    geometry = stack_curves([c if _healthy(c, spacing) else resample(c, spacing)
                             for c in initial_curves(init, shape, model.values, params.mu)])
    current = evaluate(model, *geometry[:2], params, gradient=True)
    if not np.isfinite(current.energy):
        raise ValueError("init encloses no area or the whole image: c_in or c_out is undefined")
    flow = _Flow(model, params, velocity, smoothing, max_step, min_area, model.bounds)
    energies = [current.energy]
    movement = _Movement()
    status, n_iter, last_remesh, rounds = 1, 0, -_REMESH_COOLDOWN, 0
    for k in range(max_num_iter):
        step = flow.step(geometry, current)
        if step is None:
            status = 4
            break
        new_geometry, new = flow.drop_small(*step)
        if new is None:
            geometry, status = new_geometry, 3
            break
        if _unhealthy(new_geometry, spacing) and k - last_remesh >= _REMESH_COOLDOWN:
            last_remesh = k
            remeshed = stack_curves([resample(c, spacing) for c in _split(*new_geometry[::2])])
            candidate = evaluate(model, *remeshed[:2], params, gradient=True)
            if candidate.energy <= current.energy:
                new_geometry, new = remeshed, candidate
        movement.add(new_geometry)
        geometry, current, n_iter = new_geometry, new, k + 1
        energies.append(current.energy)
        if callback is not None:
            state = FlowState(n_iter, _split(*geometry[::2]), current.energy, current.c_in,
                              current.c_out, shape, max_num_iter)
            if callback(state):
                status = 2
                break
        finest = flow.smoothing <= min_smoothing or not flow.h1
        if movement.last < (tol if finest else _STAGE_TOL * tol):
            if not finest:
                flow.refine(min_smoothing)
            elif nucleate and rounds < _NUCLEATION_ROUNDS and (grown := flow.nucleate(geometry, current)):
                rounds += 1
                geometry, current = grown
                energies[-1] = current.energy  # part of this iteration's update: lower still
                flow.restart(smoothing)
            else:
                status = 0
                break
            movement.clear()
    return build_result(model, params, _split(*geometry[::2]), energies=energies, n_iter=n_iter,
                        status=status, backend="polygon")


class _Flow:
    """One time step (6.30)-(6.31) with backtracking and topology repair; remembers the last dt."""

    def __init__(self, model, params, velocity, smoothing, max_step, min_area, bounds):
        self.model, self.params = model, params
        self.h1 = velocity == "h1"
        self.smoothing = smoothing
        self.max_step = max_step
        self.min_area = min_area
        self.low, self.high = bounds
        self.dt = np.inf

    def velocity(self, geometry, load):
        """Solve b(V, Y) = -f (6.40) for all curves at once (block-cyclic, O(K))."""
        points, next_index, offsets = geometry
        previous = np.empty_like(next_index)
        previous[next_index] = np.arange(len(next_index))
        d = points[next_index] - points
        # a crossing repair can leave an edge of (nearly) zero length: keep 1/h finite
        h = np.maximum(np.hypot(d[:, 0], d[:, 1]), _MIN_EDGE)
        diagonal, off = fem.mass_diagonals(h, previous)
        if self.h1:
            # per curve, l is at most half its radius L / 2 pi: a larger l would damp a small
            # curve's own growth and shape modes (by 1 + (k l / R)^2) while others set the step
            lengths = np.add.reduceat(h, offsets[:-1])
            smoothing = np.minimum(self.smoothing, _RELATIVE_SMOOTHING * lengths / (2 * np.pi))
            weight = np.repeat(smoothing**2, np.diff(offsets))
            stiff_diagonal, stiff_off = fem.stiffness_diagonals(h, previous)
            diagonal = diagonal + weight * stiff_diagonal
            off = off + weight * stiff_off
        return -fem.cyclic_solve(diagonal, off, load, offsets)

    def refine(self, min_smoothing):
        """Next, finer smoothing length; the step memory restarts with the new metric."""
        self.restart(max(min_smoothing, self.smoothing / _SMOOTHING_FACTOR))

    def restart(self, smoothing):
        self.smoothing = smoothing
        self.dt = np.inf

    def nucleate(self, geometry, current):
        """Add the small holes/components that the topological derivative proposes, if J drops.

        All proposed circles are tried together, then (if that does not lower the energy) one at
        a time, best first.  Returns (geometry, evaluation) or None.
        """
        curves = _split(*geometry[::2])
        inside = rasterize(curves, self.model.shape)
        sites = topology.nucleation_sites(self.model.values, inside, self.params, current.c_in,
                                          current.c_out, _NUCLEATION_RADIUS)
        seeds = [circle(center, _NUCLEATION_RADIUS)[:: -1 if hole else 1] for center, hole in sites]
        best = None
        for chosen in ([seeds], [[seed] for seed in seeds[:_NUCLEATION_TRIALS]]):
            accepted = []
            for group in chosen:
                trial = self._settle(curves + accepted + group)
                if trial is None:
                    continue
                reference = best[1].energy if best else current.energy
                if trial[1].energy < reference:
                    best = trial
                    accepted += group
            if best is not None:
                return best
        return None

    def _settle(self, curves):
        """Stack curves, resolving any overlap, and evaluate them."""
        geometry = stack_curves(curves)
        repaired = topology.repair(*geometry, min_area=self.min_area)
        if repaired is not None:
            if not repaired:
                return None
            geometry = stack_curves(repaired)
        new = evaluate(self.model, *geometry[:2], self.params, gradient=True)
        return (geometry, new) if np.isfinite(new.energy) else None

    def step(self, geometry, current):
        """Return (new geometry, its Evaluation), or None when no descent step exists.

        A trial whose edges cross is replaced by the boundary of {w > 0}
        (:func:`activecontour.topology.repair`) before the energy test, so a step that splits,
        merges or opens a hole is accepted only if the repaired curves satisfy the same descent
        condition as any other step.
        """
        points, next_index, offsets = geometry
        # Vertices on the image border that the force pushes out of the image cannot follow it:
        # leave those components out of the load and of the velocity (an active set), so that
        # f . V = -b^{-1}(f~, f~) < 0 stays a descent direction after clipping to the image.
        held = ((points <= self.low) & (current.load > 0)) | ((points >= self.high) & (current.load < 0))
        v = self.velocity(geometry, np.where(held, 0.0, current.load))
        v[held] = 0.0
        # the bulk of the curve, not its fastest vertex (a noise outlier, often 20x the median),
        # sets the scale of the first trial; backtracking still guarantees descent
        speed = np.sqrt(np.mean(v[:, 0] ** 2 + v[:, 1] ** 2))
        if not speed > 0:
            return None
        dt = min(self.max_step / speed, 2.0 * self.dt)
        for _ in range(_MAX_HALVINGS):
            trial = np.clip(points + dt * v, self.low, self.high)
            predicted = np.sum(current.load * (trial - points))
            candidate = (trial, next_index, offsets)
            repaired = topology.repair(trial, next_index, offsets, min_area=self.min_area)
            if repaired is not None:
                candidate = stack_curves(repaired) if repaired else None
            if candidate is not None and predicted < 0:
                new = evaluate(self.model, *candidate[:2], self.params, gradient=True)
                if new.energy <= current.energy + _ARMIJO * predicted:
                    self.dt = dt
                    return candidate, new
            dt *= 0.5
        return None

    def drop_small(self, geometry, current):
        """Remove curves enclosing less than ``min_area`` when that does not raise the energy.

        Returns the geometry and its evaluation, or (geometry, None) when nothing is left inside.
        """
        points, _, offsets = geometry
        areas = topology.curve_areas(*geometry)
        keep = np.abs(areas) >= self.min_area
        if keep.all():
            return geometry, current
        if not keep.any() or areas[keep].sum() <= 0:
            return geometry, (None if current.area < self.min_area else current)
        reduced = stack_curves([c for c, k in zip(_split(points, offsets), keep, strict=True) if k])
        candidate = evaluate(self.model, *reduced[:2], self.params, gradient=True)
        if candidate.energy <= current.energy:
            return reduced, candidate
        return geometry, current


class _Movement:
    """How far the contour gets per iteration, in pixels, over blocks of ``_WINDOW`` iterations.

    The measure is the mean normal displacement between the curve at the start of a block and at
    its end, divided by the block's iterations: each vertex's displacement projected on its
    normal, weighted by its share of the length, i.e. the area swept by the contour over its
    length.  It means the same on every image (no energy scale enters), and a contour that only
    jitters about a fixed place (steps at the edge of stability on noise) gets nowhere and counts
    as still.  A remesh, a topology repair or a removed curve changes the vertices: the block
    restarts there.
    """

    def __init__(self):
        self.clear()

    def add(self, geometry):
        points, next_index, offsets = geometry
        same = self.start is not None and points.shape == self.start.shape
        if not (same and np.array_equal(offsets, self.offsets)):
            self.start, self.offsets, self.count = points.copy(), offsets.copy(), 0
            return
        self.count += 1
        if self.count < _WINDOW:
            return
        start = self.start
        d = start[next_index] - start
        previous = np.empty_like(next_index)
        previous[next_index] = np.arange(len(next_index))
        edge_normal = np.column_stack([d[:, 1], -d[:, 0]])  # nu |e|
        vertex_normal = 0.5 * (edge_normal + edge_normal[previous])  # nu times the vertex's share
        swept = np.abs(np.einsum("ij,ij->i", points - start, vertex_normal)).sum()
        self.last = swept / max(np.hypot(d[:, 0], d[:, 1]).sum(), 1e-300) / self.count
        self.start, self.count = points.copy(), 0

    def clear(self):
        self.start, self.offsets, self.count, self.last = None, None, 0, np.inf


def _unhealthy(geometry, spacing):
    points, next_index, _ = geometry
    d = points[next_index] - points
    return not _spacing_ok(np.hypot(d[:, 0], d[:, 1]), spacing)


def _healthy(curve, spacing):
    return len(curve) >= 8 and _spacing_ok(edge_lengths(curve), spacing)


def _spacing_ok(h, spacing):
    return h.max() <= 2.0 * spacing and h.min() >= 0.5 * spacing


def _split(points, offsets):
    return [points[a:b].copy() for a, b in pairwise(offsets)]
