"""activecontour: sub-pixel Chan-Vese active contours.

The method is section 6.5 of *The Shapes of Things* (S. W. Walker): the Chan-Vese functional (6.38)
minimised by the gradient flow (6.30)-(6.31) with the H^1 velocity (6.39)-(6.40) and the shape
derivative (6.41), on a polygon, or on a level-set function over the pixel grid.

Parts
-----
segment            the entry point: ``segment(image, init, backend=..., mu=..., ...)``
segment_many       many images in worker processes, results as they finish (also on Dask: batch)
SegmentationResult the result of every backend
circle, rectangle  initial curves (any (K, 2) array, list of them, or bool mask also works)
chan_vese_energy   the common evaluator of (6.38) for any contours
curve, fem         polygon geometry (tangent, normal, curvature) and P1 finite elements
image, energy      the image model with its cumulative tables; the functional and its derivative
noise              the image's noise level and the default mu it implies
initial, result    starts (the default one, circles, grids, masks); the one result constructor
flow               the polygon backend (the book's H^1 flow)
backends.levelset  the level-set backend (redistancing, zero set, scheme, driver)
topology, pyramid  crossings and their repair, nucleation; a start from a reduced copy
_kernels           the compiled loops (Cython, built at install)
io, raster         writers/readers of masks, overlays and contours (atomic, image_files,
                   contour_files, vector_formats); curves <-> masks
synthetic          anti-aliased test images with exact ground truth
compat             scikit-image's signatures: ``from activecontour.compat import chan_vese``
batch              many images: worker processes, folders and globs, a Dask cluster

Conventions: points are (row, col) with pixel centres at integer coordinates; outer boundaries are
positively oriented (signed area > 0), holes negatively; the normal points out of the inside region.
"""

try:
    from activecontour import _kernels  # noqa: F401  (compiled loops, built at install by setup.py)
except ImportError as exc:  # a source tree that was never installed, or pulled new kernels
    raise ImportError(
        "activecontour's compiled kernels are not built: run `python3 -m pip install -e .` "
        "in the source tree (needs a C compiler)"
    ) from exc

from activecontour.batch import segment_many
from activecontour.energy import chan_vese_energy
from activecontour.image import load_image
from activecontour.initial import circle, rectangle
from activecontour.result import FlowState, SegmentationResult
from activecontour.segment import segment

__all__ = [
    "FlowState",
    "SegmentationResult",
    "chan_vese_energy",
    "circle",
    "load_image",
    "rectangle",
    "segment",
    "segment_many",
]

__version__ = "0.1.0"
