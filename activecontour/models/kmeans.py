"""The global K-means of the intensities: the best K-level quantisation of a gray image.

Without its length term, the constant fit (6.42) of K regions is the K-means problem of the pixel
values: choose K levels and give every pixel the nearest one, minimising the sum of squares.  In
one dimension the optimal clusters are intervals of the sorted values, so dynamic programming over
a histogram finds the global optimum exactly (Wang and Song 2011, "Ckmeans.1d.dp"): with
``cost(i, j)`` the sum of squares of the bins i..j about their mean (from prefix sums),

    D[k, j] = min_i  D[k - 1, i - 1] + cost(i, j),

in O(K B^2) for B bins (vectorised: one B x B matrix per k).  This is multi-Otsu's criterion
(maximal between-class variance is minimal within-class sum of squares) at a cost independent of
K's combinatorics: ``skimage.filters.threshold_multiotsu`` searches every threshold tuple, which
grows like B^(K-1).
"""

from __future__ import annotations

import numpy as np

__all__ = ["histogram_kmeans"]


def histogram_kmeans(values, n_classes, *, bins=256):
    """Thresholds and levels of the optimal K-means of ``values`` binned into ``bins`` bins.

    Parameters
    ----------
    values : ndarray
        Any shape; finite.
    n_classes : int
        K >= 1.
    bins : int
        Histogram bins over ``[min, max]``; every value of a bin goes to one class.

    Returns
    -------
    thresholds : ndarray (K - 1,)
        Increasing; class k holds the values in ``(thresholds[k - 1], thresholds[k]]``, i.e.
        ``np.digitize(values, thresholds, right=True)``.
    levels : ndarray (K,)
        The mean of each class (of the binned values' means).
    """
    values = np.asarray(values, dtype=np.float64).ravel()
    low, high = float(values.min()), float(values.max())
    if high <= low:
        return np.full(n_classes - 1, high), np.full(n_classes, high)
    width = (high - low) / bins
    index = np.minimum(((values - low) / width).astype(np.intp), bins - 1)
    count = np.bincount(index, minlength=bins).astype(np.float64)
    total = np.bincount(index, weights=values, minlength=bins)
    square = np.bincount(index, weights=values * values, minlength=bins)
    used = count > 0
    count, total, square = count[used], total[used], square[used]
    edges = low + width * (np.flatnonzero(used) + 1)  # upper edge of each used bin
    n = len(count)
    n_classes = min(n_classes, n)
    p_count = np.concatenate([[0.0], np.cumsum(count)])
    p_total = np.concatenate([[0.0], np.cumsum(total)])
    p_square = np.concatenate([[0.0], np.cumsum(square)])
    # cost[i, j]: bins i..j (inclusive) as one class; inf below the diagonal
    first, last = np.arange(n)[:, None], np.arange(n)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        weight = p_count[last + 1] - p_count[first]
        sums = p_total[last + 1] - p_total[first]
        cost = p_square[last + 1] - p_square[first] - sums * sums / weight
    cost = np.where(last >= first, np.maximum(cost, 0.0), np.inf)
    best = cost[0].copy()  # D[0, j]: bins 0..j in one class
    choice = np.zeros((n_classes, n), dtype=np.intp)
    for k in range(1, n_classes):
        # D[k, j] = min over i >= 1 of D[k - 1, i - 1] + cost[i, j]
        candidates = np.full((n, n), np.inf)
        candidates[1:] = best[:-1, None] + cost[1:]
        choice[k] = np.argmin(candidates, axis=0)
        best = candidates[choice[k], np.arange(n)]
    starts = np.zeros(n_classes, dtype=np.intp)
    j = n - 1
    for k in range(n_classes - 1, 0, -1):
        starts[k] = choice[k, j]
        j = starts[k] - 1
    stops = np.append(starts[1:], n)
    levels = np.array([(p_total[b] - p_total[a]) / (p_count[b] - p_count[a])
                       for a, b in zip(starts, stops, strict=True)])
    thresholds = edges[stops[:-1] - 1]
    return thresholds, levels
