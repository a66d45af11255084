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

__all__ = ["ChanVeseParameters", "QuadraticForm", "noise_model"]


def noise_model(noise):
    """A noise model's two parts: ``build(values, light, params) -> (ImageModel, params)`` (light
    None: uniform) and its light update ``fit(values, classes, constants, params, previous)
    -> (light, drop)``.

    Parameters
    ----------
    noise : str
        One of :data:`activecontour.settings.NOISES` (checked there): ``"gaussian"``, (6.38)'s
        squared error, or ``"poisson"``, the likelihood of photon counts.
    """
    if noise == "poisson":
        from activecontour.models.poisson import fit_poisson_light, poisson_model

        return poisson_model, fit_poisson_light
    from activecontour.models.smooth import fit_light, smooth_light_model

    return smooth_light_model, fit_light
