"""The energies: each region's integrand as one quadratic form that every consumer reads.

Parts
-----
base        :class:`QuadraticForm`, the per-pixel integrand of a region (or a difference of two)
two_region  :class:`ChanVeseParameters`, the two-region Chan-Vese model (6.38) with (6.42)
"""

from activecontour.models.base import QuadraticForm
from activecontour.models.two_region import ChanVeseParameters

__all__ = ["ChanVeseParameters", "QuadraticForm"]
