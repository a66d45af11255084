"""The backends: each minimises the Chan-Vese functional (6.38) over its own representation.

The registry: one :class:`Solver` record per solver, with its run function (imported on first
use), its options dataclass (:mod:`activecontour.backends.options`) and what it supports.
:func:`activecontour.segment` picks the record of its ``backend`` and number of regions
(:func:`solver_for`); the front ends take their choices and options from :data:`BACKENDS`.

polygon     the book's H^1 gradient flow of a polygon: :mod:`activecontour.backends.polygon`
network     N regions on the polygon backend: the H^1 flow of the regions' boundary network
levelset    a level set over the pixel grid: redistancing, zero set, scheme and driver
labelfield  N regions on the pixel grid: a label field from the global K-means

A new solver is its own module and one record here.
"""

from __future__ import annotations

import dataclasses
import importlib

from activecontour.backends.options import (
    LevelSetOptions,
    NoOptions,
    PolygonOptions,
    option_specs,
    parse_options,
)

__all__ = ["BACKENDS", "INITS", "SOLVERS", "Solver", "solver_for"]

#: The kinds of ``init`` a solver may accept (:attr:`Solver.inits`): None (the default start),
#: curves, a bool mask, a previous result, a label image (N regions), and the named starts.
INITS = ("default", "curves", "mask", "result", "labels", "grid", "checkerboard")


@dataclasses.dataclass(frozen=True)
class Solver:
    """One solver of :func:`activecontour.segment`: a registry record.

    Attributes
    ----------
    name : str
        The solver's name (the result's ``backend`` is its ``backend``).
    backend : str
        The ``backend`` keyword that selects it; ``many_regions`` tells which of the backend's
        solvers.
    help : str
        What it is, in a user's words.
    module, function : str
        Where its run function lives (imported on first use, see :attr:`run`).
    options : type
        Its frozen options dataclass (:mod:`activecontour.backends.options`).
    many_regions : bool
        False: the two regions of (6.38); True: ``n_regions > 2``.
    roi : bool
        Whether it solves on a restricted domain (``segment(roi=...)``).
    inits : tuple of str
        The kinds of ``init`` it accepts, from :data:`INITS`.
    """

    name: str
    backend: str
    help: str
    module: str
    function: str
    options: type
    many_regions: bool
    roi: bool
    inits: tuple

    @property
    def run(self):
        """The run function, ``run(model, init, params, *, max_num_iter, tol, callback, options)``
        for two regions and ``run(model, init, params, *, n_regions, max_num_iter, tol, callback)``
        for more; it returns a :class:`~activecontour.result.SegmentationResult` in the frame of
        ``model``."""
        return getattr(importlib.import_module(self.module), self.function)

    def option_specs(self):
        """The options (name, kind, default, help, choices, typical values), from the options dataclass
        (:func:`~activecontour.backends.options.option_specs`)."""
        return option_specs(self.options)

    def parse(self, options):
        """The options dataclass from an ``options`` dict, checked
        (:func:`~activecontour.backends.options.parse_options`)."""
        return parse_options(self.options, self.backend, options)

    def solve(self, model, init, params, *, options, n_regions, max_num_iter, tol, callback):
        """Run the solver: its options (two regions) or the number of regions (more)."""
        if self.many_regions:
            return self.run(model, init, params, n_regions=n_regions, max_num_iter=max_num_iter, tol=tol,
                            callback=callback)
        return self.run(model, init, params, max_num_iter=max_num_iter, tol=tol, callback=callback,
                        options=options)


_CURVES = ("default", "curves", "mask", "result", "grid")
_CLASSES = ("default", "labels", "result")

#: solver name -> its record.
SOLVERS = {solver.name: solver for solver in (
    Solver("polygon", "polygon", "sub-pixel polygons moved by the book's gradient flow",
           "activecontour.backends.polygon", "segment_polygon", PolygonOptions, False, True, _CURVES),
    Solver("network", "polygon", "the regions' boundaries as one network of sub-pixel curves",
           "activecontour.backends.network", "segment_network", NoOptions, True, False, _CLASSES),
    Solver("levelset", "levelset", "a function on the pixel grid: objects split and merge freely",
           "activecontour.backends.levelset.driver", "segment_levelset", LevelSetOptions, False, True,
           (*_CURVES, "checkerboard")),
    Solver("labelfield", "levelset", "a label per pixel", "activecontour.backends.labelfield",
           "segment_labels", NoOptions, True, False, _CLASSES),
)}

#: backend name (the ``backend`` keyword) -> the record of its two-region solver, whose options
#: are the backend's options.
BACKENDS = {solver.backend: solver for solver in SOLVERS.values() if not solver.many_regions}


def solver_for(backend, n_regions):
    """The record of the solver ``segment(backend=..., n_regions=...)`` runs; ``"auto"`` counts as
    more than two regions (it may choose them)."""
    many = isinstance(n_regions, str) or n_regions != 2
    return next(solver for solver in SOLVERS.values()
                if solver.backend == backend and solver.many_regions == many)
