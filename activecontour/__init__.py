"""activecontour: sub-pixel Chan-Vese active contours.

The method is section 6.5 of *The Shapes of Things* (S. W. Walker): the Chan-Vese functional (6.38)
minimised by the gradient flow (6.30)-(6.31) with the H^1 velocity (6.39)-(6.40) and the shape
derivative (6.41), on a polygon, or on a level-set function over the pixel grid.

Parts (arrows point down only: a room imports the rooms below it, never one above)
-----
segment            the entry point: ``segment(image, init, backend=..., mu=..., ...)`` (_segment)
Settings           segment's keywords: defaults, choices, help and checks, stated once (settings)
segment_sequence   a time-lapse or z-stack, each frame from the last, objects tracked (sequence/)
segment_many       many images in worker processes, results as they finish (also on Dask: batch/)
SegmentationResult the result of every backend (result)
chan_vese_energy   the common evaluator of (6.38) for any contours (evaluate)
circle, rectangle  initial curves; the default start (initial)
problem            prepare(image, settings): the working frame, noise, mu, parameters, model
backends/          the registry of solvers: polygon (the book's H^1 flow), network (N regions),
                   levelset/, labelfield; their options (backends.options)
objects/           the label image, measurements, touching objects kept apart, metrics
energy             the discrete functional and its shape derivative (6.41) on stacked curves
models/            the integrands: two regions, N regions, smooth light, Poisson
imaging/           normalisation, working frame, image tables, noise level and default mu, roi
geometry/          curves (tangent, normal, curvature), P1 elements, crossings, rasters, regions
io/                every reader and writer: images, stacks, videos, contours, masks, overlays,
                   object formats; atomic writes
synthetic          anti-aliased test images with exact ground truth
compat             scikit-image's signatures: ``from activecontour.compat import chan_vese``
_kernels           the compiled loops (Cython, built at install)

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

#: Each public name and the module that defines it, imported on first use (PEP 562): ``import
#: activecontour`` loads no solver, and ``activecontour --help`` answers without one.
_PUBLIC = {
    "FlowState": "activecontour.result",
    "SegmentationResult": "activecontour.result",
    "SequenceResult": "activecontour.sequence.results",
    "Settings": "activecontour.settings",
    "chan_vese_energy": "activecontour.evaluate",
    "circle": "activecontour.initial",
    "iter_sequence": "activecontour.sequence.results",
    "load_image": "activecontour.io.images",
    "rectangle": "activecontour.initial",
    "segment": "activecontour._segment",
    "segment_many": "activecontour.batch",
    "segment_sequence": "activecontour.sequence.results",
}

__all__ = sorted(_PUBLIC)

__version__ = "0.1.0"


def __getattr__(name):
    """A public name, or a submodule (``activecontour.initial``), imported on first use."""
    import importlib
    import importlib.util

    if name in _PUBLIC:
        value = getattr(importlib.import_module(_PUBLIC[name]), name)
    elif not name.startswith("__") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # found directly from now on
    return value


def __dir__():
    return sorted({*globals(), *__all__})
