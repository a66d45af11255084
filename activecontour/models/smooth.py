"""``fit="smooth"``: every region's intensity is its constant times one smooth light field.

Region k's integrand is ``g_k = omega_k + sum_c lambda_k,c (I_c - c_k,c b(x))^2`` (the bias-corrected
Chan-Vese of Li et al. 2011 and MICO, Li et al. 2014): b(x) is the illumination (vignetting, a
gradient across a slide, uneven light on a page), shared by all regions and all channels, and the
constants c_k are the regions' reflectances.  The pair (c, b) is defined up to a factor; b is
kept at mean 1 over the image.

The light field
---------------
b lies in the space of polynomials of degree <= ``LIGHT_DEGREE`` in the row and column
(tensor Legendre polynomials P_i(y) P_j(x), i + j <= 3, on [-1, 1]^2: ten functions, well
conditioned): smooth enough that it cannot follow an object's edge, rich enough for a gradient
plus a vignette.  A coarse tensor B-spline would follow more complex light at the price of more
unknowns; ten keep the least-squares update a 10 x 10 solve.

The same kernels serve
----------------------
With b fixed, (6.38)'s fit term is a diagonal quadratic form in the feature channels
``v = (I_1..I_C, b, I_1 + b, ..., I_C + b)``, by ``2 I b = (I + b)^2 - I^2 - b^2``:

    (I - c b)^2 = (1 + c) I^2 + (c^2 + c) b^2 - c (I + b)^2,

and the bilinear interpolants of the features obey the same identity pointwise (``I + b`` is
linear in the pixel values).  So the row-antiderivative tables of the features
(:class:`activecontour.image.ImageModel`), the exact edge integrals, the load (6.41), the level
set's force and nucleation all work unchanged (:class:`SmoothLightParameters` is the model they
read); the constants (6.42) become ``c_k = int I b / int b^2``, from the second moments.

Alternating minimisation (:func:`fit_light`): with the partition and the constants fixed, b is the
weighted least-squares fit ``min_b sum_x sum_c lambda_k (I_c - c_k b)^2`` over the pixels; the
backend then runs with the new tables.  Each step lowers J; a few rounds settle b.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["LIGHT_DEGREE", "SmoothLightParameters", "fit_light", "light_basis", "light_features",
           "smooth_light_model"]

#: Largest total degree of the light field's polynomials.
LIGHT_DEGREE = 3


@dataclass(frozen=True)
class SmoothLightParameters(ChanVeseParameters):
    """The smooth-light model: (6.38) with ``c_k b(x)`` for ``c_k``, on the feature channels of
    :func:`light_features` (``n_channels`` is the image's C; the features have 2 C + 1)."""

    n_channels: int = 1

    def image_channels(self, n_features):
        return self.n_channels

    def region_constant(self, area, first, second):
        """``c = int I b / int b^2`` from the second moments of the features."""
        channels = self.n_channels
        light = second[channels]
        cross = 0.5 * (second[channels + 1:] - second[:channels] - light)
        return cross / light

    def class_forms(self, constants):
        """``g_k`` as a quadratic form in the features: ``(1 + c) I^2 + (c^2 + c) b^2 - c (I + b)^2``
        per channel, times the channel weights, plus omega for k >= 1."""
        constants = np.asarray(constants, dtype=np.float64)
        lambda_in, lambda_out = self.weights(self.n_channels)
        forms = []
        for k, c in enumerate(constants):
            weight = lambda_out if k == 0 else lambda_in
            square = np.concatenate([weight * (1.0 + c), [np.sum(weight * (c * c + c))], -weight * c])
            forms.append(QuadraticForm(self.omega if k > 0 else 0.0, np.zeros(square.size), square))
        return forms


def light_basis(shape, degree=LIGHT_DEGREE):
    """The light field's basis, shape (P, M, N): ``P_i(y) P_j(x)`` for ``i + j <= degree``, with
    y, x the pixel centres mapped onto [-1, 1]."""
    m, n = shape
    y = legendre.legvander(np.linspace(-1.0, 1.0, m), degree)
    x = legendre.legvander(np.linspace(-1.0, 1.0, n), degree)
    return np.array([np.outer(y[:, i], x[:, j]) for i in range(degree + 1)
                     for j in range(degree + 1 - i)])


def smooth_light_model(image, light, params):
    """The image model (feature tables) and the model parameters of the smooth fit for a light
    field: what the backends and the common evaluator read.

    Parameters
    ----------
    image : ndarray (M, N, C)
        Normalised intensities.
    light : ndarray (M, N) or None
        b, positive; None is uniform light, the constant fit.
    params : ChanVeseParameters

    Returns
    -------
    ImageModel, SmoothLightParameters
    """
    import dataclasses

    from activecontour.image import ImageModel

    if light is None:  # uniform: the constant fit
        return ImageModel(image), params
    if light.shape != image.shape[:2] or not np.all(np.isfinite(light)) or np.any(light <= 0):
        raise ValueError(f"light must be a positive finite array of the image's shape {image.shape[:2]}")
    fields = {field.name: getattr(params, field.name) for field in dataclasses.fields(params)}
    return (ImageModel(light_features(image, light), image=image / light[..., None]),
            SmoothLightParameters(**fields, n_channels=image.shape[2]))


def light_features(image, light):
    """The feature channels ``(I_1..I_C, b, I_1 + b, ..., I_C + b)``, shape (M, N, 2 C + 1)."""
    return np.concatenate([image, light[..., None], image + light[..., None]], axis=2)


def fit_light(image, classes, constants, params, basis):
    """The least-squares light field for a partition and its constants, at mean 1.

    Minimises ``sum_x sum_c w_k,c (I_c(x) - c_k,c b(x))^2`` over b in the span of ``basis``, with
    k the region of pixel x and ``w`` the model's channel weights (lambda / C): the normal
    equations ``(B^T W B) beta = B^T r`` with ``W(x) = sum_c w c^2`` and ``r(x) = sum_c w c I_c``.
    A field that would not be positive everywhere is clipped at a tenth of its mean.

    Parameters
    ----------
    image : ndarray (M, N, C)
    classes : int ndarray (M, N)
    constants : ndarray (K, C)
    params : SmoothLightParameters
    basis : ndarray (P, M, N)

    Returns
    -------
    ndarray (M, N)
    """
    lambda_in, lambda_out = params.weights(image.shape[2])
    weights = np.where(np.arange(len(constants))[:, None] == 0, lambda_out, lambda_in)  # (K, C)
    pixel_weight = np.sum(weights * constants**2, axis=1)[classes]
    target = np.einsum("mnc,mnc->mn", image, (weights * constants)[classes])
    flat = basis.reshape(len(basis), -1)
    normal = (flat * pixel_weight.ravel()) @ flat.T
    beta = np.linalg.solve(normal, flat @ target.ravel())
    light = np.tensordot(beta, basis, axes=1)
    light /= light.mean()
    return np.maximum(light, 0.1)
