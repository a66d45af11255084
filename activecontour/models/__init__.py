"""The energies: each region's integrand as one quadratic form that every consumer reads.

Parts
-----
base        :class:`QuadraticForm`, the per-pixel integrand of a region (or a difference of two)
two_region  :class:`ChanVeseParameters`, the two-region Chan-Vese model (6.38) with (6.42)
kmeans      the global K-means of the intensities (exact on the histogram): the N-region start
modes       how many regions an image holds (``n_regions="auto"``): the significant modes of its
            flat pixels' intensities
smooth      ``fit="smooth"``: region k's intensity c_k b(x) with a smooth light field b
poisson     ``noise="poisson"``: the fit term of photon counts, with uniform or smooth light
"""

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["NOISES", "ChanVeseParameters", "QuadraticForm", "noise_model"]

#: The noise models of the fit term (``noise``): (6.38)'s squared error, or photon counts.
NOISES = ("gaussian", "poisson")


def noise_model(noise):
    """A noise model's two parts: ``build(values, light, params) -> (ImageModel, params)`` (light
    None: uniform) and its light update ``fit(values, classes, constants, params, previous)
    -> (light, drop)``.

    Raises
    ------
    ValueError
        For a name not in :data:`NOISES`.
    """
    if isinstance(noise, str) and noise == "poisson":
        from activecontour.models.poisson import fit_poisson_light, poisson_model

        return poisson_model, fit_poisson_light
    if isinstance(noise, str) and noise == "gaussian":
        from activecontour.models.smooth import fit_light, smooth_light_model

        return smooth_light_model, fit_light
    raise ValueError(f"noise must be one of {NOISES}, got {noise!r}")
