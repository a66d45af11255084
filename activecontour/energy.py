"""The Chan-Vese functional (6.38), its optimal constants (6.42) and shape derivative (6.41).

For a set of closed polygons Gamma (outer boundaries positive, holes negative) enclosing Omega_i,

    J(Gamma, c_in, c_out) = mu |Gamma| + omega |Omega_i|
                            + lambda_in  int_{Omega_i} mean_ch (I - c_in)^2
                            + lambda_out int_{Omega_o} mean_ch (I - c_out)^2         (6.38)

with I the bilinear image of :class:`~activecontour.imaging.tables.ImageModel` (the mean over channels for
a vector-valued image: Chan-Sandberg-Vese's sum with weights 1/C, see
:meth:`ChanVeseParameters.weights`).  The region integrals expand into the moments
``int 1, int I, int I^2`` over Omega_i, which Green's theorem turns into boundary integrals of the
row-antiderivatives; the outside moments are the domain totals minus the inside ones.

The shape derivative in the direction of the P1 hat function phi_j (times a unit vector) is

    f_j = mu (K X)_j + int_Gamma [omega + lambda_in mean (I - c_in)^2 - lambda_out mean (I - c_out)^2]
                                 phi_j nu ds                                          (6.41)

where ``(K X)_j = tau_{j-1} - tau_j`` is the exact derivative of the polygon's length (the weak
form of kappa nu = -Laplace_Sigma id).  Every edge is split where it crosses a grid line; on each
piece the integrands are polynomials of degree <= 5 in the edge parameter, which 3-point
Gauss-Legendre integrates exactly.  So the energy is exact for the bilinear image and ``f`` is its
exact gradient: a finite-difference check agrees to rounding error.  With ``c`` at its optimum
(6.42), ``f`` is also the gradient of the reduced energy ``min_c J`` (the c-derivative vanishes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from activecontour import _kernels
from activecontour.geometry.curve import stack_curves

__all__ = [
    "Evaluation",
    "PartitionEvaluation",
    "energy_of_moments",
    "evaluate",
    "evaluate_partition",
    "partition_load",
    "partition_moments",
    "region_moments",
    "soup_moments",
    "stack_curves",
]

@dataclass
class Evaluation:
    """Energy (6.38) of a curve set, with the constants used and optionally the load (6.41)."""

    energy: float
    c_in: np.ndarray
    c_out: np.ndarray
    area: float
    length: float
    load: np.ndarray | None = None


_NO_PARTS = np.zeros((0, 2, 0))


def region_moments(model, curves):
    """``int_{Omega_i} 1``, ``int I`` and ``int I^2`` (per channel) for closed curves in (row, col).

    Exact for the bilinear image, by Green's theorem on the row-antiderivative tables.
    """
    points, next_index, _ = stack_curves([np.asarray(c, dtype=np.float64) for c in curves])
    area, _, s1, s2 = _moments(model, points, next_index)
    return area, s1, s2


def _moments(model, points, next_index, parts=None):
    """``(area, length, int I, int I^2)`` of stacked curves; with ``parts`` (K, 2, 2 + 2C), zeros,
    also the parts of the load in the same pass (:func:`activecontour._kernels.edge_integrals`)."""
    channels = model.n_channels
    s1, s2 = np.zeros(channels), np.zeros(channels)
    sums = np.zeros(2)  # area, length
    _kernels.edge_integrals(np.ascontiguousarray(points, dtype=np.float64),
                            np.ascontiguousarray(next_index, dtype=np.intp), model.values, model.table,
                            model.anchor, True, s1, s2, sums, _NO_PARTS if parts is None else parts)
    return sums[0], sums[1], s1, s2


def _load(parts, form, mu):
    """The load (6.41), (K, 2), of the integrand ``form`` and length weight ``mu`` from the parts
    of :func:`activecontour._kernels.edge_integrals`."""
    weights = np.concatenate([[mu, form.constant], form.linear, form.square])
    load = np.empty(parts.shape[:2])
    _kernels.combine_load(parts, weights, load)
    return load


def evaluate(model, points, next_index, params, *, gradient=False, empty_ok=False):
    """Energy (6.38) of stacked curves (see :func:`stack_curves`), and with ``gradient`` the load.

    Parameters
    ----------
    model : ImageModel
    points : ndarray (K, 2)
        Vertices in image (row, col) coordinates.
    next_index : ndarray (K,)
    params : ChanVeseParameters
    gradient : bool
        Also assemble ``load`` (K, 2), the derivative of J with respect to every vertex (6.41).
    empty_ok : bool
        How to treat curves that enclose no area or the whole domain while a constant is optimised
        (6.42 is then undefined).  A region smaller than ``EMPTY_FRACTION`` of the domain counts
        as empty: its mean (6.42) is a difference of domain-sized sums divided by its area, all
        rounding (a sliver of 1e-9 px^2 outside reports a c_out far outside the image's range).
        False (the flow's view): ``energy`` is ``inf``, so no step is accepted into that state.
        True (the value of a final result): the empty region's fitting term is 0 whatever its
        constant (at most its area times the image's range squared for a sliver), so J is
        finite, and the undefined constant is reported equal to the other one.

    Returns
    -------
    Evaluation
    """
    # one pass along the edges: the moments, and with the gradient the load's parts, which the
    # constants (6.42) from those moments then combine
    parts = np.zeros((len(points), 2, 2 + 2 * model.n_channels)) if gradient else None
    area, length, s1, s2 = _moments(model, points, next_index, parts)
    total_area, total1, total2 = model.totals
    constants = params.fit_constants(area, s1, s2, model.totals, empty_ok=empty_ok)
    if constants is None:
        nan = np.full(model.n_channels, np.nan)
        return Evaluation(np.inf, nan, nan, area, length, None)
    c_in, c_out = constants
    outside, inside = params.region_forms(c_in, c_out)
    energy = (params.mu * length + inside.integral(area, s1, s2)
              + outside.integral(total_area - area, total1 - s1, total2 - s2))
    result = Evaluation(float(energy), c_in, c_out, area, length)
    if gradient:
        result.load = _load(parts, inside - outside, float(params.mu))  # the integrand of (6.41)
    return result


@dataclass
class PartitionEvaluation:
    """Energy of a partition into K regions, with each region's constants, area and the length;
    ``first`` and ``second`` the regions' ``int I`` and ``int I^2`` (K, C)."""

    energy: float
    constants: np.ndarray
    areas: np.ndarray
    length: float
    parts: np.ndarray | None = None
    first: np.ndarray | None = None
    second: np.ndarray | None = None
    sums: np.ndarray | None = None


def partition_moments(model, boundary, n_classes, *, parts=False):
    """``int 1``, ``int I`` and ``int I^2`` over every region of a partition.

    One pass over the boundary segments (:func:`activecontour._kernels.segment_integrals`): each
    segment's Green integrals count for the region on its inner side and against the one on its
    outer side, so an interface between two regions is integrated once.

    Parameters
    ----------
    model : ImageModel
    boundary : activecontour.geometry.partition.Boundary
    n_classes : int
    parts : bool
        Also return the integrals along every segment that make the load (6.41) of any quadratic
        form (:func:`partition_load`), from the same pass.

    Returns
    -------
    areas : ndarray (K,)
    first, second : ndarray (K, C)
    parts : ndarray (S, 2, 2C)
        With ``parts`` only.
    """
    *moments, _, along, _ = _segment_integrals(model, boundary, n_classes, parts)
    return (*moments, along) if parts else tuple(moments)


#: No segment known (:func:`_segment_integrals`).
_UNKNOWN = (np.empty(0, dtype=np.intp), np.empty((0, 0)), np.empty((0, 2, 0)))


def _segment_integrals(model, boundary, n_classes, parts, known=None):
    """``(areas, first, second, counted length, parts or None, sums or None)`` of a partition's
    boundary in one pass (:func:`activecontour._kernels.segment_integrals`), the background's
    moments the domain's totals less the others' (as the two-region outside); ``known`` as for
    :func:`evaluate_partition`."""
    channels = model.n_channels
    if boundary.inner.size and max(boundary.inner.max(), boundary.outer.max()) >= n_classes:
        raise ValueError(f"a boundary between more than {n_classes} regions")
    starts, ends = np.ascontiguousarray(boundary.start), np.ascontiguousarray(boundary.end)
    moments = np.zeros((n_classes, 1 + 2 * channels))
    along = np.empty((len(starts) if parts else 0, 2, 2 * channels))
    sums = np.empty((len(starts) if parts else 0, 2 * channels))
    if known is None:
        index, known_sums, known_parts = _UNKNOWN
    else:
        index, earlier = known
        index, known_sums, known_parts = _indices(index), earlier.sums, earlier.parts
    length = _kernels.segment_integrals(starts, ends, _indices(boundary.inner), _indices(boundary.outer),
                                        model.values, model.table, model.anchor, moments, along, sums,
                                        index, known_sums, known_parts)
    areas, first, second = moments[:, 0], moments[:, 1:1 + channels], moments[:, 1 + channels:]
    total_area, total_first, total_second = model.totals
    areas[0] = total_area - areas[1:].sum()
    first[0] = total_first - first[1:].sum(axis=0)
    second[0] = total_second - second[1:].sum(axis=0)
    return areas, first, second, length, (along if parts else None), (sums if parts else None)


def _indices(labels):
    return np.ascontiguousarray(labels, dtype=np.intp)


def soup_moments(model, starts, ends):
    """``int 1``, ``int I``, ``int I^2`` (per channel) over the region that oriented segments
    (S, 2) bound, in any order (Green's theorem needs no chaining)."""
    points = np.empty((2 * len(starts), 2))
    points[0::2], points[1::2] = starts, ends
    next_index = np.repeat(np.arange(1, len(points), 2), 2)  # start -> end -> itself
    area, _, first, second = _moments(model, points, next_index)
    return area, first, second


def evaluate_partition(model, boundary, params, n_classes, constants=None, *, parts=False, known=None):
    """The N-region functional of a partition (:meth:`ChanVeseParameters.class_forms`).

    ``J = mu L + sum_k int_{Omega_k} g_k`` with L the length of the interfaces between regions,
    each counted once, plus the domain's edge where a region other than the background (0) lies
    on it: for two regions this is (6.38) of the contours of region 1 (:func:`evaluate`), which
    close along the image border there.  ``constants`` (K, C), by default the region means (6.42);
    an empty region's term is 0 whatever its constant, which is then the image mean.  With
    ``parts`` the evaluation keeps the segments' integrals of :func:`partition_moments` as
    ``parts``, for :func:`partition_load` at the same boundary, and their closed-integral terms as
    ``sums``.  ``known``: ``(index, earlier)``, an evaluation with ``parts`` of a boundary that
    shares segments with this one (the same ends in the same order), ``index[e]`` the row there
    of segment e (-1: none): those segments' integrals are taken from it, not computed again, and
    the result is the same as computed afresh, bit for bit.
    """
    areas, first, second, length, along, sums = _segment_integrals(model, boundary, n_classes, parts, known)
    evaluation = energy_of_moments(model, params, areas, first, second, length, constants)
    evaluation.parts, evaluation.sums = along, sums
    return evaluation


def energy_of_moments(model, params, areas, first, second, length, constants=None):
    """:func:`evaluate_partition` from the regions' moments and the counted length."""
    if constants is None:
        whole = params.region_constant(*model.totals)
        constants = np.array([params.region_constant(a, f, q) if a > 1e-9 else whole
                              for a, f, q in zip(areas, first, second, strict=True)])
    forms = params.class_forms(constants)
    energy = params.mu * length + sum(form.integral(a, f, q) for form, a, f, q
                                      in zip(forms, areas, first, second, strict=True))
    return PartitionEvaluation(float(energy), constants, areas, length, first=first, second=second)


def partition_load(model, boundary, params, constants, parts=None):
    """The derivative of the N-region functional (:func:`evaluate_partition`, constants fixed) with
    respect to both ends of every boundary segment, shape (S, 2, 2): ``[s, 0]`` the start's.

    On a segment between regions i (inner) and o (outer) the integrand of (6.41) is ``g_i - g_o``
    (``g_i`` alone on the image border); the length term is mu's on interfaces and on the border
    of regions other than the background.  A point shared by several segments (a junction) moves
    with the sum of their loads.  ``parts``: the segments' integrals of :func:`partition_moments`
    at this boundary, when the caller has them.
    """
    if parts is None:
        *_, parts = partition_moments(model, boundary, len(constants), parts=True)
    forms = params.class_forms(constants)
    # each region's (constant, linear, square)
    table = np.array([np.concatenate([[form.constant], form.linear, form.square]) for form in forms])
    # int phi (g_i - g_o) ds / |e| at each end (the constant's int phi = 1/2, the rest from the
    # parts) times the normal nu |e| = (dv, -du) (section 4.5.2), and mu times the unit tangent
    load = np.empty((len(parts), 2, 2))
    _kernels.segment_loads(np.ascontiguousarray(boundary.start), np.ascontiguousarray(boundary.end),
                           _indices(boundary.inner), _indices(boundary.outer), np.ascontiguousarray(parts),
                           table, float(params.mu), load)
    return load
