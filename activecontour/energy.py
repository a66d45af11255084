"""The Chan-Vese functional (6.38), its optimal constants (6.42) and shape derivative (6.41).

For a set of closed polygons Gamma (outer boundaries positive, holes negative) enclosing Omega_i,

    J(Gamma, c_in, c_out) = mu |Gamma| + omega |Omega_i|
                            + lambda_in  int_{Omega_i} mean_ch (I - c_in)^2
                            + lambda_out int_{Omega_o} mean_ch (I - c_out)^2         (6.38)

with I the bilinear image of :class:`~activecontour.image.ImageModel` (the mean over channels for
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
from activecontour.curve import as_curve, stack_curves
from activecontour.models import ChanVeseParameters
from activecontour.models.two_region import EMPTY_FRACTION, PARAMETER_LIMIT

__all__ = [
    "EMPTY_FRACTION",
    "PARAMETER_LIMIT",
    "ChanVeseParameters",
    "Evaluation",
    "PartitionEvaluation",
    "chan_vese_energy",
    "evaluate",
    "energy_of_moments",
    "evaluate_partition",
    "partition_load",
    "partition_moments",
    "region_moments",
    "soup_moments",
    "stack_curves",
    "to_frame",
    "working_frame",
]


def working_frame(values):
    """``(offset, scale)`` with ``(values - offset) / scale`` spanning [0, 1]; (0, 1) for values
    already within [0, 1] (every image ``normalize="range"`` gives, and integers by ``"dtype"``).

    A constant image gets scale 1.

    Raises
    ------
    ValueError
        For intensities (``normalize=None`` or float ``"dtype"``) whose span squared overflows:
        (6.38) of such intensities is not a float.
    """
    low, high = float(values.min()), float(values.max())
    if 0.0 <= low and high <= 1.0:
        return 0.0, 1.0
    with np.errstate(over="ignore"):
        span = high - low
        if not np.isfinite(span * span * values.shape[0] * values.shape[1]):
            raise ValueError(f"the image's intensities span {low:.3g}..{high:.3g}: (6.38) of them overflows; "
                             "pass normalize='range' (the default) to scale them to [0, 1]")
    return low, (span if span > 0 else 1.0)


def to_frame(values, offset, scale):
    """``(values - offset) / scale``: the image in the frame of :func:`working_frame`."""
    return values if offset == 0.0 and scale == 1.0 else (values - offset) / scale


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
    """Energy of a partition into K regions, with each region's constants, area and the length."""

    energy: float
    constants: np.ndarray
    areas: np.ndarray
    length: float


def partition_moments(model, boundary, n_classes):
    """``int 1``, ``int I`` and ``int I^2`` over every region of a partition.

    Parameters
    ----------
    model : ImageModel
    boundary : activecontour.partition.Boundary
    n_classes : int

    Returns
    -------
    areas : ndarray (K,)
    first, second : ndarray (K, C)
    """
    from activecontour.partition import class_soup

    areas = np.zeros(n_classes)
    first = np.zeros((n_classes, model.n_channels))
    second = np.zeros((n_classes, model.n_channels))
    for k in range(1, n_classes):
        areas[k], first[k], second[k] = soup_moments(model, *class_soup(boundary, k))
    # the background: the domain's totals minus the others (as the two-region outside)
    total_area, total_first, total_second = model.totals
    areas[0] = total_area - areas[1:].sum()
    first[0] = total_first - first[1:].sum(axis=0)
    second[0] = total_second - second[1:].sum(axis=0)
    return areas, first, second


def soup_moments(model, starts, ends):
    """``int 1``, ``int I``, ``int I^2`` (per channel) over the region that oriented segments
    (S, 2) bound, in any order (Green's theorem needs no chaining)."""
    points = np.empty((2 * len(starts), 2))
    points[0::2], points[1::2] = starts, ends
    next_index = np.repeat(np.arange(1, len(points), 2), 2)  # start -> end -> itself
    area, _, first, second = _moments(model, points, next_index)
    return area, first, second


def evaluate_partition(model, boundary, params, n_classes, constants=None):
    """The N-region functional of a partition (:meth:`ChanVeseParameters.class_forms`).

    ``J = mu L + sum_k int_{Omega_k} g_k`` with L the length of the interfaces between regions,
    each counted once, plus the domain's edge where a region other than the background (0) lies
    on it: for two regions this is (6.38) of the contours of region 1 (:func:`evaluate`), which
    close along the image border there.  ``constants`` (K, C), by default the region means (6.42);
    an empty region's term is 0 whatever its constant, which is then the image mean.
    """
    moments = partition_moments(model, boundary, n_classes)
    lengths = boundary.length
    counted = (boundary.outer >= 0) | (boundary.inner > 0)  # interfaces; the border outside region 0
    return energy_of_moments(model, params, *moments, float(lengths[counted].sum()), constants)


def energy_of_moments(model, params, areas, first, second, length, constants=None):
    """:func:`evaluate_partition` from the regions' moments and the counted length."""
    if constants is None:
        whole = params.region_constant(*model.totals)
        constants = np.array([params.region_constant(a, f, q) if a > 1e-9 else whole
                              for a, f, q in zip(areas, first, second, strict=True)])
    forms = params.class_forms(constants)
    energy = params.mu * length + sum(form.integral(a, f, q) for form, a, f, q
                                      in zip(forms, areas, first, second, strict=True))
    return PartitionEvaluation(float(energy), constants, areas, length)


def partition_load(model, boundary, params, constants):
    """The derivative of the N-region functional (:func:`evaluate_partition`, constants fixed) with
    respect to both ends of every boundary segment, shape (S, 2, 2): ``[s, 0]`` the start's.

    On a segment between regions i (inner) and o (outer) the integrand of (6.41) is ``g_i - g_o``
    (``g_i`` alone on the image border); the length term is mu's on interfaces and on the border
    of regions other than the background.  A point shared by several segments (a junction) moves
    with the sum of their loads.
    """
    forms = params.class_forms(constants)
    zero = forms[0] - forms[0]
    load = np.zeros((len(boundary.start), 2, 2))
    for inner, outer, chosen in boundary.sides.pairs:
        form = forms[inner] - (forms[outer] if outer >= 0 else zero)
        mu = params.mu if (outer >= 0 or inner > 0) else 0.0
        points = np.empty((2 * chosen.size, 2))
        points[0::2], points[1::2] = boundary.start[chosen], boundary.end[chosen]
        next_index = np.repeat(np.arange(1, len(points), 2), 2)
        parts = np.zeros((len(points), 2, 2 + 2 * model.n_channels))
        _moments(model, points, next_index, parts)
        out = _load(parts, form, float(mu))
        load[chosen, 0], load[chosen, 1] = out[0::2], out[1::2]
    return load


def chan_vese_energy(image, contours=None, *, classes=None, regions=None, mu="auto", omega=0.0, lambda_in=1.0,
                     lambda_out=1.0, c_in=None, c_out=None, color="gray", normalize="range",
                     light=None, noise="gaussian"):
    """Evaluate the Chan-Vese functional (6.38) of contours on an image: the common evaluator.

    Any backend's result can be scored the same way: pass ``result.contours`` (two regions) or
    ``classes=result.classes`` (a result with ``n_regions > 2``, whose class boundaries are those
    of its label image, see :mod:`activecontour.partition`).

    Parameters
    ----------
    image : ndarray (M, N) or (M, N, C)
    contours : list of ndarray (K, 2)
        Closed curves in (row, col), outer boundaries positive, holes negative.  An empty list is
        the empty set: J is then the outside term alone.
    classes : int ndarray (M, N), optional
        Instead of ``contours``: a label image, 0 = the background region, 1..K-1 the others.
        Scored as the partition of the domain it stands for (:mod:`activecontour.partition`:
        boundaries through the midpoints between pixels of different classes, junctions at cell
        centres) with the N-region functional of :func:`evaluate_partition`; for two classes it
        is (6.38) of the marching-squares contours of ``classes == 1``.
    regions : list of list of ndarray (K, 2), optional
        Instead of ``contours``: a sub-pixel partition, the closed curves of every region k
        (``result.class_contours`` of a result with ``n_regions > 2``), region 0 the background.
        The regions must tile the image domain; scored with the N-region functional of
        :func:`evaluate_partition` (each interface once, the border outside region 0).
    mu, omega, lambda_in, lambda_out : float
        Weights of (6.38); ``mu="auto"`` as in :func:`activecontour.segment` (``result.mu`` is the
        value a result used).
    c_in, c_out : float, optional
        Fixed constants, in normalised units; by default the optimal ones (6.42).
    color : {"gray", "vector"}
    normalize : {"range", "dtype", None}
        As in :func:`activecontour.segment`: pass the same choices to score a result.
    light : ndarray (M, N), optional
        The light field b of the smooth fit (``result.light`` of ``fit="smooth"``): region k's
        intensity is ``c_k b`` (:mod:`activecontour.models.smooth`).  None: the constant fit.
    noise : {"gaussian", "poisson"}
        The fit term, as in :func:`activecontour.segment`.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For a contour that is not a closed curve (see :func:`activecontour.curve.as_curve`) or has
        a vertex outside the image domain ``[-0.5, M - 0.5] x [-0.5, N - 0.5]``, and for contours
        that cross themselves or each other, overlap, repeat a curve, or are oriented against
        their nesting (:func:`activecontour.topology.region_problem`): they bound no region, and
        (6.38) is not defined.  :func:`activecontour.topology.region_union` turns such curves
        into the boundary of the region they outline.
    """
    from activecontour.image import normalize_image
    from activecontour.models import noise_model
    from activecontour.noise import auto_mu, is_auto

    values = normalize_image(image, color=color, normalize=normalize)
    offset, scale = working_frame(values)
    values = to_frame(values, offset, scale)
    params = ChanVeseParameters(auto_mu(values) * scale**2 if is_auto(mu) else mu, omega, lambda_in,
                                lambda_out, c_in, c_out).in_frame(offset, scale)
    build = noise_model(noise)[0]
    model, params = build(values, None if light is None else np.asarray(light, dtype=np.float64), params)
    if sum(given is not None for given in (contours, classes, regions)) != 1:
        raise TypeError("chan_vese_energy takes one of contours, classes or regions")
    if classes is not None:
        return scale**2 * _classes_energy(model, classes, params)
    if regions is not None:
        return scale**2 * _regions_energy(model, regions, params)
    if isinstance(contours, np.ndarray) and contours.ndim == 2:
        contours = [contours]
    curves = [as_curve(c, name=f"contours[{i}]") for i, c in enumerate(contours)]
    for i, curve in enumerate(curves):
        _check_in_domain(curve, model.bounds, f"contours[{i}]")
    from activecontour.topology import region_problem  # shapely: imported when scoring

    problem = region_problem(curves)
    if problem is not None:
        raise ValueError(f"contours do not bound a region, (6.38) is not defined: {problem}")
    points, next_index, _ = stack_curves(curves)
    return scale**2 * evaluate(model, points, next_index, params, empty_ok=True).energy


def _check_in_domain(curve, bounds, name):
    """ValueError naming ``name`` unless every vertex lies in the image domain D (a rectangle, so
    then every edge does too).  Checked before the compiled kernel, which walks every grid line an
    edge crosses: a vertex at 1e10 would keep it busy for hours."""
    (low_r, low_c), (high_r, high_c) = bounds
    slack = 1e-9 * max(high_r - low_r, high_c - low_c)  # rounding of a vertex clipped to the border
    outside = np.any((curve < bounds[0] - slack) | (curve > bounds[1] + slack), axis=1)
    if np.any(outside):
        row, col = curve[np.argmax(outside)]
        raise ValueError(
            f"{name} has a vertex at (row, col) = ({row:.6g}, {col:.6g}) outside the image domain "
            f"rows {low_r:g}..{high_r:g}, cols {low_c:g}..{high_c:g}"
        )


def _classes_energy(model, classes, params):
    from activecontour.partition import class_boundary

    classes = np.asarray(classes)
    if classes.shape != tuple(model.shape) or not np.issubdtype(classes.dtype, np.integer):
        raise ValueError(f"classes must be an integer array of the image's shape {tuple(model.shape)}, "
                         f"got {classes.dtype} {classes.shape}")
    if classes.min() < 0:
        raise ValueError("classes must be >= 0 (0 = the background region)")
    n_classes = int(classes.max()) + 1
    constants = None
    if params.c_in is not None or params.c_out is not None:
        if n_classes > 2:
            raise ValueError("c_in and c_out fix the constants of two regions; leave them None "
                             "for classes with more than two regions")
        fit = evaluate_partition(model, class_boundary(classes), params, 2)
        channels = params.image_channels(model.n_channels)
        fixed = {name: params.constant(name, channels) for name in ("c_out", "c_in")}
        constants = np.array([fit.constants[k] if fixed[name] is None else fixed[name]
                              for k, name in enumerate(("c_out", "c_in"))])
    return evaluate_partition(model, class_boundary(classes), params, max(n_classes, 2),
                              constants).energy


def _regions_energy(model, regions, params):
    """The N-region functional of a partition given as closed curves per region.

    The moments of each region are boundary integrals of its curves (Green).  The counted length
    is ``L_interfaces + |border| - B_0`` (B_0: the border along region 0); every interface bounds
    two regions and the border one, so ``sum_k |boundary of region k| = 2 L_interfaces + |border|``.
    """
    if not isinstance(regions, (list, tuple)) or len(regions) < 2:
        raise ValueError("regions must be a list of at least two regions, each a list of closed curves")
    if params.c_in is not None or params.c_out is not None:
        raise ValueError("c_in and c_out fix the constants of two regions; leave them None with regions")
    n_classes = len(regions)
    areas = np.zeros(n_classes)
    first = np.zeros((n_classes, model.n_channels))
    second = np.zeros((n_classes, model.n_channels))
    perimeter, border_of_background = 0.0, 0.0
    (low_r, low_c), (high_r, high_c) = model.bounds
    for k, curves in enumerate(regions):
        curves = [as_curve(c, name=f"regions[{k}][{i}]") for i, c in enumerate(curves)]
        for i, curve in enumerate(curves):
            _check_in_domain(curve, model.bounds, f"regions[{k}][{i}]")
        if curves:
            areas[k], first[k], second[k] = region_moments(model, curves)
        for curve in curves:
            following = np.roll(curve, -1, axis=0)
            lengths = np.hypot(*(following - curve).T)
            perimeter += float(lengths.sum())
            if k == 0:
                along = np.zeros(len(curve), dtype=bool)
                for axis, value in ((0, low_r), (0, high_r), (1, low_c), (1, high_c)):
                    along |= (curve[:, axis] == value) & (following[:, axis] == value)
                border_of_background += float(lengths[along].sum())
    domain = (high_r - low_r) * (high_c - low_c)
    if not np.isclose(areas.sum(), domain, rtol=1e-9, atol=0.0) or np.any(areas < -1e-9 * domain):
        raise ValueError(f"regions do not tile the image domain: their areas sum to {areas.sum():.6g}, "
                         f"the domain's is {domain:.6g}")
    whole = params.region_constant(*model.totals)
    constants = np.array([params.region_constant(a, f, q) if a > 1e-9 else whole
                          for a, f, q in zip(areas, first, second, strict=True)])
    border = 2.0 * ((high_r - low_r) + (high_c - low_c))
    length = 0.5 * (perimeter + border) - border_of_background
    forms = params.class_forms(constants)
    return float(params.mu * length + sum(form.integral(a, f, q) for form, a, f, q
                                          in zip(forms, areas, first, second, strict=True)))
