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
   the previous iterate's, so the recorded energy sequence never increases.  The start is taken
   as given: only its edges longer than twice ``spacing`` are split (the same polygon), so a
   previous result restarts at its own energy and mask.

The flow stalls when the contour stops getting anywhere: its mean normal displacement (the area it
sweeps over its length, in pixels) between the start and the end of a block of five iterations,
per iteration, falls below ``tol``, and so does its fastest part (the 99.9th percentile of the
vertices' own normal displacements, over 100: a lobe still on its way holds the stop; see
:class:`_Movement`).  No energy scale enters, so the test
means the same on every image: a relative energy decrease would stop earlier the larger or noisier
the image, as J holds the noise energy sigma^2 |D|.  A coarse l gives way to the next after one
block below 10 tol; convergence at the finest l takes two blocks in a row below tol (one slow
block can be a pause: on scikit-image's cat a lobe still retracting moved 0.5 % of the mask after
such a stop); the run also stops at ``max_num_iter``.
"""

from __future__ import annotations

import numpy as np

from activecontour.backends.options import PolygonOptions
from activecontour.energy import evaluate
from activecontour.geometry import fem, topology
from activecontour.geometry.curve import (
    resample_stacked,
    split_curves,
    stack_curves,
    stacked_next,
    subdivide,
    take_curves,
)
from activecontour.geometry.raster import rasterize
from activecontour.initial import circle, initial_curves
from activecontour.result import FlowState, build_result

__all__ = ["PolygonOptions", "segment_polygon"]

_ARMIJO = 1e-4
_MAX_HALVINGS = 40
_WINDOW = 5  # iterations over which the movement is averaged for the stopping test
_STILL_BLOCKS = 2  # consecutive slow blocks that make convergence: one can be a pause (see _Movement)
_MEMORY = 8  # step pairs of the L-BFGS acceleration
_SMOOTHING = 30.0  # first smoothing length (px) from given curves ...
_START_SMOOTHING = 2.0  # ... and from the default start or a result, on the boundaries already
_CURVE_STEP = 0.25  # a trial step moves a curve by at most this fraction of its radius (RMS)
_SMOOTHING_FACTOR = 4.0
_STAGE_TOL = 10.0  # a coarse stage ends at 10 tol: the finer metric then makes faster progress
_MIN_EDGE = 1e-9
_RELATIVE_SMOOTHING = 0.5
_NUCLEATION_RADIUS = 4.0
_NUCLEATION_ROUNDS = 4
_NUCLEATION_TRIALS = 30
_REMESH_COOLDOWN = 10
_LOCAL_QUANTILE = 0.999  # the stopping test also reads the fastest part of the curve (see _Movement):
_LOCAL_FACTOR = 100.0  # its normal displacement (this quantile over the vertices) must be below 100 tol
_BACKGROUND_SHARE = 1.5  # the global move takes the background when the given curves hold 1.5x
                         # the share of it that they hold of the objects


def segment_polygon(model, init, params, *, max_num_iter, tol, callback, options=None):
    """Minimise (6.38) by the H^1 gradient flow of a polygon (``backend="polygon"``).

    Called by :func:`activecontour.segment` with its ``options`` read into :class:`PolygonOptions`
    (names, types, defaults, ranges and their documentation).

    Parameters
    ----------
    model : ImageModel
    init : see :func:`activecontour.initial.initial_curves`
    params : ChanVeseParameters
    max_num_iter : int
    tol : float
    callback : callable or None
    options : PolygonOptions, optional
        None: the defaults.

    Returns
    -------
    SegmentationResult
    """
    chosen = PolygonOptions() if options is None else options
    velocity, spacing, max_step = chosen.velocity, chosen.spacing, chosen.max_step
    smoothing, min_smoothing, min_area = chosen.smoothing, chosen.min_smoothing, chosen.min_area
    nucleate, accelerate, global_start = chosen.nucleate, chosen.accelerate, chosen.global_start
    from_result = hasattr(init, "contours") and hasattr(init, "mask")
    shape = model.shape
    # a given start is kept exactly (a previous result's energy and mask): long edges are split,
    # nothing is cut, and the remesh takes short edges when that lowers the energy; the starts we
    # draw ourselves (the default start, the global move's threshold set) are at the spacing
    start = stack_curves(initial_curves(init, shape, model.image, params.mu))
    geometry = _resampled(start, spacing) if init is None else _subdivided(start, spacing)
    current = evaluate(model, *geometry[:2], params, gradient=True)
    # a start around the whole image (or nothing) has the energy of the empty set plus its
    # length, but no constant (6.42) for the empty region: the global move can still leave it
    energies = [current.energy if np.isfinite(current.energy)
                else evaluate(model, *geometry[:2], params, empty_ok=True).energy]
    n_iter = 0
    jumped = global_start and init is not None and not from_result and max_num_iter > 0 and (
        moved := _global_move(model, params, geometry, energies[0], spacing)) is not None
    if not (jumped or np.isfinite(current.energy)):
        # a start around the whole image: the empty region's constant is the other's (so the fit
        # terms' force is zero and the length term shrinks the curve); once the region is not
        # empty its constant (6.42) is defined, and the fit drives the curve onto the objects
        current = evaluate(model, *geometry[:2], params, gradient=True, empty_ok=True)
    if jumped:
        (geometry, current), n_iter = moved, 1
        energies.append(current.energy)
        if callback is not None and callback(FlowState(n_iter, split_curves(*geometry[::2]), current.energy,
                                                       current.c_in, current.c_out, shape, max_num_iter)):
            return build_result(model, params, split_curves(*geometry[::2]), energies=energies, n_iter=n_iter,
                                status=2, backend="polygon")
    if smoothing is None:
        # the default start, a result and the global move lie on the objects' boundaries already
        on_boundaries = init is None or from_result or jumped
        smoothing = max(min_smoothing, _START_SMOOTHING if on_boundaries else _SMOOTHING)
    flow = _Flow(model, params, velocity, smoothing, max_step, min_area, model.bounds, accelerate)
    movement = _Movement()
    status, last_remesh, rounds = 1, -_REMESH_COOLDOWN, 0
    for k in range(n_iter, max_num_iter):
        step = flow.step(geometry, current)
        if step is None:
            status = 4
            break
        new_geometry, new = flow.drop_small(*step)
        if new is None:
            geometry, status = new_geometry, 3
            break
        if k - last_remesh >= _REMESH_COOLDOWN and _unhealthy(flow.edge_lengths(new_geometry), spacing):
            last_remesh = k
            remeshed = _resampled(new_geometry, spacing)
            candidate = evaluate(model, *remeshed[:2], params, gradient=True)
            if candidate.energy <= current.energy:
                new_geometry, new = remeshed, candidate
        movement.add(new_geometry)
        geometry, current, n_iter = new_geometry, new, k + 1
        energies.append(current.energy)
        if callback is not None:
            state = FlowState(n_iter, split_curves(*geometry[::2]), current.energy, current.c_in,
                              current.c_out, shape, max_num_iter)
            if callback(state):
                status = 2
                break
        finest = flow.smoothing <= min_smoothing or not flow.h1
        # a coarse stage gives way after one slow block; convergence takes _STILL_BLOCKS in a row
        if movement.still(tol if finest else _STAGE_TOL * tol) >= (_STILL_BLOCKS if finest else 1):
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
    return build_result(model, params, split_curves(*geometry[::2]), energies=energies, n_iter=n_iter,
                        status=status, backend="polygon")


def _global_move(model, params, geometry, energy, spacing):
    """The default start's threshold set or its complement, as (geometry, evaluation), when its
    (6.38) is below ``energy`` (the given curves'); else None.

    Of the two classes, the one that has the larger share of its area inside the given curves
    is inside: a curve drawn around an object (with background around it) or inside one selects
    the object, a curve drawn on the background the background.  The background must hold
    ``_BACKGROUND_SHARE`` times the objects' share: a start that selects neither (a speckle
    mask, the whole image) gets the default start's objects.  (With lambda_in = lambda_out and
    omega = 0 a region and its complement have the same energy: the curves, not rounding, choose.)
    """
    from activecontour.initial import threshold_starts

    given = rasterize(split_curves(*geometry[::2]), model.shape)
    objects, background = threshold_starts(model.values, params.mu, background=True)
    shares = []
    for curves in (objects, background):
        region = rasterize(curves, model.shape)
        shares.append(np.count_nonzero(region & given) / max(1, np.count_nonzero(region)))
    # the background only when the curves clearly select it: a speckle mask selects neither
    chosen = background if shares[1] > _BACKGROUND_SHARE * shares[0] else objects
    if not chosen:
        return None
    moved = _resampled(stack_curves(chosen), spacing)
    new = evaluate(model, *moved[:2], params, gradient=True)
    return (moved, new) if new.energy < energy else None


class _Flow:
    """One time step (6.30)-(6.31) with backtracking and topology repair; remembers the last dt."""

    def __init__(self, model, params, velocity, smoothing, max_step, min_area, bounds, accelerate):
        self.model, self.params = model, params
        self.h1 = velocity == "h1"
        self.smoothing = smoothing
        self.max_step = max_step
        self.min_area = min_area
        self.bounds = bounds
        self.low, self.high = bounds
        self.dt = np.inf
        self.memory = _Memory(accelerate)
        # of the last geometry seen (the arrays are never changed in place): identity, values
        self._metric = self._lengths = self._areas = None

    def velocity(self, geometry, load):
        """Solve b(V, Y) = -f (6.40) for all curves at once (block-cyclic, O(K))."""
        diagonal, off = self.metric(geometry)
        return -fem.cyclic_solve(diagonal, off, load, geometry[2])

    def metric(self, geometry):
        """The cyclic tridiagonal matrix of b (6.39) or (6.25) on these curves, as (diagonal, off):
        assembled once per geometry and smoothing length (a step solves with it up to three times)."""
        points, next_index, offsets = geometry
        if self._metric is not None and self._metric[0] is points and self._metric[1] == self.smoothing:
            return self._metric[2]
        previous = np.arange(-1, len(points) - 1)
        previous[offsets[:-1]] = offsets[1:] - 1
        # a crossing repair can leave an edge of (nearly) zero length: keep 1/h finite
        h = np.maximum(self.edge_lengths(geometry), _MIN_EDGE)
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
        self._metric = (points, self.smoothing, (diagonal, off))
        return diagonal, off

    def edge_lengths(self, geometry):
        """The length of every edge of these curves (computed once per geometry)."""
        points, next_index, _ = geometry
        if self._lengths is None or self._lengths[0] is not points:
            d = np.take(points, next_index, axis=0) - points  # (take: ~10x a fancy index here)
            self._lengths = (points, np.hypot(d[:, 0], d[:, 1]))
        return self._lengths[1]

    def areas(self, geometry):
        """The signed area of every curve (computed once per geometry)."""
        if self._areas is None or self._areas[0] is not geometry[0]:
            self._areas = (geometry[0], topology.curve_areas(*geometry))
        return self._areas[1]

    def refine(self, min_smoothing):
        """Next, finer smoothing length; the step memory restarts with the new metric."""
        self.restart(max(min_smoothing, self.smoothing / _SMOOTHING_FACTOR))

    def restart(self, smoothing):
        self.smoothing = smoothing
        self.dt = np.inf
        self.memory.clear()

    def nucleate(self, geometry, current):
        """Add the small holes/components that the topological derivative proposes, if J drops.

        All proposed circles are tried together, then (if that does not lower the energy) one at
        a time, best first.  Returns (geometry, evaluation) or None.
        """
        curves = split_curves(*geometry[::2])
        inside = rasterize(curves, self.model.shape)
        sites = topology.nucleation_sites(self.model.values, inside,
                                          self.params.load_form(current.c_in, current.c_out),
                                          self.params.mu, _NUCLEATION_RADIUS)
        seeds = [np.clip(circle(center, _NUCLEATION_RADIUS), self.low, self.high)[:: -1 if hole else 1]
                 for center, hole in sites]
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
        # a seed clipped to the border can run along a curve's stretch of it: edges that coincide,
        # which the repair cannot resolve (see step)
        if topology.border_overlap(*geometry[:2], self.bounds):
            return None
        repaired = topology.repair_stacked(*geometry, min_area=self.min_area)
        if repaired is not None:
            if len(repaired[2]) == 1:  # nothing left
                return None
            geometry = repaired
        new = evaluate(self.model, *geometry[:2], self.params, gradient=True)
        return (geometry, new) if np.isfinite(new.energy) else None

    def step(self, geometry, current):
        """Return (new geometry, its Evaluation), or None when no descent step exists.

        A trial whose edges cross is replaced by the boundary of {w > 0}
        (:func:`activecontour.geometry.topology.repair`) before the energy test, so a step that splits,
        merges or opens a hole is accepted only if the repaired curves satisfy the same descent
        condition as any other step.  A trial that runs two edges along the same stretch of the
        image border (:func:`activecontour.geometry.topology.border_overlap`) is no region: it is
        rejected as a step too long, before the repair: the repair keeps an edge by the winding
        number on its right, taking the one on its left to be one more, which an edge that another
        covers does not separate (such a trial once ended as a hole outside every curve, a region
        of winding number -1 along the border).
        """
        points, next_index, offsets = geometry
        # Vertices on the image border that the force pushes out of the image cannot follow it:
        # leave those components out of the load and of the velocity (an active set), so that
        # f . V = -b^{-1}(f~, f~) < 0 stays a descent direction after clipping to the image.
        held = _held(points, current.load, self.low, self.high)
        load = np.where(held, 0.0, current.load)
        accelerated = self.memory.direction(geometry, load, held, self.velocity)
        if accelerated is not None:
            # a quasi-Newton step in the same metric: its natural length is 1 (a descent
            # direction, f . V < 0, so f and the gradient step are not zero)
            v = accelerated
            dt = min(1.0, self.max_step / np.sqrt(np.mean(v[:, 0] ** 2 + v[:, 1] ** 2)))
        else:
            v = self.velocity(geometry, load)
            v[held] = 0.0
            # the bulk of the curve, not its fastest vertex (a noise outlier, often 20x the
            # median), sets the scale of the first trial; backtracking still guarantees descent
            speed = np.sqrt(np.mean(v[:, 0] ** 2 + v[:, 1] ** 2))
            if not speed > 0:
                return None
            dt = min(self.max_step / speed, 2.0 * self.dt)
        dt = min(dt, _size_limit(geometry, self.edge_lengths(geometry), v))
        areas = self.areas(geometry)  # the iterate bounds a region: see repair
        for _ in range(_MAX_HALVINGS):
            trial = _clipped(points + dt * v, self.low, self.high)
            predicted = np.sum(current.load * (trial - points))
            # clipping can run two pieces of curve along the same stretch of the border
            candidate = None
            if predicted < 0 and not topology.border_overlap(trial, next_index, self.bounds):
                candidate = (trial, next_index, offsets)
                repaired = topology.repair_stacked(trial, next_index, offsets, min_area=self.min_area,
                                                   before=areas)
                if repaired is not None:
                    candidate = repaired if len(repaired[2]) > 1 else None
            if candidate is not None:
                new = evaluate(self.model, *candidate[:2], self.params, gradient=True)
                if new.energy <= current.energy + _ARMIJO * predicted:
                    if accelerated is None:
                        self.dt = dt
                    self.memory.remember(geometry, candidate, current.load, new.load)
                    return candidate, new
            dt *= 0.5
        return None

    def drop_small(self, geometry, current):
        """Remove curves enclosing less than ``min_area`` when that does not raise the energy.

        Returns the geometry and its evaluation, or (geometry, None) when nothing worth a curve
        is left inside and the empty set's energy is not above the curves' (the collapse).
        """
        points, _, offsets = geometry
        areas = self.areas(geometry)
        keep = np.abs(areas) >= self.min_area
        if keep.all():
            return geometry, current
        if not keep.any() or areas[keep].sum() <= 0:
            if current.area >= self.min_area:
                return geometry, current
            # nothing left worth a curve: collapse to the empty set, unless that costs energy
            empty = evaluate(self.model, np.zeros((0, 2)), np.zeros(0, dtype=np.intp), self.params,
                             empty_ok=True)
            return geometry, (None if empty.energy <= current.energy else current)
        reduced = take_curves(points, offsets, keep)
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
    restarts there.  ``blocks`` holds every block's measure since the stage began.

    The mean alone misses a part of the curve that is still on its way while the rest is still:
    on scikit-image's cat and coins, at the stop a lobe moved 0.07-0.14 px per iteration (its
    vertices' 99.9th percentile, the mean 6e-4), and a run continued with ``tol / 100`` moved
    0.15-0.38 % of the mask.  So a block's measure is the larger of the mean and the
    ``_LOCAL_QUANTILE`` quantile of the vertices' own normal displacements over ``_LOCAL_FACTOR``:
    a block is slow only when both are below the threshold.  (A quantile, not the maximum: one
    vertex jittering on noise does not hold the curve.)
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
        d = np.take(start, next_index, axis=0) - start
        previous = np.empty_like(next_index)
        previous[next_index] = np.arange(len(next_index))
        edge_normal = np.column_stack([d[:, 1], -d[:, 0]])  # nu |e|
        # nu times the vertex's share
        vertex_normal = 0.5 * (edge_normal + np.take(edge_normal, previous, axis=0))
        normal = np.abs(np.einsum("ij,ij->i", points - start, vertex_normal))  # area, per vertex
        mean = normal.sum() / max(np.hypot(d[:, 0], d[:, 1]).sum(), 1e-300)
        share = np.hypot(vertex_normal[:, 0], vertex_normal[:, 1])  # half the two edges' lengths
        local = np.quantile(normal / np.maximum(share, 1e-300), _LOCAL_QUANTILE)
        self.blocks.append(max(mean, local / _LOCAL_FACTOR) / self.count)
        self.start, self.count = points.copy(), 0

    def still(self, threshold):
        """How many of the last blocks, in a row, moved less than ``threshold`` px per iteration."""
        count = 0
        for moved in reversed(self.blocks):
            if moved >= threshold:
                break
            count += 1
        return count

    def clear(self):
        self.start, self.offsets, self.count, self.blocks = None, None, 0, []


def _held(points, load, low, high):
    """Which components of the (K, 2) vertices sit on the image border with the load pushing them
    out: ``((points <= low) & (load > 0)) | ((points >= high) & (load < 0))`` for the (2,) bounds,
    computed column by column (see :func:`_clipped`)."""
    held = np.empty(points.shape, dtype=bool)
    for axis in range(points.shape[1]):
        p, f = points[:, axis], load[:, axis]
        held[:, axis] = ((p <= low[axis]) & (f > 0)) | ((p >= high[axis]) & (f < 0))
    return held


def _clipped(points, low, high):
    """``np.clip(points, low, high)`` for (K, 2) vertices and (2,) bounds, in place, column by column.

    The same numbers; numpy broadcasts (2,) bounds over a (K, 2) array as an inner loop of length
    2, which costs several times a scalar bound per column (0.42 ms against 0.05 ms at K = 18000,
    scikit-image's brick; 0.05 against 0.01 ms at K = 4000): once per trial of every step, about
    7 % of brick's flow.
    """
    for axis in range(points.shape[1]):
        column = points[:, axis]
        np.clip(column, low[axis], high[axis], out=column)
    return points


def _size_limit(geometry, edge_lengths, v):
    """The largest dt that moves no curve by more than a quarter of its radius (RMS).

    A first trial that jumps a small curve across itself (or shrinks it to nothing in one go)
    can pass the descent test and still land far from where the flow was going.
    """
    offsets = geometry[2]
    radius = np.add.reduceat(edge_lengths, offsets[:-1]) / (2 * np.pi)
    rms = np.sqrt(np.add.reduceat(v[:, 0] ** 2 + v[:, 1] ** 2, offsets[:-1]) / np.diff(offsets))
    moving = rms > 0
    return float(np.min(_CURVE_STEP * radius[moving] / rms[moving])) if moving.any() else np.inf


class _Memory:
    """Limited-memory BFGS pairs (s, y) = (step, change of the load) in the metric b (6.39)."""

    def __init__(self, enabled, size=_MEMORY):
        self.enabled, self.size = enabled, size
        self.clear()

    def clear(self):
        self.pairs, self.signature = [], None

    def _matches(self, geometry):
        return self.signature is not None and geometry[0].shape == self.signature[0] \
            and np.array_equal(geometry[2], self.signature[1])

    def remember(self, old, new, old_load, new_load):
        """Store the pair of an accepted step; a step that changed the vertices ends the memory."""
        if not self.enabled:
            return
        if new[0].shape != old[0].shape or not np.array_equal(new[2], old[2]):
            self.clear()
            return
        if self.pairs and not self._matches(old):  # pairs of other vertices (after a remesh)
            self.pairs = []
        s, y = (new[0] - old[0]).ravel(), (new_load - old_load).ravel()
        curvature = _dot(s, y)
        if curvature > 1e-12 * np.sqrt(_dot(s, s) * _dot(y, y)):
            self.pairs = (self.pairs + [(s, y, 1.0 / curvature)])[-self.size:]
        self.signature = (new[0].shape, new[2].copy())

    def direction(self, geometry, load, held, velocity):
        """The L-BFGS direction -H f (two-loop recursion, H_0 = gamma b^{-1}), or None."""
        if not (self.enabled and self.pairs and self._matches(geometry)):
            return None
        q = load.ravel().copy()
        alphas = []
        for s, y, rho in reversed(self.pairs):
            alpha = rho * _dot(s, q)
            q -= alpha * y
            alphas.append(alpha)
        s, y, _ = self.pairs[-1]
        # b^{-1} y and b^{-1} q in one solve (one elimination for the four columns)
        solved = -velocity(geometry, np.hstack([y.reshape(load.shape), q.reshape(load.shape)]))
        metric_y, r = solved[:, :2].ravel(), solved[:, 2:].ravel()
        r *= _dot(s, y) / max(_dot(y, metric_y), 1e-300)
        for (s, y, rho), alpha in zip(self.pairs, reversed(alphas), strict=True):
            r += s * (alpha - rho * _dot(y, r))
        direction = -r.reshape(load.shape)
        direction[held] = 0.0
        return direction if np.sum(load * direction) < 0 else None


def _dot(a, b):
    """``a . b`` of two long vectors without BLAS (its threads cost more than the product here)."""
    return float(np.einsum("i,i->", a, b))


def _subdivided(geometry, spacing):
    """Stacked curves split where the flow needs vertices and nowhere else: the same polygons.

    An edge longer than twice ``spacing`` becomes pieces of at most ``spacing``, and a curve of
    fewer than 8 vertices gets at least 8 (:func:`activecontour.geometry.curve.subdivide`): the
    new vertices lie on the old edges, so the region, its energy and its mask are the given ones
    exactly (a previous result restarts where it ended).  Short edges stay: the remesh
    (:func:`_resampled`) takes them when that does not raise the energy.
    """
    points, next_index, offsets = geometry
    if len(offsets) == 1:
        return geometry
    counts = np.diff(offsets)
    d = np.take(points, next_index, axis=0) - points
    totals = np.add.reduceat(np.hypot(d[:, 0], d[:, 1]), offsets[:-1])
    few = counts < 8  # every edge split, into pieces of at most a curve's length / 8
    piece = np.repeat(np.where(few, np.minimum(spacing, totals / 8.0), spacing), counts)
    longest = np.repeat(np.where(few, 0.0, 2.0 * spacing), counts)
    dense, counts = subdivide(points, counts, piece, longest)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)
    return dense, stacked_next(offsets), offsets


def _resampled(geometry, spacing):
    """Stacked curves resampled at equal arc length ``spacing``.  A chord of the resampling can
    cut across a narrow neck or a notch and cross the curve: the result is then the boundary of
    {w > 0} (:func:`activecontour.geometry.topology.repair_stacked`), so that its energy is that
    of a region."""
    resampled = resample_stacked(*geometry, spacing)
    repaired = topology.repair_stacked(*resampled, before=topology.curve_areas(*geometry))
    return resampled if repaired is None else repaired


def _unhealthy(edge_lengths, spacing):
    """Whether an edge is shorter than half or longer than twice ``spacing``."""
    return not (edge_lengths.max() <= 2.0 * spacing and edge_lengths.min() >= 0.5 * spacing)
