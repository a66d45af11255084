"""The common evaluator: (6.38) of any contours, classes or regions, as every result reports it.

``res.energy == chan_vese_energy(image, res.contours, mu=res.mu, ...)`` on every backend, so
results of the two backends and of different runs compare (DESIGN.md, Invariants).
"""

from __future__ import annotations

import numpy as np

from activecontour.energy import evaluate, evaluate_partition, region_moments
from activecontour.geometry.curve import as_curve, stack_curves
from activecontour.problem import prepare
from activecontour.settings import Settings

__all__ = ["chan_vese_energy"]

#: The defaults of the keywords segment and the evaluator share (stated in :class:`Settings`).
_DEFAULT = Settings()


def chan_vese_energy(image, contours=None, *, classes=None, regions=None, mu=_DEFAULT.mu,
                     omega=_DEFAULT.omega, lambda_in=_DEFAULT.lambda_in, lambda_out=_DEFAULT.lambda_out,
                     c_in=_DEFAULT.c_in, c_out=_DEFAULT.c_out, color=_DEFAULT.color,
                     normalize=_DEFAULT.normalize, light=None, noise=_DEFAULT.noise,
                     channel_axis=_DEFAULT.channel_axis):
    """Evaluate the Chan-Vese functional (6.38) of contours on an image: the common evaluator.

    Any backend's result can be scored the same way: pass ``result.contours`` (two regions) or
    ``classes=result.classes`` (a result with ``n_regions > 2``, whose class boundaries are those
    of its label image, see :mod:`activecontour.geometry.partition`).  The image and the keywords
    are prepared as :func:`activecontour.segment` prepares them (:func:`activecontour.problem.prepare`,
    the keywords checked by :class:`activecontour.settings.Settings`).

    Parameters
    ----------
    image : ndarray (M, N) or (M, N, C)
    contours : list of ndarray (K, 2)
        Closed curves in (row, col), each vertex once or the first repeated last, in either
        orientation: the nesting decides (:func:`activecontour.geometry.regions.orient_by_nesting`,
        the rule ``init`` follows too), a curve inside an even number of the others bounds an
        object, inside an odd number a hole.  So ``skimage.measure.find_contours`` output, OpenCV's
        ``findContours`` (converted to (row, col)) and shapely's rings score as they are.  An
        empty list is the empty set: J is then the outside term alone.
    classes : int ndarray (M, N), optional
        Instead of ``contours``: a label image, 0 = the background region, 1..K-1 the others.
        Scored as the partition of the domain it stands for (:mod:`activecontour.geometry.partition`:
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
    channel_axis : int, optional
        As in :func:`activecontour.segment`: the axis of a 3-D array that holds the channels (a
        channel-first (2-4, M, N) array needs it; it could be frames).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For a contour that is not a closed curve (see :func:`activecontour.geometry.curve.as_curve`) or has
        a vertex outside the image domain ``[-0.5, M - 0.5] x [-0.5, N - 0.5]``, and for contours
        that cross themselves or each other, overlap or repeat a curve
        (:func:`activecontour.geometry.topology.region_problem`): they bound no region, and
        (6.38) is not defined.  :func:`activecontour.geometry.topology.region_union` turns such curves
        into the boundary of the region they outline.
    """
    problem = prepare(image, Settings(mu=mu, omega=omega, lambda_in=lambda_in, lambda_out=lambda_out,
                                      c_in=c_in, c_out=c_out, color=color, normalize=normalize, noise=noise,
                                      channel_axis=channel_axis))
    scale = problem.frame[1]
    model, params = problem.model(None if light is None else np.asarray(light, dtype=np.float64))
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
    from activecontour.geometry.regions import nesting, orient_by_nesting, polygons
    from activecontour.geometry.topology import region_problem

    nested = nesting(polygons(curves))  # once, for the orientation and the check
    curves = orient_by_nesting(curves, nested[0])
    problem = region_problem(curves, nested)
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
    from activecontour.geometry.partition import class_boundary

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
