"""The level-set backend: the Chan-Vese functional (6.38) on a function phi over the pixel grid.

The inside region is ``Omega_i = {phi > 0}`` and Gamma is the zero level set of phi.  The backend
minimises the same functional as the polygon backend, with the same parameters and units,

    J = mu |Gamma| + omega |Omega_i| + lambda_in  int_{Omega_i} sum_ch (I - c_in)^2
                                     + lambda_out int_{Omega_o} sum_ch (I - c_out)^2          (6.38)

but Gamma may split, merge, open holes and grow new components.  The zero level set is returned
as sub-pixel contours (marching squares) in the polygon backend's convention, so either backend
can start from the other's result (level set for the topology, polygon for a sub-pixel finish).

One iteration
-------------
1. ``c_in, c_out`` by (6.42), with the regularised Heaviside of the signed distance as the weight
   (unless they are fixed).
2. A semi-implicit step of the level-set form of the gradient flow of (6.38).  Every level line
   moves with the normal velocity ``-(mu kappa + f)``, where ``f = omega + lambda_in sum (I -
   c_in)^2 - lambda_out sum (I - c_out)^2`` is the integrand of (6.41); in level-set form
   ``phi_t = |grad phi| (mu div(grad phi / |grad phi|) - f)``, and as phi is kept a signed
   distance (``|grad phi| = 1``) this is ``phi_t = mu Laplace(phi) - f``.  (With delta(phi) in place
   of |grad phi| it would be the equation of Chan & Vese 2001; |grad phi| makes it the level-set
   motion of Osher & Sethian 1988, which moves every level line, not only those near Gamma.)  Two
   forms of the step, with ``S = (1 - tau mu Laplace)^{-1}``:

   (a) smoothed force: ``phi^{k+1} = S (phi^k - tau f)``, i.e. the velocity
       ``S (mu Laplace(phi) - f)``: a Sobolev (H^1-type) gradient with smoothing length
       ``l = sqrt(tau mu)``, the level-set counterpart of the polygon's H^1 velocity (6.39).
       It moves whole regions at once and, with large tau, flips regions far from Gamma (see
       below); but its fixed point (``S (mu Laplace(phi) - f) = 0`` on Gamma) is biased by the
       smoothing, so it is only the first stage;
   (b) unsmoothed force: ``phi^{k+1} = S phi^k - tau f``: implicit curvature, explicit force, the
       L^2 flow (6.25) whose fixed point is ``mu kappa + f = 0`` on Gamma, i.e. (6.41) = 0.

   ``S`` has constant coefficients: one pair of discrete cosine transforms applies it exactly
   (Neumann boundary), unconditionally stable, with none of the splitting error of additive
   operator splitting (AOS, Weickert, ter Haar Romeny & Viergever 1998), which is what a
   variable-coefficient curvature operator would need.
3. Reinitialisation: phi is replaced by the signed distance to its zero level set, computed in a
   narrow band ``|phi| < band`` only and clipped to ``+-band`` beyond (:func:`signed_distance`).
4. The step is accepted if the discrete energy E below decreases; otherwise tau is halved and the
   step retried (backtracking).

The schedule, coarse to fine like the polygon's smoothing length: tau starts at ``dt`` and doubles
after every accepted step until a step is rejected or ``dt_max`` is reached; whenever stage (a)
stalls, tau is divided by 4, down to ``dt_min``; then stage (b) runs with tau <= ``dt_min`` until
the convergence test (the polygon backend's: see ``tol`` in :func:`segment_levelset`).

Why large steps are safe and useful: ``S`` is stable for every tau, and the backtracking keeps every
accepted step a descent step.  Far from Gamma phi sits at ``+-band``, and a step (a) moves it by
about ``-tau f`` smoothed over ``l``: where a whole region inside Gamma looks like the outside (the
hole of an annulus) phi crosses zero and a hole opens without a seed, while single noisy pixels
are held by the smoothing; the energy test accepts such a change only when it pays, length
included.  A compactly supported delta(phi) in the flow would never do that, and the arctan delta
of Chan & Vese 2001 does it slowly and at the price of biased areas.  In stage (b) tau <=
``dt_min`` keeps ``tau |f|`` within the band for intensities in [0, 1], so no pixel far from
Gamma flips on its own there.

Cost: an iteration is one DCT pair over the image (O(MN log MN), float32), a few vectorised passes
over the image, and the reinitialisation and the energy on the pixels of the narrow band only
(O(band |Gamma|)).  On 512 x 512 the DCT pair is about 5 ms of a trial step's 30-50 ms, so a
band-restricted solve (which would need a solver for varying geometry instead of the DCT) would
not pay; the band pays in the reinitialisation, which dominates.

The discrete energy
-------------------
The energy history is this backend's discrete energy of the zero level set Gamma of phi,

    E = mu L(Gamma) + sum_px H_eps(d) (omega + lambda_in sum_ch (I - c_in)^2)
                    + sum_px (1 - H_eps(d)) lambda_out sum_ch (I - c_out)^2

with ``d`` the signed distance to Gamma, ``L`` the exact length of the marching-squares polylines
(the returned contours, without the parts that close along the image border: the flow has a
Neumann condition there) and ``I`` the pixel values.  The regularised Heaviside and delta are the
cosine pair of Zhao, Chan, Merriman & Osher (1996)

    H_eps(s) = (1 + s/eps + sin(pi s/eps)/pi) / 2,   delta_eps(s) = (1 + cos(pi s/eps)) / (2 eps)

for ``|s| < eps`` (0 and 1 beyond).  Why this pair: delta_eps has compact support, so only pixels
within eps of Gamma enter (the narrow band), and for integer or half-integer ``eps >= 1`` its
integer translates sum to exactly 1 (its Fourier transform vanishes at every non-zero multiple of
2 pi), so ``sum_px H_eps(d)`` is the exact area of a half-plane at any sub-pixel offset and a
second-order accurate one for curved Gamma; the pixel area fractions are smooth in Gamma.  The
arctan pair of Chan & Vese 2001 never vanishes and biases area and length.

Because E depends on phi only through its zero level set, a reinitialisation leaves it unchanged
(up to the O(h^2 kappa) chord error of re-deriving Gamma from a distance function), and every
iteration's acceptance test compares energies *after* the reinitialisation: the history is
non-increasing at every iteration, reinitialisations included.  That is how they are accounted
for.  E approximates (6.38) with the pixel values as a piecewise-constant image; it is not the
common evaluator :func:`activecontour.energy.chan_vese_energy`, which integrates the bilinear
image exactly along polygon contours: use that one to compare backends.
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from activecontour.initial import initial_curves
from activecontour.raster import level_curves, rasterize
from activecontour.result import FlowState, SegmentationResult

__all__ = [
    "DEFAULT_OPTIONS",
    "checkerboard_level_set",
    "curves_level_set",
    "heaviside",
    "initial_level_set",
    "level_set_contours",
    "segment_levelset",
    "signed_distance",
    "smoothed_delta",
]

#: The backend-specific keywords of :func:`segment_levelset` and their defaults.
DEFAULT_OPTIONS = {
    "dt": 64.0,
    "dt_min": 4.0,
    "dt_max": 256.0,
    "epsilon": 1.0,
    "band": 4.0,
    "checkerboard_period": 16.0,
    "max_backtracks": 5,
}

#: The strings ``init`` may be, besides None, curves, masks and results.
INIT_STRINGS = ("checkerboard", "grid")

_FAR = 1e15  # a sentinel segment start: its squared distance stays finite in float32
_ONE_SWEEP_BAND = 8.0  # bands up to this half-width (pixels) need one sweep per ring
_STAGE_TOL = 10.0  # a smoothed-force stage ends at 10 tol: the next, finer one moves faster
_PATIENCE = 3  # iterations in a row below tol (pixels) that count as a stall
_ENERGY_WINDOW = 5  # the final stall test averages the energy decrease over this many iterations
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


# --------------------------------------------------------------------------------------------
# Regularised Heaviside and delta


def heaviside(phi, epsilon=1.0):
    """The cosine-regularised Heaviside ``H_eps``: 0 below -eps, 1 above eps, smooth between."""
    s = np.asarray(phi, dtype=np.float64) / epsilon
    ramp = 0.5 * (1.0 + s + np.sin(np.pi * np.clip(s, -1.0, 1.0)) / np.pi)
    return np.where(s >= 1.0, 1.0, np.where(s <= -1.0, 0.0, ramp))


def smoothed_delta(phi, epsilon=1.0):
    """``delta_eps = H_eps'``: ``(1 + cos(pi phi / eps)) / (2 eps)`` for ``|phi| < eps``, else 0."""
    s = np.clip(np.asarray(phi, dtype=np.float64) / epsilon, -1.0, 1.0)
    return (1.0 + np.cos(np.pi * s)) / (2.0 * epsilon)


# --------------------------------------------------------------------------------------------
# Signed distance to the zero level set (reinitialisation), in a narrow band


class _Redistanced:
    """A band-clipped signed distance with what the energy needs: the band and Gamma's length."""

    def __init__(self, phi, length, positive, near_flat, near_distance):
        self.phi = phi  # (M, N) float64, exact within the band, +-band beyond
        self.length = length  # length of the marching-squares zero set
        self.positive = positive  # phi > 0
        self.near_flat = near_flat  # flat indices of the pixels whose distance was computed
        self.near_distance = near_distance  # their signed distances


def signed_distance(phi, band=np.inf):
    """Reinitialise phi to the signed distance from its zero level set, keeping that set in place.

    Parameters
    ----------
    phi : ndarray (M, N)
        A level-set function; ``phi > 0`` is inside.
    band : float
        Narrow band: distances are computed up to ``band`` and clipped to ``[-band, band]``.

    Returns
    -------
    ndarray (M, N) float64

    Notes
    -----
    Gamma is the marching-squares zero set of phi (the segments :func:`level_set_contours`
    returns), so a straight front stays exactly where it was and a curved one within
    O(h^2 kappa).  A front pixel (one with a 4-neighbour of the other sign) is within one pixel of
    Gamma, so its nearest segment lies in one of the four grid cells around it: that search is
    exact.  The band then grows ring by ring from the front pixels: each new pixel takes the
    nearest of its eight neighbours' segments and walks along Gamma from it to nearer ones
    (closest-segment propagation, ordered like fast marching).  Within the band this is exact to
    ~1e-3 px in practice; the cost is a few passes over the image plus O(pixels in the band).
    """
    return _redistance(np.asarray(phi, dtype=np.float64), band).phi


def _redistance(phi, band):
    positive = phi > 0
    front = np.flatnonzero(_front_pixels(positive))
    if front.size == 0:
        return _Redistanced(_clipped(positive, band), 0.0, positive, np.zeros(0, dtype=np.intp),
                            np.zeros(0))
    rows, cols = np.divmod(front, phi.shape[1])
    segments, nearest = _front_segments(phi, positive, rows, cols)
    # far from Gamma a second sweep per ring keeps the propagation exact; within the few rings
    # of a narrow band, one sweep and the walk along Gamma are
    sweeps = 1 if band <= _ONE_SWEEP_BAND else 2
    return _propagate(positive, rows, cols, segments, nearest, band, sweeps)


def _clipped(positive, band):
    """``+band`` inside, ``-band`` outside (inf for an infinite band)."""
    if np.isfinite(band):
        return positive * (2.0 * band) - band
    return np.where(positive, np.inf, -np.inf)


def _front_pixels(positive):
    front = np.zeros_like(positive)
    change = positive[1:] != positive[:-1]
    front[1:] |= change
    front[:-1] |= change
    change = positive[:, 1:] != positive[:, :-1]
    front[:, 1:] |= change
    front[:, :-1] |= change
    return front


def _cell_segments(phi, positive, cell_r, cell_c):
    """Marching-squares segments of the zero set in grid cells, shape (K, 2 slots, 2 ends, 2).

    Cell (i, j) has the corners (i, j), (i, j+1), (i+1, j+1), (i+1, j).  Slot 1 is used by saddle
    cells only; unused slots are NaN.  A saddle isolates its two inside corners, the rule of
    ``skimage.measure.find_contours`` (``fully_connected="low"``), so the segments are those of
    :func:`level_set_contours`.  Also returns the key of the grid edge of every segment end
    (K, 2, 2), -1 for unused slots: two segments with a common key meet there.
    """
    width = phi.shape[1]
    a = phi[cell_r, cell_c]
    b = phi[cell_r, cell_c + 1]
    c = phi[cell_r + 1, cell_c + 1]
    d = phi[cell_r + 1, cell_c]
    sa, sb = positive[cell_r, cell_c], positive[cell_r, cell_c + 1]
    sc, sd = positive[cell_r + 1, cell_c + 1], positive[cell_r + 1, cell_c]
    r, q = cell_r.astype(np.float64), cell_c.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        # crossings on the edges top (a-b), right (b-c), bottom (d-c), left (a-d)
        points = np.stack([
            np.column_stack([r, q + a / (a - b)]),
            np.column_stack([r + b / (b - c), q + 1.0]),
            np.column_stack([r + 1.0, q + d / (d - c)]),
            np.column_stack([r + a / (a - d), q]),
        ], axis=1)
    exists = np.column_stack([sa != sb, sb != sc, sd != sc, sa != sd])
    # every crossing is named by its grid edge: 2 (row n + col) for the edge from (row, col) to
    # (row, col + 1), plus 1 for the edge from (row, col) to (row + 1, col)
    cell = cell_r * width + cell_c
    keys = np.column_stack([2 * cell, 2 * (cell + 1) + 1, 2 * (cell + width), 2 * cell + 1])
    count = exists.sum(axis=1)
    segments = np.full((len(a), 2, 2, 2), np.nan)
    segment_keys = np.full((len(a), 2, 2), -1, dtype=np.intp)
    simple = count == 2
    order = np.argsort(~exists[simple], axis=1, kind="stable")[:, :2]
    segments[simple, 0] = np.take_along_axis(points[simple], order[:, :, None], axis=1)
    segment_keys[simple, 0] = np.take_along_axis(keys[simple], order, axis=1)
    saddle = count == 4
    if saddle.any():
        p, k = points[saddle], keys[saddle]
        a_inside = sa[saddle][:, None]
        # inside corners a and c: cut off a (top, left) and c (right, bottom); else b and d
        segments[saddle, 0] = np.where(a_inside[:, :, None], p[:, [0, 3]], p[:, [0, 1]])
        segments[saddle, 1] = np.where(a_inside[:, :, None], p[:, [1, 2]], p[:, [3, 2]])
        segment_keys[saddle, 0] = np.where(a_inside, k[:, [0, 3]], k[:, [0, 1]])
        segment_keys[saddle, 1] = np.where(a_inside, k[:, [1, 2]], k[:, [3, 2]])
    return segments, segment_keys


def _segment_distance(points, starts, ends):
    """Distance from points (..., 2) to segments (..., 2); NaN segments give inf."""
    direction = ends - starts
    offset = points - starts
    length_sq = np.sum(direction * direction, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.sum(offset * direction, axis=-1) / length_sq, 0.0, 1.0)
    t = np.where(length_sq > 0, t, 0.0)
    gap = np.hypot(offset[..., 0] - t * direction[..., 0], offset[..., 1] - t * direction[..., 1])
    return np.where(np.isnan(gap), np.inf, gap)


def _front_segments(phi, positive, rows, cols):
    """The zero-set segments (every cell with a sign change) and the nearest one to each front pixel.

    Returns a :class:`_Segments` (every segment of Gamma once, and empty saddle slots) and
    ``nearest (F,)``, an index into it.
    """
    m, n = phi.shape
    corner = positive[:-1, :-1]
    change = (corner != positive[:-1, 1:]) | (corner != positive[1:, 1:]) | (corner != positive[1:, :-1])
    cells = np.flatnonzero(change)
    segments, keys = _cell_segments(phi, positive, cells // (n - 1), cells % (n - 1))
    segments, keys = segments.reshape(-1, 2, 2), keys.reshape(-1, 2)
    # the cells around every front pixel, as slots into ``cells`` (-1: none, or no sign change)
    slot = np.full(m * n, -1, dtype=np.intp)  # indexed by cell row * n + cell col
    slot[(cells // (n - 1)) * n + cells % (n - 1)] = np.arange(cells.size)
    around = []
    for dr, dc in ((-1, -1), (-1, 0), (0, -1), (0, 0)):
        r, c = rows + dr, cols + dc
        inside = (r >= 0) & (r < m - 1) & (c >= 0) & (c < n - 1)
        around.append(np.where(inside, slot[np.clip(r, 0, m - 1) * n + np.clip(c, 0, n - 1)], -1))
    around = np.column_stack(around)
    candidates = np.where(around[:, :, None] >= 0, 2 * around[:, :, None] + np.arange(2), -1)
    candidates = candidates.reshape(len(rows), 8)
    table = _Segments(segments, _links(keys))
    gap = table.squared_gap(rows.astype(np.float32)[:, None], cols.astype(np.float32)[:, None], candidates)
    nearest = candidates[np.arange(len(rows)), np.argmin(gap, axis=1)]
    return table, nearest


def _links(keys):
    """The neighbours of every segment along Gamma, (S, 2), from the keys of its two ends.

    Two segments are neighbours when an end of each has the same key; -1 where there is none.
    """
    flat = keys.ravel()
    used = np.flatnonzero(flat >= 0)
    order = used[np.argsort(flat[used], kind="stable")]
    links = np.full(flat.size, -1, dtype=np.intp)
    pair = np.flatnonzero(flat[order[:-1]] == flat[order[1:]])
    links[order[pair]] = order[pair + 1] // 2
    links[order[pair + 1]] = order[pair] // 2
    return links.reshape(-1, 2)


class _Segments:
    """Segments of Gamma set up for nearest-segment queries; id -1 is a far sentinel.

    ``segments (S, 2, 2)`` holds start and end in (row, col), NaN for an empty slot (also far);
    ``links (S, 2)`` the neighbours of each along Gamma (-1: none).  The queries run in float32
    (a quarter of the memory traffic, ample to rank candidates on images up to ~10^4 pixels);
    ``exact=True`` gives float64 for the final distances.
    """

    def __init__(self, segments, links):
        valid = ~np.isnan(segments[:, 0, 0])
        self.length = float(np.sum(np.hypot(*(segments[valid, 1] - segments[valid, 0]).T)))
        start = np.nan_to_num(segments[:, 0], nan=_FAR)
        direction = np.nan_to_num(segments[:, 1] - segments[:, 0])
        length_sq = np.sum(direction * direction, axis=1)
        inverse = np.divide(1.0, length_sq, out=np.zeros_like(length_sq), where=length_sq > 0)
        table = np.concatenate([np.column_stack([start, direction, inverse]), [[_FAR, _FAR, 0, 0, 0]]])
        self.columns = [np.ascontiguousarray(column) for column in table.T]
        self.columns32 = [column.astype(np.float32) for column in self.columns]
        self.links = np.concatenate([links, [[-1, -1]]])

    def squared_gap(self, point_r, point_c, ids, exact=False):
        """Squared distance from points to the segments ``ids`` (broadcast together)."""
        columns = self.columns if exact else self.columns32
        start_r, start_c, dir_r, dir_c, inverse = (column[ids] for column in columns)
        off_r = point_r - start_r
        off_c = point_c - start_c
        t = (off_r * dir_r + off_c * dir_c) * inverse
        np.clip(t, 0.0, 1.0, out=t)
        off_r -= t * dir_r
        off_c -= t * dir_c
        off_r *= off_r
        off_c *= off_c
        off_r += off_c
        return off_r

    def walk(self, point_r, point_c, own, best):
        """The nearest point of Gamma may lie on a segment next to ``own``: step along Gamma."""
        for _ in range(2):
            for side in (0, 1):
                candidate = self.links[own, side]
                trial = self.squared_gap(point_r, point_c, candidate)
                better = trial < best
                own = np.where(better, candidate, own)
                best = np.where(better, trial, best)
        return own, best


def _propagate(positive, rows, cols, segments, nearest, band, sweeps=1):
    """Grow the band ring by ring from the front pixels; each new pixel takes the nearest of its
    eight neighbours' segments, then walks along Gamma while that gets nearer."""
    m, n = positive.shape
    width = n + 2  # a one-pixel frame, marked visited, spares every bounds check
    visited = np.zeros((m + 2, width), dtype=bool)
    visited[0], visited[-1], visited[:, 0], visited[:, -1] = True, True, True, True
    visited = visited.ravel()
    owner = np.full((m + 2) * width, -1, dtype=np.intp)
    stamp = np.zeros((m + 2) * width, dtype=np.intp)
    steps = np.array([dr * width + dc for dr, dc in _NEIGHBOURS], dtype=np.intp)
    ring = (rows + 1) * width + cols + 1
    owner[ring] = nearest
    visited[ring] = True
    flats = [ring]
    # a pixel k rings away from the front pixels is at least k - 1 from Gamma
    max_rings = int(np.ceil(band)) + 1 if np.isfinite(band) else m + n
    for _ring in range(max_rings):
        fresh = (ring[:, None] + steps).ravel()
        fresh = fresh[~visited[fresh]]
        if fresh.size == 0:
            break
        # drop duplicates without sorting: the last writer of each pixel keeps it
        stamp[fresh] = np.arange(fresh.size)
        fresh = fresh[stamp[fresh] == np.arange(fresh.size)]
        visited[fresh] = True
        pr, pc = np.divmod(fresh, width)
        pr, pc = (pr - 1).astype(np.float32), (pc - 1).astype(np.float32)
        neighbours = fresh[:, None] + steps
        # the nearest of the neighbours' segments, then a walk along Gamma from it; a second
        # sweep lets a ring learn from itself (short segments, far distances)
        for _sweep in range(sweeps):
            candidates = owner[neighbours]
            trial = segments.squared_gap(pr[:, None], pc[:, None], candidates)
            pick = np.argmin(trial, axis=1)
            own = candidates[np.arange(fresh.size), pick]
            best = trial[np.arange(fresh.size), pick]
            own, best = segments.walk(pr, pc, own, best)
            owner[fresh] = own
        flats.append(fresh)
        ring = fresh
    flat = np.concatenate(flats)
    r, c = np.divmod(flat, width)
    distance = np.sqrt(segments.squared_gap((r - 1).astype(np.float64), (c - 1).astype(np.float64),
                                            owner[flat], exact=True))
    flat = (r - 1) * n + (c - 1)
    signed = np.where(positive.ravel()[flat], distance, -distance)
    phi = _clipped(positive, band)
    phi.ravel()[flat] = np.clip(signed, -band, band)
    return _Redistanced(phi, segments.length, positive, flat, signed)


def curves_level_set(curves, shape, band=np.inf):
    """Signed distance to closed curves (inside positive), exact in the band.

    The inside is the rasterised region (pixel centres with nonzero winding,
    :func:`activecontour.raster.rasterize`); the pixels next to its boundary get their exact
    distance to the curves (split into pieces of at most half a pixel), and the band inherits it
    by closest-segment propagation.

    Raises
    ------
    ValueError
        When the curves contain no pixel centre, or all of them.
    """
    import scipy.spatial

    positive = rasterize(curves, shape)
    if not positive.any():
        raise ValueError("init selects no pixel centre of the image: nothing would be inside")
    if positive.all():
        raise ValueError("init contains every pixel centre of the image: nothing would be outside")
    rows, cols = np.divmod(np.flatnonzero(_front_pixels(positive)), shape[1])
    pieces = [_densify(np.asarray(c, dtype=np.float64), 0.5) for c in curves]
    starts = np.concatenate(pieces)
    ends = np.concatenate([np.roll(piece, -1, axis=0) for piece in pieces])
    # the neighbours of piece i along its curve are i - 1 and i + 1, cyclically
    offsets = np.cumsum([0] + [len(piece) for piece in pieces])
    index = np.arange(len(starts))
    first = np.repeat(offsets[:-1], np.diff(offsets))
    size = np.repeat(np.diff(offsets), np.diff(offsets))
    links = np.column_stack([first + (index - first - 1) % size, first + (index - first + 1) % size])
    points = np.column_stack([rows, cols]).astype(np.float64)
    count = min(8, len(starts))
    _, near = scipy.spatial.cKDTree(0.5 * (starts + ends)).query(points, k=count)
    near = near.reshape(len(points), count)
    gap = _segment_distance(points[:, None, :], starts[near], ends[near])
    nearest = near[np.arange(len(points)), np.argmin(gap, axis=1)]
    segments = _Segments(np.stack([starts, ends], axis=1), links)
    return _propagate(positive, rows, cols, segments, nearest, band, sweeps=2).phi


def _densify(curve, spacing):
    end = np.roll(curve, -1, axis=0)
    length = np.hypot(*(end - curve).T)
    count = np.maximum(np.ceil(length / spacing).astype(np.intp), 1)
    edge = np.repeat(np.arange(len(curve)), count)
    t = (np.arange(edge.size) - np.repeat(np.cumsum(count) - count, count)) / count[edge]
    return curve[edge] + t[:, None] * (end - curve)[edge]


def checkerboard_level_set(shape, period):
    """Squares of p x p pixels, alternately in and out: ``(p/pi) sin(pi (r+1/2)/p) sin(pi (c+1/2)/p)``.

    The zero lines run between pixel centres (at ``r, c = k p - 1/2``), the square at the origin
    is inside, and the scaling makes ``|grad phi| = 1`` on the square sides.  A checkerboard start
    sees the whole image at once (Getreuer 2012; the default of ``skimage.segmentation.chan_vese``).
    """
    if not (np.isfinite(period) and period >= 2):
        raise ValueError(f"checkerboard_period must be a number >= 2 (pixels), got {period!r}")
    m, n = shape
    r = np.arange(m, dtype=np.float64)[:, None] + 0.5
    c = np.arange(n, dtype=np.float64)[None, :] + 0.5
    return (period / np.pi) * np.sin(np.pi * r / period) * np.sin(np.pi * c / period)


def initial_level_set(init, shape, *, band=np.inf, checkerboard_period=16.0, values=None):
    """The signed-distance level set of any ``init`` that :func:`segment_levelset` accepts.

    ``values`` (M, N, C), the normalised image, is used by ``"grid"`` only (see
    :func:`activecontour.initial.grid`).

    Raises
    ------
    ValueError
        For an unknown string (listing the valid ones), a mask or ``phi`` of the wrong shape, or
        an init that leaves nothing inside or nothing outside.
    """
    if isinstance(init, str):
        if init == "checkerboard":
            return signed_distance(checkerboard_level_set(shape, checkerboard_period), band)
        if init not in INIT_STRINGS:
            raise ValueError(
                f"init {init!r} is not understood by the level-set backend; the valid strings are "
                f"{', '.join(map(repr, INIT_STRINGS))} (or pass None, a (K, 2) curve, a list of "
                "curves, a bool mask or a SegmentationResult)"
            )
    phi = getattr(init, "phi", None)
    if phi is not None and hasattr(init, "mask"):
        phi = np.asarray(phi, dtype=np.float64)
        if phi.shape != tuple(shape):
            raise ValueError(
                f"init result has phi of shape {phi.shape}, but the image has shape {tuple(shape)}"
            )
        if not np.any(phi > 0):
            raise ValueError("init result has an empty inside (phi <= 0 everywhere)")
        return signed_distance(phi, band)
    return curves_level_set(initial_curves(init, shape, values), shape, band)


# --------------------------------------------------------------------------------------------
# Contours of the zero level set


def level_set_contours(phi):
    """The zero level set of phi as closed sub-pixel curves in the convention of :mod:`activecontour.curve`.

    Marching squares (``skimage.measure.find_contours``) on phi padded by one pixel of
    ``-|phi|``: a region that touches the image border closes along the domain edge, half a
    pixel outside the outermost pixel centres, so every curve is closed.  With
    ``positive_orientation="high"`` outer boundaries have positive signed area and holes
    negative.  Each vertex is stored once.
    """
    phi = np.asarray(phi, dtype=np.float64)
    padded = np.pad(phi, 1, mode="edge")
    padded[0], padded[-1] = -np.abs(padded[0]), -np.abs(padded[-1])
    padded[:, 0], padded[:, -1] = -np.abs(padded[:, 0]), -np.abs(padded[:, -1])
    padded[padded == 0] = -1e-300  # phi = 0 is outside, as in the mask phi > 0
    return level_curves(padded, 0.0)


# --------------------------------------------------------------------------------------------
# The energy E, the force f of (6.41) and the steps (a), (b)


class _Problem:
    """Image, parameters and the precomputed pieces of E, f and the operator S."""

    def __init__(self, model, params, settings):
        values = model.values
        self.shape = tuple(model.shape)
        self.n_channels = values.shape[2]
        self.values = values
        flat = values.reshape(-1, self.n_channels)
        # columns 1, I, I^2 per channel: the moments of a region are one matrix-vector product
        self.moments_matrix = np.ascontiguousarray(np.vstack([np.ones(len(flat)), flat.T, (flat * flat).T]))
        self.totals = self.moments_matrix.sum(axis=1)
        self.intensity_sq = np.sum(values * values, axis=2)
        self.params = params
        self.fixed_in = params.constant("c_in", self.n_channels)
        self.fixed_out = params.constant("c_out", self.n_channels)
        self.epsilon = settings["epsilon"]
        self.band = settings["band"]
        m, n = self.shape
        # eigenvalues of -Laplace (5-point, Neumann) in the DCT-II basis
        wave_r = 4.0 * np.sin(np.pi * np.arange(m) / (2.0 * m)) ** 2
        wave_c = 4.0 * np.sin(np.pi * np.arange(n) / (2.0 * n)) ** 2
        self.laplace_symbol = (wave_r[:, None] + wave_c[None, :]).astype(np.float32)

    def redistance(self, phi):
        return _redistance(phi, self.band)

    def energy(self, state):
        """E of a redistanced state with the optimal (or fixed) constants (6.42).

        Returns ``(E, c_in, c_out)``; a constant is NaN when its region is empty (6.42 is then
        undefined) and its fitting term is 0.
        """
        channels = self.n_channels
        moments = self.moments_matrix @ state.positive.ravel().astype(np.float64)
        near = np.abs(state.near_distance) < self.epsilon
        if near.any():
            d = state.near_distance[near]
            correction = heaviside(d, self.epsilon) - (d > 0)
            moments = moments + self.moments_matrix[:, state.near_flat[near]] @ correction
        area, s1, s2 = moments[0], moments[1 : 1 + channels], moments[1 + channels :]
        total_area = self.totals[0]
        t1, t2 = self.totals[1 : 1 + channels], self.totals[1 + channels :]
        outside = total_area - area
        c_in, c_out = self.fixed_in, self.fixed_out
        if c_in is None:
            c_in = s1 / area if area > 1e-12 else np.full(channels, np.nan)
        if c_out is None:
            c_out = (t1 - s1) / outside if outside > 1e-12 else np.full(channels, np.nan)
        p = self.params
        fit_in = float(np.sum(s2 - 2.0 * c_in * s1 + c_in * c_in * area)) if area > 1e-12 else 0.0
        fit_out = (
            float(np.sum((t2 - s2) - 2.0 * c_out * (t1 - s1) + c_out * c_out * outside))
            if outside > 1e-12 else 0.0
        )
        energy = p.mu * state.length + p.omega * area + p.lambda_in * fit_in + p.lambda_out * fit_out
        return float(energy), c_in, c_out

    def force(self, c_in, c_out):
        """f = omega + lambda_in sum (I - c_in)^2 - lambda_out sum (I - c_out)^2, per pixel (6.41)."""
        p = self.params
        c_in = np.nan_to_num(np.asarray(c_in, dtype=np.float64))
        c_out = np.nan_to_num(np.asarray(c_out, dtype=np.float64))
        linear = -2.0 * (p.lambda_in * c_in - p.lambda_out * c_out)
        constant = p.omega + p.lambda_in * float(c_in @ c_in) - p.lambda_out * float(c_out @ c_out)
        if self.n_channels == 1:
            f = self.values[:, :, 0] * linear[0] + constant
        else:
            f = self.values @ linear + constant
        if p.lambda_in != p.lambda_out:
            f += (p.lambda_in - p.lambda_out) * self.intensity_sq
        return f

    def step(self, phi, force, tau, smooth_force):
        """Step (a) ``S (phi - tau f)`` with ``smooth_force``, else (b) ``S phi - tau f``.

        ``S = (1 - tau mu Laplace)^{-1}`` by DCT-II in float32 (phi is a distance of a few pixels:
        its rounding, ~1e-6 px, is far below what matters).
        """
        rhs = (phi - tau * force if smooth_force else phi).astype(np.float32)
        if self.params.mu > 0:
            spectrum = scipy.fft.dctn(rhs, norm="ortho")
            spectrum /= 1.0 + np.float32(tau * self.params.mu) * self.laplace_symbol
            rhs = scipy.fft.idctn(spectrum, norm="ortho")
        out = rhs.astype(np.float64)
        if not smooth_force:
            out -= tau * force
        return out


def _parse_options(options):
    unknown = sorted(set(options) - set(DEFAULT_OPTIONS))
    if unknown:
        raise TypeError(
            f"unknown option(s) {', '.join(map(repr, unknown))} for backend 'levelset'; "
            f"the valid options are {', '.join(sorted(DEFAULT_OPTIONS))}"
        )
    settings = {**DEFAULT_OPTIONS, **options}
    for name in ("dt", "dt_min", "dt_max", "epsilon", "band", "checkerboard_period"):
        value = settings[name]
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"option {name!r} must be a number, got {type(value).__name__}")
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"option {name!r} must be a positive finite number, got {value!r}")
        settings[name] = float(value)
    value = settings["max_backtracks"]
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"option 'max_backtracks' must be an integer >= 0, got {value!r}")
    settings["max_backtracks"] = int(value)
    # a first step outside the default range widens it (a viewer's step slider, say); only
    # bounds given explicitly must hold
    if "dt_min" not in options:
        settings["dt_min"] = min(settings["dt_min"], settings["dt"])
    if "dt_max" not in options:
        settings["dt_max"] = max(settings["dt_max"], settings["dt"])
    if not settings["dt_min"] <= settings["dt"] <= settings["dt_max"]:
        raise ValueError(
            f"options must satisfy dt_min <= dt <= dt_max, got dt_min={settings['dt_min']}, "
            f"dt={settings['dt']}, dt_max={settings['dt_max']}"
        )
    if settings["band"] < settings["epsilon"] + 1.0:
        raise ValueError(
            f"option 'band' ({settings['band']}) must be at least epsilon + 1 ({settings['epsilon'] + 1})"
        )
    return settings


# --------------------------------------------------------------------------------------------
# The backend


def _stalled(energies, stage_start, tol):
    """Mean relative decrease of E over the last iterations of the stage below tol."""
    if len(energies) - stage_start <= _ENERGY_WINDOW:
        return False
    decrease = (energies[-1 - _ENERGY_WINDOW] - energies[-1]) / _ENERGY_WINDOW
    return decrease < tol * max(abs(energies[-1]), 1e-300)


def segment_levelset(model, init, params, *, max_num_iter, tol, callback, **options):
    """Minimise the Chan-Vese functional (6.38) with a level set over the pixel grid.

    Called by :func:`activecontour.segment` with ``backend="levelset"``; the keywords under
    Other Parameters are passed there as ``options={...}``.  The scheme, the regularised
    Heaviside/delta and the discrete energy are described in :mod:`activecontour.levelset`.

    Parameters
    ----------
    model : activecontour.image.ImageModel
    init : None, ndarray (K, 2), list of them, bool ndarray (M, N), SegmentationResult, or str
        None: the default circle (:func:`activecontour.initial.default_init`).  Curves, masks
        and ``"grid"`` as for the polygon backend (pixel centres with nonzero winding are
        inside).  A result of either backend: its ``phi`` when it has one, else its contours.
        ``"checkerboard"``: squares of ``checkerboard_period`` x ``checkerboard_period`` pixels
        (:func:`checkerboard_level_set`); it has no preferred phase, so when the functional is
        symmetric (omega = 0, lambda_in = lambda_out, c free) and the final inside covers most of
        the image border, the phases are swapped (phi -> -phi, E unchanged) so that the inside is
        the object rather than the background.
    params : activecontour.energy.ChanVeseParameters
        mu, omega, lambda_in, lambda_out and optional fixed c_in, c_out of (6.38), as for the
        polygon backend.
    max_num_iter : int
    tol : float
        As for the polygon backend: the final stage stalls, which is convergence (status 0), when
        the relative decrease of E per iteration, averaged over the last five iterations, falls
        below ``tol`` (the end of the slow tail of noisy images), or when the zero level set moves
        less than ``tol`` pixels (largest change of the signed distance within a pixel of Gamma)
        three iterations in a row.  A smoothed-force stage (module docstring) ends at 10 tol, or
        at the same displacement test.  The run also ends when no step, down to the current one
        halved ``max_backtracks`` times, decreases E (status 4: stationary to working precision).
    callback : callable or None
        Called with a :class:`~activecontour.result.FlowState` (contours and ``phi``) after every
        iteration; returning True stops the flow (status 2).

    Other Parameters
    ----------------
    dt : float, default 64.0
        First time step tau, in pixels per unit of intensity^2: a front in a force ``|f| = 1``
        moves about tau pixels.  It doubles after each accepted step until a step is rejected
        (then it is halved) or ``dt_max`` is reached.  Large steps let whole regions flip at once
        (holes open, far objects appear); the energy test rejects those that do not pay.
    dt_min : float, default 4.0
        The smoothed-force stage divides tau by 4 at every stall down to ``dt_min`` (its fixed
        point is biased by the smoothing length ``sqrt(tau mu)``); the final, unsmoothed stage
        keeps tau <= ``dt_min``, which must stay below ``band / max|f|`` so that no single pixel
        flips.
    dt_max : float, default 256.0
        Largest time step.  A ``dt`` outside ``[dt_min, dt_max]`` widens the defaults; bounds given
        explicitly must satisfy ``dt_min <= dt <= dt_max``.
    epsilon : float, default 1.0
        Half-width (pixels) of the regularised Heaviside/delta of E.  Use an integer or a
        half-integer >= 1 (exact areas, see the module docstring).
    band : float, default 4.0
        Narrow band: phi is the signed distance up to ``band`` pixels from Gamma and is clipped to
        ``+-band`` beyond.  Must be >= epsilon + 1.
    checkerboard_period : float, default 16.0
        Side (pixels) of the squares of the ``"checkerboard"`` start.
    max_backtracks : int, default 5
        Halvings of the time step before an iteration counts as stationary.

    Returns
    -------
    SegmentationResult
        ``mask = phi > 0``, ``contours`` the zero level set (marching squares, outer boundaries
        positive, holes negative), ``phi`` the final signed distance (clipped to the band), and
        ``energies`` the discrete energy E before the first and after every iteration (not
        increasing).

    Raises
    ------
    TypeError
        For an unknown option (the message lists the valid ones) or an option of the wrong type.
    ValueError
        For an unknown ``init`` string, a mask of the wrong shape, an init with nothing inside or
        nothing outside, or an option out of range.
    """
    settings = _parse_options(options)
    shape = tuple(model.shape)
    problem = _Problem(model, params, settings)
    if isinstance(init, str) and init == "checkerboard":
        phi = checkerboard_level_set(shape, settings["checkerboard_period"])  # redistanced below
    else:
        phi = initial_level_set(init, shape, band=settings["band"], values=model.values)
    state = problem.redistance(phi)
    energy, c_in, c_out = problem.energy(state)
    energies = [energy]
    tau, grow, smooth_force = settings["dt"], True, True
    status, n_iter, quiet, stage_start = 1, 0, 0, 0
    for k in range(1, max_num_iter + 1):
        if not state.positive.any():
            status = 3
            break
        force = problem.force(c_in, c_out)
        first_try = True
        for _ in range(settings["max_backtracks"] + 1):
            trial = problem.redistance(problem.step(state.phi, force, tau, smooth_force))
            trial_energy, trial_in, trial_out = problem.energy(trial)
            # A large step uses the constants of the old region; one that empties a region jumps
            # past what c would have followed, so emptying is left to small steps.
            degenerate = tau > settings["dt_min"] and (
                not trial.positive.any() or trial.positive.all())
            if trial_energy <= energy and not degenerate:
                break
            tau *= 0.5
            grow = first_try = False
        else:
            status = 4
            break
        n_iter = k
        near = (np.abs(trial.phi) < 1.0) | (np.abs(state.phi) < 1.0)
        displacement = float(np.max(np.abs(trial.phi - state.phi)[near], initial=0.0))
        decrease = (energy - trial_energy) / max(abs(trial_energy), 1e-300)
        state, energy, c_in, c_out = trial, trial_energy, trial_in, trial_out
        energies.append(energy)
        quiet = quiet + 1 if displacement < tol else 0
        if callback is not None:
            flow_state = FlowState(
                iteration=k, contours=level_set_contours(state.phi), energy=energy, c_in=c_in,
                c_out=c_out, shape=shape, max_num_iter=max_num_iter, phi=state.phi,
            )
            if callback(flow_state):
                status = 2
                break
        if smooth_force:
            if grow and tau < settings["dt_max"]:
                tau = min(2.0 * tau, settings["dt_max"])  # no rejection yet: still speeding up
                continue
            if decrease >= _STAGE_TOL * tol and quiet < _PATIENCE:
                continue
            # the smoothed-force step has stalled at this tau; its fixed point is biased by the
            # smoothing of width sqrt(tau mu), so go on with a smaller tau, then unsmoothed
            if tau > settings["dt_min"]:
                tau = max(0.25 * tau, settings["dt_min"])
            else:
                smooth_force, tau = False, settings["dt_min"]
            quiet, stage_start = 0, len(energies) - 1
        elif quiet >= _PATIENCE or _stalled(energies, stage_start, tol):
            status = 0
            break
        elif first_try:
            # the unsmoothed force moves single pixels: tau stays below dt_min, so that no
            # noise pixel can cross the band (|tau f| < band) and nucleate
            tau = min(1.5 * tau, settings["dt_min"])
    phi = state.phi
    if isinstance(init, str) and init == "checkerboard" and _symmetric(params) and _border_inside(phi):
        # The checkerboard has no preferred phase and, for this symmetric functional, neither
        # has E (H_eps(-d) = 1 - H_eps(d)): return the phase whose inside is not the background,
        # taken to be the region that covers most of the image border.  E is unchanged.
        phi, c_in, c_out = -phi, c_out, c_in
    if not np.any(phi > 0):
        status = 3
    return SegmentationResult(
        mask=phi > 0, contours=level_set_contours(phi), c_in=c_in, c_out=c_out, energy=energy,
        energies=energies, n_iter=n_iter, status=status, backend="levelset", phi=phi,
    )


def _symmetric(params):
    return (params.omega == 0 and params.lambda_in == params.lambda_out
            and params.c_in is None and params.c_out is None)


def _border_inside(phi):
    border = np.concatenate([phi[0], phi[-1], phi[1:-1, 0], phi[1:-1, -1]])
    return np.count_nonzero(border > 0) > border.size / 2
