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
   The first trial moves the fastest vertex by ``max_step`` pixels (at most twice the last accepted
   dt), so a step is scale-free: it does not depend on the image contrast.
4. Mesh health: when an edge is shorter than half or longer than twice ``spacing``, the curve
   is resampled at equal arc length; the resampled curve is kept only if its energy is not above
   the previous iterate's, so the recorded energy sequence never increases.

The flow stalls when either measure falls below ``tol``: the relative energy decrease per iteration
averaged over the last five iterations (this ends the slow tail of noisy images, where the curve
keeps chasing noise for no measurable gain), or the largest vertex displacement, in pixels, for three
iterations in a row (clean images whose energy tends to zero).  A stall at the finest l is
convergence; the run also stops at ``max_num_iter``.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np

from activecontour import fem
from activecontour.curve import edge_lengths, resample
from activecontour.energy import evaluate, stack_curves
from activecontour.initial import initial_curves
from activecontour.raster import rasterize
from activecontour.result import FlowState, SegmentationResult

__all__ = ["segment_polygon"]

_VELOCITIES = ("h1", "l2")
_ARMIJO = 1e-4
_MAX_HALVINGS = 40
_PATIENCE = 3
_ENERGY_WINDOW = 5
_SMOOTHING_FACTOR = 4.0
_REMESH_COOLDOWN = 10


def segment_polygon(model, init, params, *, max_num_iter, tol, callback, velocity="h1", spacing=1.0,
                    max_step=2.0, smoothing=30.0, min_smoothing=1.0):
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
        Largest vertex displacement of a first trial step, in pixels (> 0).
    smoothing, min_smoothing : float
        First and last length l in ``b(V, Y) = int V.Y + l^2 int grad V : grad Y``, in pixels
        (``smoothing >= min_smoothing >= 0``).  The book's (6.39) is l = 1 in its units.  In pixel
        units l = 1 barely smooths: on noisy images the fastest (noise-driven) vertex then caps the
        step and the bulk of the curve crawls; a large l alone spreads every local force over l
        pixels and fills corners slowly.  Coarse to fine gets both: the curve reaches the object
        in a few tens of iterations and then settles into its details.

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
    shape = model.shape
    curves = [resample(c, spacing) for c in initial_curves(init, shape)]
    points, next_index, offsets = stack_curves(curves)
    current = evaluate(model, points, next_index, params, gradient=True)
    if not np.isfinite(current.energy):
        raise ValueError("init encloses no area or the whole image: c_in or c_out is undefined")
    flow = _Flow(model, params, velocity, smoothing, max_step, model.bounds)
    energies = [current.energy]
    status, n_iter, quiet, last_remesh, stage_start = 1, 0, 0, -_REMESH_COOLDOWN, 0
    for k in range(max_num_iter):
        step = flow.step(points, next_index, offsets, current)
        if step is None:
            status = 4
            break
        new_points, new = step
        if _unhealthy(new_points, next_index, spacing) and k - last_remesh >= _REMESH_COOLDOWN:
            last_remesh = k
            remeshed = _remesh(new_points, offsets, spacing)
            candidate = evaluate(model, *remeshed[:2], params, gradient=True)
            if candidate.energy <= current.energy:
                (new_points, next_index, offsets), new = remeshed, candidate
        displacement = (_max_displacement(points, new_points) if new_points.shape == points.shape
                        else np.inf)  # a remeshed curve has no vertex-to-vertex displacement
        points, current, n_iter = new_points, new, k + 1
        energies.append(current.energy)
        quiet = quiet + 1 if displacement < tol else 0
        if current.area < 1.0:
            status = 3
            break
        if callback is not None:
            state = FlowState(n_iter, _split(points, offsets), current.energy, current.c_in,
                              current.c_out, shape, max_num_iter)
            if callback(state):
                status = 2
                break
        if quiet >= _PATIENCE or _stalled(energies, stage_start, tol):
            if flow.smoothing <= min_smoothing or not flow.h1:
                status = 0
                break
            flow.refine(min_smoothing)
            quiet, stage_start = 0, len(energies) - 1
    contours = _split(points, offsets)
    return SegmentationResult(
        mask=rasterize(contours, shape), contours=contours, c_in=current.c_in, c_out=current.c_out,
        energy=current.energy, energies=energies, n_iter=n_iter, status=status, backend="polygon",
    )


class _Flow:
    """One time step (6.30)-(6.31) with backtracking; remembers the last accepted dt."""

    def __init__(self, model, params, velocity, smoothing, max_step, bounds):
        self.model, self.params = model, params
        self.h1 = velocity == "h1"
        self.smoothing = smoothing
        self.max_step = max_step
        self.low, self.high = bounds
        self.dt = np.inf

    def velocity(self, points, offsets, load):
        """Solve b(V, Y) = -f (6.40) curve by curve."""
        out = np.empty_like(load)
        for start, stop in pairwise(offsets):
            h = edge_lengths(points[start:stop])
            diagonal, off = fem.mass_diagonals(h)
            if self.h1:
                stiff_diagonal, stiff_off = fem.stiffness_diagonals(h)
                diagonal = diagonal + self.smoothing**2 * stiff_diagonal
                off = off + self.smoothing**2 * stiff_off
            out[start:stop] = -fem.cyclic_solve(diagonal, off, load[start:stop])
        return out

    def refine(self, min_smoothing):
        """Next, finer smoothing length; the step memory restarts with the new metric."""
        self.smoothing = max(min_smoothing, self.smoothing / _SMOOTHING_FACTOR)
        self.dt = np.inf

    def step(self, points, next_index, offsets, current):
        """Return (new points, their Evaluation), or None when no descent step exists."""
        v = self.velocity(points, offsets, current.load)
        speed = np.hypot(v[:, 0], v[:, 1]).max()
        if not speed > 0:
            return None
        dt = min(self.max_step / speed, 2.0 * self.dt)
        for _ in range(_MAX_HALVINGS):
            trial = np.clip(points + dt * v, self.low, self.high)
            new = evaluate(self.model, trial, next_index, self.params, gradient=True)
            predicted = np.sum(current.load * (trial - points))
            if new.energy <= current.energy + _ARMIJO * predicted and predicted < 0:
                self.dt = dt
                return trial, new
            dt *= 0.5
        return None


def _stalled(energies, stage_start, tol):
    if len(energies) - stage_start <= _ENERGY_WINDOW:
        return False
    decrease = (energies[-1 - _ENERGY_WINDOW] - energies[-1]) / _ENERGY_WINDOW
    return decrease < tol * max(abs(energies[-1]), 1e-300)


def _unhealthy(points, next_index, spacing):
    d = points[next_index] - points
    h = np.hypot(d[:, 0], d[:, 1])
    return h.max() > 2.0 * spacing or h.min() < 0.5 * spacing


def _remesh(points, offsets, spacing):
    return stack_curves([resample(c, spacing) for c in _split(points, offsets)])


def _split(points, offsets):
    return [points[a:b].copy() for a, b in pairwise(offsets)]


def _max_displacement(old, new):
    d = new - old
    return float(np.hypot(d[:, 0], d[:, 1]).max())
