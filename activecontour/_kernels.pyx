# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The compiled inner loops, built ahead of time at install (no compile on first use).

One implementation of each loop; the Python modules that own the mathematics call them:

* :func:`build_tables`, :func:`edge_integrals` -- :mod:`activecontour.image`, :mod:`activecontour.energy`
  (the row-antiderivative tables and the exact integrals along the edges, (6.38) and (6.41));
* :func:`cyclic_thomas` -- :mod:`activecontour.fem` (the block-cyclic tridiagonal solve of (6.40));
* :func:`segments_meet`, :func:`winding`, :func:`winding_banded`, :func:`curve_areas`, :func:`border_overlap` --
  :mod:`activecontour.topology`, :mod:`activecontour.curve` (crossing curves, edges along the border) and
  :mod:`activecontour.backends.network` (a network's segments that meet);
* :func:`mask_contours` -- :mod:`activecontour.raster` (the outlines of a mask);
* :func:`sampled_distance` -- :mod:`activecontour.objects.split` (the distance to an object's
  boundary at its pixel centres, from a finer raster), :func:`near_reaches` (whether the
  distance transform reaches a radius of a few pixels, for the split's tests against it), :func:`distance_peaks`
  (an object's distance transform and its pieces of peaks: the first test for necks),
  :func:`fill_holes` (an object's window without holes),
  :func:`ellipse_moments`, :func:`conic_residuals`, :func:`convex_clip_area`, :func:`segment_inside`, :func:`cut_ratios` (the corner stage's
  ellipse fits and cut search);
* :func:`convex_hull` -- :mod:`activecontour.geometry.hull` (a polygon's convex hull);
* :func:`segment_integrals`, :func:`segment_loads`, :func:`h1_band`, :func:`band_cholesky`, :func:`band_solve`,
  :func:`cycles`, :func:`untwist`, :func:`step_bounds`, :func:`normal_part` -- :mod:`activecontour.energy`,
  :mod:`activecontour.geometry.partition`,
  :mod:`activecontour.backends.network` (the N-region network: its integrals, load (6.41), H^1
  solve and the bounds of an iteration's steps);
* :func:`front_and_cells`, :func:`cell_segments`, :func:`nearest_segments`, :func:`grow_band`,
  :func:`band_distances`, :func:`edge_soup`, :func:`swept_area`, :func:`force_step`,
  :func:`force_step_tiles`, :func:`tile_pieces`, :func:`block_moments`,
  :func:`divide_spectrum`, :func:`block_means`, :func:`explicit_step`, :func:`band_couplings`, :func:`sides`,
  :func:`sides_at`, :func:`front_distances`, :func:`segment_table` -- :mod:`activecontour.backends.levelset` (the
  sides of phi, the front, the marching-squares segments of the zero set and their table, the
  narrow band's distances, the oriented soup of segments that the common evaluator scores by
  (6.38), the area swept by Gamma, the steps (a) and (b)).

Arrays come in as typed memoryviews (the buffer protocol), so the build needs no numpy headers.
Loops over a whole image poll for Ctrl-C every few hundred rows.
"""

from cpython.exc cimport PyErr_CheckSignals
from libc.math cimport INFINITY, M_PI, fabs, fma, hypot, isnan, sin, sqrt
from libc.stdint cimport uint64_t
from libc.stdlib cimport calloc, free, malloc, qsort, realloc
from libc.string cimport memcpy, memmove

cdef Py_ssize_t _POLL_ROWS = 256

cdef enum:
    # edges ahead of the one integrated whose image cells :func:`edge_integrals` asks the cache for
    _PREFETCH_EDGES = 8

cdef extern from *:
    """
    #if defined(__GNUC__) || defined(__clang__)
    #define AC_PREFETCH(address) __builtin_prefetch(address)
    #else
    #define AC_PREFETCH(address) ((void) 0)
    #endif
    """
    # a hint: fetch the cache line of an address now; changes no value.  Written in the loop
    # itself: GCC takes a function that only prefetches for one without effect and drops its calls
    void AC_PREFETCH(const void *address) noexcept nogil


cdef inline Py_ssize_t _clamp(Py_ssize_t i, Py_ssize_t size) noexcept nogil:
    if i < 0:
        return 0
    if i >= size:
        return size - 1
    return i


cdef inline double _floor(double x) noexcept nogil:
    """floor(x) for |x| < 2^63 in a few instructions (for the generic x86-64 target, without SSE4.1's
    rounding instruction, the compiler spends about twenty on libm's floor)."""
    cdef double truncated = <double> (<long long> x)
    return truncated - 1.0 if truncated > x else truncated


def build_tables(const double[:, :, ::1] values, double[:, :, :, ::1] table, Py_ssize_t anchor,
                 double[::1] total1, double[::1] total2):
    """One pass over the image: the row-antiderivative tables and the domain totals.

    In padded coordinates ``(u, v) = (r + 1, c + 1)`` (the image padded by one replicated pixel,
    P), the exact integrals along the column profiles, which are piecewise linear in u, are

        t1[a, j] = int_0^a P(s, j) ds,  t2[a, j] = int_0^a P(s, j)^2 ds,
        t3[a, j] = int_0^a P(s, j) P(s, j + 1) ds.

    Only every ``anchor``-th row ``a = k anchor`` is stored, ``table[k, j, ch] = (t1, t2, t3)``
    (``table`` has ``(M + 1) // anchor + 1`` rows); :func:`edge_integrals` adds the few increments
    from there to the row it needs, from the image itself.  ``anchor = 8`` keeps the tables at 3/8 of
    a float64 per pixel and channel, ``anchor = 1`` (3 float64) saves those increments.  Float64:
    t1 grows to M, and float32 would carry an absolute error of ~M * 6e-8 into every boundary
    integral, far above the rounding level that makes (6.41) the exact gradient of (6.38).

    ``total1[ch] = int_D I``, ``total2[ch] = int_D I^2`` over the domain D (the union of the pixel
    squares), exactly: along each axis the hat functions of the replicated-edge interpolant
    integrate to 1 and their products to the tridiagonal matrix with 1/6 off the diagonal and
    2/3 on it (5/6 at the two ends), so ``int_D I^2 = sum_{a,c} B_ac R(V_a, V_c)`` with R the same
    form along the columns.
    """
    cdef Py_ssize_t m = values.shape[0], n = values.shape[1], channels = values.shape[2]
    cdef Py_ssize_t width = n + 2, a, j, ch, c_lo, c_hi, index
    cdef const double *lo
    cdef const double *hi
    cdef double diagonal, same, following
    cdef double *acc = <double *> malloc(width * channels * 3 * sizeof(double))
    if acc == NULL:
        raise MemoryError()
    try:
        for index in range(width * channels * 3):
            acc[index] = 0.0
        table[0, :, :, :] = 0.0
        total1[:] = 0.0
        total2[:] = 0.0
        for a in range(m + 1):  # padded rows a -> a + 1, i.e. image rows a - 1 -> a (clamped)
            if a % _POLL_ROWS == 0:
                PyErr_CheckSignals()
            lo = &values[_clamp(a - 1, m), 0, 0]
            hi = &values[_clamp(a, m), 0, 0]
            with nogil:
                if channels == 1:  # gray: t1, t2, t3 each in a row of its own (the loop vectorises)
                    _gray_row(lo, hi, n, acc, acc + width, acc + 2 * width)
                else:
                    for j in range(width):
                        c_lo = _clamp(j - 1, n) * channels
                        c_hi = _clamp(j, n) * channels  # the right neighbour j + 1 in padded columns
                        for ch in range(channels):
                            index = (j * channels + ch) * 3
                            _accumulate(lo[c_lo + ch], hi[c_lo + ch], lo[c_hi + ch], hi[c_hi + ch],
                                        acc + index, acc + index + 1, acc + index + 2)
            if (a + 1) % anchor == 0:
                for j in range(width):
                    for ch in range(channels):
                        for index in range(3):
                            table[(a + 1) // anchor, j, ch, index] = (
                                acc[index * width + j] if channels == 1 else acc[(j * channels + ch) * 3 + index])
        for ch in range(channels):
            table[:, width - 1, ch, 2] = 0.0  # t3 of the last column has no right neighbour
        for a in range(m):  # domain totals, image row by image row
            if a % _POLL_ROWS == 0:
                PyErr_CheckSignals()
            diagonal = 2.0 / 3.0 + (1.0 / 6.0 if a == 0 else 0.0) + (1.0 / 6.0 if a == m - 1 else 0.0)
            for ch in range(channels):
                same, following = _row_forms(values, a, ch, total1)
                total2[ch] += diagonal * same + following / 3.0
    finally:
        free(acc)


cdef inline void _accumulate(double p_lo, double p_hi, double q_lo, double q_hi, double *t1, double *t2,
                             double *t3) noexcept nogil:
    """Add one padded row step of a column's profile P (and its right neighbour Q) to the
    column's (t1, t2, t3) of :func:`build_tables`: the exact integrals of P, P^2 and P Q over it."""
    t1[0] += 0.5 * (p_lo + p_hi)
    t2[0] += (p_lo * p_lo + p_lo * p_hi + p_hi * p_hi) / 3.0
    t3[0] += (2.0 * p_lo * q_lo + p_lo * q_hi + p_hi * q_lo + 2.0 * p_hi * q_hi) / 6.0


cdef inline void _gray_row(const double *lo, const double *hi, Py_ssize_t n, double *t1, double *t2,
                           double *t3) noexcept nogil:
    """:func:`_accumulate` of the n + 2 padded columns of a gray row step (columns 0, n and n + 1
    replicate the image's first and last)."""
    cdef Py_ssize_t j
    _accumulate(lo[0], hi[0], lo[0], hi[0], t1, t2, t3)
    for j in range(1, n):
        _accumulate(lo[j - 1], hi[j - 1], lo[j], hi[j], t1 + j, t2 + j, t3 + j)
    for j in range(n, n + 2):
        _accumulate(lo[n - 1], hi[n - 1], lo[n - 1], hi[n - 1], t1 + j, t2 + j, t3 + j)


cdef (double, double) _row_forms(const double[:, :, ::1] values, Py_ssize_t a, Py_ssize_t ch,
                                 double[::1] total1) noexcept nogil:
    """``R(V_a, V_a)`` and ``R(V_a, V_{a+1})`` (0 for the last row), ``R(x, y) = int x(v) y(v) dv``
    of the column interpolants of two image rows; adds row a's sum to ``total1[ch]``."""
    cdef Py_ssize_t n = values.shape[1], j, last = values.shape[0] - 1
    cdef Py_ssize_t below = a + 1 if a < last else a
    cdef double same = 0.0, following = 0.0, row_sum = 0.0, x0, x1, y0, y1, weight
    for j in range(n):
        x0, y0 = values[a, j, ch], values[below, j, ch]
        row_sum += x0
        weight = 2.0 / 3.0 if 0 < j < n - 1 else (1.0 if n == 1 else 5.0 / 6.0)
        same += weight * x0 * x0
        following += weight * x0 * y0
        if j + 1 < n:
            x1, y1 = values[a, j + 1, ch], values[below, j + 1, ch]
            same += x0 * x1 / 3.0
            following += (x0 * y1 + x1 * y0) / 6.0
    total1[ch] += row_sum
    return same, (following if a < last else 0.0)


cdef struct Cell:
    # interpolation cell [a, a + 1] x [j, j + 1] in local coordinates (t, w) in [0, 1]^2: the image
    # I = (1 - w) P(t) + w Q(t), P = p0 + t dp on column j and Q = q0 + t dq on column j + 1, and the
    # row-antiderivatives from padded row 0 as polynomials in t (Horner coefficients):
    #   int P = t1 + t (p0 + t hp),               int Q = r1 + t (q0 + t hq),
    #   int P^2 = t2 + t (pp1 + t (pp2 + t pp3)),  int Q^2 = r2 + t (qq1 + t (qq2 + t qq3)),
    #   int P Q = t3 + t (pq1 + t (pq2 + t pq3))
    double p0, q0, dp, dq, hp, hq, t1, r1
    double t2, pp1, pp2, pp3
    double r2, qq1, qq2, qq3
    double t3, pq1, pq2, pq3


cdef inline void _cells(const double[:, :, ::1] values, const double[:, :, :, ::1] table, Py_ssize_t anchor,
                        Py_ssize_t a, Py_ssize_t j, Cell *cells) noexcept nogil:
    """The data of cell (a, j) of every channel: the stored row at or below a, plus the increments
    from there up to a."""
    cdef Py_ssize_t k = a if anchor == 1 else a // anchor, i, ch, channels = values.shape[2]
    cdef Py_ssize_t rows = values.shape[0], cols = values.shape[1]
    # the padded image's columns j and j + 1, rows a and a + 1: image indices, clamped
    cdef Py_ssize_t left = _clamp(j - 1, cols), right = _clamp(j, cols)
    cdef Py_ssize_t low = _clamp(a - 1, rows), high = _clamp(a, rows)
    cdef double p_lo, q_lo, p_hi, q_hi
    cdef Cell *cell
    for ch in range(channels):
        cell = &cells[ch]
        cell.t1 = table[k, j, ch, 0]
        cell.t2 = table[k, j, ch, 1]
        cell.t3 = table[k, j, ch, 2]
        cell.r1 = table[k, j + 1, ch, 0]
        cell.r2 = table[k, j + 1, ch, 1]
        if k * anchor == a:
            p_lo, q_lo = values[low, left, ch], values[low, right, ch]
        else:
            p_lo = values[_clamp(k * anchor - 1, rows), left, ch]
            q_lo = values[_clamp(k * anchor - 1, rows), right, ch]
            for i in range(k * anchor, a):
                p_hi = values[_clamp(i, rows), left, ch]
                q_hi = values[_clamp(i, rows), right, ch]
                cell.t1 += 0.5 * (p_lo + p_hi)
                cell.t2 += (p_lo * p_lo + p_lo * p_hi + p_hi * p_hi) / 3.0
                cell.t3 += (2.0 * p_lo * q_lo + p_lo * q_hi + p_hi * q_lo + 2.0 * p_hi * q_hi) / 6.0
                cell.r1 += 0.5 * (q_lo + q_hi)
                cell.r2 += (q_lo * q_lo + q_lo * q_hi + q_hi * q_hi) / 3.0
                p_lo, q_lo = p_hi, q_hi
        cell.p0, cell.q0 = p_lo, q_lo
        cell.dp = values[high, left, ch] - p_lo
        cell.dq = values[high, right, ch] - q_lo
        cell.hp, cell.hq = 0.5 * cell.dp, 0.5 * cell.dq
        cell.pp1, cell.pp2, cell.pp3 = cell.p0 * cell.p0, cell.p0 * cell.dp, cell.dp * cell.dp / 3.0
        cell.qq1, cell.qq2, cell.qq3 = cell.q0 * cell.q0, cell.q0 * cell.dq, cell.dq * cell.dq / 3.0
        cell.pq1 = cell.p0 * cell.q0
        cell.pq2 = 0.5 * (cell.p0 * cell.dq + cell.q0 * cell.dp)
        cell.pq3 = cell.dp * cell.dq / 3.0


cdef inline (double, double) _green(const Cell *cell, double t, double w) noexcept nogil:
    """``(G_1, G_2)`` at local (t, w) of the cell: the row-antiderivatives of I and I^2 from padded
    row 0, whose closed integrals ``G dc`` are the region integrals of I and I^2 (Green's theorem)."""
    cdef double w0 = 1.0 - w
    return ((w0 * (cell.t1 + t * (cell.p0 + t * cell.hp)) + w * (cell.r1 + t * (cell.q0 + t * cell.hq))),
            (w0 * w0 * (cell.t2 + t * (cell.pp1 + t * (cell.pp2 + t * cell.pp3)))
             + 2.0 * w * w0 * (cell.t3 + t * (cell.pq1 + t * (cell.pq2 + t * cell.pq3)))
             + w * w * (cell.r2 + t * (cell.qq1 + t * (cell.qq2 + t * cell.qq3)))))


def edge_integrals(const double[:, ::1] points, const Py_ssize_t[::1] next_index,
                   const double[:, :, ::1] values, const double[:, :, :, ::1] table, Py_ssize_t anchor,
                   bint moments, double[::1] s1, double[::1] s2, double[::1] sums, double[:, :, ::1] parts):
    """Exact integrals along every edge, split where it crosses a grid line, in one pass.

    With ``moments`` it adds the moments ``closed integral of G dc`` (Green's theorem, the region
    integrals of I and I^2 per channel) into s1, s2 and the signed area and length into ``sums``.
    With ``parts`` of shape (K, 2, 2 + 2C) (a (0, 2, 0) array for none) it adds the derivatives of
    the terms of (6.38) with respect to every vertex X_j, component d, whose combination with the
    weights ``(mu, constant, linear_1..C, square_1..C)`` of a quadratic form g
    (:class:`activecontour.models.base.QuadraticForm`) is the load (6.41) (:func:`combine_load`):

        parts[j, d, 0]          = (tau_{j-1} - tau_j)_d      (the derivative of the length)
        parts[j, d, 1]          = int_Gamma phi_j nu_d ds
        parts[j, d, 2 + ch]     = int_Gamma I_ch phi_j nu_d ds
        parts[j, d, 2 + C + ch] = int_Gamma I_ch^2 phi_j nu_d ds.

    Each piece between grid lines lies in one interpolation cell [a, a + 1] x [j, j + 1]: there,
    with local coordinates (t, w), I is bilinear and its row-antiderivatives are the table values at
    row a plus the exact integral from a to u, so the integrands are polynomials of degree <= 5 in
    the edge parameter and 3-point Gauss-Legendre is exact.  The table stores every ``anchor``-th
    padded row (:func:`build_tables`); a cell is read once for consecutive pieces in it (the end of
    one edge and the start of the next).
    """
    cdef Py_ssize_t channels = values.shape[2], rows = values.shape[0], cols = values.shape[1]
    cdef Py_ssize_t e, b, ch, g, a, j, p, count = points.shape[0], last_a = -1, last_j = -1
    cdef Py_ssize_t ahead_a, ahead_j, ahead_k
    cdef Py_ssize_t n_parts = parts.shape[2] if parts.shape[0] > 0 else 0
    cdef double nodes[3]
    cdef double weights[3]
    cdef double t[3]         # the Gauss points of a piece in the cell's local coordinates (t, w)
    cdef double w[3]
    cdef double moment[3]    # their weights in the moments (times dv: Green's closed integral of G dc)
    cdef double to_start[3]  # ... in the load on the edge's start (phi = 1 - s) and end (phi = s)
    cdef double to_end[3]
    cdef double u0, v0, du, dv, k_u, k_v, t_prev, t_u, t_v, t_next, span, t_mid, at, weight
    cdef double intensity, g1, g2, length, area = 0.0, total_length = 0.0
    cdef double tangent_r, tangent_c, step_u, step_v, inverse_u, inverse_v
    cdef double *start_r
    cdef double *start_c
    cdef double *end_r
    cdef double *end_c
    cdef Cell *cell
    cdef Cell *cells = <Cell *> malloc(channels * sizeof(Cell))
    cdef double *acc = <double *> calloc(2 * channels, sizeof(double))  # int I, int I^2
    cdef double *at_start = <double *> malloc((n_parts + 1) * sizeof(double))
    cdef double *at_end = <double *> malloc((n_parts + 1) * sizeof(double))
    if cells == NULL or at_start == NULL or at_end == NULL or acc == NULL:
        free(acc)
        free(cells)
        free(at_start)
        free(at_end)
        raise MemoryError()
    if n_parts and (parts.shape[0] != count or parts.shape[1] != 2 or n_parts != 2 + 2 * channels):
        free(acc)
        free(cells)
        free(at_start)
        free(at_end)
        raise ValueError(f"parts must have shape ({count}, 2, {2 + 2 * channels}), got "
                         f"({parts.shape[0]}, {parts.shape[1]}, {parts.shape[2]})")
    nodes[0], nodes[1], nodes[2] = 0.5 - 0.5 * sqrt(0.6), 0.5, 0.5 + 0.5 * sqrt(0.6)
    weights[0], weights[1], weights[2] = 5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0
    with nogil:
        for e in range(count):
            if e + _PREFETCH_EDGES < count:
                # the stacked curves run through the image in no order and the table (24 bytes a
                # pixel and channel) outgrows the caches: without this most cells of :func:`_cells`
                # are a memory load each (a third of the time at 512^2); asked for a few edges
                # ahead, the cell of an edge's start arrives while the edges before are integrated
                ahead_a = <Py_ssize_t> min(max(points[e + _PREFETCH_EDGES, 0] + 1.0, 0.0), <double> rows)
                ahead_j = <Py_ssize_t> min(max(points[e + _PREFETCH_EDGES, 1] + 1.0, 0.0), <double> cols)
                ahead_k = ahead_a if anchor == 1 else ahead_a // anchor
                AC_PREFETCH(&table[ahead_k, ahead_j, 0, 0])
                AC_PREFETCH(&table[ahead_k, ahead_j + 1, channels - 1, 2])
                AC_PREFETCH(&values[_clamp(ahead_a - 1, rows), _clamp(ahead_j - 1, cols), 0])
                AC_PREFETCH(&values[_clamp(ahead_a, rows), _clamp(ahead_j, cols), 0])
            b = next_index[e]
            u0, v0 = points[e, 0] + 1.0, points[e, 1] + 1.0
            du, dv = points[b, 0] + 1.0 - u0, points[b, 1] + 1.0 - v0
            inverse_u = 1.0 / du if du != 0.0 else 0.0
            inverse_v = 1.0 / dv if dv != 0.0 else 0.0
            # next grid lines in the direction of travel
            step_u = 1.0 if du > 0 else -1.0
            step_v = 1.0 if dv > 0 else -1.0
            k_u = _floor(u0) + 1.0 if du > 0 else -_floor(-u0) - 1.0
            k_v = _floor(v0) + 1.0 if dv > 0 else -_floor(-v0) - 1.0
            for p in range(n_parts):
                at_start[p] = 0.0
                at_end[p] = 0.0
            t_prev = 0.0
            while True:
                t_u = (k_u - u0) * inverse_u if du != 0.0 else 2.0
                t_v = (k_v - v0) * inverse_v if dv != 0.0 else 2.0
                t_next = min(t_u, t_v, 1.0)
                span = t_next - t_prev
                if span > 0.0:
                    t_mid = t_prev + 0.5 * span
                    # the cell of the piece's middle (clamped to the padded image: >= 0, so a
                    # truncation is its floor)
                    a = <Py_ssize_t> min(max(u0 + t_mid * du, 0.0), <double> rows)
                    j = <Py_ssize_t> min(max(v0 + t_mid * dv, 0.0), <double> cols)
                    if a != last_a or j != last_j:
                        _cells(values, table, anchor, a, j, cells)
                        last_a, last_j = a, j
                    for g in range(3):
                        at = t_prev + span * nodes[g]
                        t[g] = u0 + at * du - a
                        w[g] = v0 + at * dv - j
                        weight = span * weights[g]
                        moment[g] = weight * dv
                        to_start[g] = weight * (1.0 - at)
                        to_end[g] = weight * at
                    for ch in range(channels):
                        cell = &cells[ch]
                        if moments:
                            for g in range(3):
                                g1, g2 = _green(cell, t[g], w[g])
                                acc[ch] += moment[g] * g1
                                acc[channels + ch] += moment[g] * g2
                        if n_parts:
                            for g in range(3):
                                intensity = ((1.0 - w[g]) * (cell.p0 + t[g] * cell.dp)
                                             + w[g] * (cell.q0 + t[g] * cell.dq))
                                at_start[2 + ch] += to_start[g] * intensity
                                at_end[2 + ch] += to_end[g] * intensity
                                at_start[2 + channels + ch] += to_start[g] * intensity * intensity
                                at_end[2 + channels + ch] += to_end[g] * intensity * intensity
                    if n_parts:
                        at_start[1] += to_start[0] + to_start[1] + to_start[2]
                        at_end[1] += to_end[0] + to_end[1] + to_end[2]
                if t_next >= 1.0:
                    break
                k_u += step_u * (t_u <= t_next)  # branch-free: which line comes next is a coin toss
                k_v += step_v * (t_v <= t_next)
                t_prev = t_next
            length = sqrt(du * du + dv * dv)
            if moments:
                area += 0.5 * ((u0 - 1.0) * (v0 - 1.0 + dv) - (u0 - 1.0 + du) * (v0 - 1.0))
                total_length += length
            if n_parts:
                # nu |e| = (dv, -du): the edge normal (section 4.5.2) times its length
                tangent_r = du / length if length > 0.0 else 0.0
                tangent_c = dv / length if length > 0.0 else 0.0
                start_r, start_c = &parts[e, 0, 0], &parts[e, 1, 0]
                end_r, end_c = &parts[b, 0, 0], &parts[b, 1, 0]
                start_r[0] -= tangent_r
                start_c[0] -= tangent_c
                end_r[0] += tangent_r
                end_c[0] += tangent_c
                for p in range(1, n_parts):
                    start_r[p] += at_start[p] * dv
                    start_c[p] -= at_start[p] * du
                    end_r[p] += at_end[p] * dv
                    end_c[p] -= at_end[p] * du
        if moments:
            for ch in range(channels):
                s1[ch] += acc[ch]
                s2[ch] += acc[channels + ch]
            sums[0] += area
            sums[1] += total_length
    free(acc)
    free(cells)
    free(at_start)
    free(at_end)


def combine_load(const double[:, :, ::1] parts, const double[::1] weights, double[:, ::1] load):
    """``load[j, d] = sum_p weights[p] parts[j, d, p]``: the load (6.41) of the quadratic form
    with these weights from the parts of :func:`edge_integrals`."""
    cdef Py_ssize_t j, d, p
    cdef double total
    with nogil:
        for j in range(parts.shape[0]):
            for d in range(2):
                total = 0.0
                for p in range(parts.shape[2]):
                    total += weights[p] * parts[j, d, p]
                load[j, d] = total


def cyclic_thomas(const double[::1] diagonal, const double[::1] off, const double[:, ::1] rhs,
                  const Py_ssize_t[::1] offsets, double[:, ::1] out):
    """Solve each diagonal block of the block-cyclic tridiagonal system (see :func:`fem.cyclic_solve`).

    Block ``[first, stop)`` is ``T + u v^T`` with T tridiagonal (Sherman-Morrison): T is
    eliminated once (Thomas, no pivoting for SPD) for the block's right-hand sides and u.
    """
    cdef Py_ssize_t columns = rhs.shape[1], width = rhs.shape[1] + 1, block, first, k, i, col
    cdef Py_ssize_t longest = 0
    cdef double gamma, corner, denominator, z0, zk, scale, factor
    for block in range(offsets.shape[0] - 1):
        longest = max(longest, offsets[block + 1] - offsets[block])
    cdef double *d = <double *> malloc(longest * sizeof(double))
    cdef double *c_prime = <double *> malloc(longest * sizeof(double))
    cdef double *y = <double *> malloc(longest * width * sizeof(double))
    if d == NULL or c_prime == NULL or y == NULL:
        free(d)
        free(c_prime)
        free(y)
        raise MemoryError()
    with nogil:
        for block in range(offsets.shape[0] - 1):
            first = offsets[block]
            k = offsets[block + 1] - first
            for i in range(k):
                d[i] = diagonal[first + i]
            gamma = -d[0]
            corner = off[first + k - 1]
            d[0] -= gamma
            d[k - 1] -= corner * corner / gamma
            # right-hand sides: the block's columns plus u = (gamma, 0, ..., 0, corner)
            for i in range(k):
                for col in range(columns):
                    y[i * width + col] = rhs[first + i, col]
                y[i * width + columns] = 0.0
            y[columns] = gamma
            y[(k - 1) * width + columns] += corner
            # Thomas: forward elimination on the tridiagonal part (super-diagonal off[:k-1])
            c_prime[0] = off[first] / d[0]
            for col in range(width):
                y[col] /= d[0]
            for i in range(1, k):
                denominator = d[i] - off[first + i - 1] * c_prime[i - 1]
                c_prime[i] = off[first + i] / denominator if i < k - 1 else 0.0
                for col in range(width):
                    y[i * width + col] = (y[i * width + col]
                                          - off[first + i - 1] * y[(i - 1) * width + col]) / denominator
            for i in range(k - 2, -1, -1):
                for col in range(width):
                    y[i * width + col] -= c_prime[i] * y[(i + 1) * width + col]
            z0, zk = y[columns], y[(k - 1) * width + columns]
            scale = 1.0 + z0 + (corner / gamma) * zk
            for col in range(columns):
                factor = (y[col] + (corner / gamma) * y[(k - 1) * width + col]) / scale
                for i in range(k):
                    out[first + i, col] = y[i * width + col] - factor * y[i * width + columns]
    free(d)
    free(c_prime)
    free(y)


def curve_areas(const double[:, ::1] points, const Py_ssize_t[::1] next_index, const Py_ssize_t[::1] offsets,
                double[::1] out):
    """The signed area ``0.5 sum_e (r_e c_next(e) - r_next(e) c_e)`` of every stacked closed curve
    (curve k: the edges ``offsets[k]`` to ``offsets[k + 1] - 1``) into ``out``."""
    cdef Py_ssize_t k, e, b
    cdef double total
    with nogil:
        for k in range(offsets.shape[0] - 1):
            total = 0.0
            for e in range(offsets[k], offsets[k + 1]):
                b = next_index[e]
                total += points[e, 0] * points[b, 1] - points[b, 0] * points[e, 1]
            out[k] = 0.5 * total



cdef struct _Span:
    # an edge lying on one side of the domain: its extent along that side, and its index
    double low
    double high
    Py_ssize_t index


cdef int _span_order(const void *a, const void *b) noexcept nogil:
    # by ``low``, ties by index: the order of a stable sort of the edges by ``low``
    cdef const _Span *x = <const _Span *> a
    cdef const _Span *y = <const _Span *> b
    if x.low < y.low:
        return -1
    if x.low > y.low:
        return 1
    return (x.index > y.index) - (x.index < y.index)


def border_overlap(const double[:, ::1] points, const Py_ssize_t[::1] next_index, const double[:, ::1] bounds):
    """Whether a corner of ``bounds`` (2, 2) is left twice, or two edges lying on the same side
    overlap: :func:`activecontour.geometry.topology.border_overlap`.  Per side, the edges on it
    sorted by their low end (ties in edge order); an edge starting before the farthest reach of
    the earlier ones, by more than ``1e-12 max(1, |side|)``, overlaps one of them."""
    cdef Py_ssize_t n = points.shape[0], e, b, k, axis, side, count
    cdef Py_ssize_t leaves[4]
    cdef Py_ssize_t lying[4]
    cdef double value, reach, tolerance
    cdef bint found = False
    cdef _Span *spans
    for k in range(4):
        leaves[k] = lying[k] = 0
    for e in range(n):
        if (points[e, 0] != bounds[0, 0] and points[e, 0] != bounds[1, 0] and points[e, 1] != bounds[0, 1]
                and points[e, 1] != bounds[1, 1]):
            continue  # an edge that starts off the border neither leaves a corner nor lies on a side
        b = next_index[e]
        for k in range(4):
            # corner k = (bounds[k // 2, 0], bounds[k % 2, 1]); side k: axis k // 2, bounds[k % 2, axis]
            if (points[e, 0] == bounds[k // 2, 0] and points[e, 1] == bounds[k % 2, 1]
                    and not (points[b, 0] == bounds[k // 2, 0] and points[b, 1] == bounds[k % 2, 1])):
                leaves[k] += 1
            value = bounds[k % 2, k // 2]
            if points[e, k // 2] == value and points[b, k // 2] == value:
                lying[k] += 1
    for k in range(4):
        if leaves[k] > 1:
            return True
    for k in range(4):
        if lying[k] < 2:
            continue
        axis, side = k // 2, k % 2
        value = bounds[side, axis]
        spans = <_Span *> malloc(lying[k] * sizeof(_Span))
        if spans == NULL:
            raise MemoryError()
        count = 0
        for e in range(n):
            b = next_index[e]
            if points[e, axis] == value and points[b, axis] == value:
                spans[count].low = points[e, 1 - axis] if points[e, 1 - axis] < points[b, 1 - axis] \
                    else points[b, 1 - axis]
                spans[count].high = points[e, 1 - axis] if points[e, 1 - axis] > points[b, 1 - axis] \
                    else points[b, 1 - axis]
                spans[count].index = e
                count += 1
        qsort(spans, count, sizeof(_Span), _span_order)
        tolerance = 1e-12 * (fabs(value) if fabs(value) > 1.0 else 1.0)
        reach = spans[0].high
        for e in range(1, count):
            if spans[e].low < reach - tolerance:
                found = True
                break
            if spans[e].high > reach:
                reach = spans[e].high
        free(spans)
        if found:
            return True
    return False


cdef struct Grid:
    # square cells of side 1 / scale from (low_r, low_c), ``rows`` x ``cols`` of them; the edges
    # filed in cell c are ``items[start[c]:start[c + 1]]``, in edge order; edge e meets the cells
    # from (first_row[e], first_col[e]) on
    double low_r, low_c, scale
    Py_ssize_t rows, cols
    Py_ssize_t *start
    Py_ssize_t *items
    Py_ssize_t *first_row
    Py_ssize_t *first_col


cdef inline Py_ssize_t _cell_of(double x, double low, double scale, Py_ssize_t count) noexcept nogil:
    """The index of the cell of coordinate x (clamped to the grid)."""
    cdef double k = (x - low) * scale
    if k <= 0.0:
        return 0
    if k >= <double> (count - 1):
        return count - 1
    return <Py_ssize_t> k


cdef void _free_grid(Grid *grid) noexcept nogil:
    free(grid.start)
    free(grid.items)
    free(grid.first_row)
    free(grid.first_col)


cdef int _file_edges(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                     double size, bint rows_only, Grid *grid) noexcept nogil:
    """File every segment ``nodes[start[e]] -> nodes[end[e]]`` under each cell its bounding box
    meets (under each band of rows it meets, with ``rows_only``; horizontal segments then under
    none): a counting sort, O(segments + cells), in segment order within a cell.  Returns -1 when
    out of memory (the grid is then freed)."""
    cdef Py_ssize_t n = start.shape[0], e, a, b, r, c, r1, c1, cells, position
    cdef double high_r = nodes[start[0], 0], high_c = nodes[start[0], 1]
    grid.low_r, grid.low_c, grid.scale = high_r, high_c, 1.0 / size
    for e in range(n):
        a, b = start[e], end[e]
        grid.low_r = min(grid.low_r, nodes[a, 0], nodes[b, 0])
        grid.low_c = min(grid.low_c, nodes[a, 1], nodes[b, 1])
        high_r = max(high_r, nodes[a, 0], nodes[b, 0])
        high_c = max(high_c, nodes[a, 1], nodes[b, 1])
    grid.rows = <Py_ssize_t> ((high_r - grid.low_r) * grid.scale) + 1
    grid.cols = 1 if rows_only else <Py_ssize_t> ((high_c - grid.low_c) * grid.scale) + 1
    cells = grid.rows * grid.cols
    grid.start = <Py_ssize_t *> calloc(cells + 1, sizeof(Py_ssize_t))
    grid.first_row = <Py_ssize_t *> malloc(n * sizeof(Py_ssize_t))
    grid.first_col = <Py_ssize_t *> malloc(n * sizeof(Py_ssize_t))
    grid.items = NULL
    if grid.start == NULL or grid.first_row == NULL or grid.first_col == NULL:
        _free_grid(grid)
        return -1
    for e in range(n):  # count the entries of every cell (shifted by one: start[c + 1])
        a, b = start[e], end[e]
        if rows_only and nodes[a, 0] == nodes[b, 0]:
            grid.first_row[e] = -1
            continue
        grid.first_row[e] = _cell_of(min(nodes[a, 0], nodes[b, 0]), grid.low_r, grid.scale, grid.rows)
        r1 = _cell_of(max(nodes[a, 0], nodes[b, 0]), grid.low_r, grid.scale, grid.rows)
        if rows_only:
            grid.first_col[e], c1 = 0, 0
        else:
            grid.first_col[e] = _cell_of(min(nodes[a, 1], nodes[b, 1]), grid.low_c, grid.scale, grid.cols)
            c1 = _cell_of(max(nodes[a, 1], nodes[b, 1]), grid.low_c, grid.scale, grid.cols)
        for r in range(grid.first_row[e], r1 + 1):
            for c in range(grid.first_col[e], c1 + 1):
                grid.start[r * grid.cols + c + 1] += 1
    for c in range(cells):
        grid.start[c + 1] += grid.start[c]
    grid.items = <Py_ssize_t *> malloc(max(grid.start[cells], 1) * sizeof(Py_ssize_t))
    if grid.items == NULL:
        _free_grid(grid)
        return -1
    for e in range(n):  # fill, in segment order within each cell; start[c] ends as the next cell's start
        if grid.first_row[e] < 0:
            continue
        a, b = start[e], end[e]
        r1 = _cell_of(max(nodes[a, 0], nodes[b, 0]), grid.low_r, grid.scale, grid.rows)
        c1 = 0 if rows_only else _cell_of(max(nodes[a, 1], nodes[b, 1]), grid.low_c, grid.scale, grid.cols)
        for r in range(grid.first_row[e], r1 + 1):
            for c in range(grid.first_col[e], c1 + 1):
                position = grid.start[r * grid.cols + c]
                grid.items[position] = e
                grid.start[r * grid.cols + c] = position + 1
    for c in range(cells, 0, -1):
        grid.start[c] = grid.start[c - 1]
    grid.start[0] = 0
    return 0


cdef double _cell_size(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                       bint rows_only) noexcept nogil:
    """A cell side for :func:`_file_edges`: the mean segment extent (along the rows, with
    ``rows_only``), at least what makes about one cell per segment, so the grid has O(segments)
    cells and each segment meets a few."""
    cdef Py_ssize_t n = start.shape[0], e, a, b
    cdef double extent = 0.0, low_r = nodes[start[0], 0], high_r = low_r
    cdef double low_c = nodes[start[0], 1], high_c = low_c, size
    for e in range(n):
        a, b = start[e], end[e]
        low_r, high_r = min(low_r, nodes[a, 0], nodes[b, 0]), max(high_r, nodes[a, 0], nodes[b, 0])
        low_c, high_c = min(low_c, nodes[a, 1], nodes[b, 1]), max(high_c, nodes[a, 1], nodes[b, 1])
        if rows_only:
            extent += abs(nodes[b, 0] - nodes[a, 0])
        else:
            extent += max(abs(nodes[b, 0] - nodes[a, 0]), abs(nodes[b, 1] - nodes[a, 1]))
    size = extent / n
    if rows_only:
        size = max(size, (high_r - low_r) / n)
    else:
        size = max(size, sqrt((high_r - low_r) * (high_c - low_c) / n),
                   ((high_r - low_r) + (high_c - low_c)) / n)
    # a grid of no extent (every point the same) still needs a positive cell
    return max(size, 1e-12 * max(1.0, max(abs(low_r), abs(high_r), abs(low_c), abs(high_c))))


cdef bint _touch(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                 Py_ssize_t e, Py_ssize_t f) noexcept nogil:
    """Segments e and f meet anywhere but at a node they share: a crossing, a touch (an end on
    the other segment), or an overlap (collinear, also of two segments with a common node)."""
    cdef double ar = nodes[start[e], 0], ac = nodes[start[e], 1], br = nodes[end[e], 0], bc = nodes[end[e], 1]
    cdef double cr = nodes[start[f], 0], cc = nodes[start[f], 1], dr = nodes[end[f], 0], dc = nodes[end[f], 1]
    cdef double o1, o2, o3, o4, along
    cdef Py_ssize_t shared
    if (max(min(ar, br), min(cr, dr)) > min(max(ar, br), max(cr, dr))
            or max(min(ac, bc), min(cc, dc)) > min(max(ac, bc), max(cc, dc))):
        return False  # their boxes do not meet
    shared = (start[e] == start[f]) + (start[e] == end[f]) + (end[e] == start[f]) + (end[e] == end[f])
    if shared >= 2:  # the same two nodes: they coincide
        return True
    o1 = (br - ar) * (cc - ac) - (bc - ac) * (cr - ar)  # c, d against a -> b
    o2 = (br - ar) * (dc - ac) - (bc - ac) * (dr - ar)
    if shared == 1:
        # meeting only at the common node unless collinear and on the same side
        along = (br - ar) * (dr - cr) + (bc - ac) * (dc - cc)
        return o1 == 0.0 and o2 == 0.0 and (
            ((start[e] == start[f] or end[e] == end[f]) and along > 0)
            or ((start[e] == end[f] or end[e] == start[f]) and along < 0))
    o3 = (dr - cr) * (ac - cc) - (dc - cc) * (ar - cr)  # a, b against c -> d
    o4 = (dr - cr) * (bc - cc) - (dc - cc) * (br - cr)
    # unless one lies wholly on one side of the other's line: a crossing, an end on the other
    # segment, or collinear with meeting boxes (an overlap or a touch)
    return not ((o1 > 0.0 and o2 > 0.0) or (o1 < 0.0 and o2 < 0.0)
                or (o3 > 0.0 and o4 > 0.0) or (o3 < 0.0 and o4 < 0.0))


def segments_meet(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                  bint touching, Py_ssize_t limit, Py_ssize_t[:, ::1] pairs, double[:, ::1] where):
    """The pairs ``e < f`` of the segments ``nodes[start[s]] -> nodes[end[s]]`` that meet.

    ``touching`` False (closed curves, :func:`activecontour.geometry.topology.crossings`): the
    pairs without a common node that cross properly, at ``where[k] = (s, t)`` on e and f, both in
    (0, 1).  ``touching`` True (a planar network,
    :meth:`activecontour.backends.network.Network.simple`): the pairs that meet anywhere but at a
    node they share -- a crossing, a touch (an end on another segment), or an overlap (collinear,
    also of two segments with a common node); ``where`` may then be a (0, 2) array.

    Returns the number of pairs found, stopping at ``limit``; the first ``len(pairs)`` of them go
    into ``pairs`` (P, 2) (and ``where``, as far as it holds them): call again with longer ones
    when the count exceeds them.  The order is the grid's, not sorted.

    Every segment is filed under each cell of a uniform grid that its bounding box meets (cells
    about the mean segment extent, about one per segment: :func:`_cell_size`); two segments can
    meet only when their boxes do, so only segments sharing a cell are tested, each pair once: in
    the first cell both meet (that of the low corner of the intersection of their boxes).  O(S)
    for segments of even length, whatever their number.
    """
    cdef Py_ssize_t n = start.shape[0], capacity = pairs.shape[0], found = 0
    cdef Py_ssize_t cell, i, k, e, f, row, col
    cdef double r0, r1, u0, u1, q0, q1, denominator, s, t
    cdef bint met
    cdef Grid grid
    if n < 2 or limit <= 0:
        return 0
    with nogil:
        if _file_edges(nodes, start, end, _cell_size(nodes, start, end, False), False, &grid) != 0:
            with gil:
                raise MemoryError()
        for cell in range(grid.rows * grid.cols):
            if found >= limit:
                break
            row, col = cell // grid.cols, cell % grid.cols
            for i in range(grid.start[cell], grid.start[cell + 1]):
                if found >= limit:
                    break
                for k in range(i + 1, grid.start[cell + 1]):
                    e, f = grid.items[i], grid.items[k]  # e < f: filed in segment order
                    # each pair once: in the first cell both meet
                    if (max(grid.first_row[e], grid.first_row[f]) != row
                            or max(grid.first_col[e], grid.first_col[f]) != col):
                        continue
                    if touching:
                        met = _touch(nodes, start, end, e, f)
                    else:
                        if start[e] == start[f] or start[e] == end[f] or end[e] == start[f] or end[e] == end[f]:
                            continue  # neighbours along a curve
                        r0, r1 = nodes[end[e], 0] - nodes[start[e], 0], nodes[end[e], 1] - nodes[start[e], 1]
                        u0, u1 = nodes[end[f], 0] - nodes[start[f], 0], nodes[end[f], 1] - nodes[start[f], 1]
                        denominator = r0 * u1 - r1 * u0
                        if denominator == 0.0:
                            continue
                        q0, q1 = nodes[start[f], 0] - nodes[start[e], 0], nodes[start[f], 1] - nodes[start[e], 1]
                        s = (q0 * u1 - q1 * u0) / denominator
                        t = (q0 * r1 - q1 * r0) / denominator
                        met = 0.0 < s < 1.0 and 0.0 < t < 1.0
                        if met and found < where.shape[0]:
                            where[found, 0], where[found, 1] = s, t
                    if met:
                        if found < capacity:
                            pairs[found, 0], pairs[found, 1] = e, f
                        found += 1
                        if found >= limit:
                            break
        _free_grid(&grid)
    return found


def winding_banded(const double[:, ::1] points, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                   const double[:, ::1] probes, long long[::1] out):
    """:func:`winding` through bands of rows: every edge ``start[e] -> end[e]`` is filed under the
    bands its rows meet (:func:`_file_edges`), and a probe meets only the edges of its band.  The
    same count, in O(probes x edges per band + edges) instead of O(probes x edges)."""
    cdef Py_ssize_t i, k, e, count, band
    cdef double r, c, r0, r1, t, high_r
    cdef bint upward
    cdef Grid grid
    if start.shape[0] == 0:
        out[:] = 0
        return
    with nogil:
        if _file_edges(points, start, end, _cell_size(points, start, end, True), True, &grid) != 0:
            with gil:
                raise MemoryError()
        high_r = grid.low_r + grid.rows / grid.scale
        for i in range(probes.shape[0]):
            r, c = probes[i, 0], probes[i, 1]
            count = 0
            if grid.low_r <= r <= high_r:
                band = _cell_of(r, grid.low_r, grid.scale, grid.rows)
                for k in range(grid.start[band], grid.start[band + 1]):
                    e = grid.items[k]
                    r0, r1 = points[start[e], 0], points[end[e], 0]
                    upward = r0 <= r < r1
                    if not (upward or r1 <= r < r0):
                        continue
                    t = (r - r0) / (r1 - r0)
                    if points[start[e], 1] + t * (points[end[e], 1] - points[start[e], 1]) > c:
                        count += -1 if upward else 1  # as in :func:`winding`
            out[i] = count
        _free_grid(&grid)


def winding(const double[:, ::1] points, const Py_ssize_t[::1] next_index,
            const double[:, ::1] probes, long long[::1] out):
    """Winding number of each probe point with respect to the oriented curves, into ``out``."""
    cdef Py_ssize_t i, e, count
    cdef double r, c, r0, r1, t
    cdef bint upward
    with nogil:
        for i in range(probes.shape[0]):
            r, c = probes[i, 0], probes[i, 1]
            count = 0
            for e in range(points.shape[0]):
                r0, r1 = points[e, 0], points[next_index[e], 0]
                upward = r0 <= r < r1
                if not (upward or r1 <= r < r0):
                    continue
                t = (r - r0) / (r1 - r0)
                if points[e, 1] + t * (points[next_index[e], 1] - points[e, 1]) > c:
                    # a positively oriented curve (area > 0) runs towards smaller rows on its
                    # larger-column side: a downward crossing to the right counts +1
                    count += -1 if upward else 1
            out[i] = count


def convex_hull(const double[:, ::1] points, const Py_ssize_t[::1] order, Py_ssize_t[::1] out):
    """The convex hull's vertices (Andrew's monotone chain): ``order`` sorts ``points``
    lexicographically (row, then column); the indices of the extreme points go to ``out`` (length
    at least n + 1) in one turning direction, without collinear or repeated points.  Returns their
    count (under 3: the points lie on a line)."""
    cdef Py_ssize_t n = order.shape[0], k = 0, i, lower, p
    cdef double ar, ac
    with nogil:
        for i in range(n):  # the lower chain, then the upper one back
            p = order[i]
            while k >= 2:
                ar, ac = points[out[k - 2], 0], points[out[k - 2], 1]
                if ((points[out[k - 1], 0] - ar) * (points[p, 1] - ac)
                        - (points[out[k - 1], 1] - ac) * (points[p, 0] - ar)) > 0.0:
                    break
                k -= 1
            out[k] = p
            k += 1
        lower = k + 1
        for i in range(n - 2, -1, -1):
            p = order[i]
            while k >= lower:
                ar, ac = points[out[k - 2], 0], points[out[k - 2], 1]
                if ((points[out[k - 1], 0] - ar) * (points[p, 1] - ac)
                        - (points[out[k - 1], 1] - ac) * (points[p, 0] - ar)) > 0.0:
                    break
                k -= 1
            out[k] = p
            k += 1
    return k - 1 if k > 1 else k  # the last point closes the chain at the first


cdef inline double _segment_gap(double pr, double pc, Py_ssize_t k, const double[::1] start_r,
                                const double[::1] start_c, const double[::1] dir_r,
                                const double[::1] dir_c, const double[::1] inverse) noexcept nogil:
    """Squared distance from (pr, pc) to segment k (the last one is a far sentinel)."""
    cdef double off_r = pr - start_r[k], off_c = pc - start_c[k]
    cdef double t = (off_r * dir_r[k] + off_c * dir_c[k]) * inverse[k]
    t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
    off_r -= t * dir_r[k]
    off_c -= t * dir_c[k]
    return off_r * off_r + off_c * off_c


def grow_band(unsigned char[::1] visited, int[::1] owner, Py_ssize_t[::1] out, int[::1] chosen,
              Py_ssize_t n_ring, const Py_ssize_t[::1] steps, Py_ssize_t width, Py_ssize_t max_rings,
              int sweeps, const double[::1] start_r, const double[::1] start_c,
              const double[::1] dir_r, const double[::1] dir_c, const double[::1] inverse,
              const Py_ssize_t[:, ::1] links):
    """The rings of the level set's narrow band (:func:`activecontour.backends.levelset.redistancing._propagate`).

    ``out[:n_ring]`` holds the front pixels (flat indices of the framed grid, their ``owner`` set);
    each further ring's pixels take the nearest of their neighbours' segments as of the previous
    sweep (a second sweep lets a ring learn from itself), then walk twice along Gamma to both
    neighbouring segments while that is nearer.  Fills ``owner`` and ``out``; returns the number
    of band pixels.  ``chosen`` is scratch space of the size of ``out``.
    """
    cdef Py_ssize_t sentinel = start_r.shape[0] - 1
    cdef Py_ssize_t count = n_ring, begin = 0, end, i, s, q, p, k, own
    cdef Py_ssize_t ring_index, sweep, walk, side
    cdef double pr, pc, best, gap
    for ring_index in range(max_rings):
        with nogil:
            end = count
            for i in range(begin, end):
                for s in range(steps.shape[0]):
                    q = out[i] + steps[s]
                    if not visited[q]:
                        visited[q] = 1
                        out[count] = q
                        count += 1
            if count > end:
                for sweep in range(sweeps):
                    for i in range(end, count):
                        p = out[i]
                        pr = <double>(p // width - 1)
                        pc = <double>(p % width - 1)
                        own = -1
                        best = 1e300
                        for s in range(steps.shape[0]):
                            k = owner[p + steps[s]]
                            if k < 0 or k == own:  # neighbours often share a segment: no better
                                continue
                            gap = _segment_gap(pr, pc, k, start_r, start_c, dir_r, dir_c, inverse)
                            if gap < best:
                                own, best = k, gap
                        for walk in range(2):
                            for side in range(2):
                                if own < 0:
                                    break
                                k = links[own, side]
                                if k < 0 or k == sentinel:
                                    continue
                                gap = _segment_gap(pr, pc, k, start_r, start_c, dir_r, dir_c, inverse)
                                if gap < best:
                                    own, best = k, gap
                        chosen[i] = <int>own
                    for i in range(end, count):
                        owner[out[i]] = chosen[i]
        if count == end:
            break
        begin = end
        PyErr_CheckSignals()
    return count


cdef struct Tracer:
    # the open ends of the contours being assembled, by point: a contour id or -1.  Horizontal
    # points H(r, c) = padded (r, c + 1/2) of the square rows' top and bottom lines (two lines,
    # by the parity of r), vertical points V(r, c) = (r + 1/2, c) of the current square row.
    Py_ssize_t width, row
    Py_ssize_t *start_h
    Py_ssize_t *end_h
    Py_ssize_t *start_v
    Py_ssize_t *end_v
    # per contour its first and last node (first = -1: merged into another); per node its
    # successor and its point as doubled padded coordinates (2r, 2c + 1) or (2r + 1, 2c)
    Py_ssize_t *first
    Py_ssize_t *last
    Py_ssize_t contours, contour_capacity
    Py_ssize_t *following
    int *point_r
    int *point_c
    Py_ssize_t nodes, node_capacity


cdef Py_ssize_t *_end_slot(Tracer *tracer, bint start, int point_r, int point_c) noexcept nogil:
    """Where the open end at a point (doubled coordinates) is kept; NULL for a point outside the
    current square row, which no later segment can meet."""
    cdef Py_ssize_t r
    if point_r % 2 == 0:  # horizontal: line r, column (point_c - 1) / 2
        r = point_r // 2
        if r != tracer.row and r != tracer.row + 1:
            return NULL
        return &(tracer.start_h if start else tracer.end_h)[(r % 2) * tracer.width + (point_c - 1) // 2]
    if (point_r - 1) // 2 != tracer.row:
        return NULL
    return &(tracer.start_v if start else tracer.end_v)[point_c // 2]


cdef Py_ssize_t _pop(Tracer *tracer, bint start, int point_r, int point_c) noexcept nogil:
    cdef Py_ssize_t *slot = _end_slot(tracer, start, point_r, point_c)
    cdef Py_ssize_t found = -1
    if slot != NULL:
        found = slot[0]
        slot[0] = -1
    return found


cdef void _put(Tracer *tracer, bint start, Py_ssize_t node, Py_ssize_t contour) noexcept nogil:
    cdef Py_ssize_t *slot = _end_slot(tracer, start, tracer.point_r[node], tracer.point_c[node])
    if slot != NULL:
        slot[0] = contour


cdef Py_ssize_t _node(Tracer *tracer, int point_r, int point_c) noexcept nogil:
    """A new node at the point; -1 when out of memory."""
    cdef Py_ssize_t capacity
    cdef void *grown
    if tracer.nodes == tracer.node_capacity:
        capacity = 2 * tracer.node_capacity + 64
        grown = realloc(tracer.following, capacity * sizeof(Py_ssize_t))
        if grown == NULL:
            return -1
        tracer.following = <Py_ssize_t *> grown
        grown = realloc(tracer.point_r, capacity * sizeof(int))
        if grown == NULL:
            return -1
        tracer.point_r = <int *> grown
        grown = realloc(tracer.point_c, capacity * sizeof(int))
        if grown == NULL:
            return -1
        tracer.point_c = <int *> grown
        tracer.node_capacity = capacity
    tracer.following[tracer.nodes] = -1
    tracer.point_r[tracer.nodes] = point_r
    tracer.point_c[tracer.nodes] = point_c
    tracer.nodes += 1
    return tracer.nodes - 1


cdef int _segment(Tracer *tracer, int from_r, int from_c, int to_r, int to_c) noexcept nogil:
    """Add the segment from -> to to the contours, as scikit-image's ``_assemble_contours`` does
    (the same joins in the same order, so the same contours start at the same points): extend
    the contour ending at ``from`` and/or the one starting at ``to``, close a contour, join two
    (into the older one), or open a new one.  Returns -1 when out of memory."""
    cdef Py_ssize_t tail = _pop(tracer, True, to_r, to_c), head = _pop(tracer, False, from_r, from_c)
    cdef Py_ssize_t node, other, capacity
    cdef void *grown
    if tail >= 0 and head >= 0:
        if tail == head:  # closed: the end point repeats the first
            node = _node(tracer, to_r, to_c)
            if node < 0:
                return -1
            tracer.following[tracer.last[head]] = node
            tracer.last[head] = node
        elif tail > head:  # the tail contour appended to the head contour
            tracer.following[tracer.last[head]] = tracer.first[tail]
            tracer.last[head] = tracer.last[tail]
            tracer.first[tail] = -1
            _put(tracer, True, tracer.first[head], head)
            _put(tracer, False, tracer.last[head], head)
        else:  # the head contour prepended to the tail contour
            tracer.following[tracer.last[head]] = tracer.first[tail]
            tracer.first[tail] = tracer.first[head]
            tracer.first[head] = -1
            _put(tracer, True, tracer.first[tail], tail)
            _put(tracer, False, tracer.last[tail], tail)
        return 0
    if tail < 0 and head < 0:  # a new contour
        if tracer.contours == tracer.contour_capacity:
            capacity = 2 * tracer.contour_capacity + 16
            grown = realloc(tracer.first, capacity * sizeof(Py_ssize_t))
            if grown == NULL:
                return -1
            tracer.first = <Py_ssize_t *> grown
            grown = realloc(tracer.last, capacity * sizeof(Py_ssize_t))
            if grown == NULL:
                return -1
            tracer.last = <Py_ssize_t *> grown
            tracer.contour_capacity = capacity
        node, other = _node(tracer, from_r, from_c), _node(tracer, to_r, to_c)
        if node < 0 or other < 0:
            return -1
        tracer.following[node] = other
        tracer.first[tracer.contours], tracer.last[tracer.contours] = node, other
        _put(tracer, True, node, tracer.contours)
        _put(tracer, False, other, tracer.contours)
        tracer.contours += 1
        return 0
    if head < 0:  # prepend to the contour starting at ``to``
        node = _node(tracer, from_r, from_c)
        if node < 0:
            return -1
        tracer.following[node] = tracer.first[tail]
        tracer.first[tail] = node
        _put(tracer, True, node, tail)
        return 0
    node = _node(tracer, to_r, to_c)  # append to the contour ending at ``from``
    if node < 0:
        return -1
    tracer.following[tracer.last[head]] = node
    tracer.last[head] = node
    _put(tracer, False, node, head)
    return 0


cdef void _free_tracer(Tracer *tracer) noexcept nogil:
    free(tracer.start_h)
    free(tracer.end_h)
    free(tracer.start_v)
    free(tracer.end_v)
    free(tracer.first)
    free(tracer.last)
    free(tracer.following)
    free(tracer.point_r)
    free(tracer.point_c)


def mask_contours(const unsigned char[:, ::1] mask):
    """The closed 1/2-level curves of a boolean mask padded by one pixel of False: exactly the
    curves of ``skimage.measure.find_contours(padded, 0.5, positive_orientation="high")`` (its
    fully_connected="low"), in its order, each without its repeated closing vertex and shifted
    back by the padding (:func:`activecontour.raster.mask_to_curves`).

    Marching squares over the padded mask, row by row, every segment joined to the contours as
    it is made: only the ends on the current row of squares are kept, so the memory beyond the
    curves is O(N).  Returns ``(points, offsets)`` as bytearrays: float64 (row, col) pairs and
    the Py_ssize_t start of every curve (one more than the curves).
    """
    cdef Py_ssize_t m = mask.shape[0], n = mask.shape[1], r, c, k, node, total, count
    cdef int case, top_r, top_c, bottom_r, left_r, left_c, right_c, upper_left, lower_left, upper, lower
    cdef uint64_t above, below, uniform
    cdef const unsigned char *upper_row
    cdef const unsigned char *lower_row
    cdef unsigned char *blank = <unsigned char *> calloc(n + 1, 1)  # the padding's rows: False
    cdef Tracer tracer
    cdef double *points
    cdef Py_ssize_t *offsets
    cdef unsigned char[::1] points_view, offsets_view
    cdef int failed = 0
    tracer.width, tracer.row = n + 2, -1
    tracer.start_h = <Py_ssize_t *> malloc(2 * (n + 2) * sizeof(Py_ssize_t))
    tracer.end_h = <Py_ssize_t *> malloc(2 * (n + 2) * sizeof(Py_ssize_t))
    tracer.start_v = <Py_ssize_t *> malloc((n + 2) * sizeof(Py_ssize_t))
    tracer.end_v = <Py_ssize_t *> malloc((n + 2) * sizeof(Py_ssize_t))
    tracer.first, tracer.last, tracer.following, tracer.point_r, tracer.point_c = NULL, NULL, NULL, NULL, NULL
    tracer.contours, tracer.contour_capacity, tracer.nodes, tracer.node_capacity = 0, 0, 0, 0
    if (blank == NULL or tracer.start_h == NULL or tracer.end_h == NULL or tracer.start_v == NULL
            or tracer.end_v == NULL):
        free(blank)
        _free_tracer(&tracer)
        raise MemoryError()
    for k in range(2 * (n + 2)):
        tracer.start_h[k] = -1
        tracer.end_h[k] = -1
    for k in range(n + 2):
        tracer.start_v[k] = -1
        tracer.end_v[k] = -1
    try:
        for r in range(m + 1):  # square rows of the padded mask: padded rows r and r + 1
            if r % _POLL_ROWS == 0:
                PyErr_CheckSignals()
            with nogil:
                # No slot needs clearing: each crossing lies on two segments, of the two squares
                # beside it (the same square row for a vertical one, this row and the one before
                # for one on the top line), and the second pops the end the first left, so every
                # slot of the vertical points and of the line before is -1 again here.
                tracer.row = r
                # padded rows r and r + 1 are mask rows r - 1 and r, False beyond the mask; the
                # corners of square c: upper left 1, upper right 2, lower left 4, lower right 8
                # (padded (i, j) is mask[i - 1, j - 1]); the right ones of square c are the left
                # ones of square c + 1
                upper_row = &mask[r - 1, 0] if 0 < r else blank
                lower_row = &mask[r, 0] if r < m else blank
                upper_left, lower_left = 0, 0
                c = 0
                while c <= n:
                    if c < n:
                        upper, lower = (1 if upper_row[c] else 0), (1 if lower_row[c] else 0)
                    else:  # the padding's column
                        upper, lower = 0, 0
                    case = upper_left | (upper << 1) | (lower_left << 2) | (lower << 3)
                    upper_left, lower_left = upper, lower
                    if case == 0 or case == 15:
                        # whole words of 8 squares alike ahead (every corner 0, or every one 1) are
                        # skipped: no segment
                        uniform = 0 if case == 0 else 0x0101010101010101
                        while c + 8 < n:
                            memcpy(&above, upper_row + c + 1, 8)
                            memcpy(&below, lower_row + c + 1, 8)
                            if above != uniform or below != uniform:
                                break
                            c += 8
                        c += 1
                        continue
                    # doubled coordinates: top (2r, 2c + 1), bottom (2r + 2, 2c + 1),
                    # left (2r + 1, 2c), right (2r + 1, 2c + 2)
                    top_r, top_c, bottom_r = 2 * r, 2 * c + 1, 2 * r + 2
                    left_r, left_c, right_c = 2 * r + 1, 2 * c, 2 * c + 2
                    if case == 1:
                        failed = _segment(&tracer, top_r, top_c, left_r, left_c)
                    elif case == 2:
                        failed = _segment(&tracer, left_r, right_c, top_r, top_c)
                    elif case == 3:
                        failed = _segment(&tracer, left_r, right_c, left_r, left_c)
                    elif case == 4:
                        failed = _segment(&tracer, left_r, left_c, bottom_r, top_c)
                    elif case == 5:
                        failed = _segment(&tracer, top_r, top_c, bottom_r, top_c)
                    elif case == 6:
                        failed = _segment(&tracer, left_r, right_c, top_r, top_c)
                        if failed == 0:
                            failed = _segment(&tracer, left_r, left_c, bottom_r, top_c)
                    elif case == 7:
                        failed = _segment(&tracer, left_r, right_c, bottom_r, top_c)
                    elif case == 8:
                        failed = _segment(&tracer, bottom_r, top_c, left_r, right_c)
                    elif case == 9:
                        failed = _segment(&tracer, top_r, top_c, left_r, left_c)
                        if failed == 0:
                            failed = _segment(&tracer, bottom_r, top_c, left_r, right_c)
                    elif case == 10:
                        failed = _segment(&tracer, bottom_r, top_c, top_r, top_c)
                    elif case == 11:
                        failed = _segment(&tracer, bottom_r, top_c, left_r, left_c)
                    elif case == 12:
                        failed = _segment(&tracer, left_r, left_c, left_r, right_c)
                    elif case == 13:
                        failed = _segment(&tracer, top_r, top_c, left_r, right_c)
                    else:
                        failed = _segment(&tracer, left_r, left_c, top_r, top_c)
                    if failed != 0:
                        break
                    c += 1
            if failed != 0:
                raise MemoryError()
        # every live contour in the order of creation, reversed (positive_orientation="high"),
        # without its last point then (the first one again), in unpadded coordinates
        total = 0
        for k in range(tracer.contours):
            if tracer.first[k] >= 0:
                node = tracer.first[k]
                while node != tracer.last[k]:
                    total += 1
                    node = tracer.following[node]
        points_out = bytearray(total * 2 * sizeof(double))
        offsets_out = bytearray((tracer.contours + 1) * sizeof(Py_ssize_t))
        points_view, offsets_view = points_out, offsets_out
        points = <double *> (&points_view[0] if total else NULL)
        offsets = <Py_ssize_t *> &offsets_view[0]
        offsets[0], count = 0, 0
        for k in range(tracer.contours):
            if tracer.first[k] < 0:
                continue
            # its nodes from the second to the last, written from the end backwards
            total = offsets[count]
            node = tracer.first[k]
            while node != tracer.last[k]:
                node = tracer.following[node]
                total += 1
            offsets[count + 1] = total
            node = tracer.following[tracer.first[k]]
            for r in range(offsets[count + 1] - 1, offsets[count] - 1, -1):
                points[2 * r] = 0.5 * tracer.point_r[node] - 1.0
                points[2 * r + 1] = 0.5 * tracer.point_c[node] - 1.0
                node = tracer.following[node]
            count += 1
        return points_out, offsets_out[:(count + 1) * sizeof(Py_ssize_t)]
    finally:
        free(blank)
        _free_tracer(&tracer)


cdef inline void _compensated(double *total, double *carry, double term) noexcept nogil:
    """``total + carry += term`` by Neumaier's compensated summation (the rounding of each
    addition collected in ``carry``)."""
    cdef double summed = total[0] + term
    if abs(total[0]) >= abs(term):
        carry[0] += (total[0] - summed) + term
    else:
        carry[0] += (term - summed) + total[0]
    total[0] = summed


def segment_integrals(const double[:, ::1] starts, const double[:, ::1] ends, const Py_ssize_t[::1] inner,
                      const Py_ssize_t[::1] outer, const double[:, :, ::1] values,
                      const double[:, :, :, ::1] table, Py_ssize_t anchor, double[:, ::1] moments,
                      double[:, :, ::1] parts, double[:, ::1] sums, const Py_ssize_t[::1] known,
                      const double[:, ::1] known_sums, const double[:, :, ::1] known_parts):
    """The exact edge integrals of a partition's boundary segments (the N-region network of
    :mod:`activecontour.backends.network`), in one pass: what :func:`edge_integrals` gives for one
    closed curve, kept apart per region and per segment.

    ``moments[k] += (area, closed integral of G_1 dc, of G_2 dc)`` (per channel, Green's theorem:
    the region integrals of 1, I and I^2; the area by the shoelace formula) over the segments with
    region k on their inner side, and minus those with k on their outer side (``outer < 0``: the
    image's edge, no region).  With ``parts`` of shape (S, 2, 2C) (a (0, 2, 0) array for none),
    for every segment and each of its ends (phi = 1 - s at the start, s at the end, s the
    segment's parameter) the integrals in s:

        parts[e, 0 or 1, ch]     = int_0^1 phi I_ch ds,
        parts[e, 0 or 1, C + ch] = int_0^1 phi I_ch^2 ds,

    from which a quadratic form's load (6.41) on the segment's ends is the form's combination
    times the segment's normal ``nu |e| = (dv, -du)``.  With ``sums`` of shape (S, 2C) (a (0, 0)
    array for none), ``sums[e]`` receives segment e's closed-integral terms (of G_1, then G_2, per
    channel).  Given ``known`` (S,) (a (0,) array for none), a segment with ``known[e] = r >= 0``
    is not integrated: it is the same segment (the same ends, in the same order, at the same
    points) as row r of an earlier call's ``sums`` and ``parts``, passed as ``known_sums`` and
    ``known_parts``, which it takes; its terms then enter the sums exactly as computed afresh (a
    network changed locally costs its changed segments and one pass of additions).

    The pieces between grid lines and their quadrature are those of :func:`edge_integrals`; a
    cell's data is read once for consecutive pieces in it (along a segment, and from one segment
    to the next along a chain).  The sums over the segments are compensated (Neumaier): Green's integrals add terms of the size of the
    row-antiderivatives that cancel around a closed curve, and the compensation keeps the result
    independent of the segments' order to about one rounding.

    Returns the length of the segments that count in the functional's length term: the
    interfaces, and the image's edge where a region other than 0 lies on it.
    """
    cdef Py_ssize_t channels = values.shape[2], rows = values.shape[0], cols = values.shape[1]
    cdef Py_ssize_t e, ch, g, a, j, i, o, count = starts.shape[0], last_a = -1, last_j = -1
    cdef bint with_parts = parts.shape[0] > 0, with_sums = sums.shape[0] > 0, with_known = known.shape[0] > 0
    cdef Py_ssize_t r
    cdef double nodes[3]
    cdef double weights[3]
    cdef double u0, v0, du, dv, k_u, k_v, t_prev, t_u, t_v, t_next, span, t_mid, area, length = 0.0
    cdef double t_edge, t, w, g1, g2, weight, intensity
    cdef double *acc
    cdef double *part
    cdef double *carry
    cdef double length_carry = 0.0
    cdef Cell *cells
    cdef Cell *cell
    if moments.shape[1] != 1 + 2 * channels or (with_parts and (
            parts.shape[0] != count or parts.shape[1] != 2 or parts.shape[2] != 2 * channels)):
        raise ValueError("moments must be (K, 1 + 2C) and parts (S, 2, 2C) or empty")
    if (with_sums and (sums.shape[0] != count or sums.shape[1] != 2 * channels)) or (with_known and (
            known.shape[0] != count or known_sums.shape[1] != 2 * channels
            or (with_parts and (known_parts.shape[1] != 2 or known_parts.shape[2] != 2 * channels)))):
        raise ValueError("sums must be (S, 2C) or empty; known (S,) or empty, with known_sums (S', 2C) "
                         "and known_parts (S', 2, 2C)")
    acc = <double *> malloc((2 * channels + 1) * sizeof(double))
    part = <double *> malloc(4 * channels * sizeof(double))  # a segment's parts, in registers' reach
    cells = <Cell *> malloc(channels * sizeof(Cell))
    carry = <double *> calloc(moments.shape[0] * moments.shape[1], sizeof(double))
    if acc == NULL or part == NULL or cells == NULL or carry == NULL:
        free(acc)
        free(part)
        free(cells)
        free(carry)
        raise MemoryError()
    nodes[0], nodes[1], nodes[2] = 0.5 - 0.5 * sqrt(0.6), 0.5, 0.5 + 0.5 * sqrt(0.6)
    weights[0], weights[1], weights[2] = 5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0
    with nogil:
        for e in range(count):
            u0, v0 = starts[e, 0] + 1.0, starts[e, 1] + 1.0
            du, dv = ends[e, 0] + 1.0 - u0, ends[e, 1] + 1.0 - v0
            r = known[e] if with_known else -1
            if r >= 0:
                for ch in range(2 * channels):
                    acc[ch] = known_sums[r, ch]
                if with_parts:
                    for ch in range(2 * channels):
                        parts[e, 0, ch], parts[e, 1, ch] = known_parts[r, 0, ch], known_parts[r, 1, ch]
            else:
                for ch in range(2 * channels):
                    acc[ch] = 0.0
                for ch in range(4 * channels):
                    part[ch] = 0.0
                # next grid lines in the direction of travel
                k_u = _floor(u0) + 1.0 if du > 0 else -_floor(-u0) - 1.0
                k_v = _floor(v0) + 1.0 if dv > 0 else -_floor(-v0) - 1.0
                t_prev = 0.0
                while True:
                    t_u = (k_u - u0) / du if du != 0.0 else 2.0
                    t_v = (k_v - v0) / dv if dv != 0.0 else 2.0
                    t_next = min(t_u, t_v, 1.0)
                    span = t_next - t_prev
                    if span > 0.0:
                        t_mid = t_prev + 0.5 * span
                        # the cell of the piece's middle (clamped to the padded image: >= 0, so a
                        # truncation is its floor)
                        a = <Py_ssize_t> min(max(u0 + t_mid * du, 0.0), <double> rows)
                        j = <Py_ssize_t> min(max(v0 + t_mid * dv, 0.0), <double> cols)
                        if a != last_a or j != last_j:
                            _cells(values, table, anchor, a, j, cells)
                            last_a, last_j = a, j
                        for ch in range(channels):
                            cell = &cells[ch]
                            for g in range(3):
                                t_edge = t_prev + span * nodes[g]
                                t = u0 + t_edge * du - a
                                w = v0 + t_edge * dv - j
                                g1, g2 = _green(cell, t, w)
                                weight = span * weights[g]
                                acc[ch] += weight * dv * g1
                                acc[channels + ch] += weight * dv * g2
                                if with_parts:
                                    intensity = (1.0 - w) * (cell.p0 + t * cell.dp) + w * (cell.q0 + t * cell.dq)
                                    # part: [start's I, start's I^2, end's I, end's I^2] per channel
                                    part[4 * ch] += weight * (1.0 - t_edge) * intensity
                                    part[4 * ch + 2] += weight * t_edge * intensity
                                    part[4 * ch + 1] += weight * (1.0 - t_edge) * intensity * intensity
                                    part[4 * ch + 3] += weight * t_edge * intensity * intensity
                    if t_next >= 1.0:
                        break
                    if t_u <= t_next:
                        k_u += 1.0 if du > 0 else -1.0
                    if t_v <= t_next:
                        k_v += 1.0 if dv > 0 else -1.0
                    t_prev = t_next
                if with_parts:
                    for ch in range(channels):
                        parts[e, 0, ch], parts[e, 0, channels + ch] = part[4 * ch], part[4 * ch + 1]
                        parts[e, 1, ch], parts[e, 1, channels + ch] = part[4 * ch + 2], part[4 * ch + 3]
            if with_sums:
                for ch in range(2 * channels):
                    sums[e, ch] = acc[ch]
            i, o = inner[e], outer[e]
            acc[2 * channels] = 0.5 * (starts[e, 0] * ends[e, 1] - ends[e, 0] * starts[e, 1])  # the area
            for ch in range(2 * channels + 1):
                g = 0 if ch == 2 * channels else 1 + ch  # the column: area first, then I, then I^2
                _compensated(&moments[i, g], &carry[i * moments.shape[1] + g], acc[ch])
                if o >= 0:
                    _compensated(&moments[o, g], &carry[o * moments.shape[1] + g], -acc[ch])
            if o >= 0 or i > 0:
                _compensated(&length, &length_carry, sqrt(du * du + dv * dv))
        for i in range(moments.shape[0] * moments.shape[1]):
            moments[i // moments.shape[1], i % moments.shape[1]] += carry[i]
    free(acc)
    free(part)
    free(cells)
    free(carry)
    return length + length_carry


def band_cholesky(double[:, ::1] band, Py_ssize_t[:, ::1] envelope):
    """Cholesky factorisation ``A = U^T U`` of a symmetric positive definite band matrix, in place.

    ``band[j, w + i - j] = A[i, j]`` for ``j - w <= i <= j`` (column j's entries on and above the
    diagonal, w the half bandwidth) becomes U in the same layout.  O(n w^2), no fill outside the
    band.  Returns 0, or ``j + 1`` where the leading minor of order ``j + 1`` is not positive.

    The factor has no entry above a column's first nonzero of A (its envelope, which the reverse
    Cuthill-McKee order keeps narrow: a few rows where the band is about ten), so the sums run
    over the envelopes only: the products left out are zeros, the result the same.  ``envelope``
    (n, 2) receives each column's first row and each row's last column with an entry in it, for
    :func:`band_solve`.
    """
    cdef Py_ssize_t n = band.shape[0], w = band.shape[1] - 1, i, j, k, low, failed = 0
    cdef double total
    cdef double *column_j
    if envelope.shape[0] != n or envelope.shape[1] != 2:
        raise ValueError(f"envelope must have shape ({n}, 2)")
    with nogil:
        for j in range(n):
            envelope[j, 0] = j  # the first row of column j's envelope
            envelope[j, 1] = j
            for k in range(w - min(j, w), w):
                if band[j, k] != 0.0:
                    envelope[j, 0] = j - w + k
                    break
            for i in range(envelope[j, 0], j):
                envelope[i, 1] = j  # the last column with row i in its envelope, so far
            column_j = &band[j, w - j]  # column_j[i] = A[i, j]
            for i in range(envelope[j, 0], j + 1):
                total = column_j[i]
                low = max(envelope[j, 0], envelope[i, 0])
                for k in range(low, i):
                    total -= band[i, w + k - i] * column_j[k]
                if i < j:
                    column_j[i] = total / band[i, w]
                elif total > 0.0:
                    band[j, w] = sqrt(total)
                else:
                    failed = j + 1
                    break
            if failed:
                break
    return failed


def h1_band(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
            const Py_ssize_t[::1] position, double[:, ::1] band):
    """The matrix ``M + K`` of the H^1 form (6.39) of P1 functions on segments, in
    :func:`band_cholesky`'s layout (``band`` zeros, of shape (n, w + 1)), restricted to the nodes
    with ``position >= 0`` and ordered by it: a segment of length h adds ``h / 3 + 1 / h`` to the
    diagonal at each end and puts ``h / 6 - 1 / h`` between them (one segment per pair of nodes).
    Each diagonal entry is its sum over the segments starting there plus its sum over those
    ending there, each in segment order."""
    cdef Py_ssize_t n = band.shape[0], w = band.shape[1] - 1, e, i, j
    cdef double h, dr, dc, diagonal
    cdef double *ending = <double *> calloc(max(n, 1), sizeof(double))
    if ending == NULL:
        raise MemoryError()
    with nogil:
        for e in range(start.shape[0]):
            i, j = position[start[e]], position[end[e]]
            if i < 0 and j < 0:
                continue
            dr = nodes[end[e], 0] - nodes[start[e], 0]
            dc = nodes[end[e], 1] - nodes[start[e], 1]
            h = hypot(dr, dc)
            diagonal = h / 3.0 + 1.0 / h
            if i >= 0:
                band[i, w] += diagonal
            if j >= 0:
                ending[j] += diagonal
            if i >= 0 and j >= 0:
                if i < j:
                    band[j, w + i - j] = h / 6.0 - 1.0 / h
                else:
                    band[i, w + j - i] = h / 6.0 - 1.0 / h
        for i in range(n):
            band[i, w] += ending[i]
    free(ending)


def band_solve(const double[:, ::1] factor, const Py_ssize_t[:, ::1] envelope, double[::1] rhs):
    """Solve ``U^T U x = rhs`` in place with the factor and the envelope of :func:`band_cholesky`
    (the sums over its entries only: the products left out are zeros)."""
    cdef Py_ssize_t n = factor.shape[0], w = factor.shape[1] - 1, i, j, k
    cdef double total
    if envelope.shape[0] != n or envelope.shape[1] != 2:
        raise ValueError(f"envelope must have shape ({n}, 2)")
    with nogil:
        for j in range(n):  # U^T y = rhs
            total = rhs[j]
            for k in range(envelope[j, 0], j):
                total -= factor[j, w + k - j] * rhs[k]
            rhs[j] = total / factor[j, w]
        for i in range(n - 1, -1, -1):  # U x = y
            total = rhs[i]
            for j in range(i + 1, envelope[i, 1] + 1):
                total -= factor[j, w + i - j] * rhs[j]
            rhs[i] = total / factor[i, w]


def cycles(const Py_ssize_t[::1] following, Py_ssize_t[::1] order, Py_ssize_t[::1] offsets):
    """The cycles of the map ``i -> following[i]`` (a permutation), each from its smallest
    element: ``order[offsets[c]:offsets[c + 1]]`` is cycle c in order (``offsets`` holds n + 1).
    Returns the number of cycles."""
    cdef Py_ssize_t n = following.shape[0], first, current, count = 0, position = 0
    cdef unsigned char *seen = <unsigned char *> calloc(max(n, 1), sizeof(unsigned char))
    if seen == NULL:
        raise MemoryError()
    with nogil:
        for first in range(n):
            if seen[first]:
                continue
            offsets[count] = position
            count += 1
            current = first
            while not seen[current]:
                seen[current] = 1
                order[position] = current
                position += 1
                current = following[current]
        offsets[count] = position
    free(seen)
    return count


def follow(const Py_ssize_t[::1] start_ids, const Py_ssize_t[::1] end_ids, Py_ssize_t distinct,
           Py_ssize_t[::1] following):
    """The chaining of :func:`activecontour.geometry.partition.loop_order` for dense point ids
    (0..distinct-1): the i-th element (in index order) ending at a point is followed by the i-th
    starting there, in O(n + distinct) (a counting sort of the starts by id).  Raises ValueError
    when a point has more ends than starts."""
    cdef Py_ssize_t n = start_ids.shape[0], e, k, failed = 0
    cdef Py_ssize_t *first = <Py_ssize_t *> calloc(distinct + 1, sizeof(Py_ssize_t))
    cdef Py_ssize_t *cursor = <Py_ssize_t *> malloc(max(distinct, 1) * sizeof(Py_ssize_t))
    cdef Py_ssize_t *slots = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    if first == NULL or cursor == NULL or slots == NULL:
        free(first)
        free(cursor)
        free(slots)
        raise MemoryError()
    with nogil:
        for e in range(n):
            first[start_ids[e] + 1] += 1
        for k in range(distinct):
            first[k + 1] += first[k]
            cursor[k] = first[k]
        for e in range(n):  # the starts by id, each id's in index order
            k = start_ids[e]
            slots[cursor[k]] = e
            cursor[k] += 1
        for k in range(distinct):
            cursor[k] = first[k]
        for e in range(n):
            k = end_ids[e]
            if cursor[k] >= first[k + 1]:
                failed = 1
                break
            following[e] = slots[cursor[k]]
            cursor[k] += 1
    free(first)
    free(cursor)
    free(slots)
    if failed:
        raise ValueError("a point where more segments end than start")


def passes_twice(const Py_ssize_t[::1] order, const Py_ssize_t[::1] offsets, const Py_ssize_t[::1] ids,
                 Py_ssize_t distinct, unsigned char[::1] twice):
    """``twice[c] = 1`` for the loops ``order[offsets[c]:offsets[c + 1]]`` that pass a point
    (dense ids 0..distinct-1 of their elements) more than once, in O(n + distinct)."""
    cdef Py_ssize_t count = offsets.shape[0] - 1, c, k, key
    cdef Py_ssize_t *stamp = <Py_ssize_t *> malloc(max(distinct, 1) * sizeof(Py_ssize_t))
    if stamp == NULL:
        raise MemoryError()
    with nogil:
        for k in range(distinct):
            stamp[k] = -1
        for c in range(count):
            twice[c] = 0
            for k in range(offsets[c], offsets[c + 1]):
                key = ids[order[k]]
                if stamp[key] == c:
                    twice[c] = 1
                stamp[key] = c
    free(stamp)


ctypedef fused real:
    float
    double


cdef inline Py_ssize_t _marching_cell(double a, double b, double c, double d, double r, double q,
                                      Py_ssize_t cell, Py_ssize_t width, double *segments,
                                      Py_ssize_t *keys) noexcept nogil:
    """The marching-squares segments of the zero set in one cell (corners a, b, c, d clockwise from
    the top left at row r, column q): ``segments`` gets 2 slots x 2 ends x (row, col), ``keys``
    2 slots x 2 ends (the grid edge of each end, for ``width`` cells a row).  Slot 1 is for
    saddles; unused slots are left as they are.  Returns the number of segments (0, 1 or 2)."""
    cdef bint sa = a > 0, sb = b > 0, sc = c > 0, sd = d > 0
    cdef bint exists[4]
    cdef double point[4][2]
    cdef Py_ssize_t key[4]
    cdef Py_ssize_t count = 0, e, found = 0
    cdef Py_ssize_t order[2]
    exists[0], exists[1], exists[2], exists[3] = sa != sb, sb != sc, sd != sc, sa != sd
    # crossings on the edges top (a-b), right (b-c), bottom (d-c), left (a-d), named by grid edge
    if exists[0]:
        point[0][0], point[0][1] = r, q + a / (a - b)
    if exists[1]:
        point[1][0], point[1][1] = r + b / (b - c), q + 1.0
    if exists[2]:
        point[2][0], point[2][1] = r + 1.0, q + d / (d - c)
    if exists[3]:
        point[3][0], point[3][1] = r + a / (a - d), q
    key[0], key[1] = 2 * cell, 2 * (cell + 1) + 1
    key[2], key[3] = 2 * (cell + width), 2 * cell + 1
    for e in range(4):
        count += exists[e]
    if count == 2:  # the two crossings in edge order
        for e in range(4):
            if exists[e]:
                order[found] = e
                found += 1
        for e in range(2):
            segments[2 * e], segments[2 * e + 1] = point[order[e]][0], point[order[e]][1]
            keys[e] = key[order[e]]
        return 1
    if count == 4:  # a saddle isolates its inside corners: a and c (top-left, right-bottom) or b and d
        if sa:
            order[0], order[1] = 3, 2
        else:
            order[0], order[1] = 1, 2
        segments[0], segments[1] = point[0][0], point[0][1]
        segments[2], segments[3] = point[order[0]][0], point[order[0]][1]
        keys[0], keys[1] = key[0], key[order[0]]
        e = 1 if sa else 3
        segments[4], segments[5] = point[e][0], point[e][1]
        segments[6], segments[7] = point[2][0], point[2][1]
        keys[2], keys[3] = key[e], key[2]
        return 2
    return 0


def cell_segments(const real[:, ::1] phi, const Py_ssize_t[::1] cells, double[:, :, :, ::1] segments,
                  Py_ssize_t[:, :, ::1] keys):
    """Marching-squares segments of phi's zero set in the grid cells ``cells`` (flat indices
    ``row * (N - 1) + col``) (:func:`activecontour.backends.levelset.zeroset._cell_segments`).

    ``segments (K, 2, 2, 2)`` (slot, end, row/col) and ``keys (K, 2, 2)`` are written where a
    cell has segments and left as they are elsewhere (fill them with NaN and -1).  The keys name
    each end's grid edge, for a grid of N columns."""
    cdef Py_ssize_t n = phi.shape[1], k, row, col
    with nogil:
        for k in range(cells.shape[0]):
            row = cells[k] // (n - 1)
            col = cells[k] % (n - 1)
            _marching_cell(phi[row, col], phi[row, col + 1], phi[row + 1, col + 1], phi[row + 1, col],
                           <double> row, <double> col, row * n + col, n, &segments[k, 0, 0, 0],
                           &keys[k, 0, 0])


cdef inline double _padded(const real[:, ::1] phi, Py_ssize_t row, Py_ssize_t col) noexcept nogil:
    """phi padded by one pixel of ``-|phi|`` (zeroset._closed_padding) at (row, col) of the padded grid."""
    cdef Py_ssize_t m = phi.shape[0], n = phi.shape[1]
    cdef double value = phi[_clamp(row - 1, m), _clamp(col - 1, n)]
    if (row == 0 or row == m + 1 or col == 0 or col == n + 1) and value > 0:
        value = -value
    return -1e-300 if value == 0 else value


cdef inline Py_ssize_t _oriented(const real[:, ::1] phi, Py_ssize_t row, Py_ssize_t col,
                                 double[:, :, ::1] out, Py_ssize_t count) noexcept nogil:
    """The segments of cell (row, col) of the padded grid, each directed with the inside on its left
    and shifted to the image's coordinates, appended to ``out`` at ``count``; the new count."""
    cdef double a = _padded(phi, row, col), b = _padded(phi, row, col + 1)
    cdef double c = _padded(phi, row + 1, col + 1), d = _padded(phi, row + 1, col)
    cdef double segments[8]
    cdef Py_ssize_t keys[4]
    cdef Py_ssize_t made = _marching_cell(a, b, c, d, <double> row, <double> col, 0, 0, segments, keys)
    cdef Py_ssize_t s, inside = (a > 0) + (b > 0) + (c > 0) + (d > 0)
    cdef double ref_r, ref_c, tangent_r, tangent_c
    for s in range(made):
        # a point on the inside of the segment: the mean of the inside corners of a simple cell;
        # in a saddle each segment cuts off one inside corner (a and c, or b and d)
        if made == 2:
            ref_r = row + (0.0 if s == 0 else 1.0)
            ref_c = col + ((0.0 if s == 0 else 1.0) if a > 0 else (1.0 if s == 0 else 0.0))
        else:
            ref_r = row + ((c > 0) + (d > 0)) / <double> inside
            ref_c = col + ((b > 0) + (c > 0)) / <double> inside
        tangent_r = segments[4 * s + 2] - segments[4 * s]
        tangent_c = segments[4 * s + 3] - segments[4 * s + 1]
        ref_r -= segments[4 * s]
        ref_c -= segments[4 * s + 1]
        # inside on the left: (x - p) . nu < 0 for the inside point x
        if ref_r * tangent_c - ref_c * tangent_r > 0:
            out[count, 0, 0], out[count, 0, 1] = segments[4 * s + 2] - 1.0, segments[4 * s + 3] - 1.0
            out[count, 1, 0], out[count, 1, 1] = segments[4 * s] - 1.0, segments[4 * s + 1] - 1.0
        else:
            out[count, 0, 0], out[count, 0, 1] = segments[4 * s] - 1.0, segments[4 * s + 1] - 1.0
            out[count, 1, 0], out[count, 1, 1] = segments[4 * s + 2] - 1.0, segments[4 * s + 3] - 1.0
        count += 1
    return count


def edge_soup(const real[:, ::1] phi, const Py_ssize_t[::1] cells, double[:, :, ::1] out):
    """The oriented zero-set segments of phi padded by ``-|phi|``
    (:func:`activecontour.backends.levelset.zeroset._edge_soup`): the image's cells ``cells`` with a
    sign change (flat ``row * (N - 1) + col``), then the frame's cells next to an inside pixel (top,
    bottom, left, right), two slots a cell, in image coordinates.  ``out`` holds at least
    ``2 (K + 2 (N + 1) + 2 (M - 1))`` segments; returns how many were written."""
    cdef Py_ssize_t m = phi.shape[0], n = phi.shape[1], k, col, row, side, pixel, count = 0
    with nogil:
        for k in range(cells.shape[0]):
            count = _oriented(phi, cells[k] // (n - 1) + 1, cells[k] % (n - 1) + 1, out, count)
        for side in range(2):  # the frame's top and bottom rows of cells
            row, pixel = side * m, side * (m - 1)
            for col in range(n + 1):
                if phi[pixel, _clamp(col - 1, n)] > 0 or phi[pixel, _clamp(col, n)] > 0:
                    count = _oriented(phi, row, col, out, count)
        for side in range(2):  # its left and right columns
            col, pixel = side * n, side * (n - 1)
            for row in range(1, m):
                if phi[row - 1, pixel] > 0 or phi[row, pixel] > 0:
                    count = _oriented(phi, row, col, out, count)
    return count


cdef inline bint _on_front(const unsigned char[:, ::1] positive, Py_ssize_t r, Py_ssize_t c) noexcept nogil:
    """Whether pixel (r, c) has a 4-neighbour on the other side."""
    cdef Py_ssize_t m = positive.shape[0], n = positive.shape[1]
    cdef unsigned char side = positive[r, c]
    return ((r > 0 and positive[r - 1, c] != side) or (r < m - 1 and positive[r + 1, c] != side)
            or (c > 0 and positive[r, c - 1] != side) or (c < n - 1 and positive[r, c + 1] != side))


def front_and_cells(const unsigned char[:, ::1] positive, const Py_ssize_t[::1] seeds,
                    unsigned char[::1] mark, Py_ssize_t[::1] front, Py_ssize_t[::1] cells):
    """The front pixels among ``seeds`` and their 4-neighbours, and the cells with a sign change
    around them (:func:`activecontour.backends.levelset.redistancing._front_and_cells`).

    ``seeds``: flat pixel indices (repeats allowed); ``mark``: M N zeros, returned cleared.
    ``front`` (room for 5 seeds each) gets the front pixels (those with a 4-neighbour on the
    other side), ``cells`` (room for 4 front pixels each) the cells ``row * (N - 1) + col`` around
    them whose corners are not all on one side, each once, in no particular order.  Returns the
    two counts."""
    cdef Py_ssize_t m = positive.shape[0], n = positive.shape[1]
    cdef Py_ssize_t i, k, s, r, c, p, n_front = 0, n_cells = 0
    cdef unsigned char corner
    with nogil:
        for i in range(seeds.shape[0]):
            r, c = seeds[i] // n, seeds[i] % n
            for s in range(5):
                p = r + (s == 1) - (s == 2)
                k = c + (s == 3) - (s == 4)
                if p < 0 or p >= m or k < 0 or k >= n or mark[p * n + k]:
                    continue
                mark[p * n + k] = 1
                if _on_front(positive, p, k):
                    front[n_front] = p * n + k
                    n_front += 1
        for i in range(seeds.shape[0]):  # clear the marks
            r, c = seeds[i] // n, seeds[i] % n
            for s in range(5):
                p = r + (s == 1) - (s == 2)
                k = c + (s == 3) - (s == 4)
                if 0 <= p < m and 0 <= k < n:
                    mark[p * n + k] = 0
        # every cell with a sign change has an edge with one, whose ends are front pixels; a cell
        # is marked at its top-left pixel
        for i in range(n_front):
            r, c = front[i] // n, front[i] % n
            for s in range(4):
                p = r - 1 + s // 2
                k = c - 1 + s % 2
                if p < 0 or p >= m - 1 or k < 0 or k >= n - 1 or mark[p * n + k]:
                    continue
                mark[p * n + k] = 1
                corner = positive[p, k]
                if positive[p, k + 1] != corner or positive[p + 1, k + 1] != corner \
                        or positive[p + 1, k] != corner:
                    cells[n_cells] = p * (n - 1) + k
                    n_cells += 1
        for i in range(n_front):
            r, c = front[i] // n, front[i] % n
            for s in range(4):
                p = r - 1 + s // 2
                k = c - 1 + s % 2
                if 0 <= p < m - 1 and 0 <= k < n - 1:
                    mark[p * n + k] = 0
    return n_front, n_cells


cdef inline double _signed(double gap, double band, double least, bint inside) noexcept nogil:
    """The distance ``sqrt(gap)``, at least ``least`` and at most ``band``, signed by the side."""
    cdef double distance = sqrt(gap)
    if distance < least:
        distance = least
    if distance > band:
        distance = band
    return distance if inside else -distance


def band_distances(const Py_ssize_t[::1] framed, int[::1] owner, unsigned char[::1] visited,
                   Py_ssize_t width, const unsigned char[::1] positive, double band, double least,
                   const double[::1] start_r, const double[::1] start_c, const double[::1] dir_r,
                   const double[::1] dir_c, const double[::1] inverse, real[::1] phi, Py_ssize_t[::1] flat):
    """The signed distances of the band's pixels from their segments (after :func:`grow_band`).

    For each framed pixel ``framed[i]`` (row length ``width``): its distance to segment
    ``owner[...]`` (-1: the far sentinel, the last one), at least ``least`` (every pixel keeps
    its side), clipped to ``band``, signed by its side (``positive``, flat over the M x N image)
    and written to ``phi`` (flat); ``flat[i]`` gets its index in the image.  Clears the pixel's
    ``visited`` and ``owner``."""
    cdef Py_ssize_t sentinel = start_r.shape[0] - 1, i, p, k, index
    with nogil:
        for i in range(framed.shape[0]):
            p = framed[i]
            k = owner[p]
            owner[p] = -1
            visited[p] = 0
            index = (p // width - 1) * (width - 2) + (p % width - 1)
            flat[i] = index
            phi[index] = _signed(_segment_gap(<double> (p // width - 1), <double> (p % width - 1),
                                              sentinel if k < 0 else k, start_r, start_c, dir_r, dir_c,
                                              inverse), band, least, positive[index])


def front_distances(const Py_ssize_t[::1] front, Py_ssize_t n, const Py_ssize_t[::1] nearest,
                    const double[::1] start_r, const double[::1] start_c, const double[::1] dir_r,
                    const double[::1] dir_c, const double[::1] inverse, double band, double least,
                    const unsigned char[::1] positive, real[::1] phi):
    """The signed distances of the front pixels (flat, ``n`` columns) from their nearest segments
    (-1: the far sentinel), written to ``phi`` as :func:`band_distances` writes them."""
    cdef Py_ssize_t sentinel = start_r.shape[0] - 1, i, p, k
    with nogil:
        for i in range(front.shape[0]):
            p = front[i]
            k = nearest[i]
            phi[p] = _signed(_segment_gap(<double> (p // n), <double> (p % n), sentinel if k < 0 else k,
                                          start_r, start_c, dir_r, dir_c, inverse), band, least, positive[p])


def nearest_segments(const Py_ssize_t[::1] front, Py_ssize_t n, const Py_ssize_t[::1] cells,
                     const float[::1] start_r, const float[::1] start_c, const float[::1] dir_r,
                     const float[::1] dir_c, const float[::1] inverse, Py_ssize_t[::1] nearest):
    """The nearest zero-set segment to each front pixel among those of the four cells around it
    (:func:`activecontour.backends.levelset.redistancing._front_segments`), in float32.

    ``front``: sorted flat pixel indices of an image of ``n`` columns; ``cells``: the sorted cells
    with a sign change (``row * (n - 1) + col``), two segment slots each (segment ``2 slot + s``),
    the segment columns ending with a far sentinel.  The first nearest in the order of the cells
    top-left, top-right, bottom-left, bottom-right and their slots; -1 where no cell has one.
    Both lists sorted, the cell at each corner of the front pixels only moves forward: four
    pointers walk the cells once."""
    cdef Py_ssize_t sentinel = start_r.shape[0] - 1, count = cells.shape[0]
    cdef Py_ssize_t i, j, s, r, c, rr, cc, key, candidate, k, own
    cdef Py_ssize_t pointer[4]
    cdef float pr, pc, off_r, off_c, t, gap, best
    pointer[0], pointer[1], pointer[2], pointer[3] = 0, 0, 0, 0
    with nogil:
        for i in range(front.shape[0]):
            r, c = front[i] // n, front[i] % n
            pr, pc = <float> r, <float> c
            own, best = -1, 0
            for j in range(4):
                rr, cc = r - 1 + j // 2, c - 1 + j % 2
                candidate = -1
                if rr >= 0 and cc >= 0 and cc < n - 1:
                    key = rr * (n - 1) + cc  # increases with the front pixel
                    while pointer[j] < count and cells[pointer[j]] < key:
                        pointer[j] += 1
                    if pointer[j] < count and cells[pointer[j]] == key:
                        candidate = pointer[j]
                for s in range(2):
                    k = sentinel if candidate < 0 else 2 * candidate + s
                    off_r = pr - start_r[k]
                    off_c = pc - start_c[k]
                    t = (off_r * dir_r[k] + off_c * dir_c[k]) * inverse[k]
                    t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
                    off_r = off_r - t * dir_r[k]
                    off_c = off_c - t * dir_c[k]
                    gap = off_r * off_r + off_c * off_c
                    if (j == 0 and s == 0) or gap < best:
                        own, best = (-1 if candidate < 0 else 2 * candidate + s), gap
            nearest[i] = own


cdef inline double _heaviside(double s) noexcept nogil:
    """The cosine-regularised Heaviside of width 1 (scheme.heaviside)."""
    if s >= 1.0:
        return 1.0
    if s <= -1.0:
        return 0.0
    return 0.5 * (1.0 + s + sin(M_PI * s) / M_PI)


def swept_area(const real[::1] old, const real[::1] new, const Py_ssize_t[::1] old_band,
               const Py_ssize_t[::1] new_band, unsigned char[::1] mark):
    """``sum |H(new) - H(old)|`` over the pixels of either band, each once
    (:func:`activecontour.backends.levelset.scheme._swept_area`); ``mark``: zeros, returned cleared."""
    cdef double total = 0.0
    cdef Py_ssize_t i, p
    with nogil:
        for i in range(old_band.shape[0] + new_band.shape[0]):
            p = old_band[i] if i < old_band.shape[0] else new_band[i - old_band.shape[0]]
            if not mark[p]:
                mark[p] = 1
                total += fabs(_heaviside(new[p]) - _heaviside(old[p]))
        for i in range(old_band.shape[0]):
            mark[old_band[i]] = 0
        for i in range(new_band.shape[0]):
            mark[new_band[i]] = 0
    return total


def force_step(const float[:, ::1] phi, const double[:, :, ::1] values, double constant,
               const double[::1] linear, const double[::1] square, double wall, double tau,
               float[:, ::1] out, Py_ssize_t row0=0, Py_ssize_t col0=0):
    """``phi - tau f`` over the image, rounded to float32: the right-hand side of the level set's
    smoothed-force step (:meth:`activecontour.backends.levelset.scheme._Problem.step`).

    ``f = constant + sum_c v_c (linear_c + square_c v_c)`` is the integrand of (6.41), a
    quadratic form in the channels ``values (M, N, C)`` (``QuadraticForm.density``, term by term
    in the same order), plus ``wall`` per side of the image that a pixel lies on.  ``out`` may be
    a box of the image: its pixel ``(i, j)`` is the image's ``(row0 + i, col0 + j)``."""
    cdef Py_ssize_t rows = out.shape[0], cols = out.shape[1]
    cdef Py_ssize_t block
    if row0 < 0 or col0 < 0 or row0 + rows > phi.shape[0] or col0 + cols > phi.shape[1]:
        raise ValueError("force_step: the box lies outside the image")
    for block in range(0, rows, _POLL_ROWS):
        with nogil:
            _force_rows(phi, values, constant, linear, square, wall, tau, out, row0, col0, block,
                        min(block + _POLL_ROWS, rows))
        PyErr_CheckSignals()


cdef void _force_rows(const float[:, ::1] phi, const double[:, :, ::1] values, double constant,
                      const double[::1] linear, const double[::1] square, double wall, double tau,
                      float[:, ::1] out, Py_ssize_t row0, Py_ssize_t col0, Py_ssize_t first,
                      Py_ssize_t stop) noexcept nogil:
    """Rows ``first .. stop - 1`` of :func:`force_step`'s ``out``."""
    cdef Py_ssize_t m = phi.shape[0], n = phi.shape[1], channels = values.shape[2]
    cdef Py_ssize_t cols = out.shape[1], i, j, r, c, ch
    cdef double f, v
    for i in range(first, stop):
        r = row0 + i
        for j in range(cols):
            c = col0 + j
            f = constant
            for ch in range(channels):
                v = values[r, c, ch]
                if square[ch] != 0:
                    f += v * (linear[ch] + square[ch] * v)
                else:
                    f += linear[ch] * v
            if wall > 0:  # the wall term, columns first as in the numpy blocks
                if c == 0:
                    f += wall
                if c == n - 1:
                    f += wall
                if r == 0:
                    f += wall
                if r == m - 1:
                    f += wall
            out[i, j] = <float> (phi[r, c] - tau * f)


def force_step_tiles(const float[:, ::1] phi, const double[:, :, ::1] values, double constant,
                     const double[::1] linear, const double[::1] square, double wall, double tau,
                     float[:, :, ::1] out, const Py_ssize_t[::1] tops, const Py_ssize_t[::1] lefts):
    """:func:`force_step` into every tile ``out[t]`` (``S x S``), whose pixel ``(i, j)`` is the
    image's ``(tops[t] + i, lefts[t] + j)``: the right-hand sides of the smoothed step on tiles
    along the band (:meth:`activecontour.backends.levelset.scheme._Problem._tile_step`)."""
    cdef Py_ssize_t t, side = out.shape[1]
    for t in range(out.shape[0]):
        if tops[t] < 0 or lefts[t] < 0 or tops[t] + side > phi.shape[0] or lefts[t] + out.shape[2] > phi.shape[1]:
            raise ValueError("force_step_tiles: a tile lies outside the image")
        with nogil:
            _force_rows(phi, values, constant, linear, square, wall, tau, out[t], tops[t], lefts[t], 0, side)
        PyErr_CheckSignals()


def tile_pieces(const float[:, :, ::1] tiles, const Py_ssize_t[::1] tops, const Py_ssize_t[::1] lefts,
                const Py_ssize_t[:, ::1] pieces, float limit, float[:, ::1] out, bint write):
    """Rectangles of tiles, tested or written into the image ``out``.

    ``pieces (P, 6)``: tile, first row, stop row, first column, stop column (image coordinates,
    inside the tile ``tiles[tile]`` whose pixel ``(0, 0)`` is the image's ``(tops[tile],
    lefts[tile])``) and side: +1 (a piece inside: its values must be at least ``limit``), -1 (outside:
    at most ``-limit``) or 0 (not tested).  ``write``: copy every piece into ``out``; else test
    them only.  Returns False when a tested piece fails (nothing is written then), else True.
    """
    cdef Py_ssize_t k, i, j, t, top, left
    cdef float value
    cdef bint passed = True
    for k in range(pieces.shape[0]):
        t = pieces[k, 0]
        if pieces[k, 1] < tops[t] or pieces[k, 2] > tops[t] + tiles.shape[1] \
                or pieces[k, 3] < lefts[t] or pieces[k, 4] > lefts[t] + tiles.shape[2] \
                or pieces[k, 2] > out.shape[0] or pieces[k, 4] > out.shape[1]:
            raise ValueError("tile_pieces: a piece lies outside its tile or the image")
    with nogil:
        for k in range(pieces.shape[0]):
            if not passed:
                break
            t, top, left = pieces[k, 0], tops[pieces[k, 0]], lefts[pieces[k, 0]]
            for i in range(pieces[k, 1], pieces[k, 2]):
                for j in range(pieces[k, 3], pieces[k, 4]):
                    value = tiles[t, i - top, j - left]
                    if write:
                        out[i, j] = value
                    elif (pieces[k, 5] > 0 and value < limit) or (pieces[k, 5] < 0 and value > -limit):
                        passed = False
    return passed


def divide_spectrum(float[:, ::1] spectrum, const float[::1] wave_r, const float[::1] wave_c, float weight):
    """``spectrum /= 1 + weight (wave_r[:, None] + wave_c[None, :])`` in float32: the operator
    ``(1 - weight Laplace)^{-1}`` in the DCT-II basis (the eigenvalues of -Laplace per axis)."""
    cdef Py_ssize_t m = spectrum.shape[0], n = spectrum.shape[1], block, i, j
    cdef float one = 1.0
    for block in range(0, m, _POLL_ROWS):
        with nogil:
            for i in range(block, min(block + _POLL_ROWS, m)):
                for j in range(n):
                    spectrum[i, j] /= one + weight * (wave_r[i] + wave_c[j])
        PyErr_CheckSignals()


cdef inline double _density(const double[:, ::1] values, Py_ssize_t p, double constant,
                            const double[::1] linear, const double[::1] square) noexcept nogil:
    """``constant + sum_c v_c (linear_c + square_c v_c)`` at pixel p, term by term as
    ``QuadraticForm.density``."""
    cdef double f = constant, v
    cdef Py_ssize_t ch
    for ch in range(values.shape[1]):
        v = values[p, ch]
        if square[ch] != 0:
            f += v * (linear[ch] + square[ch] * v)
        else:
            f += linear[ch] * v
    return f


def block_means(const float[:, ::1] a, Py_ssize_t k, float[:, ::1] out, const Py_ssize_t[:, ::1] boxes=None,
                const unsigned char[:, ::1] sides=None, float[:, ::1] signs=None):
    """``out[I, J]`` = the mean of ``a`` over the block of rows ``k I .. k I + k - 1`` and columns
    ``k J .. k J + k - 1`` (cut at the edge), in one pass: the level set's coarse grid
    (:meth:`activecontour.backends.levelset.scheme._Problem._far_flips`).

    ``boxes`` (R, 4) (first row, stop row, first column, stop column): only the blocks that meet
    a box are made, the others keep their values (those of an array that differs from ``a`` in
    the boxes only); each block's sums are the same in the same order either way, so the same
    numbers.  ``sides`` (bool of ``a``'s shape, as uint8) and ``signs`` (``out``'s shape): +1
    where the first pixel of the block is on the inside (``sides`` true), else -1, for the same
    blocks."""
    cdef Py_ssize_t m = a.shape[0], n = a.shape[1], b, first, stop
    if out.shape[0] != (m + k - 1) // k or out.shape[1] != (n + k - 1) // k:
        raise ValueError("block_means: out is not the shape of the blocks")
    if (sides is None) != (signs is None):
        raise ValueError("block_means: sides and signs come together")
    if sides is not None and (sides.shape[0] != m or sides.shape[1] != n
                              or signs.shape[0] != out.shape[0] or signs.shape[1] != out.shape[1]):
        raise ValueError("block_means: sides or signs of the wrong shape")
    if boxes is None:
        for first in range(0, out.shape[0], _POLL_ROWS):  # block rows, polling for Ctrl-C
            stop = min(first + _POLL_ROWS, out.shape[0])
            with nogil:
                _block_means_in(a, k, out, sides, signs, first, stop, 0, out.shape[1])
            PyErr_CheckSignals()
        return
    for b in range(boxes.shape[0]):
        if boxes[b, 0] < 0 or boxes[b, 2] < 0 or boxes[b, 1] > m or boxes[b, 3] > n:
            raise ValueError("block_means: a box lies outside the image")
        if boxes[b, 1] > boxes[b, 0] and boxes[b, 3] > boxes[b, 2]:
            with nogil:
                _block_means_in(a, k, out, sides, signs, boxes[b, 0] // k, (boxes[b, 1] + k - 1) // k,
                                boxes[b, 2] // k, (boxes[b, 3] + k - 1) // k)


cdef void _block_means_in(const float[:, ::1] a, Py_ssize_t k, float[:, ::1] out,
                          const unsigned char[:, ::1] sides, float[:, ::1] signs, Py_ssize_t first_row,
                          Py_ssize_t stop_row, Py_ssize_t first_col, Py_ssize_t stop_col) noexcept nogil:
    """:func:`block_means` of the blocks ``first_row:stop_row, first_col:stop_col``: each block's
    rows summed in order, each row's pixels in order, then divided by its pixel count."""
    cdef Py_ssize_t m = a.shape[0], n = a.shape[1], i, j, bi, bj
    cdef float rows_in, cols_in, total
    for bi in range(first_row, stop_row):
        for bj in range(first_col, stop_col):
            out[bi, bj] = 0
        for i in range(k * bi, min(k * bi + k, m)):
            for bj in range(first_col, stop_col):
                total = 0
                for j in range(k * bj, min(k * bj + k, n)):
                    total += a[i, j]
                out[bi, bj] += total
        rows_in = <float> (min(k * bi + k, m) - k * bi)
        for bj in range(first_col, stop_col):
            cols_in = <float> (min(k * bj + k, n) - k * bj)
            out[bi, bj] /= rows_in * cols_in
            if signs is not None:
                signs[bi, bj] = 1 if sides[k * bi, k * bj] else -1


def block_moments(const double[:, :, ::1] values, Py_ssize_t k, float[:, :, ::1] means,
                  float[:, :, ::1] squares):
    """:func:`block_means` of every channel of ``values (M, N, C)`` rounded to float32 and of its
    square (in float32), into ``means`` and ``squares`` ``(C, M', N')``, in one pass without the
    float32 copies: the same sums in the same order, so the same numbers."""
    cdef Py_ssize_t m = values.shape[0], n = values.shape[1], channels = values.shape[2]
    cdef Py_ssize_t block, i, j, bi, bj, ch
    cdef float rows_in, cols_in, total, total_sq, v, area
    means[:, :, :] = 0
    squares[:, :, :] = 0
    for block in range(0, m, _POLL_ROWS):
        with nogil:
            for i in range(block, min(block + _POLL_ROWS, m)):
                bi = i // k
                for ch in range(channels):
                    for bj in range(means.shape[2]):
                        total = 0
                        total_sq = 0
                        for j in range(k * bj, min(k * bj + k, n)):
                            v = <float> values[i, j, ch]
                            total += v
                            total_sq += v * v
                        means[ch, bi, bj] += total
                        squares[ch, bi, bj] += total_sq
        PyErr_CheckSignals()
    with nogil:
        for ch in range(channels):
            for bi in range(means.shape[1]):
                rows_in = <float> (min(k * bi + k, m) - k * bi)
                for bj in range(means.shape[2]):
                    cols_in = <float> (min(k * bj + k, n) - k * bj)
                    area = rows_in * cols_in
                    means[ch, bi, bj] /= area
                    squares[ch, bi, bj] /= area


def explicit_step(const float[::1] phi, const Py_ssize_t[::1] flat, Py_ssize_t m, Py_ssize_t n,
                  double rate, double band, const double[:, ::1] values, double constant,
                  const double[::1] linear, const double[::1] square, double mu, double tau,
                  float[::1] out):
    """``phi + rate Laplace(phi) - tau f`` at the band's pixels ``flat``, written to ``out``
    (:meth:`activecontour.backends.levelset.scheme._Problem._explicit_step`).

    The 5-point Laplacian with mirrored pixels at the image border (Neumann), its four neighbours
    summed in float32; the force f of (6.41) (the quadratic form of ``values (M N, C)`` plus
    ``mu`` times the number of image sides the pixel lies on) only where ``|phi| < band``."""
    cdef Py_ssize_t i, p, r, c
    cdef float around
    cdef double centre, moved, f
    with nogil:
        for i in range(flat.shape[0]):
            p = flat[i]
            r, c = p // n, p % n
            centre = phi[p]
            around = phi[p - n if r > 0 else p] + phi[p + n if r < m - 1 else p]
            around = around + phi[p - 1 if c > 0 else p]
            around = around + phi[p + 1 if c < n - 1 else p]
            moved = centre + rate * (around - 4.0 * centre)
            if fabs(centre) < band:
                f = _density(values, p, constant, linear, square)
                if mu > 0:
                    f += mu * <double> ((r == 0) + (r == m - 1) + (c == 0) + (c == n - 1))
                moved -= tau * f
            out[p] = <float> moved


def band_couplings(const Py_ssize_t[::1] flat, Py_ssize_t m, Py_ssize_t n, int[::1] index,
                   Py_ssize_t[:, ::1] couplings, Py_ssize_t[:, ::1] held, double[::1] degree):
    """The 4-neighbours (up, down, left, right) of the band's pixels ``flat``, for the solve of S on
    the band (:meth:`activecontour.backends.levelset.scheme._Problem._band_smooth`).

    ``couplings[d, i]``: the band index of pixel i's neighbour d, -1 where it is beyond the band
    or the image; ``held[d, i]``: its flat index where it is in the image but beyond the band,
    else -1; ``degree[i]``: the number of neighbours in the image.  ``index``: a framed
    (M + 2) x (N + 2) array of -1 (row length N + 2), returned so."""
    cdef Py_ssize_t width = n + 2, i, d, p, q, r, c, k
    cdef bint exists
    with nogil:
        for i in range(flat.shape[0]):
            p = flat[i]
            index[(p // n + 1) * width + p % n + 1] = <int> i
        for i in range(flat.shape[0]):
            p = flat[i]
            r, c = p // n, p % n
            degree[i] = 0.0
            for d in range(4):
                if d == 0:
                    exists, q = r > 0, p - n
                elif d == 1:
                    exists, q = r < m - 1, p + n
                elif d == 2:
                    exists, q = c > 0, p - 1
                else:
                    exists, q = c < n - 1, p + 1
                couplings[d, i], held[d, i] = -1, -1
                if exists:
                    degree[i] += 1.0
                    k = index[(q // n + 1) * width + q % n + 1]
                    if k >= 0:
                        couplings[d, i] = k
                    else:
                        held[d, i] = q
        for i in range(flat.shape[0]):
            p = flat[i]
            index[(p // n + 1) * width + p % n + 1] = -1


def sides(const real[:, ::1] phi, const unsigned char[:, ::1] before, unsigned char[:, ::1] positive,
          const Py_ssize_t[:, ::1] boxes, Py_ssize_t[::1] switched):
    """``positive = phi > 0`` and the pixels whose side differs from ``before``, in one pass over
    each box (rows ``(first row, stop row, first column, stop column)``: where a step changed phi;
    beyond them ``positive`` is left as it is)
    (:func:`activecontour.backends.levelset.redistancing._locate`): ``switched`` (room for every
    pixel of the boxes) gets their flat indices in the image, per box in increasing order (a pixel
    of two boxes twice); returns how many."""
    cdef Py_ssize_t m = phi.shape[0], n = phi.shape[1], b, block, r, c, count = 0
    cdef Py_ssize_t row0, row1, col0, col1
    cdef unsigned char side
    for b in range(boxes.shape[0]):
        row0, row1, col0, col1 = boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3]
        if row0 < 0 or col0 < 0 or row1 > m or col1 > n:
            raise ValueError("sides: a box lies outside the image")
        if row1 <= row0 or col1 <= col0:
            continue
        if count + (row1 - row0) * (col1 - col0) > switched.shape[0]:
            raise ValueError("sides: no room in switched for the boxes' pixels")
        for block in range(row0, row1, _POLL_ROWS):
            with nogil:
                for r in range(block, min(block + _POLL_ROWS, row1)):
                    for c in range(col0, col1):
                        side = phi[r, c] > 0
                        positive[r, c] = side
                        if side != before[r, c]:
                            switched[count] = r * n + c
                            count += 1
            PyErr_CheckSignals()
    return count


def copy_boxes(const real[:, ::1] source, real[:, ::1] target, const Py_ssize_t[:, ::1] boxes):
    """``target = source`` over each box (rows as for :func:`sides`): the previous state's phi put
    back where a step changed it (:meth:`activecontour.backends.levelset.redistancing._Located.finish`)."""
    cdef Py_ssize_t m = source.shape[0], n = source.shape[1], b, r, c
    cdef Py_ssize_t row0, row1, col0, col1
    if target.shape[0] != m or target.shape[1] != n:
        raise ValueError("copy_boxes: source and target differ in shape")
    for b in range(boxes.shape[0]):
        row0, row1, col0, col1 = boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3]
        if row0 < 0 or col0 < 0 or row1 > m or col1 > n:
            raise ValueError("copy_boxes: a box lies outside the image")
        with nogil:
            for r in range(row0, row1):
                for c in range(col0, col1):
                    target[r, c] = source[r, c]


def sides_at(const real[::1] phi, const unsigned char[::1] before, unsigned char[::1] positive,
             const Py_ssize_t[::1] flat, Py_ssize_t[::1] switched):
    """:func:`sides` at the pixels ``flat`` only (flat indices, each once: the band a step (b)
    changed): ``positive[p] = phi[p] > 0`` there, and ``switched`` (room for ``flat.size``) gets
    those whose side differs from ``before``, in the order of ``flat``; returns how many."""
    cdef Py_ssize_t i, p, count = 0
    cdef unsigned char side
    with nogil:
        for i in range(flat.shape[0]):
            p = flat[i]
            side = phi[p] > 0
            positive[p] = side
            if side != before[p]:
                switched[count] = p
                count += 1
    return count


def segment_table(const double[:, :, ::1] segments, double far, double[:, ::1] columns,
                  float[:, ::1] columns32):
    """The columns of the level set's segment table
    (:class:`activecontour.backends.levelset.redistancing._Segments`): for each segment ``(S, 2
    ends, 2)`` its start (row, col; ``far`` for an empty, NaN slot), its direction (0 where NaN)
    and its inverse squared length (0 for a point), in ``columns (5, S + 1)`` and as float32 in
    ``columns32``; the last column is the far sentinel ``(far, far, 0, 0, 0)``."""
    cdef Py_ssize_t count = segments.shape[0], i, k
    cdef double row[5]
    with nogil:
        for i in range(count + 1):
            if i == count:
                row[0], row[1], row[2], row[3], row[4] = far, far, 0.0, 0.0, 0.0
            else:
                row[0], row[1] = segments[i, 0, 0], segments[i, 0, 1]
                row[2], row[3] = segments[i, 1, 0] - row[0], segments[i, 1, 1] - row[1]
                for k in range(2):
                    if isnan(row[k]):
                        row[k] = far
                    if isnan(row[2 + k]):
                        row[2 + k] = 0.0
                row[4] = row[2] * row[2] + row[3] * row[3]
                row[4] = 1.0 / row[4] if row[4] > 0 else 0.0
            for k in range(5):
                columns[k, i] = row[k]
                columns32[k, i] = <float> row[k]


cdef Py_ssize_t _lower_envelope(const long long *g, Py_ssize_t count, Py_ssize_t stride, long long far,
                                Py_ssize_t *vertex, long long *height) noexcept nogil:
    """The lower envelope of the parabolas ``(x - q)^2 + g_q^2`` over q < ``count`` with
    ``g_q = g[q * stride] < far`` (Felzenszwalb and Huttenlocher), its breakpoints compared as
    integers: parabola ``vertex[k]`` with ``height[k] = g^2 + q^2`` is lowest from its breakpoint
    with ``vertex[k - 1]`` to its breakpoint with ``vertex[k + 1]``, the breakpoint of u < p lying
    at ``(height_p - height_u) / (2 (p - u))``.  Returns the last index k (-1: no parabola)."""
    cdef Py_ssize_t k = -1, q, p, u
    cdef long long h
    for q in range(count):
        h = g[q * stride]
        if h >= far:
            continue
        h = h * h + <long long> q * q
        while k >= 1:
            p, u = vertex[k], vertex[k - 1]
            # drop p when q's breakpoint with it comes no later than p's with u
            if (h - height[k]) * (p - u) <= (height[k] - height[k - 1]) * (q - p):
                k -= 1
            else:
                break
        if k == 0 and h - height[0] <= 0:
            k = -1  # q is as low as vertex[0] from x = 0 on
        k += 1
        vertex[k] = q
        height[k] = h
    return k


cdef inline long long _envelope_at(const Py_ssize_t *vertex, const long long *height, Py_ssize_t k,
                                   Py_ssize_t *last, Py_ssize_t x) noexcept nogil:
    """The envelope of :func:`_lower_envelope` (last index ``k``) at ``x``, the squared distance;
    ``last`` is the parabola that was lowest at the previous, smaller x (start at 0)."""
    cdef Py_ssize_t p = last[0]
    # move right while the next parabola takes over at or before x
    while p < k and height[p + 1] - height[p] <= 2 * x * (vertex[p + 1] - vertex[p]):
        p += 1
    last[0] = p
    return <long long> (x - vertex[p]) * (x - vertex[p]) + height[p] - <long long> vertex[p] * vertex[p]


def sampled_distance(const Py_ssize_t[::1] row, const Py_ssize_t[::1] first, const int[::1] direction,
                     Py_ssize_t rows, Py_ssize_t cols, Py_ssize_t step, double[:, ::1] out):
    """The Euclidean distance transform (as ``scipy.ndimage.distance_transform_edt``: from each
    pixel to the nearest pixel outside, 0 outside) of the ``rows x cols`` mask that
    :func:`activecontour.geometry.raster.rasterize` draws from its row crossings (``row``,
    ``first`` column right of the crossing, ``direction``; sorted by row, then column: a pixel is
    inside when the directions of the crossings at or left of it do not add up to 0), read every
    ``step`` pixels: ``out[i, j]`` at pixel ``(step i, step j)``.  The mask must have a pixel
    outside.

    Separable and exact, without drawing the mask: per row, the runs of inside pixels from its
    crossings, and the distance h along the row from each sampled column to the nearest pixel
    outside; per sampled column, the lower envelope of the parabolas ``(x - r)^2 + h_r^2`` over
    the rows r (:func:`_lower_envelope`), read at the sampled rows: the least squared distance
    as an integer, then one square root (the transform's own values).  O(rows x sampled columns
    + crossings)."""
    cdef Py_ssize_t m = out.shape[0], n = out.shape[1], count = row.shape[0]
    cdef Py_ssize_t r, c, i, j, k, at = 0, start, stop, winding, before, last
    cdef long long far = (rows + cols) * (rows + cols) + 1
    cdef long long *across = <long long *> malloc(max(rows * n, 1) * sizeof(long long))
    cdef Py_ssize_t *vertex = <Py_ssize_t *> malloc(max(rows, 1) * sizeof(Py_ssize_t))
    cdef long long *height = <long long *> malloc(max(rows, 1) * sizeof(long long))
    if across == NULL or vertex == NULL or height == NULL:
        free(across)
        free(vertex)
        free(height)
        raise MemoryError()
    with nogil:
        for r in range(rows):
            for j in range(n):
                across[r * n + j] = 0
            while at < count and row[at] < r:
                at += 1
            # the runs [start, stop) where the winding is not 0; the sampled columns in each
            winding = 0
            start = -1
            while at < count and row[at] == r:
                c = first[at]
                before = winding
                while at < count and row[at] == r and first[at] == c:
                    winding += direction[at]
                    at += 1
                if before == 0 and winding != 0:
                    start = c
                elif before != 0 and winding == 0:
                    _run_distances(across, r, n, step, start, c, cols, far)
            if winding != 0:
                _run_distances(across, r, n, step, start, cols, cols, far)
        for j in range(n):
            k = _lower_envelope(&across[j], rows, n, far, vertex, height)
            if k < 0:
                for i in range(m):
                    out[i, j] = sqrt(<double> far)
                continue
            last = 0
            for i in range(m):
                out[i, j] = sqrt(<double> _envelope_at(vertex, height, k, &last, i * step))
    free(across)
    free(vertex)
    free(height)


cdef inline void _run_distances(long long *across, Py_ssize_t r, Py_ssize_t n, Py_ssize_t step,
                                Py_ssize_t start, Py_ssize_t stop, Py_ssize_t cols,
                                long long far) noexcept nogil:
    """Row r's sampled columns in the run of inside pixels [start, stop) (clipped to the row):
    their distance to the nearest pixel outside, on the left (start - 1) or the right (stop),
    those outside the row's ends not counting."""
    cdef Py_ssize_t j, c
    cdef long long left, right
    if start < 0:
        start = 0
    if stop > cols:
        stop = cols
    j = (start + step - 1) // step
    while j < n and j * step < stop:
        c = j * step
        left = c - start + 1 if start > 0 else far
        right = stop - c if stop < cols else far
        across[r * n + j] = left if left < right else right
        j += 1


# ==== the network's kernels (issue 24 item 5, branch net2) =========================================


def segment_loads(const double[:, ::1] starts, const double[:, ::1] ends, const Py_ssize_t[::1] inner,
                  const Py_ssize_t[::1] outer, const double[:, :, ::1] parts, const double[:, ::1] table,
                  double mu, double[:, :, ::1] load):
    """The load (6.41) of every boundary segment on its two ends, for
    :func:`activecontour.energy.partition_load` (its docstring has the mathematics).

    ``table[k] = (constant, linear (C), square (C))`` of region k's quadratic form; a segment
    between regions i (inner) and o (outer, < 0: the image's edge, no form) carries
    ``g_i - g_o``, whose integral against the end's hat function is ``parts[e, end] . (linear,
    square) + constant / 2``, times the normal ``nu |e| = (dv, -du)``; the length term is
    ``mu`` times the unit tangent (pulling the ends together) on interfaces (``o >= 0``) and on
    the border of regions other than 0.  ``load[e, 0]`` is the start's, ``load[e, 1]`` the end's.
    """
    cdef Py_ssize_t count = starts.shape[0], width = parts.shape[2], e, end, c, i, o
    cdef double du, dv, length, pull, density, coefficient
    if table.shape[1] != 1 + width or load.shape[0] != count or parts.shape[0] != count:
        raise ValueError("table must be (K, 1 + 2C), parts (S, 2, 2C) and load (S, 2, 2)")
    with nogil:
        for e in range(count):
            i, o = inner[e], outer[e]
            du, dv = ends[e, 0] - starts[e, 0], ends[e, 1] - starts[e, 1]
            length = sqrt(du * du + dv * dv)
            pull = mu / length if (o >= 0 or i > 0) and length > 0.0 else 0.0
            for end in range(2):
                density = 0.0
                for c in range(width):
                    coefficient = table[i, 1 + c] - (table[o, 1 + c] if o >= 0 else 0.0)
                    density += parts[e, end, c] * coefficient
                density += 0.5 * (table[i, 0] - (table[o, 0] if o >= 0 else 0.0))
                load[e, end, 0] = density * dv
                load[e, end, 1] = -density * du
            load[e, 0, 0] -= pull * du
            load[e, 0, 1] -= pull * dv
            load[e, 1, 0] += pull * du
            load[e, 1, 1] += pull * dv


def step_bounds(const double[:, ::1] nodes, const double[:, ::1] velocity, const Py_ssize_t[::1] start,
                const Py_ssize_t[::1] end, const Py_ssize_t[::1] face, const Py_ssize_t[::1] segment,
                const double[::1] sign, double high_r, double high_c, double[::1] areas,
                double[::1] perimeter, double[::1] speed):
    """The bounds of the steps ``nodes + dt velocity`` of a network's iteration, in one pass
    (:class:`activecontour.backends.network._Steps` has the reasoning).

    Returns ``(reverse, inside)``: the least dt at which a segment's projection on its old
    direction falls to a quarter of its squared length (``(old + dt turn) . old = |old|^2 / 4``,
    over the segments that shrink), and the least dt at which a vertex reaches the domain's
    edge ``[-0.5, high]``; inf when none.  Per face f of the entries ``(face, segment, sign)``
    (grouped by face): ``areas[f]`` its signed area (the shoelace sum, each segment's cross
    product times its sign), ``perimeter[f]`` its length and ``speed[f]`` its fastest vertex's
    speed (the square root of the largest squared speed of its vertices, each found once).
    """
    cdef Py_ssize_t count = start.shape[0], points = nodes.shape[0], entries = face.shape[0], k, s, f, d
    cdef double reverse = INFINITY, inside = INFINITY, old_r, old_c, along, room, value, fast
    cdef double high[2]
    cdef double *squared = <double *> malloc(max(points, 1) * sizeof(double))
    if squared == NULL:
        raise MemoryError()
    high[0], high[1] = high_r, high_c
    with nogil:
        for k in range(points):
            squared[k] = velocity[k, 0] * velocity[k, 0] + velocity[k, 1] * velocity[k, 1]
        for s in range(count):
            old_r = nodes[end[s], 0] - nodes[start[s], 0]
            old_c = nodes[end[s], 1] - nodes[start[s], 1]
            along = (old_r * (velocity[end[s], 0] - velocity[start[s], 0])
                     + old_c * (velocity[end[s], 1] - velocity[start[s], 1]))
            if along < 0.0:
                value = 0.75 * (old_r * old_r + old_c * old_c) / -along
                if value < reverse:
                    reverse = value
        for k in range(points):
            for d in range(2):
                if velocity[k, d] > 0.0:
                    room = (high[d] - nodes[k, d]) / velocity[k, d]
                elif velocity[k, d] < 0.0:
                    room = (-0.5 - nodes[k, d]) / velocity[k, d]
                else:
                    continue
                if room < inside:
                    inside = room
        for f in range(areas.shape[0]):
            areas[f] = 0.0
            perimeter[f] = 0.0
            speed[f] = 0.0
        for k in range(entries):
            f, s = face[k], segment[k]
            old_r = nodes[end[s], 0] - nodes[start[s], 0]
            old_c = nodes[end[s], 1] - nodes[start[s], 1]
            areas[f] += sign[k] * (nodes[start[s], 0] * nodes[end[s], 1]
                                   - nodes[end[s], 0] * nodes[start[s], 1])
            perimeter[f] += sqrt(old_r * old_r + old_c * old_c)
            fast = max(squared[start[s]], squared[end[s]])
            if fast > speed[f]:
                speed[f] = fast
        for f in range(areas.shape[0]):
            areas[f] *= 0.5
            speed[f] = sqrt(speed[f])
    free(squared)
    return reverse, inside



cdef Py_ssize_t _untwist_loop(const Py_ssize_t *loop, Py_ssize_t n, const Py_ssize_t[::1] ids,
                              unsigned char *seen, Py_ssize_t[::1] out, Py_ssize_t[::1] out_offsets,
                              Py_ssize_t *position, Py_ssize_t *loops) noexcept nogil:
    """One loop of :func:`untwist` (recursive, as the definition); -1 when out of memory."""
    cdef Py_ssize_t k, key, best = -1, i = -1, j = -1, size
    cdef Py_ssize_t *part
    for k in range(n):  # the smallest key the loop passes twice
        key = ids[loop[k]]
        if seen[key] and (best < 0 or key < best):
            best = key
        seen[key] = 1
    for k in range(n):
        seen[ids[loop[k]]] = 0
    if best < 0:
        for k in range(n):
            out[position[0] + k] = loop[k]
        position[0] += n
        loops[0] += 1
        out_offsets[loops[0]] = position[0]
        return 0
    for k in range(n):  # its first two passes
        if ids[loop[k]] == best:
            if i < 0:
                i = k
            else:
                j = k
                break
    part = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    if part == NULL:
        return -1
    size = 0
    for k in range(i, j):
        part[size] = loop[k]
        size += 1
    if _untwist_loop(part, size, ids, seen, out, out_offsets, position, loops) < 0:
        free(part)
        return -1
    size = 0
    for k in range(j, n):
        part[size] = loop[k]
        size += 1
    for k in range(i):
        part[size] = loop[k]
        size += 1
    k = _untwist_loop(part, size, ids, seen, out, out_offsets, position, loops)
    free(part)
    return k


def untwist(const Py_ssize_t[::1] order, const Py_ssize_t[::1] offsets, const unsigned char[::1] twisted,
            const Py_ssize_t[::1] ids, Py_ssize_t distinct, Py_ssize_t[::1] out, Py_ssize_t[::1] out_offsets):
    """Loops cut where they pass a point twice (:func:`activecontour.geometry.partition.chain_loops`).

    Loop c is ``order[offsets[c]:offsets[c + 1]]`` (elements whose points have the keys ``ids``,
    dense in 0..distinct-1 and in the order of the points' keys); a loop with ``twisted[c]`` is
    cut, recursively: at its smallest key that it passes twice, between the first two passes,
    into the loop from the first pass to the second and the rest from the second pass on (then
    its start), in that order.  The loops that pass every point once go to ``out`` (as long as
    ``order``), loop l at ``out[out_offsets[l]:out_offsets[l + 1]]`` (``out_offsets`` as long as
    ``order`` + 1).  Returns the number of loops.
    """
    cdef Py_ssize_t count = offsets.shape[0] - 1, c, k, position = 0, loops = 0, failed = 0
    cdef unsigned char *seen = <unsigned char *> calloc(max(distinct, 1), sizeof(unsigned char))
    if seen == NULL:
        raise MemoryError()
    out_offsets[0] = 0
    with nogil:
        for c in range(count):
            if twisted[c]:
                if _untwist_loop(&order[offsets[c]], offsets[c + 1] - offsets[c], ids, seen, out,
                                 out_offsets, &position, &loops) < 0:
                    failed = 1
                    break
            else:
                for k in range(offsets[c], offsets[c + 1]):
                    out[position] = order[k]
                    position += 1
                loops += 1
                out_offsets[loops] = position
    free(seen)
    if failed:
        raise MemoryError()
    return loops


def normal_part(const double[:, ::1] nodes, double[:, ::1] velocity, const Py_ssize_t[::1] start,
                const Py_ssize_t[::1] end, const Py_ssize_t[::1] plain):
    """A velocity without its tangential part at the nodes ``plain`` (inside an interface), in
    place (:meth:`activecontour.backends.network.Network.normal_part`).

    A plain node's normal is that of the sum of its segments' vectors ``t`` (the segments
    ``start -> end``; their starts' sums first, then their ends'): ``(t_c, -t_r)``, normalised;
    its velocity v becomes ``(v . n) n``.  A node whose sum vanishes keeps its velocity.
    """
    cdef Py_ssize_t count = start.shape[0], points = nodes.shape[0], s, k, p
    cdef double n_r, n_c, squared, along, norm
    cdef double *at_start = <double *> calloc(2 * max(points, 1), sizeof(double))
    cdef double *at_end = <double *> calloc(2 * max(points, 1), sizeof(double))
    if at_start == NULL or at_end == NULL:
        free(at_start)
        free(at_end)
        raise MemoryError()
    with nogil:
        for s in range(count):
            for k in range(2):
                at_start[2 * start[s] + k] += nodes[end[s], k] - nodes[start[s], k]
                at_end[2 * end[s] + k] += nodes[end[s], k] - nodes[start[s], k]
        for k in range(plain.shape[0]):
            p = plain[k]
            n_r = at_start[2 * p + 1] + at_end[2 * p + 1]
            n_c = -(at_start[2 * p] + at_end[2 * p])
            squared = n_r * n_r + n_c * n_c
            if squared > 0.0:
                norm = sqrt(squared)
                n_r, n_c = n_r / norm, n_c / norm
                along = velocity[p, 0] * n_r + velocity[p, 1] * n_c
                velocity[p, 0] = along * n_r
                velocity[p, 1] = along * n_c
    free(at_start)
    free(at_end)

# ==== end of the network's kernels ==============================================================


# ==== split2 (issue 23 item 2): the split's cheap exact tests ====================================

def near_reaches(const unsigned char[:, ::1] mask, long long least, unsigned char[:, ::1] out):
    """Whether the squared Euclidean distance transform of a mask reaches ``least``: ``out[i, j]``
    is 1 where D >= least, for D the squared distance from pixel (i, j) to the nearest pixel
    where ``mask`` is 0 (pixels beyond the array's edge do not count, as in
    ``scipy.ndimage.distance_transform_edt``, whose values are ``sqrt(D)``; a mask without a 0
    reaches every ``least``), else 0.

    Only rows within ``sqrt(least)`` of a pixel can hold a 0 nearer than that: per row, the
    distance h along it to the nearest 0 (two passes, capped), then per pixel whether some
    ``dy^2 + h^2`` over those rows is below ``least`` (the first one found ends the search).
    O(pixels x sqrt(least)): for small radii (a few pixels)."""
    cdef Py_ssize_t m = mask.shape[0], n = mask.shape[1], i, j, d, reach = 0
    cdef long long h
    cdef unsigned char reached
    cdef int *along
    if least <= 0:
        out[:, :] = 1
        return
    while (reach + 1) * (reach + 1) < least:
        reach += 1
    along = <int *> malloc(max(m * n, 1) * sizeof(int))
    if along == NULL:
        raise MemoryError()
    with nogil:
        for i in range(m):
            h = reach + 1  # no 0 within reach: h^2 >= least
            for j in range(n):
                h = 0 if mask[i, j] == 0 else (h + 1 if h <= reach else reach + 1)
                along[i * n + j] = <int> h
            h = reach + 1
            for j in range(n - 1, -1, -1):
                h = 0 if mask[i, j] == 0 else (h + 1 if h <= reach else reach + 1)
                if h < along[i * n + j]:
                    along[i * n + j] = <int> h
        for i in range(m):
            for j in range(n):
                reached = 1
                for d in range(-reach, reach + 1):
                    if 0 <= i + d < m:
                        h = along[(i + d) * n + j]
                        if d * d + h * h < least:
                            reached = 0
                            break
                out[i, j] = reached
    free(along)


def ellipse_moments(const double[:, ::1] points, const Py_ssize_t[::1] starts, double[:, ::1] out):
    """The sums of the direct least-squares ellipse fit (Fitzgibbon, Pilu and Fisher; Halir and
    Flusser's blocks) of each point set ``points[starts[s]:starts[s + 1]]`` (stacked (P, 2)), in
    its normalised frame: ``out[s, 0:2]`` its mean, ``out[s, 2]`` its rms distance to it (1 when
    0), and with (x, y) the points less the mean over that scale, q = (x^2, xy, y^2) and
    l = (x, y, 1): ``out[s, 3:12]`` the 3 x 3 sums of ``q q^T``, ``out[s, 12:21]`` of ``q l^T``,
    ``out[s, 21:30]`` of ``l l^T`` (row-major).  All sets in one call: the split's arc grouping
    fits hundreds of small sets at a time."""
    cdef Py_ssize_t s, p, first, last, count, i, j
    cdef double mean0, mean1, scale, x, y
    cdef double q[3]
    cdef double l[3]
    with nogil:
        for s in range(starts.shape[0] - 1):
            first, last = starts[s], starts[s + 1]
            count = last - first
            for i in range(3, 30):
                out[s, i] = 0.0
            if count == 0:
                continue
            mean0, mean1, scale = 0.0, 0.0, 0.0
            for p in range(first, last):
                mean0 += points[p, 0]
                mean1 += points[p, 1]
            mean0 /= count
            mean1 /= count
            for p in range(first, last):
                x = points[p, 0] - mean0
                y = points[p, 1] - mean1
                scale += x * x + y * y
            scale = sqrt(scale / count)
            if scale == 0.0:
                scale = 1.0
            out[s, 0], out[s, 1], out[s, 2] = mean0, mean1, scale
            l[2] = 1.0
            for p in range(first, last):
                x = (points[p, 0] - mean0) / scale
                y = (points[p, 1] - mean1) / scale
                q[0], q[1], q[2] = x * x, x * y, y * y
                l[0], l[1] = x, y
                for i in range(3):
                    for j in range(3):
                        out[s, 3 + 3 * i + j] += q[i] * q[j]
                        out[s, 12 + 3 * i + j] += q[i] * l[j]
                        out[s, 21 + 3 * i + j] += l[i] * l[j]


def conic_residuals(const double[:, ::1] points, const Py_ssize_t[::1] starts, const double[:, ::1] conics,
                    double[::1] out):
    """For each point set ``points[starts[s]:starts[s + 1]]`` (as :func:`ellipse_moments`), the
    sum of squared Sampson distances (in the points' units) to the conic ``conics[s]`` = (mean0,
    mean1, scale, a, b, c, d, e, f), ``a x^2 + b xy + c y^2 + d x + e y + f = 0`` in the set's
    normalised frame: ``(scale value / |gradient|)^2`` (the gradient's norm at least 1e-12)."""
    cdef Py_ssize_t s, p
    cdef double total, x, y, value, gx, gy, norm, mean0, mean1, scale, a, b, c, d, e, f
    with nogil:
        for s in range(starts.shape[0] - 1):
            mean0, mean1, scale = conics[s, 0], conics[s, 1], conics[s, 2]
            a, b, c, d, e, f = conics[s, 3], conics[s, 4], conics[s, 5], conics[s, 6], conics[s, 7], conics[s, 8]
            total = 0.0
            for p in range(starts[s], starts[s + 1]):
                x = (points[p, 0] - mean0) / scale
                y = (points[p, 1] - mean1) / scale
                value = a * x * x + b * x * y + c * y * y + d * x + e * y + f
                gx = 2 * a * x + b * y + d
                gy = b * x + 2 * c * y + e
                norm = sqrt(gx * gx + gy * gy)
                if norm < 1e-12:
                    norm = 1e-12
                value = scale * value / norm
                total += value * value
            out[s] = total


def convex_clip_area(const double[:, ::1] polygon, const double[:, ::1] convex):
    """The area of the intersection of a simple polygon (K, 2), either orientation, with a convex
    polygon (L, 2), either orientation: the polygon clipped by each edge's half-plane in turn
    (Sutherland and Hodgman), then the shoelace of what is left.  A concave polygon clipped so
    may come out as several pieces joined along the clipping lines; those joins enclose nothing,
    so the area is still the intersection's (each clip keeps the winding number of every point
    inside its half-plane, and the points outside have none)."""
    cdef Py_ssize_t count = polygon.shape[0], sides = convex.shape[0], capacity, size, i, k, n_out
    cdef double orientation = 0.0, area = 0.0, a0, a1, b0, b1, p0, p1, q0, q1, sp, sq, t
    cdef double *current
    cdef double *clipped
    cdef double *swap
    if count < 3 or sides < 3:
        return 0.0
    for i in range(sides):
        k = (i + 1) % sides
        orientation += convex[i, 0] * convex[k, 1] - convex[k, 0] * convex[i, 1]
    orientation = 1.0 if orientation > 0 else -1.0
    capacity = 2 * count + 2 * sides + 8
    current = <double *> malloc(2 * capacity * sizeof(double))
    clipped = <double *> malloc(2 * capacity * sizeof(double))
    if current == NULL or clipped == NULL:
        free(current)
        free(clipped)
        raise MemoryError()
    with nogil:
        for i in range(count):
            current[2 * i], current[2 * i + 1] = polygon[i, 0], polygon[i, 1]
        size = count
        for k in range(sides):
            if size == 0:
                break
            if 2 * size + 2 > capacity:  # (each vertex gives two at most)
                capacity = 2 * size + 2
                swap = <double *> realloc(clipped, 2 * capacity * sizeof(double))
                if swap == NULL:
                    break
                clipped = swap
                swap = <double *> realloc(current, 2 * capacity * sizeof(double))
                if swap == NULL:
                    break
                current = swap
            a0, a1 = convex[k, 0], convex[k, 1]
            b0, b1 = convex[(k + 1) % sides, 0], convex[(k + 1) % sides, 1]
            n_out = 0
            p0, p1 = current[2 * (size - 1)], current[2 * (size - 1) + 1]
            sp = orientation * _side(a0, a1, b0, b1, p0, p1)
            for i in range(size):
                q0, q1 = current[2 * i], current[2 * i + 1]
                sq = orientation * _side(a0, a1, b0, b1, q0, q1)
                if (sp >= 0) != (sq >= 0):  # the edge p -> q crosses the clipping line
                    t = sp / (sp - sq)
                    clipped[2 * n_out], clipped[2 * n_out + 1] = p0 + t * (q0 - p0), p1 + t * (q1 - p1)
                    n_out += 1
                if sq >= 0:
                    clipped[2 * n_out], clipped[2 * n_out + 1] = q0, q1
                    n_out += 1
                p0, p1, sp = q0, q1, sq
            swap = current
            current = clipped
            clipped = swap
            size = n_out
        for i in range(size):
            k = (i + 1) % size
            area += current[2 * i] * current[2 * k + 1] - current[2 * k] * current[2 * i + 1]
    free(current)
    free(clipped)
    return fabs(0.5 * area)


cdef inline double _side(double u0, double u1, double v0, double v1, double w0, double w1) noexcept nogil:
    return (v0 - u0) * (w1 - u1) - (v1 - u1) * (w0 - u0)


def segment_inside(const double[:, ::1] start, const double[:, ::1] end, Py_ssize_t a, Py_ssize_t b):
    """Whether the segment from vertex a to vertex b of a simple polygon (edge i from
    ``start[i]`` to ``end[i]``) lies inside it: it crosses no edge properly (the edges at a and
    b aside) and its midpoint is inside (the crossing count of the row through it, each
    crossing counted by the side it passes on).  The same sign tests, in the same arithmetic,
    as :func:`activecontour.objects.split`'s definition."""
    cdef Py_ssize_t i, count = start.shape[0], up = 0, down = 0
    cdef double p0 = start[a, 0], p1 = start[a, 1], q0 = start[b, 0], q1 = start[b, 1]
    cdef double m0, m1, turn
    for i in range(count):
        if i == a or (i + 1) % count == a or i == b or (i + 1) % count == b:
            continue
        if (_side(p0, p1, q0, q1, start[i, 0], start[i, 1]) * _side(p0, p1, q0, q1, end[i, 0], end[i, 1]) < 0
                and _side(start[i, 0], start[i, 1], end[i, 0], end[i, 1], p0, p1)
                * _side(start[i, 0], start[i, 1], end[i, 0], end[i, 1], q0, q1) < 0):
            return False
    m0 = 0.5 * (p0 + q0)
    m1 = 0.5 * (p1 + q1)
    for i in range(count):
        turn = _side(start[i, 0], start[i, 1], end[i, 0], end[i, 1], m0, m1)
        if start[i, 0] <= m0 and end[i, 0] > m0 and turn > 0:
            up += 1
        elif start[i, 0] > m0 and end[i, 0] <= m0 and turn < 0:
            down += 1
    return up != down



def cut_ratios(const double[:, ::1] part, const double[:, ::1] centred, const double[:, ::1] normals,
               const Py_ssize_t[::1] first, const Py_ssize_t[::1] second, double least, double[::1] out):
    """The neck ratio of each candidate cut ``(first[k], second[k])`` (a < b) of a part of the
    corner stage (:func:`activecontour.objects.corners._cuts`): the cut's length over the smaller of
    the part's extents along it, on each side of the cut (its vertices ``part``, their offsets
    from the mean ``centred``); infinity for a cut of no length or one that does not face the
    inward normal (``-normals``, the outward unit normals at the part's vertices) within
    ``acos(least)`` at both ends.

    The same arithmetic as the definition in numpy, to the bit: the dot product of two
    2-vectors as numpy's BLAS computes it (``x @ y = fma(x1, y1, x0 y0)``) and the rows of a
    matrix times a 2-vector (``(A @ y)_i = fma(A_i0, y0, A_i1 y1)``)."""
    cdef Py_ssize_t k, i, a, b, n = part.shape[0]
    cdef double d0, d1, length, value, low1, high1, low2, high2, extent
    for k in range(first.shape[0]):
        a = first[k]
        b = second[k]
        out[k] = INFINITY
        d0 = part[b, 0] - part[a, 0]
        d1 = part[b, 1] - part[a, 1]
        length = hypot(d0, d1)
        if length == 0:
            continue
        d0 = d0 / length
        d1 = d1 / length
        if (fma(-normals[a, 1], d1, (-normals[a, 0]) * d0) < least
                or fma(normals[b, 1], d1, normals[b, 0] * d0) < least):
            continue
        low1 = high1 = fma(centred[a, 0], d0, centred[a, 1] * d1)
        for i in range(a + 1, b + 1):
            value = fma(centred[i, 0], d0, centred[i, 1] * d1)
            low1 = value if value < low1 else low1
            high1 = value if value > high1 else high1
        low2 = high2 = fma(centred[b, 0], d0, centred[b, 1] * d1)
        for i in range(b + 1, n + a + 1):
            value = fma(centred[i % n, 0], d0, centred[i % n, 1] * d1)
            low2 = value if value < low2 else low2
            high2 = value if value > high2 else high2
        extent = high1 - low1 if high1 - low1 < high2 - low2 else high2 - low2
        out[k] = length / (extent if extent > 1e-12 else 1e-12)



def ray_hits(const double[:, ::1] start, const double[:, ::1] edge, const double[:, :, ::1] turns,
             const double[:, ::1] normals, const Py_ssize_t[::1] positions, Py_ssize_t[:, ::1] nearest,
             double[:, ::1] along, unsigned char[:, ::1] hit):
    """For each ray ``-turns[t] @ normals[c]`` (as numpy's BLAS computes a matrix times a
    2-vector, ``(A @ y)_i = fma(A_i0, y0, A_i1 y1)``) from vertex ``positions[c]`` of a part (its edges from
    ``start[e]`` along ``edge[e]``) the first edge it meets (:func:`activecontour.objects.corners.
    _ray_hits`): ``nearest[c, t]``, the least distance along the ray over the edges it crosses
    (``along_ray > 1e-9``, ``0 <= along_edge <= 1``, a denominator above 1e-12 in size, not the
    two edges at the vertex), the first such edge on a tie and edge 0 when there is none, as
    ``numpy.argmin`` picks it; ``along[c, t]``, where on that edge it lies (``along_edge``), and
    ``hit[c, t]``, whether the ray crosses it.  The numpy definition's arithmetic, term by term."""
    cdef Py_ssize_t c, t, e, count = start.shape[0], at
    cdef double r0, r1, o0, o1, denominator, on_ray, on_edge, best
    cdef bint crosses
    for c in range(positions.shape[0]):
        at = positions[c]
        for t in range(turns.shape[0]):
            r0 = -fma(turns[t, 0, 0], normals[c, 0], turns[t, 0, 1] * normals[c, 1])
            r1 = -fma(turns[t, 1, 0], normals[c, 0], turns[t, 1, 1] * normals[c, 1])
            best = INFINITY
            nearest[c, t] = 0
            hit[c, t] = 0
            for e in range(count):
                o0 = start[e, 0] - start[at, 0]
                o1 = start[e, 1] - start[at, 1]
                denominator = r0 * edge[e, 1] - r1 * edge[e, 0]
                on_ray = (o0 * edge[e, 1] - o1 * edge[e, 0]) / denominator
                on_edge = (o0 * r1 - o1 * r0) / denominator
                crosses = (fabs(denominator) > 1e-12 and on_ray > 1e-9 and on_edge >= 0 and on_edge <= 1
                           and e != at and (e + 1) % count != at)
                if e == 0 or (crosses and on_ray < best):
                    if crosses and on_ray < best:
                        best = on_ray
                    nearest[c, t] = e
                    along[c, t] = on_edge
                    hit[c, t] = crosses


# ==== end of split2's kernels ===================================================================


# ==== necks (issue 23 item 2): one object's distance transform and its peaks ======================

def distance_peaks(const unsigned char[:, ::1] mask, long long[:, ::1] out):
    """The squared Euclidean distance transform of a mask (``out[i, j]``: the squared distance
    from pixel (i, j) to the nearest pixel where ``mask`` is 0, 0 there; pixels beyond the
    array's edge do not count, as in ``scipy.ndimage.distance_transform_edt``, whose values are
    its square roots), and the number of 4-connected pieces of its peaks: the pixels of the mask
    not below any of their 8 neighbours (the array's edge repeated, as in
    ``scipy.ndimage.maximum_filter(size=3)`` with its default mode).  The mask must hold a 0.

    Separable and exact: per column the distance g to the nearest 0 in it (two passes down the
    rows, row by row), then per row the lower envelope of the parabolas ``(j - q)^2 + g_q^2``
    over the columns q (:func:`_lower_envelope`).
    O(pixels); the peaks' pieces by a flood fill over the peaks alone."""
    cdef Py_ssize_t m = mask.shape[0], n = mask.shape[1], i, j, k, last, di, dj
    cdef Py_ssize_t pieces = 0
    cdef long long far = m + 1, value
    cdef bint peak
    cdef Py_ssize_t *vertex = <Py_ssize_t *> malloc(max(n, 1) * sizeof(Py_ssize_t))
    cdef long long *height = <long long *> malloc(max(n, 1) * sizeof(long long))
    cdef unsigned char *flag = <unsigned char *> calloc(max(m * n, 1), sizeof(unsigned char))
    if vertex == NULL or height == NULL or flag == NULL:
        free(vertex)
        free(height)
        free(flag)
        raise MemoryError()
    with nogil:
        for i in range(m):
            for j in range(n):
                if mask[i, j] == 0:
                    out[i, j] = 0
                else:
                    out[i, j] = out[i - 1, j] + 1 if i > 0 and out[i - 1, j] < far else far
        for i in range(m - 2, -1, -1):
            for j in range(n):
                if out[i + 1, j] + 1 < out[i, j]:
                    out[i, j] = out[i + 1, j] + 1
        for i in range(m):
            k = _lower_envelope(&out[i, 0], n, 1, far, vertex, height)
            last = 0
            for j in range(n):
                out[i, j] = _envelope_at(vertex, height, k, &last, j)
        # the peaks (flag 1), then their pieces (a piece's pixels flagged 2 as the fill reaches them)
        for i in range(m):
            for j in range(n):
                if mask[i, j] == 0:
                    continue
                value = out[i, j]
                peak = True
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        if out[_clamp(i + di, m), _clamp(j + dj, n)] > value:
                            peak = False
                if peak:
                    flag[i * n + j] = 1
        pieces = _pieces(flag, m, n)
    free(vertex)
    free(height)
    free(flag)
    if pieces < 0:
        raise MemoryError()
    return pieces


cdef Py_ssize_t _pieces(unsigned char *flag, Py_ssize_t m, Py_ssize_t n) noexcept nogil:
    """The number of 4-connected pieces of the pixels flagged 1 in an m x n array (row-major),
    each flagged 2 as a flood fill reaches it (as ``scipy.ndimage.label``'s count with its default
    structure); -1 when memory runs out."""
    cdef Py_ssize_t at, size, capacity = 1024, pieces = 0, p, i, j, k, di, dj
    cdef Py_ssize_t *stack = <Py_ssize_t *> malloc(capacity * sizeof(Py_ssize_t))
    cdef Py_ssize_t *grown
    if stack == NULL:
        return -1
    for at in range(m * n):
        if flag[at] != 1:
            continue
        pieces += 1
        flag[at] = 2
        stack[0] = at
        size = 1
        while size > 0:
            size -= 1
            p = stack[size]
            i, j = p // n, p % n
            for k in range(4):
                di = (k == 1) - (k == 0)
                dj = (k == 3) - (k == 2)
                if not (0 <= i + di < m and 0 <= j + dj < n) or flag[(i + di) * n + j + dj] != 1:
                    continue
                flag[(i + di) * n + j + dj] = 2
                if size == capacity:
                    capacity *= 2
                    grown = <Py_ssize_t *> realloc(stack, capacity * sizeof(Py_ssize_t))
                    if grown == NULL:
                        free(stack)
                        return -1
                    stack = grown
                stack[size] = (i + di) * n + j + dj
                size += 1
    free(stack)
    return pieces


def h_maxima_pieces(const double[:, ::1] image, const double[:, ::1] shifted, double h):
    """The number of 4-connected pieces of ``skimage.morphology.h_maxima(image, h)`` where it
    reconstructs (``scipy.ndimage.label``'s count, default structure), given its marker
    ``shifted`` (``image - h - resolution``, computed as it computes it, at most ``image``): the
    pixels whose residue ``image - rec`` is at least ``h``, ``rec`` the grey reconstruction by
    dilation of ``shifted`` under ``image`` with the 3 x 3 footprint
    (``skimage.morphology.reconstruction``'s default).

    The reconstruction is a lattice operation (each value the largest over paths of 8-neighbours
    of the least of the marker at the path's start and the image along it: every value one of
    the inputs'), so any exact algorithm gives skimage's values to the last bit: Vincent's hybrid
    one (IEEE Trans. Image Process. 2(2), 1993), a raster and an anti-raster scan, then a queue
    of the pixels still to raise.  O(pixels) for a distance transform, with no sort."""
    cdef Py_ssize_t m = image.shape[0], n = image.shape[1], i, j, di, dj, p, q, pieces = 0
    cdef _Queue queue
    cdef double value, best
    cdef bint later
    cdef double *rec = <double *> malloc(max(m * n, 1) * sizeof(double))
    cdef unsigned char *flag = <unsigned char *> calloc(max(m * n, 1), sizeof(unsigned char))
    queue.head, queue.tail, queue.capacity = 0, 0, 1024
    queue.items = <Py_ssize_t *> malloc(queue.capacity * sizeof(Py_ssize_t))
    if rec == NULL or flag == NULL or queue.items == NULL:
        free(rec)
        free(flag)
        free(queue.items)
        raise MemoryError()
    with nogil:
        # raster scan: each pixel raised to its neighbours before it, up to the image
        for i in range(m):
            for j in range(n):
                best = shifted[i, j]
                for di in range(-1, 1):
                    for dj in range(-1, 2):
                        if (di == 0 and dj >= 0) or i + di < 0 or not 0 <= j + dj < n:
                            continue
                        if rec[(i + di) * n + j + dj] > best:
                            best = rec[(i + di) * n + j + dj]
                rec[i * n + j] = best if best < image[i, j] else image[i, j]
        # anti-raster scan: the same with the neighbours after it; a pixel that may still raise
        # one of those is queued
        for i in range(m - 1, -1, -1):
            for j in range(n - 1, -1, -1):
                best = rec[i * n + j]
                for di in range(0, 2):
                    for dj in range(-1, 2):
                        if (di == 0 and dj <= 0) or i + di >= m or not 0 <= j + dj < n:
                            continue
                        if rec[(i + di) * n + j + dj] > best:
                            best = rec[(i + di) * n + j + dj]
                value = best if best < image[i, j] else image[i, j]
                rec[i * n + j] = value
                later = False
                for di in range(0, 2):
                    for dj in range(-1, 2):
                        if (di == 0 and dj <= 0) or i + di >= m or not 0 <= j + dj < n:
                            continue
                        q = (i + di) * n + j + dj
                        if rec[q] < value and rec[q] < image[i + di, j + dj]:
                            later = True
                if later and not _enqueue(&queue, i * n + j):
                    pieces = -1
                    break
            if pieces < 0:
                break
        # propagation: a queued pixel raises each neighbour below it and below the image
        while pieces >= 0 and queue.head < queue.tail:
            p = queue.items[queue.head]
            queue.head += 1
            i, j = p // n, p % n
            value = rec[p]
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if (di == 0 and dj == 0) or not (0 <= i + di < m and 0 <= j + dj < n):
                        continue
                    q = (i + di) * n + j + dj
                    if rec[q] < value and rec[q] != image[i + di, j + dj]:
                        rec[q] = value if value < image[i + di, j + dj] else image[i + di, j + dj]
                        if not _enqueue(&queue, q):
                            pieces = -1
                            break
                if pieces < 0:
                    break
        if pieces >= 0:
            for i in range(m):
                for j in range(n):
                    if image[i, j] - rec[i * n + j] >= h:
                        flag[i * n + j] = 1
            pieces = _pieces(flag, m, n)
    free(rec)
    free(flag)
    free(queue.items)
    if pieces < 0:
        raise MemoryError()
    return pieces


cdef struct _Queue:
    Py_ssize_t *items
    Py_ssize_t head, tail, capacity


cdef bint _enqueue(_Queue *queue, Py_ssize_t item) noexcept nogil:
    """Append to a first-in first-out queue (its live part moved to the front, or the array
    doubled, when the end is reached); False when memory runs out."""
    cdef Py_ssize_t count
    cdef Py_ssize_t *grown
    if queue.tail == queue.capacity:
        count = queue.tail - queue.head
        if count < queue.capacity // 2:
            memmove(queue.items, queue.items + queue.head, count * sizeof(Py_ssize_t))
        else:
            grown = <Py_ssize_t *> realloc(queue.items, 2 * queue.capacity * sizeof(Py_ssize_t))
            if grown == NULL:
                return False
            queue.items, queue.capacity = grown, 2 * queue.capacity
            memmove(queue.items, queue.items + queue.head, count * sizeof(Py_ssize_t))
        queue.head, queue.tail = 0, count
    queue.items[queue.tail] = item
    queue.tail += 1
    return True


def fill_holes(unsigned char[:, ::1] mask):
    """Fill the holes of a mask whose edge rows and columns are 0, in place: every 0 pixel that
    no path of 4-neighbours through 0 pixels joins to pixel (0, 0) becomes 1, as
    ``scipy.ndimage.binary_fill_holes`` with its default structure (on the mask without its
    frame: the frame joins every 0 pixel on the inner edge).  One flood fill over the 0 pixels
    reached, then one pass."""
    cdef Py_ssize_t m = mask.shape[0], n = mask.shape[1], i, j, k, p, size = 1, capacity = 4096
    cdef Py_ssize_t *stack = <Py_ssize_t *> malloc(capacity * sizeof(Py_ssize_t))
    cdef Py_ssize_t *grown
    cdef bint failed = False
    if stack == NULL:
        raise MemoryError()
    if m == 0 or n == 0:
        free(stack)
        return
    with nogil:
        # reached 0 pixels become 2 as they are pushed
        mask[0, 0] = 2
        stack[0] = 0
        while size > 0 and not failed:
            size -= 1
            p = stack[size]
            i, j = p // n, p % n
            for k in range(4):
                if k == 0:
                    if i == 0:
                        continue
                    p = (i - 1) * n + j
                elif k == 1:
                    if i == m - 1:
                        continue
                    p = (i + 1) * n + j
                elif k == 2:
                    if j == 0:
                        continue
                    p = i * n + j - 1
                else:
                    if j == n - 1:
                        continue
                    p = i * n + j + 1
                if mask[p // n, p % n] != 0:
                    continue
                mask[p // n, p % n] = 2
                if size == capacity:
                    capacity *= 2
                    grown = <Py_ssize_t *> realloc(stack, capacity * sizeof(Py_ssize_t))
                    if grown == NULL:
                        failed = True
                        break
                    stack = grown
                stack[size] = p
                size += 1
        for i in range(m):
            for j in range(n):
                mask[i, j] = 0 if mask[i, j] == 2 else 1
    free(stack)
    if failed:
        raise MemoryError()
