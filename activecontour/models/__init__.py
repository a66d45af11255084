"""The energies: each region's integrand as one quadratic form that every consumer reads.

Parts
-----
base        :class:`QuadraticForm`, the per-pixel integrand of a region (or a difference of two)
two_region  :class:`ChanVeseParameters`, the two-region Chan-Vese model (6.38) with (6.42)
kmeans      the global K-means of the intensities (exact on the histogram): the N-region start
modes       how many regions an image holds (``n_regions="auto"``): the significant modes of its
            flat pixels' intensities
smooth      the smooth-light model (``fit="smooth"``)
"""

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["ChanVeseParameters", "QuadraticForm"]
