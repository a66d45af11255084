# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""The compiled inner loops, built ahead of time at install (no compile on first use).

One implementation of each loop; the Python modules that own the mathematics call them:

* :func:`build_tables`, :func:`edge_integrals` -- :mod:`activecontour.image`, :mod:`activecontour.energy`
  (the row-antiderivative tables and the exact integrals along the edges, (6.38) and (6.41));
* :func:`cyclic_thomas` -- :mod:`activecontour.fem` (the block-cyclic tridiagonal solve of (6.40));
* :func:`crossings`, :func:`winding` -- :mod:`activecontour.topology`.

Arrays come in as typed memoryviews (the buffer protocol), so the build needs no numpy headers.
Loops over a whole image poll for Ctrl-C every few hundred rows.
"""

from cpython.exc cimport PyErr_CheckSignals
from libc.math cimport ceil, floor, sqrt
from libc.stdlib cimport calloc, free, malloc

#: rows between two stored rows of the antiderivative tables (see :func:`build_tables`)
ANCHOR_ROWS = 8
cdef Py_ssize_t _ANCHOR = 8
cdef Py_ssize_t _POLL_ROWS = 256


cdef inline Py_ssize_t _clamp(Py_ssize_t i, Py_ssize_t size) noexcept nogil:
    if i < 0:
        return 0
    if i >= size:
        return size - 1
    return i


cdef inline double _padded(const double[:, :, ::1] values, Py_ssize_t a, Py_ssize_t j,
                           Py_ssize_t ch) noexcept nogil:
    """The image padded by one replicated pixel, at padded (row, col) = (a, j)."""
    return values[_clamp(a - 1, values.shape[0]), _clamp(j - 1, values.shape[1]), ch]


def build_tables(const double[:, :, ::1] values, double[:, :, :, ::1] table, double[::1] total1,
                 double[::1] total2):
    """One pass over the image: the row-antiderivative tables and the domain totals.

    In padded coordinates ``(u, v) = (r + 1, c + 1)`` (the image padded by one replicated pixel,
    P), the exact integrals along the column profiles, which are piecewise linear in u, are

        t1[a, j] = int_0^a P(s, j) ds,  t2[a, j] = int_0^a P(s, j)^2 ds,
        t3[a, j] = int_0^a P(s, j) P(s, j + 1) ds.

    Only every ``ANCHOR_ROWS``-th row ``a = k ANCHOR_ROWS`` is stored, ``table[k, j, ch] = (t1, t2,
    t3)``; :func:`edge_integrals` adds the few increments from there to the row it needs, from the
    image itself.  That keeps the tables at 3/8 of a float64 per pixel and channel, in float64:
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
    cdef double p_lo, p_hi, q_lo, q_hi, diagonal, same, following
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
                for j in range(width):
                    c_lo = _clamp(j - 1, n) * channels
                    c_hi = _clamp(j, n) * channels  # the right neighbour j + 1 in padded columns
                    for ch in range(channels):
                        p_lo, p_hi = lo[c_lo + ch], hi[c_lo + ch]
                        q_lo, q_hi = lo[c_hi + ch], hi[c_hi + ch]
                        index = (j * channels + ch) * 3
                        acc[index] += 0.5 * (p_lo + p_hi)
                        acc[index + 1] += (p_lo * p_lo + p_lo * p_hi + p_hi * p_hi) / 3.0
                        acc[index + 2] += (2.0 * p_lo * q_lo + p_lo * q_hi + p_hi * q_lo
                                           + 2.0 * p_hi * q_hi) / 6.0
            if (a + 1) % _ANCHOR == 0:
                for j in range(width):
                    for ch in range(channels):
                        for index in range(3):
                            table[(a + 1) // _ANCHOR, j, ch, index] = acc[(j * channels + ch) * 3 + index]
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
    # interpolation cell [a, a + 1] x [j, j + 1]: corner values, and the antiderivatives at row a
    double p0, q0, dp, dq
    double t1, t2, t3   # column j
    double r1, r2       # column j + 1


cdef inline void _cell(const double[:, :, ::1] values, const double[:, :, :, ::1] table,
                       Py_ssize_t a, Py_ssize_t j, Py_ssize_t ch, Cell *cell) noexcept nogil:
    """The cell's data: the stored row below a, plus the increments from there up to a."""
    cdef Py_ssize_t k = a // _ANCHOR, i
    cdef double p_lo, q_lo, p_hi, q_hi
    cell.t1 = table[k, j, ch, 0]
    cell.t2 = table[k, j, ch, 1]
    cell.t3 = table[k, j, ch, 2]
    cell.r1 = table[k, j + 1, ch, 0]
    cell.r2 = table[k, j + 1, ch, 1]
    p_lo = _padded(values, k * _ANCHOR, j, ch)
    q_lo = _padded(values, k * _ANCHOR, j + 1, ch)
    for i in range(k * _ANCHOR, a):
        p_hi = _padded(values, i + 1, j, ch)
        q_hi = _padded(values, i + 1, j + 1, ch)
        cell.t1 += 0.5 * (p_lo + p_hi)
        cell.t2 += (p_lo * p_lo + p_lo * p_hi + p_hi * p_hi) / 3.0
        cell.t3 += (2.0 * p_lo * q_lo + p_lo * q_hi + p_hi * q_lo + 2.0 * p_hi * q_hi) / 6.0
        cell.r1 += 0.5 * (q_lo + q_hi)
        cell.r2 += (q_lo * q_lo + q_lo * q_hi + q_hi * q_hi) / 3.0
        p_lo, q_lo = p_hi, q_hi
    cell.p0, cell.q0 = p_lo, q_lo
    cell.dp = _padded(values, a + 1, j, ch) - p_lo
    cell.dq = _padded(values, a + 1, j + 1, ch) - q_lo


def edge_integrals(const double[:, ::1] points, const Py_ssize_t[::1] next_index,
                   const double[:, :, ::1] values, const double[:, :, :, ::1] table, int stage,
                   const double[::1] linear, const double[::1] square, double constant, double mu,
                   double[::1] s1, double[::1] s2, double[::1] sums, double[:, ::1] load):
    """Exact integrals along every edge, split where it crosses a grid line.

    ``stage`` 0 accumulates the moments ``closed integral of G dc`` into s1, s2 and the signed area
    and length into ``sums``; stage 1 adds the load (6.41) into ``load``, for the integrand
    ``g(I) = constant + sum_ch (linear[ch] I_ch + square[ch] I_ch^2)``: the difference of the
    quadratic forms of the regions on the two sides of the curve
    (:class:`activecontour.models.base.QuadraticForm`), inside minus outside.  Each piece between grid
    lines lies in one interpolation cell [a, a + 1] x [j, j + 1], read once: there, with local
    coordinates (t, w), I is bilinear and its row-antiderivatives are the table values at row a
    plus the exact integral from a to u, so the integrands are polynomials of degree <= 5 in the
    edge parameter and 3-point Gauss-Legendre is exact.
    """
    cdef Py_ssize_t channels = values.shape[2], rows = values.shape[0], cols = values.shape[1]
    cdef Py_ssize_t e, b, ch, g, a, j, count = points.shape[0]
    cdef double nodes[3]
    cdef double weights[3]
    cdef double density[3]
    cdef double u0, v0, du, dv, k_u, k_v, at_start, at_end, t_prev, t_u, t_v, t_next, span, t_mid
    cdef double t_edge, t, w, w0, intensity, half, third, g1, g2, b_pp, b_qq, b_pq, weight, length
    cdef double tangent_r, tangent_c, step_u, step_v
    cdef Cell cell
    nodes[0], nodes[1], nodes[2] = 0.5 - 0.5 * sqrt(0.6), 0.5, 0.5 + 0.5 * sqrt(0.6)
    weights[0], weights[1], weights[2] = 5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0
    with nogil:
        for e in range(count):
            b = next_index[e]
            u0, v0 = points[e, 0] + 1.0, points[e, 1] + 1.0
            du, dv = points[b, 0] + 1.0 - u0, points[b, 1] + 1.0 - v0
            # next grid lines in the direction of travel
            step_u = 1.0 if du > 0 else -1.0
            step_v = 1.0 if dv > 0 else -1.0
            k_u = floor(u0) + 1.0 if du > 0 else ceil(u0) - 1.0
            k_v = floor(v0) + 1.0 if dv > 0 else ceil(v0) - 1.0
            at_start, at_end = 0.0, 0.0
            t_prev = 0.0
            while True:
                t_u = (k_u - u0) / du if du != 0.0 else 2.0
                t_v = (k_v - v0) / dv if dv != 0.0 else 2.0
                t_next = min(t_u, t_v, 1.0)
                span = t_next - t_prev
                if span > 0.0:
                    t_mid = t_prev + 0.5 * span
                    a = <Py_ssize_t> min(max(floor(u0 + t_mid * du), 0.0), <double> rows)
                    j = <Py_ssize_t> min(max(floor(v0 + t_mid * dv), 0.0), <double> cols)
                    density[0] = constant
                    density[1] = constant
                    density[2] = constant
                    for ch in range(channels):
                        _cell(values, table, a, j, ch, &cell)
                        for g in range(3):
                            t_edge = t_prev + span * nodes[g]
                            t = u0 + t_edge * du - a
                            w = v0 + t_edge * dv - j
                            w0 = 1.0 - w
                            if stage == 0:
                                half, third = 0.5 * t * t, t * t * t / 3.0
                                g1 = (w0 * (cell.t1 + t * cell.p0 + half * cell.dp)
                                      + w * (cell.r1 + t * cell.q0 + half * cell.dq))
                                b_pp = (cell.t2 + cell.p0 * cell.p0 * t + 2.0 * cell.p0 * cell.dp * half
                                        + cell.dp * cell.dp * third)
                                b_qq = (cell.r2 + cell.q0 * cell.q0 * t + 2.0 * cell.q0 * cell.dq * half
                                        + cell.dq * cell.dq * third)
                                b_pq = (cell.t3 + cell.p0 * cell.q0 * t
                                        + (cell.p0 * cell.dq + cell.q0 * cell.dp) * half
                                        + cell.dp * cell.dq * third)
                                g2 = w0 * w0 * b_pp + 2.0 * w * w0 * b_pq + w * w * b_qq
                                weight = span * weights[g] * dv
                                s1[ch] += weight * g1
                                s2[ch] += weight * g2
                            else:
                                intensity = w0 * (cell.p0 + t * cell.dp) + w * (cell.q0 + t * cell.dq)
                                density[g] += (linear[ch] + square[ch] * intensity) * intensity
                    if stage == 1:
                        for g in range(3):
                            t_edge = t_prev + span * nodes[g]
                            weight = span * weights[g] * density[g]
                            at_start += weight * (1.0 - t_edge)
                            at_end += weight * t_edge
                if t_next >= 1.0:
                    break
                if t_u <= t_next:
                    k_u += step_u
                if t_v <= t_next:
                    k_v += step_v
                t_prev = t_next
            length = sqrt(du * du + dv * dv)
            if stage == 0:
                sums[0] += 0.5 * ((u0 - 1.0) * (v0 - 1.0 + dv) - (u0 - 1.0 + du) * (v0 - 1.0))
                sums[1] += length
            else:
                # nu |e| = (dv, -du): the edge normal (section 4.5.2) times its length
                tangent_r = du / length if length > 0.0 else 0.0
                tangent_c = dv / length if length > 0.0 else 0.0
                load[e, 0] += at_start * dv - mu * tangent_r
                load[e, 1] += -at_start * du - mu * tangent_c
                load[b, 0] += at_end * dv + mu * tangent_r
                load[b, 1] += -at_end * du + mu * tangent_c


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


cdef inline Py_ssize_t _slot(long long key, long long *keys, Py_ssize_t mask, int shift) noexcept nogil:
    """Open-addressing slot of ``key`` (its own, or the empty one where it would go): Fibonacci
    hashing, the top bits of key times 2^64 / golden ratio."""
    cdef Py_ssize_t slot = <Py_ssize_t> ((<unsigned long long> key * 11400714819323198485ULL) >> shift)
    while keys[slot] != key and keys[slot] != -1:
        slot = (slot + 1) & mask
    return slot


def crossings(const double[:, ::1] points, const Py_ssize_t[::1] next_index):
    """Pairs of non-adjacent crossing edges as a list of ``(e, other, s, t)``, ``e < other``.

    Spatial hashing: every edge is filed, in a linked list per cell, under the cell of its
    bounding box's low corner.  Cells are as large as the largest edge extent, so edges whose boxes
    overlap sit in the same or neighbouring cells; only those pairs are tested.  The occupied cells
    live in a hash table of about 2 K slots, so a long curve on a large image still costs O(K), not
    O(K * edges per cell of a fixed grid).
    """
    cdef Py_ssize_t n = points.shape[0], e, b, k, f, other, c, d, slot, mask, size = 1
    cdef int shift = 64
    cdef long long cell_row, cell_col, key
    cdef double cell = 1e-9, origin_r, origin_c, r0, r1, u0, u1, q0, q1, denominator, s, t
    found = []
    if n < 4:
        return found
    while size < 2 * n:
        size *= 2
        shift -= 1
    mask = size - 1
    cdef long long *keys = <long long *> malloc(size * sizeof(long long))
    cdef Py_ssize_t *head = <Py_ssize_t *> malloc(size * sizeof(Py_ssize_t))
    cdef Py_ssize_t *following = <Py_ssize_t *> malloc(n * sizeof(Py_ssize_t))
    cdef long long *row = <long long *> malloc(n * sizeof(long long))
    cdef long long *column = <long long *> malloc(n * sizeof(long long))
    try:
        if keys == NULL or head == NULL or following == NULL or row == NULL or column == NULL:
            raise MemoryError()
        origin_r, origin_c = points[0, 0], points[0, 1]
        for e in range(n):
            b = next_index[e]
            origin_r, origin_c = min(origin_r, points[e, 0]), min(origin_c, points[e, 1])
            for k in range(2):
                cell = max(cell, abs(points[b, k] - points[e, k]))
        cell *= 1.0001
        for slot in range(size):
            keys[slot] = -1
        with nogil:
            for e in range(n):
                b = next_index[e]
                row[e] = <long long> ((min(points[e, 0], points[b, 0]) - origin_r) / cell)
                column[e] = <long long> ((min(points[e, 1], points[b, 1]) - origin_c) / cell)
                key = row[e] * 4294967296LL + column[e]
                slot = _slot(key, keys, mask, shift)
                if keys[slot] == -1:
                    keys[slot] = key
                    head[slot] = -1
                following[e] = head[slot]
                head[slot] = e
        for e in range(n):
            b = next_index[e]
            r0, r1 = points[b, 0] - points[e, 0], points[b, 1] - points[e, 1]
            for cell_row in range(row[e] - 1, row[e] + 2):
                for cell_col in range(column[e] - 1, column[e] + 2):
                    if cell_row < 0 or cell_col < 0:
                        continue
                    slot = _slot(cell_row * 4294967296LL + cell_col, keys, mask, shift)
                    f = head[slot] if keys[slot] != -1 else -1
                    while f >= 0:
                        other = f
                        f = following[f]
                        if other <= e or next_index[e] == other or next_index[other] == e:
                            continue
                        c, d = other, next_index[other]
                        u0, u1 = points[d, 0] - points[c, 0], points[d, 1] - points[c, 1]
                        denominator = r0 * u1 - r1 * u0
                        if denominator == 0.0:
                            continue
                        q0, q1 = points[c, 0] - points[e, 0], points[c, 1] - points[e, 1]
                        s = (q0 * u1 - q1 * u0) / denominator
                        t = (q0 * r1 - q1 * r0) / denominator
                        if 0.0 < s < 1.0 and 0.0 < t < 1.0:
                            found.append((e, other, s, t))
    finally:
        free(keys)
        free(head)
        free(following)
        free(row)
        free(column)
    return found


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
                            if k < 0:
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
                      const double[:, :, :, ::1] table, double[:, ::1] moments, double[:, :, ::1] parts):
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
    times the segment's normal ``nu |e| = (dv, -du)``.  The pieces between grid lines and their
    quadrature are those of :func:`edge_integrals`; a cell's data is read once for consecutive
    pieces in it (along a segment, and from one segment to the next along a chain).  The sums over
    the segments are compensated (Neumaier): Green's integrals add terms of the size of the
    row-antiderivatives that cancel around a closed curve, and the compensation keeps the result
    independent of the segments' order to about one rounding.

    Returns the length of the segments that count in the functional's length term: the
    interfaces, and the image's edge where a region other than 0 lies on it.
    """
    cdef Py_ssize_t channels = values.shape[2], rows = values.shape[0], cols = values.shape[1]
    cdef Py_ssize_t e, ch, g, a, j, i, o, count = starts.shape[0], last_a = -1, last_j = -1
    cdef bint with_parts = parts.shape[0] > 0
    cdef double nodes[3]
    cdef double weights[3]
    cdef double u0, v0, du, dv, k_u, k_v, t_prev, t_u, t_v, t_next, span, t_mid, area, length = 0.0
    cdef double t_edge, t, w, w0, half, third, g1, g2, b_pp, b_qq, b_pq, weight, intensity
    cdef double *acc
    cdef double *carry
    cdef double length_carry = 0.0
    cdef Cell *cells
    cdef Cell *cell
    if moments.shape[1] != 1 + 2 * channels or (with_parts and (
            parts.shape[0] != count or parts.shape[1] != 2 or parts.shape[2] != 2 * channels)):
        raise ValueError("moments must be (K, 1 + 2C) and parts (S, 2, 2C) or empty")
    acc = <double *> malloc((2 * channels + 1) * sizeof(double))
    cells = <Cell *> malloc(channels * sizeof(Cell))
    carry = <double *> calloc(moments.shape[0] * moments.shape[1], sizeof(double))
    if acc == NULL or cells == NULL or carry == NULL:
        free(acc)
        free(cells)
        free(carry)
        raise MemoryError()
    nodes[0], nodes[1], nodes[2] = 0.5 - 0.5 * sqrt(0.6), 0.5, 0.5 + 0.5 * sqrt(0.6)
    weights[0], weights[1], weights[2] = 5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0
    with nogil:
        for e in range(count):
            u0, v0 = starts[e, 0] + 1.0, starts[e, 1] + 1.0
            du, dv = ends[e, 0] + 1.0 - u0, ends[e, 1] + 1.0 - v0
            for ch in range(2 * channels):
                acc[ch] = 0.0
                if with_parts:
                    parts[e, 0, ch] = 0.0
                    parts[e, 1, ch] = 0.0
            # next grid lines in the direction of travel
            k_u = floor(u0) + 1.0 if du > 0 else ceil(u0) - 1.0
            k_v = floor(v0) + 1.0 if dv > 0 else ceil(v0) - 1.0
            t_prev = 0.0
            while True:
                t_u = (k_u - u0) / du if du != 0.0 else 2.0
                t_v = (k_v - v0) / dv if dv != 0.0 else 2.0
                t_next = min(t_u, t_v, 1.0)
                span = t_next - t_prev
                if span > 0.0:
                    t_mid = t_prev + 0.5 * span
                    a = <Py_ssize_t> min(max(floor(u0 + t_mid * du), 0.0), <double> rows)
                    j = <Py_ssize_t> min(max(floor(v0 + t_mid * dv), 0.0), <double> cols)
                    if a != last_a or j != last_j:
                        for ch in range(channels):
                            _cell(values, table, a, j, ch, &cells[ch])
                        last_a, last_j = a, j
                    for ch in range(channels):
                        cell = &cells[ch]
                        for g in range(3):
                            t_edge = t_prev + span * nodes[g]
                            t = u0 + t_edge * du - a
                            w = v0 + t_edge * dv - j
                            w0 = 1.0 - w
                            half, third = 0.5 * t * t, t * t * t / 3.0
                            g1 = (w0 * (cell.t1 + t * cell.p0 + half * cell.dp)
                                  + w * (cell.r1 + t * cell.q0 + half * cell.dq))
                            b_pp = (cell.t2 + cell.p0 * cell.p0 * t + 2.0 * cell.p0 * cell.dp * half
                                    + cell.dp * cell.dp * third)
                            b_qq = (cell.r2 + cell.q0 * cell.q0 * t + 2.0 * cell.q0 * cell.dq * half
                                    + cell.dq * cell.dq * third)
                            b_pq = (cell.t3 + cell.p0 * cell.q0 * t
                                    + (cell.p0 * cell.dq + cell.q0 * cell.dp) * half
                                    + cell.dp * cell.dq * third)
                            g2 = w0 * w0 * b_pp + 2.0 * w * w0 * b_pq + w * w * b_qq
                            weight = span * weights[g]
                            acc[ch] += weight * dv * g1
                            acc[channels + ch] += weight * dv * g2
                            if with_parts:
                                intensity = w0 * (cell.p0 + t * cell.dp) + w * (cell.q0 + t * cell.dq)
                                parts[e, 0, ch] += weight * (1.0 - t_edge) * intensity
                                parts[e, 1, ch] += weight * t_edge * intensity
                                parts[e, 0, channels + ch] += weight * (1.0 - t_edge) * intensity * intensity
                                parts[e, 1, channels + ch] += weight * t_edge * intensity * intensity
                if t_next >= 1.0:
                    break
                if t_u <= t_next:
                    k_u += 1.0 if du > 0 else -1.0
                if t_v <= t_next:
                    k_v += 1.0 if dv > 0 else -1.0
                t_prev = t_next
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
    free(cells)
    free(carry)
    return length + length_carry


def segments_meet(const double[:, ::1] nodes, const Py_ssize_t[::1] start, const Py_ssize_t[::1] end,
                  Py_ssize_t limit, Py_ssize_t[:, ::1] pairs):
    """The pairs of the segments ``nodes[start[s]] -> nodes[end[s]]`` that meet anywhere but at a
    node they share: a crossing, a touch (an end on another segment), or an overlap (collinear,
    also of two segments with a common node).  The segments of a planar network
    (:meth:`activecontour.backends.network.Network.simple`) meet only at their common nodes.

    Returns the number of pairs found, stopping at ``limit``; the first ``len(pairs)`` of them
    go into ``pairs`` (P, 2).

    A uniform grid of cells about the mean segment extent (at least what makes about one cell per
    segment): each segment is filed, by a counting sort, under every cell its bounding box meets,
    and only segments filed in the same cell are tested, each pair once, in the cell of the low
    corner of the intersection of their boxes.  O(S) for segments of even length.
    """
    cdef Py_ssize_t n = start.shape[0], s, k, i, f, e, cell, cells, rows, cols, r, c, r0, r1, c0, c1
    cdef Py_ssize_t row, col, position, shared, found = 0, capacity = pairs.shape[0]
    cdef double low_r, low_c, high_r, high_c, size, extent = 0.0
    cdef double ar, ac, br, bc, cr, cc, dr, dc, o1, o2, o3, o4, corner_r, corner_c
    cdef Py_ssize_t *first
    cdef Py_ssize_t *items
    cdef bint met
    if n < 2 or limit <= 0:
        return 0
    low_r, low_c = nodes[start[0], 0], nodes[start[0], 1]
    high_r, high_c = low_r, low_c
    for s in range(n):
        for k in range(2):
            i = start[s] if k == 0 else end[s]
            low_r, high_r = min(low_r, nodes[i, 0]), max(high_r, nodes[i, 0])
            low_c, high_c = min(low_c, nodes[i, 1]), max(high_c, nodes[i, 1])
        extent += max(abs(nodes[end[s], 0] - nodes[start[s], 0]), abs(nodes[end[s], 1] - nodes[start[s], 1]))
    size = max(extent / n, sqrt((high_r - low_r) * (high_c - low_c) / n), ((high_r - low_r) + (high_c - low_c)) / n)
    size = max(size, 1e-12 * max(1.0, max(abs(low_r), abs(high_r), abs(low_c), abs(high_c))))
    rows = <Py_ssize_t> ((high_r - low_r) / size) + 1
    cols = <Py_ssize_t> ((high_c - low_c) / size) + 1
    cells = rows * cols
    first = <Py_ssize_t *> calloc(cells + 1, sizeof(Py_ssize_t))
    if first == NULL:
        raise MemoryError()
    items = NULL
    with nogil:
        for k in range(2):  # count the entries of every cell (shifted by one), then file them
            if k == 1:
                for cell in range(cells):
                    first[cell + 1] += first[cell]
                items = <Py_ssize_t *> malloc(max(first[cells], 1) * sizeof(Py_ssize_t))
                if items == NULL:
                    break
            for s in range(n):
                ar, ac, br, bc = nodes[start[s], 0], nodes[start[s], 1], nodes[end[s], 0], nodes[end[s], 1]
                r0 = min(<Py_ssize_t> ((min(ar, br) - low_r) / size), rows - 1)
                r1 = min(<Py_ssize_t> ((max(ar, br) - low_r) / size), rows - 1)
                c0 = min(<Py_ssize_t> ((min(ac, bc) - low_c) / size), cols - 1)
                c1 = min(<Py_ssize_t> ((max(ac, bc) - low_c) / size), cols - 1)
                for r in range(r0, r1 + 1):
                    for c in range(c0, c1 + 1):
                        if k == 0:
                            first[r * cols + c + 1] += 1
                        else:
                            position = first[r * cols + c]
                            items[position] = s
                            first[r * cols + c] = position + 1
        if items != NULL:
            for cell in range(cells, 0, -1):  # first[c] ended as the next cell's start
                first[cell] = first[cell - 1]
            first[0] = 0
            for cell in range(cells):
                if found >= limit:
                    break
                row, col = cell // cols, cell % cols
                for i in range(first[cell], first[cell + 1]):
                    if found >= limit:
                        break
                    e = items[i]
                    ar, ac, br, bc = nodes[start[e], 0], nodes[start[e], 1], nodes[end[e], 0], nodes[end[e], 1]
                    for k in range(i + 1, first[cell + 1]):
                        f = items[k]
                        cr, cc, dr, dc = nodes[start[f], 0], nodes[start[f], 1], nodes[end[f], 0], nodes[end[f], 1]
                        # the boxes meet, and this is the cell of the low corner of their intersection
                        corner_r = max(min(ar, br), min(cr, dr))
                        corner_c = max(min(ac, bc), min(cc, dc))
                        if (corner_r > min(max(ar, br), max(cr, dr)) or corner_c > min(max(ac, bc), max(cc, dc))
                                or min(<Py_ssize_t> ((corner_r - low_r) / size), rows - 1) != row
                                or min(<Py_ssize_t> ((corner_c - low_c) / size), cols - 1) != col):
                            continue
                        met = False
                        shared = ((start[e] == start[f]) + (start[e] == end[f]) + (end[e] == start[f])
                                  + (end[e] == end[f]))
                        o1 = (br - ar) * (cc - ac) - (bc - ac) * (cr - ar)  # c, d against a -> b
                        o2 = (br - ar) * (dc - ac) - (bc - ac) * (dr - ar)
                        o3 = (dr - cr) * (ac - cc) - (dc - cc) * (ar - cr)  # a, b against c -> d
                        o4 = (dr - cr) * (bc - cc) - (dc - cc) * (br - cr)
                        if shared >= 2:  # the same two nodes: they coincide
                            met = True
                        elif shared == 1:
                            # meeting only at the common node unless collinear and on the same side
                            if o1 == 0.0 and o2 == 0.0 and (
                                    (start[e] == start[f] and (br - ar) * (dr - cr) + (bc - ac) * (dc - cc) > 0)
                                    or (end[e] == end[f] and (br - ar) * (dr - cr) + (bc - ac) * (dc - cc) > 0)
                                    or (start[e] == end[f] and (br - ar) * (dr - cr) + (bc - ac) * (dc - cc) < 0)
                                    or (end[e] == start[f] and (br - ar) * (dr - cr) + (bc - ac) * (dc - cc) < 0)):
                                met = True
                        elif ((o1 > 0.0 and o2 > 0.0) or (o1 < 0.0 and o2 < 0.0)
                              or (o3 > 0.0 and o4 > 0.0) or (o3 < 0.0 and o4 < 0.0)):
                            pass  # one lies wholly on one side of the other's line
                        elif o1 != 0.0 or o2 != 0.0 or o3 != 0.0 or o4 != 0.0:
                            met = True  # a crossing, or an end on the other segment (boxes meet)
                        else:  # collinear, boxes meet: they overlap or touch end to end
                            met = True
                        if met:
                            if found < capacity:
                                pairs[found, 0], pairs[found, 1] = e, f
                            found += 1
                            if found >= limit:
                                break
    free(first)
    if items == NULL:
        raise MemoryError()
    free(items)
    return found


def band_cholesky(double[:, ::1] band):
    """Cholesky factorisation ``A = U^T U`` of a symmetric positive definite band matrix, in place.

    ``band[j, w + i - j] = A[i, j]`` for ``j - w <= i <= j`` (column j's entries on and above the
    diagonal, w the half bandwidth) becomes U in the same layout.  O(n w^2), no fill outside the
    band.  Returns 0, or ``j + 1`` where the leading minor of order ``j + 1`` is not positive.
    """
    cdef Py_ssize_t n = band.shape[0], w = band.shape[1] - 1, i, j, k, first, failed = 0
    cdef double total
    with nogil:
        for j in range(n):
            first = j - w if j > w else 0
            for i in range(first, j + 1):
                total = band[j, w + i - j]
                for k in range(max(first, i - w), i):
                    total -= band[i, w + k - i] * band[j, w + k - j]
                if i < j:
                    band[j, w + i - j] = total / band[i, w]
                elif total > 0.0:
                    band[j, w] = sqrt(total)
                else:
                    failed = j + 1
                    break
            if failed:
                break
    return failed


def band_solve(const double[:, ::1] factor, double[::1] rhs):
    """Solve ``U^T U x = rhs`` in place with the factor of :func:`band_cholesky`."""
    cdef Py_ssize_t n = factor.shape[0], w = factor.shape[1] - 1, i, j, k
    cdef double total
    with nogil:
        for j in range(n):  # U^T y = rhs
            total = rhs[j]
            for k in range(j - w if j > w else 0, j):
                total -= factor[j, w + k - j] * rhs[k]
            rhs[j] = total / factor[j, w]
        for i in range(n - 1, -1, -1):  # U x = y
            total = rhs[i]
            for j in range(i + 1, min(n, i + w + 1)):
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
