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
(:class:`activecontour.imaging.tables.ImageModel`), the exact edge integrals, the load (6.41), the level
set's force and nucleation all work unchanged (:class:`SmoothLightParameters` is the model they
read); the constants (6.42) become ``c_k = int I b / int b^2``, from the second moments.

Alternating minimisation (:func:`fit_light`): with the partition and the constants fixed, b is the
weighted least-squares fit ``min_b sum_x sum_c lambda_k (I_c - c_k b)^2`` over the pixels (a
separable contraction, O(M N) per update), which also reports how much it lowers J; the backend
then runs with the new tables.  Each step lowers J; the driver
(:func:`activecontour.segment._smooth_light`) stops when a light step is not worth its
parameters by the Bayesian information criterion, so an image under flat light costs one
constant fit and one light fit.

What the light cannot do
------------------------
The update weighs a pixel of region k by ``c_k^2``: bright objects pull b harder than a dark
background (9x for nuclei at 0.3 on a background at 0.1).  When the objects' own brightness
varies from one to the next (nuclei of different DNA content), b follows clusters of bright
objects, and a dim object next to them falls under ``c_out b`` on the background side.  That
is the minimiser of J, not a fault of the alternation: on the DSB 2018 nuclei J of the found
partition is ~20 % below J of the true one under any light of the span, and richer light
(degree 6, 8) lowers J further while Dice falls.  Objects of different brightness need another
fit term (photon counts, :mod:`activecontour.models.poisson`, weigh region k by ``c_k`` and split
at the logarithmic mean), more classes (``n_regions=3``) or per-object constants, not a richer
light.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["LIGHT_DEGREE", "LIGHT_TERMS", "LightSpace", "SmoothLightParameters", "fit_light", "light_basis",
           "light_features", "smooth_light_model"]

#: Largest total degree of the light field's polynomials ...
LIGHT_DEGREE = 3
#: ... and their number, ``P_i(y) P_j(x)`` for ``i + j <= LIGHT_DEGREE``.
LIGHT_TERMS = (LIGHT_DEGREE + 1) * (LIGHT_DEGREE + 2) // 2


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
    y, x the pixel centres mapped onto [-1, 1] (in the order of :func:`_light_terms`)."""
    rows, cols = _light_factors(shape, degree)
    return np.array([np.outer(rows[:, i], cols[:, j]) for i, j in _light_terms(degree)])


def _light_factors(shape, degree):
    """The one-dimensional factors of the basis: ``P_i`` at the rows (M, D) and at the columns
    (N, D), D = degree + 1."""
    m, n = shape
    return (legendre.legvander(np.linspace(-1.0, 1.0, m), degree),
            legendre.legvander(np.linspace(-1.0, 1.0, n), degree))


def _light_terms(degree):
    """The index pairs (i, j), ``i + j <= degree``, of the basis functions ``P_i(y) P_j(x)``."""
    return [(i, j) for i in range(degree + 1) for j in range(degree + 1 - i)]


class LightSpace:
    """The span of :func:`light_basis` on an image's grid, with its separable contractions.

    The basis is ``P_i(y) P_j(x)``, so every sum over the pixels it needs is a contraction of the
    one-dimensional factors Y (M, D) and X (N, D): ``sum_x f(x) phi_a phi_b`` is
    ``sum_y P_i P_k(y) sum_x f(y, x) P_j P_l(x)`` and ``sum_x f(x) phi_a`` is ``(Y^T f X)_ij``,
    O(M N D^2) with D = degree + 1 and no (P, M, N) array (the basis of a 1024^2 image is 80 MB).
    """

    def __init__(self, shape, degree=LIGHT_DEGREE):
        self.rows, self.cols = _light_factors(shape, degree)
        self.size = degree + 1
        self.terms = np.array(_light_terms(degree))

    def gram(self, weight):
        """``sum_x weight(x) phi_a(x) phi_b(x)``, (P, P)."""
        size, (i, j) = self.size, self.terms.T
        rows = (self.rows[:, :, None] * self.rows[:, None, :]).reshape(len(self.rows), size * size)
        cols = (self.cols[:, :, None] * self.cols[:, None, :]).reshape(len(self.cols), size * size)
        full = (rows.T @ (weight @ cols)).reshape(size, size, size, size)  # [i, k, j, l]
        return full[i[:, None], i[None, :], j[:, None], j[None, :]]

    def project(self, field):
        """``sum_x field(x) phi_a(x)``, (P,)."""
        i, j = self.terms.T
        return (self.rows.T @ field @ self.cols)[i, j]

    def field(self, beta):
        """``sum_a beta_a phi_a`` on the grid, (M, N)."""
        coefficients = np.zeros((self.size, self.size))
        coefficients[tuple(self.terms.T)] = beta
        return self.rows @ coefficients @ self.cols.T


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

    from activecontour.imaging.tables import ImageModel

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


def fit_light(image, classes, constants, params, previous=None, degree=LIGHT_DEGREE):
    """The least-squares light field for a partition and its constants, at mean 1, and the drop
    of J it brings.

    Minimises ``sum_x sum_c w_k,c (I_c(x) - c_k,c b(x))^2`` over b in the span of
    :func:`light_basis`, with k the region of pixel x and ``w`` the model's channel weights
    (lambda / C): the normal equations ``(B^T W B) beta = B^T r`` with ``W(x) = sum_c w c^2``
    and ``r(x) = sum_c w c I_c``, by the separable contractions of :class:`LightSpace`.  A field
    that would not be positive everywhere is clipped at a tenth of its mean.

    The drop: at fixed partition and constants the fit term is ``sum_x (W b^2 - 2 r b)`` plus a
    constant, so ``b*`` lowers it from the previous field ``b_0`` by
    ``sum_x W (b_0^2 - b*^2) - 2 r (b_0 - b*)``: ``sum_x W (b* - b_0)^2`` when ``b_0`` is in
    the span (Pythagoras in the W-weighted norm), exact also for a clipped ``b_0``.  It is taken
    before the normalisation to mean 1, which the constants absorb at their next update.

    Parameters
    ----------
    image : ndarray (M, N, C)
    classes : int ndarray (M, N)
    constants : ndarray (K, C)
    params : ChanVeseParameters
    previous : ndarray (M, N), optional
        The light the constants were fitted with; None is uniform light.
    degree : int

    Returns
    -------
    light : ndarray (M, N)
    drop : float
        ``J(previous) - J(b*)`` at fixed partition and constants, >= 0.
    """
    lambda_in, lambda_out = params.weights(image.shape[2])
    weights = np.where(np.arange(len(constants))[:, None] == 0, lambda_out, lambda_in)  # (K, C)
    pixel_weight = np.sum(weights * constants**2, axis=1)[classes]
    scaled = weights * constants
    target = sum(image[..., c] * scaled[:, c][classes] for c in range(image.shape[2]))
    space = LightSpace(image.shape[:2], degree)
    light = space.field(np.linalg.solve(space.gram(pixel_weight), space.project(target)))
    before = 1.0 if previous is None else previous
    drop = float(np.sum((before - light) * (pixel_weight * (before + light) - 2.0 * target)))
    light /= light.mean()
    return np.maximum(light, 0.1), drop
