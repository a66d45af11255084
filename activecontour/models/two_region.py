"""The two-region Chan-Vese model (6.38) with constant intensities (6.42).

Region 0 is the outside Omega_o, region 1 the inside Omega_i.  With constants ``c_o, c_i`` (one per
channel) and the channel weights of :meth:`ChanVeseParameters.weights`, their integrands are

    g_0(v) = sum_c lambda_out,c (v_c - c_o,c)^2,
    g_1(v) = omega + sum_c lambda_in,c (v_c - c_i,c)^2,

diagonal quadratic forms in the channels (:class:`activecontour.models.base.QuadraticForm`), and
(6.41)'s integrand is ``g_1 - g_0`` (:meth:`ChanVeseParameters.load_form`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from activecontour.models.base import QuadraticForm

__all__ = ["EMPTY_FRACTION", "PARAMETER_LIMIT", "ChanVeseParameters"]

#: A region with less than this fraction of the domain's area is empty for its constant (6.42):
#: the domain-sized sums it is the difference of round at ~1e-16 of the domain, so its mean is
#: then exact to ~1e-7 of the image's range.
EMPTY_FRACTION = 1e-9
#: In the frame where the image spans [0, 1] (:meth:`ChanVeseParameters.in_frame`): the largest
#: mu, |omega|, |c_in|, |c_out| and lambda, and 1 / this the smallest lambda.  At 1e8 a weight
#: makes every other term of (6.38) smaller than its rounding; J stays far from overflow.
PARAMETER_LIMIT = 1e8


@dataclass(frozen=True)
class ChanVeseParameters:
    """Weights of (6.38) and, optionally, fixed region constants.

    ``c_in``/``c_out`` of None are updated by (6.42) at every evaluation; a number (or one per
    channel) holds them fixed, as the book allows when the intensities are known.
    ``lambda_in``/``lambda_out`` are numbers or, for a vector-valued image, one weight per channel
    (Chan, Sandberg and Vese 2000).  Their rules are :class:`activecontour.settings.Settings`'
    (the values of :func:`activecontour.segment` are checked there, once); weights per channel
    and fixed constants are held as arrays.
    """

    mu: float = 0.2
    omega: float = 0.0
    lambda_in: float = 1.0
    lambda_out: float = 1.0
    c_in: object = None
    c_out: object = None

    def __post_init__(self):
        for name in ("lambda_in", "lambda_out"):
            value = getattr(self, name)
            if isinstance(value, (list, tuple, np.ndarray)):
                object.__setattr__(self, name, np.asarray(value, dtype=np.float64))
        for name in ("c_in", "c_out"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, np.atleast_1d(np.asarray(value, dtype=np.float64)))

    def weights(self, n_channels):
        """(lambda_in, lambda_out) per channel, divided by the number of channels.

        The fitting terms of a vector-valued image are the *mean* of the channel terms (Chan,
        Sandberg and Vese's sum with weights lambda / C), so mu and omega mean the same relative to
        the contrast of a gray image and of a colour one: three equal channels segment exactly
        like their gray image.

        Kept per ``n_channels`` (read-only views; the fields are frozen): every evaluation of a
        partition asks for them once per region.
        """
        cache = self.__dict__.setdefault("_weights", {})
        if n_channels not in cache:
            out = []
            for name in ("lambda_in", "lambda_out"):
                value = np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))
                if value.size not in (1, n_channels):
                    raise ValueError(f"{name} has {value.size} weights for an image with {n_channels} "
                                     "channels")
                out.append(np.broadcast_to(value / n_channels, (n_channels,)))
            cache[n_channels] = out
        return list(cache[n_channels])

    def constant(self, name, n_channels):
        """The fixed constant ``name`` broadcast to ``n_channels``, or None when optimised."""
        value = getattr(self, name)
        if value is None:
            return None
        if value.size not in (1, n_channels):
            raise ValueError(f"{name} has {value.size} values for an image with {n_channels}")
        return np.broadcast_to(value, (n_channels,)).astype(np.float64)

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

    def fit_constants(self, area, first, second, totals, *, empty_ok):
        """``(c_in, c_out)`` by (6.42) from the inside moments, or None where (6.42) is undefined.

        Parameters
        ----------
        area, first, second : float, ndarray (C,), ndarray (C,)
            ``int_{Omega_i} 1``, ``int v`` and ``int v^2`` per feature channel.
        totals : tuple
            The same over the domain (the outside by subtraction).
        empty_ok : bool
            When a region whose constant is optimised is empty (6.42 is undefined; a region under
            ``EMPTY_FRACTION`` of the domain counts as empty: its mean is a difference of
            domain-sized sums divided by its area, all rounding): False returns
            None (the flow's view: no step is accepted into that state); True reports the
            constant equal to the other region's (its fitting term is 0 whatever it is).
        """
        channels = self.image_channels(len(first))
        inside = (area, first, second)
        outside = tuple(total - part for total, part in zip(totals, inside, strict=True))
        c_in = self.constant("c_in", channels)
        c_out = self.constant("c_out", channels)
        tiny = EMPTY_FRACTION * totals[0]  # a sliver's mean would be rounding: empty
        empty_in, empty_out = area <= tiny, outside[0] <= tiny
        if (empty_in and c_in is None) or (empty_out and c_out is None):
            if not empty_ok:
                return None
            whole = self.region_constant(*totals)
            if empty_in:  # the whole image is outside (or, below, inside)
                c_out = whole if c_out is None else c_out
                c_in = c_out if c_in is None else c_in
            else:
                c_in = whole if c_in is None else c_in
                c_out = c_in if c_out is None else c_out
        if c_in is None:
            c_in = self.region_constant(*inside)
        if c_out is None:
            c_out = self.region_constant(*outside)
        return c_in, c_out

    def image_channels(self, n_features):
        """The image's channels C for ``n_features`` feature channels: the same here."""
        return n_features

    def region_constant(self, area, first, second):
        """(6.42): the region's mean, from its moments ``int 1, int v, int v^2``."""
        return first / area

    def region_forms(self, c_in, c_out):
        """The integrands ``(g_0, g_1)`` of the outside and the inside as quadratic forms."""
        return self.class_forms(np.array([np.atleast_1d(c_out), np.atleast_1d(c_in)]))

    def class_forms(self, constants):
        """The integrand of every region of a partition, as quadratic forms.

        Region 0 is the background (the outside, weight ``lambda_out``); every other region k is
        an inside region (weight ``lambda_in`` and the area weight omega), with the constant
        ``constants[k]``.  Two regions are (6.38); more are its N-region form (Vese and Chan 2002
        with one weight per side): ``sum_k int_{Omega_k} g_k`` plus mu times the interfaces.

        Parameters
        ----------
        constants : ndarray (K, C)
        """
        constants = np.asarray(constants, dtype=np.float64)
        lambda_in, lambda_out = self.weights(constants.shape[1])
        return [QuadraticForm.of_fit(lambda_out, constants[0])] + [
            QuadraticForm.of_fit(lambda_in, c, self.omega) for c in constants[1:]]

    def load_form(self, c_in, c_out):
        """``g_1 - g_0``: the integrand of the shape derivative (6.41) and of the level set's force."""
        outside, inside = self.region_forms(c_in, c_out)
        return inside - outside
