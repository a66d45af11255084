"""``noise="poisson"``: the fit term of photon counts, with uniform or smooth light.

(6.38)'s squared error is the negative log-likelihood of Gaussian noise of one variance
everywhere.  A fluorescence image counts photons: the count at x is Poisson with the rate
``m_k(x) = c_k b(x)`` of its region (b = 1 for ``fit="constant"``; the smooth light of
:mod:`activecontour.models.smooth` otherwise), so its variance grows with its mean.  Region k's
integrand is the Poisson negative log-likelihood, less what does not depend on the model, times
``2 r`` (r the channel's mean intensity):

    g_k = omega_k + sum_c w_k,c 2 r_c (m_k,c - I_c ln m_k,c),      w = lambda / C.

Near ``I = m``, ``2 r (m - I ln m) = const + r (I - m)^2 / I + O((I - m)^3)``: at the mean
intensity it is (6.38)'s squared error, so mu and omega keep their meaning; a bright pixel weighs
less (its shot noise is larger), a dark one more.

What it changes
---------------
* Two regions split where ``c_0 - I ln c_0 = c_1 - I ln c_1``: at the logarithmic mean
  ``(c_1 - c_0) / ln(c_1 / c_0)`` of the constants, below (6.38)'s arithmetic midpoint.  Objects
  brighter than their neighbours pull ``c_1`` up, and under (6.38) the dim ones fall under the
  midpoint; the logarithmic mean keeps them (DSB 2018 nuclei: the best global threshold is at
  0.175 of the range, the arithmetic midpoint of the two classes at 0.19, their logarithmic
  mean at 0.176).
* The light's update weighs region k by ``c_k`` (the Fisher information of a Poisson rate,
  ``c_k / b``), not ``c_k^2`` as the least squares do: bright objects pull b three times as hard
  as a background a third as bright, not nine times (:func:`fit_poisson_light`).
* The constants are the maximum-likelihood rates ``c_k = int_k I / int_k b``: the region's mean
  under uniform light, as (6.42).

The same kernels serve: g_k is *linear* in the feature channels ``(I_1..I_C)`` (uniform light) or
``(I_1..I_C, b, I_1 ln b, .., I_C ln b)`` (smooth light; ``- I ln b`` is the same in every region,
but J's value across light fields needs it), so the tables, the exact edge integrals, the load
(6.41), the level set's force and nucleation read :class:`PoissonParameters` as any model.

The zero of the counts is the working frame's: the normalised image's zero where it lies within
[0, 1] (``normalize="dtype"`` of integer counts, or floats in [0, 1] with ``normalize=None``),
else its minimum (``normalize="range"``, the default: a camera's dark level is not known; the
minimum estimates it from below).  A region whose rate is below ``RATE_FLOOR`` of the
frame (all its pixels at the minimum) is given that rate: a pixel above it costs
``-2 r I ln RATE_FLOOR``, large and finite.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from activecontour.models.base import QuadraticForm
from activecontour.models.smooth import LIGHT_DEGREE, LightSpace
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["RATE_FLOOR", "PoissonParameters", "fit_poisson_light", "poisson_model"]

#: The smallest rate of a region, in the working frame (the image spans [0, 1]).
RATE_FLOOR = 1e-6
#: Newton steps of the light's update at most; each at least halves the Newton decrement.
_NEWTON_STEPS = 50


@dataclass(frozen=True)
class PoissonParameters(ChanVeseParameters):
    """The Poisson model on the feature channels of :func:`poisson_model`.

    ``reference`` holds ``r_c``, the channels' mean intensities; ``light`` whether the features
    carry a light field b (``fit="smooth"``).
    """

    n_channels: int = 1
    reference: tuple = (1.0,)
    light: bool = False

    def image_channels(self, n_features):
        return self.n_channels

    def region_constant(self, area, first, second):
        """The maximum-likelihood rate ``int I / int b`` (``int I / |Omega|`` under uniform light)."""
        channels = self.n_channels
        return first[:channels] / (first[channels] if self.light else area)

    def class_forms(self, constants):
        """``g_k`` as a linear form in the features (see the module's docstring)."""
        constants = np.maximum(np.asarray(constants, dtype=np.float64), RATE_FLOOR)
        lambda_in, lambda_out = self.weights(self.n_channels)
        reference = 2.0 * np.asarray(self.reference, dtype=np.float64)
        forms = []
        for k, c in enumerate(constants):
            scale = reference * (lambda_out if k == 0 else lambda_in)
            area_weight = self.omega if k > 0 else 0.0
            if self.light:
                linear = np.concatenate([-scale * np.log(c), [np.sum(scale * c)], -scale])
                forms.append(QuadraticForm(area_weight, linear, np.zeros(linear.size)))
            else:
                forms.append(QuadraticForm(area_weight + float(np.sum(scale * c)), -scale * np.log(c),
                                           np.zeros(c.size)))
        return forms


def poisson_model(image, light, params):
    """The image model (feature tables) and parameters of the Poisson fit for a light field.

    The default start looks at the square root of the (light-corrected) counts: the variance-
    stabilising transform of Poisson counts (Anscombe 1948), under which the start's least-
    squares split (:func:`activecontour.initial.threshold_split`, (6.38) without its length) is
    the Poisson split to first order; on the counts themselves it would split at the arithmetic
    midpoint, which the Poisson flow cannot always leave (a dim object apart from the start's
    curves is out of the level set's reach).

    Parameters
    ----------
    image : ndarray (M, N, C)
        Intensities in the working frame ([0, 1]).
    light : ndarray (M, N) or None
        b, positive; None is uniform light.
    params : ChanVeseParameters

    Returns
    -------
    ImageModel, PoissonParameters
    """
    from activecontour.imaging.tables import ImageModel

    fields = {field.name: getattr(params, field.name) for field in dataclasses.fields(ChanVeseParameters)}
    reference = tuple(float(max(r, RATE_FLOOR)) for r in image.reshape(-1, image.shape[2]).mean(axis=0))
    model_params = PoissonParameters(**fields, n_channels=image.shape[2], reference=reference,
                                     light=light is not None)
    if light is None:
        return ImageModel(image, image=np.sqrt(image)), model_params
    if light.shape != image.shape[:2] or not np.all(np.isfinite(light)) or np.any(light <= 0):
        raise ValueError(f"light must be a positive finite array of the image's shape {image.shape[:2]}")
    features = np.concatenate([image, light[..., None], image * np.log(light)[..., None]], axis=2)
    return ImageModel(features, image=np.sqrt(image / light[..., None])), model_params


def fit_poisson_light(image, classes, constants, params, previous=None, degree=LIGHT_DEGREE):
    """The maximum-likelihood light field of the Poisson model for a partition and its constants,
    at mean 1, and the drop of J it brings.

    Minimises ``F(b) = sum_x A(x) b(x) - B(x) ln b(x)`` over b in the span of
    :func:`~activecontour.models.smooth.light_basis`, with ``A = sum_c s_k,c c_k,c`` and
    ``B = sum_c s_k,c I_c``, ``s = 2 r w`` the model's channel scales of region k: J's fit term
    at fixed partition and constants, less what does not depend on b.  F is convex in the
    coefficients where b > 0 (``-ln`` is convex, b linear in them): Newton's method, its gradient
    ``sum phi (A - B / b)`` and Hessian ``sum phi phi^T B / b^2`` the separable contractions of
    :class:`~activecontour.models.smooth.LightSpace`, from the best uniform light
    ``sum B / sum A`` with a backtracking line search that keeps b > 0 on the pixels and F
    decreasing, until the Newton decrement is below 1e-12 of F's scale.  At the optimum
    ``sum A b = sum B`` (the gradient along the constant function), so the update weighs a pixel
    of region k by ``B / b^2 ~ s c_k / b``, the Fisher information of its rate.

    Parameters
    ----------
    image : ndarray (M, N, C)
    classes : int ndarray (M, N)
    constants : ndarray (K, C)
    params : PoissonParameters or ChanVeseParameters
        Its weights; its ``reference`` where it has one (else the channels' means).
    previous : ndarray (M, N), optional
        The light the constants were fitted with; None is uniform light.
    degree : int

    Returns
    -------
    light : ndarray (M, N)
    drop : float
        ``J(previous) - J(b*)`` at fixed partition and constants (before the normalisation to
        mean 1, which the constants absorb), >= 0.
    """
    channels = image.shape[2]
    lambda_in, lambda_out = params.weights(channels)
    reference = getattr(params, "reference", None)
    if reference is None:
        reference = np.maximum(image.reshape(-1, channels).mean(axis=0), RATE_FLOOR)
    scales = 2.0 * np.asarray(reference) * np.where(np.arange(len(constants))[:, None] == 0,
                                                      lambda_out, lambda_in)  # (K, C)
    rate = np.sum(scales * np.maximum(constants, RATE_FLOOR), axis=1)[classes]
    counts = sum(image[..., c] * scales[:, c][classes] for c in range(channels))

    def objective(light):
        return float(np.sum(rate * light - counts * np.log(light)))

    if not np.sum(counts) > 0:  # no counts: every light is as likely as uniform light
        return np.ones(image.shape[:2]), 0.0
    space = LightSpace(image.shape[:2], degree)
    beta = np.zeros(len(space.terms))
    beta[0] = np.sum(counts) / np.sum(rate)  # P_0 P_0 = 1: the best uniform light
    light = space.field(beta)
    value = objective(light)
    for _ in range(_NEWTON_STEPS):
        gradient = space.project(rate - counts / light)
        step = np.linalg.lstsq(space.gram(counts / light**2), gradient, rcond=None)[0]
        decrement = float(gradient @ step)
        if decrement <= 1e-12 * max(abs(value), 1.0):
            break
        length = 1.0
        while length > 1e-10:
            trial = space.field(beta - length * step)
            if np.all(trial > 0) and objective(trial) <= value - 0.25 * length * decrement:
                break
            length *= 0.5
        else:
            break
        beta -= length * step
        light, value = trial, objective(trial)
    before = np.ones_like(light) if previous is None else previous
    drop = objective(before) - value
    light = light / light.mean()
    return np.maximum(light, 0.1), drop
