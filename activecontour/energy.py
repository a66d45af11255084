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
from activecontour.curve import as_curve

__all__ = [
    "EMPTY_FRACTION",
    "PARAMETER_LIMIT",
    "ChanVeseParameters",
    "Evaluation",
    "chan_vese_energy",
    "evaluate",
    "region_moments",
    "stack_curves",
    "to_frame",
    "working_frame",
]


#: A region with less than this fraction of the domain's area is empty for its constant (6.42):
#: the domain-sized sums it is the difference of round at ~1e-16 of the domain, so its mean is
#: then exact to ~1e-7 of the image's range.
EMPTY_FRACTION = 1e-9
#: In the frame where the image spans [0, 1] (:meth:`ChanVeseParameters.in_frame`): the largest
#: mu, |omega|, |c_in|, |c_out| and lambda, and 1 / this the smallest lambda.  At 1e8 a weight
#: makes every other term of (6.38) smaller than its rounding; J stays far from overflow.
PARAMETER_LIMIT = 1e8


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


@dataclass(frozen=True)
class ChanVeseParameters:
    """Weights of (6.38) and, optionally, fixed region constants.

    ``c_in``/``c_out`` of None are updated by (6.42) at every evaluation; a number (or one per
    channel) holds them fixed, as the book allows when the intensities are known.
    ``lambda_in``/``lambda_out`` are numbers or, for a vector-valued image, one weight per channel
    (Chan, Sandberg and Vese 2000).
    """

    mu: float = 0.2
    omega: float = 0.0
    lambda_in: float = 1.0
    lambda_out: float = 1.0
    c_in: object = None
    c_out: object = None

    def __post_init__(self):
        for name in ("mu", "omega", "lambda_in", "lambda_out"):
            value = getattr(self, name)
            if name.startswith("lambda") and isinstance(value, (list, tuple, np.ndarray)):
                value = np.asarray(value, dtype=np.float64)
                if value.ndim != 1 or value.size == 0:
                    raise ValueError(f"{name} must be a number or one number per channel")
                object.__setattr__(self, name, value)
            elif isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
                raise TypeError(f"{name} must be a number, got {type(value).__name__}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name} must be finite, got {value}")
        if self.mu < 0:
            raise ValueError(f"mu must be >= 0 (length weight), got {self.mu}")
        if np.any(self.lambda_in <= 0) or np.any(self.lambda_out <= 0):
            raise ValueError(
                f"lambda_in and lambda_out must be > 0, got {self.lambda_in}, {self.lambda_out}"
            )
        for name in ("c_in", "c_out"):
            value = getattr(self, name)
            if value is not None:
                arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
                if arr.ndim != 1 or not np.all(np.isfinite(arr)):
                    raise ValueError(f"{name} must be None, a finite number or one per channel")
                object.__setattr__(self, name, arr)

    def in_frame(self, offset, scale):
        """The same functional for the intensities ``(I - offset) / scale``, range-checked.

        (6.38) of the image ``offset + scale I'`` is ``scale^2`` times (6.38) of I' with
        ``mu / scale^2``, ``omega / scale^2``, the same lambdas and constants ``(c - offset) /
        scale``: the backends compute in this frame, where the image spans [0, 1], so that a
        large offset does not cancel (``sum (I - c)^2 = sum I^2 - 2 c sum I + c^2 |Omega|`` loses
        every digit when c^2 is 1e16 times the variance) and nothing overflows.  In that frame
        every weight and constant must lie within :data:`PARAMETER_LIMIT` (lambdas within its
        inverse, too): beyond, one term of (6.38) is below the rounding of another, or J
        overflows.

        Raises
        ------
        ValueError
            Naming the parameter, its value and the valid range in the caller's units.
        """
        low_lambda, high = 1.0 / PARAMETER_LIMIT, PARAMETER_LIMIT
        for name in ("lambda_in", "lambda_out"):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if np.any(value < low_lambda) or np.any(value > high):
                raise ValueError(f"{name} must be between {low_lambda:g} and {high:g}, "
                                 f"got {getattr(self, name)}")
        square = scale * scale
        for name, limit in (("mu", high * square), ("omega", high * square)):
            if abs(getattr(self, name)) > limit:
                raise ValueError(f"|{name}| must be at most {limit:.6g} ({high:g} times the image's "
                                 f"intensity range squared), got {getattr(self, name)}")
        constants = {}
        for name in ("c_in", "c_out"):
            value = getattr(self, name)
            if value is not None:
                scaled = (value - offset) / scale
                if np.any(np.abs(scaled) > high):
                    raise ValueError(f"{name} must be within {high:g} image ranges of the image's "
                                     f"intensities, got {value}")
                constants[name] = scaled
        if offset == 0.0 and scale == 1.0:
            return self
        return ChanVeseParameters(self.mu / square, self.omega / square, self.lambda_in, self.lambda_out,
                                  constants.get("c_in"), constants.get("c_out"))

    def weights(self, n_channels):
        """(lambda_in, lambda_out) per channel, divided by the number of channels.

        The fitting terms of a vector-valued image are the *mean* of the channel terms (Chan,
        Sandberg and Vese's sum with weights lambda / C), so mu and omega mean the same relative to
        the contrast of a gray image and of a colour one: three equal channels segment exactly
        like their gray image.
        """
        out = []
        for name in ("lambda_in", "lambda_out"):
            value = np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))
            if value.size not in (1, n_channels):
                raise ValueError(f"{name} has {value.size} weights for an image with {n_channels} channels")
            out.append(np.broadcast_to(value / n_channels, (n_channels,)))
        return out

    def constant(self, name, n_channels):
        """The fixed constant ``name`` broadcast to ``n_channels``, or None when optimised."""
        value = getattr(self, name)
        if value is None:
            return None
        if value.size not in (1, n_channels):
            raise ValueError(f"{name} has {value.size} values for an image with {n_channels}")
        return np.broadcast_to(value, (n_channels,)).astype(np.float64)


@dataclass
class Evaluation:
    """Energy (6.38) of a curve set, with the constants used and optionally the load (6.41)."""

    energy: float
    c_in: np.ndarray
    c_out: np.ndarray
    area: float
    length: float
    load: np.ndarray | None = None


def stack_curves(curves):
    """Stack a list of (K_i, 2) curves into one vertex array and the index of each edge's end.

    Returns ``points (sum K_i, 2)``, ``next_index`` with edge e joining ``e`` and ``next_index[e]``,
    and the start offset of every curve (length ``len(curves) + 1``).
    """
    counts = np.array([len(c) for c in curves], dtype=np.intp)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    points = np.concatenate(curves, axis=0) if curves else np.zeros((0, 2))
    next_index = np.arange(offsets[-1]) + 1
    next_index[offsets[1:] - 1] = offsets[:-1]
    return points, next_index, offsets


def region_moments(model, curves):
    """``int_{Omega_i} 1``, ``int I`` and ``int I^2`` (per channel) for closed curves in (row, col).

    Exact for the bilinear image, by Green's theorem on the row-antiderivative tables.
    """
    points, next_index, _ = stack_curves([np.asarray(c, dtype=np.float64) for c in curves])
    area, _, s1, s2 = _moments(model, points, next_index)
    return area, s1, s2


def _moments(model, points, next_index):
    next_index = np.ascontiguousarray(next_index, dtype=np.intp)
    channels = model.n_channels
    s1, s2 = np.zeros(channels), np.zeros(channels)
    sums = np.zeros(2)  # area, length
    unused = np.zeros(channels)
    _kernels.edge_integrals(np.ascontiguousarray(points), next_index, model.values, model.table, 0,
                            unused, unused, unused, unused, 0.0, 0.0, s1, s2, sums, np.zeros((0, 2)))
    return sums[0], sums[1], s1, s2


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
    channels = model.n_channels
    area, length, s1, s2 = _moments(model, points, next_index)
    total_area, total1, total2 = model.totals
    outside_area = total_area - area
    c_in = params.constant("c_in", channels)
    c_out = params.constant("c_out", channels)
    tiny = EMPTY_FRACTION * total_area
    empty_in, empty_out = area <= tiny, outside_area <= tiny
    if (empty_in and c_in is None) or (empty_out and c_out is None):
        if not empty_ok:
            nan = np.full(channels, np.nan)
            return Evaluation(np.inf, nan, nan, area, length, None)
        if empty_in:  # the whole image is outside (or, below, inside)
            c_out = total1 / total_area if c_out is None else c_out
            c_in = c_out if c_in is None else c_in
        else:
            c_in = total1 / total_area if c_in is None else c_in
            c_out = c_in if c_out is None else c_out
    if c_in is None:
        c_in = s1 / area
    if c_out is None:
        c_out = (total1 - s1) / outside_area
    lambda_in, lambda_out = params.weights(channels)
    inside = lambda_in @ (s2 - 2.0 * c_in * s1 + c_in * c_in * area)
    outside = lambda_out @ ((total2 - s2) - 2.0 * c_out * (total1 - s1) + c_out * c_out * outside_area)
    energy = params.mu * length + params.omega * area + inside + outside
    result = Evaluation(float(energy), c_in, c_out, area, length)
    if gradient:
        load = np.zeros_like(points)
        _kernels.edge_integrals(np.ascontiguousarray(points), np.ascontiguousarray(next_index, dtype=np.intp),
                                model.values, model.table, 1, np.ascontiguousarray(c_in),
                                np.ascontiguousarray(c_out), np.ascontiguousarray(lambda_in),
                                np.ascontiguousarray(lambda_out), float(params.omega), float(params.mu),
                                s1, s2, np.zeros(2), load)
        result.load = load
    return result


def chan_vese_energy(image, contours, *, mu="auto", omega=0.0, lambda_in=1.0, lambda_out=1.0,
                     c_in=None, c_out=None, color="gray", normalize="range"):
    """Evaluate the Chan-Vese functional (6.38) of contours on an image: the common evaluator.

    Any backend's result can be scored the same way: pass ``result.contours``.

    Parameters
    ----------
    image : ndarray (M, N) or (M, N, C)
    contours : list of ndarray (K, 2)
        Closed curves in (row, col), outer boundaries positive, holes negative.  An empty list is
        the empty set: J is then the outside term alone.
    mu, omega, lambda_in, lambda_out : float
        Weights of (6.38); ``mu="auto"`` as in :func:`activecontour.segment` (``result.mu`` is the
        value a result used).
    c_in, c_out : float, optional
        Fixed constants, in normalised units; by default the optimal ones (6.42).
    color : {"gray", "vector"}
    normalize : {"range", "dtype", None}
        As in :func:`activecontour.segment`: pass the same choices to score a result.

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
    from activecontour.image import ImageModel, normalize_image
    from activecontour.noise import auto_mu, is_auto

    values = normalize_image(image, color=color, normalize=normalize)
    offset, scale = working_frame(values)
    model = ImageModel(to_frame(values, offset, scale))
    params = ChanVeseParameters(auto_mu(model.values) * scale**2 if is_auto(mu) else mu, omega, lambda_in,
                                lambda_out, c_in, c_out).in_frame(offset, scale)
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
