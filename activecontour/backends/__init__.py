"""The backends: each minimises the Chan-Vese functional (6.38) over its own representation.

polygon     the book's H^1 gradient flow of a polygon: :mod:`activecontour.backends.polygon`
levelset    a level set over the pixel grid: redistancing, zero set, scheme and driver
labelfield  N regions on the pixel grid: a label field from the global K-means (``n_regions > 2``)
"""

from __future__ import annotations

import dataclasses
import importlib

__all__ = ["BACKENDS", "Backend"]


@dataclasses.dataclass(frozen=True)
class Backend:
    """A two-region backend of :func:`activecontour.segment`: where its run function and its
    options dataclass live (imported on first use).

    The run function is called as ``run(model, init, params, *, max_num_iter, tol, callback,
    **options)`` and returns a :class:`~activecontour.result.SegmentationResult` built by
    :func:`activecontour.result.build_result`; it reads its options with
    :func:`activecontour.backends.options.parse_options` from its options class.
    """

    module: str
    run_name: str
    options_name: str

    @property
    def run(self):
        """The backend's function."""
        return getattr(importlib.import_module(self.module), self.run_name)

    @property
    def options(self):
        """The backend's frozen options dataclass."""
        return getattr(importlib.import_module(self.module), self.options_name)

    def option_specs(self):
        """The options (name, kind, default, help): :func:`activecontour.backends.options.option_specs`."""
        from activecontour.backends.options import option_specs

        return option_specs(self.options)

    def step_slider(self):
        """``(option, label, lowest, highest)`` of the viewer's "step" slider: the option marked
        with a slider (:func:`activecontour.backends.options.option`), or None."""
        return next(((spec.name, *spec.slider) for spec in self.option_specs() if spec.slider), None)


#: backend name -> its record; a new backend is its own module and one line here.
BACKENDS = {
    "polygon": Backend("activecontour.backends.polygon", "segment_polygon", "PolygonOptions"),
    "levelset": Backend("activecontour.backends.levelset.driver", "segment_levelset", "LevelSetOptions"),
}
