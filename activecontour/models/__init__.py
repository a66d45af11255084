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

import importlib

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["NOISE_MODELS", "ChanVeseParameters", "QuadraticForm", "noise_model"]


#: The noise models by name: the module that holds each one, the name of its ``build(values, light,
#: params) -> (ImageModel, params)`` (light None: uniform) and the name of its light update ``fit(values,
#: classes, constants, params, previous) -> (light, drop)``.  A noise model is its module plus its line
#: here; :data:`activecontour.settings.NOISES`, and with it ``--noise`` and the viewer, read this table.
NOISE_MODELS = {
    "gaussian": ("activecontour.models.smooth", "smooth_light_model", "fit_light"),  # (6.38)'s squares
    "poisson": ("activecontour.models.poisson", "poisson_model", "fit_poisson_light"),  # photon counts
}


def noise_model(noise):
    """A noise model's two parts, ``(build, fit)`` (:data:`NOISE_MODELS`), its module imported now.

    Parameters
    ----------
    noise : str
        One of :data:`NOISE_MODELS` (checked in :mod:`activecontour.settings`): ``"gaussian"``,
        (6.38)'s squared error, or ``"poisson"``, the likelihood of photon counts.
    """
    module, build, fit = NOISE_MODELS[noise]
    loaded = importlib.import_module(module)
    return getattr(loaded, build), getattr(loaded, fit)
