"""Backend options: every backend states its settings once, as a frozen dataclass.

A backend's options class (:class:`PolygonOptions`, :class:`LevelSetOptions`; :class:`NoOptions`
for the N-region solvers) is the one place of each setting's name, type, default, documentation
and valid range: ``field(metadata={"help": ...})`` made by :func:`option`, the range in the class's
``__post_init__``.  :func:`activecontour.segment` reads the ``options`` dict into it once, with
:func:`parse_options` (through :class:`activecontour.settings.Settings`), and the backend runs with
that instance; the front ends read the same fields through :func:`option_specs` (name, kind,
default, help, choices, typical values).

This module imports nothing but numpy, so the registry and the command line's help need no solver.
"""

from __future__ import annotations

import dataclasses
import types
import typing

import numpy as np

__all__ = ["LevelSetOptions", "NoOptions", "OptionSpec", "PolygonOptions", "option", "option_specs",
           "parse_options"]

#: The kinds of option values: a field's type, None allowed where it is ``T | None``.
_KINDS = (bool, int, float, str)


def option(default, help, choices=None, typical=None):
    """A field of an options dataclass: its default, its documentation, for text its choices and,
    for a number worth tuning, its ``typical`` (lowest, highest) values (the valid range is the
    class's ``__post_init__``; a front end offers the typical one, a slider say)."""
    metadata = {"help": help}
    if choices is not None:
        metadata["choices"] = tuple(choices)
    if typical is not None:
        metadata["typical"] = tuple(typical)
    return dataclasses.field(default=default, metadata=metadata)


@dataclasses.dataclass(frozen=True)
class OptionSpec:
    """One option of a backend, as the front ends show it.

    Attributes
    ----------
    name : str
    kind : {bool, int, float, str}
        The type of its values.
    default : object
        Its default value (None: chosen by the backend, see ``help``).
    help : str
        Its documentation.
    optional : bool
        Whether None is a valid value.
    choices : tuple or None
        The valid values of a text option.
    typical : tuple or None
        (lowest, highest) of the values worth trying, for a number worth tuning.
    """

    name: str
    kind: type
    default: object
    help: str
    optional: bool = False
    choices: tuple | None = None
    typical: tuple | None = None

    def check(self, value, backend):
        """The value as this option's kind (an integral float as an int, a number as a float), or
        TypeError (ValueError for a fractional integer or a text not among the choices) naming the
        option and the backend."""
        if value is None and self.optional:
            return None
        where, of = f"option {self.name!r}", f" (backend {backend!r})"
        number = isinstance(value, (int, float, np.integer, np.floating)) \
            and not isinstance(value, (bool, np.bool_))
        if self.kind is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{where} must be True or False, got {value!r}{of}")
            return bool(value)
        if self.kind is int:
            if not number:
                raise TypeError(f"{where} must be an integer, got {value!r}{of}")
            if not float(value).is_integer():
                raise ValueError(f"{where} must be an integer, got {value!r}{of}")
            return int(value)
        if self.kind is float:
            if not number:
                raise TypeError(f"{where} must be a number{' or None' if self.optional else ''}, "
                                f"got {value!r}{of}")
            return float(value)
        if not isinstance(value, str):
            raise TypeError(f"{where} must be text, got {value!r}{of}")
        if self.choices is not None and value not in self.choices:
            raise ValueError(f"{self.name} must be one of {self.choices}, got {value!r}{of}")
        return value


def option_specs(options_class):
    """The options of a backend's options dataclass, in the order of its fields.

    Returns
    -------
    tuple of OptionSpec
    """
    hints = typing.get_type_hints(options_class)
    specs = []
    for field in dataclasses.fields(options_class):
        kinds = typing.get_args(hints[field.name]) if isinstance(hints[field.name], types.UnionType) \
            else (hints[field.name],)
        kind = next(k for k in kinds if k in _KINDS)
        specs.append(OptionSpec(field.name, kind, field.default, field.metadata["help"],
                                optional=type(None) in kinds, choices=field.metadata.get("choices"),
                                typical=field.metadata.get("typical")))
    return tuple(specs)


def parse_options(options_class, backend, options):
    """The options dataclass of a backend from the ``options`` dict of :func:`activecontour.segment`.

    Parameters
    ----------
    options_class : type
        The backend's frozen options dataclass.
    backend : str
        The backend's name, for the messages.
    options : dict
        Option name -> value; the others keep their defaults.  Values are taken as their field's
        kind (:meth:`OptionSpec.check`: 2 for a float option is 2.0).

    Returns
    -------
    options_class instance

    Raises
    ------
    TypeError
        For an unknown option (one message naming the backend and listing the valid options) or
        a value of the wrong type.
    ValueError
        For a text option not among its choices, a fractional integer, or a value out of the
        option's range (the options class's ``__post_init__``).
    """
    specs = {spec.name: spec for spec in option_specs(options_class)}
    unknown = sorted(set(options) - set(specs))
    if unknown:
        raise TypeError(f"unknown option(s) {', '.join(map(repr, unknown))} for backend {backend!r}; "
                        f"the valid options are {', '.join(sorted(specs))}")
    return options_class(**{name: specs[name].check(value, backend) for name, value in options.items()})


# --------------------------------------------------------------------------------------------
# The backends' options

_VELOCITIES = ("h1", "l2")
_MIN_SPACING = 0.1  # pixels: the bilinear image has no detail finer than this needs


@dataclasses.dataclass(frozen=True)
class PolygonOptions:
    """The options of the polygon backend (``segment(..., options={...})``): each field's doc is
    its ``help`` (:func:`option_specs`)."""

    velocity: str = option("h1", "The bilinear form b: H^1 (6.39), the default, or L^2 (6.25).",
                           choices=_VELOCITIES)
    spacing: float = option(1.0, (
        f"Target distance between vertices, in pixels (>= {_MIN_SPACING}).  About one vertex per pixel "
        "resolves everything the image resolves; the cost of an iteration grows with the curve's length "
        "in pixels either way."))
    max_step: float = option(8.0, (
        "Largest root-mean-square vertex displacement of a trial step, in pixels (> 0).  Steps "
        "double while they are accepted, up to this; backtracking halves them."), typical=(0.25, 10.0))
    smoothing: float | None = option(None, (
        "First length l in b(V, Y) = int V.Y + l^2 int grad V : grad Y, in pixels (smoothing >= "
        "min_smoothing).  The book's (6.39) is l = 1 in its units.  In pixel units l = 1 barely "
        "smooths: on noisy images the fastest (noise-driven) vertex then caps the step and the bulk "
        "of the curve crawls; a large l alone spreads every local force over l pixels and fills "
        "corners slowly.  Coarse to fine gets both.  None (default): 30 px from curves or a mask "
        "given as init, and 2 px from the default start (init=None), from a previous result and "
        "after the global move (global_start), which already lie on the objects' boundaries "
        "(measured on benchmarks/bench_robust.py: the same Dice to +-0.0002 in a third to a half "
        "of the iterations)."))
    min_smoothing: float = option(1.0, "Last length l of the coarse-to-fine H^1 metric, in pixels (>= 0).")
    min_area: float = option(4.0, (
        "Curves enclosing less than this many square pixels are removed (when that does not raise "
        "the energy), e.g. circles of a grid start that shrink away on the background."))
    nucleate: bool = option(True, (
        "When the flow has converged, look for holes and new components that lower the energy (the "
        "topological derivative, activecontour.geometry.topology.nucleation_sites), insert small circles "
        "there and continue; repeated at most a few times.  This is how a single initial curve "
        "finds a hole or a second object it cannot reach by deformation."))
    accelerate: bool = option(True, (
        "Combine the velocity with the last few steps (limited-memory BFGS in the metric b: the "
        "first inverse Hessian guess is b^-1, so without memory the step is the book's velocity).  "
        "Near a minimum the plain flow converges slowly along the directions the metric and the "
        "energy weigh differently; this takes them in one step.  Every step still passes the same "
        "descent test.  The memory is cleared when the vertices change and at each new stage."))
    global_start: bool = option(True, (
        "From curves, a mask or 'grid' given as init, the first iteration is a global move: to the "
        "default start's threshold set (activecontour.initial.threshold_starts) or its complement, "
        "whichever has the lower (6.38), when that is lower than the given curves' energy (the "
        "first half of Chan and Vese's alternating minimisation), so the flow then only settles "
        "details: on scikit-image's camera, from a drawn rectangle, ~70 iterations instead of "
        "~1000 to the same J within 1 %.  False keeps the flow local to the given curves."))

    def __post_init__(self):
        if not (np.isfinite(self.spacing) and self.spacing >= _MIN_SPACING):
            raise ValueError(f"spacing must be a number of pixels >= {_MIN_SPACING} (vertices closer than "
                             f"the image resolves only cost time), got {self.spacing!r}")
        if not (np.isfinite(self.max_step) and self.max_step > 0):
            raise ValueError(f"max_step must be a positive number of pixels, got {self.max_step!r}")
        smoothing, min_smoothing = self.smoothing, self.min_smoothing
        if not (np.isfinite(min_smoothing) and (smoothing is None or np.isfinite(smoothing))
                and (smoothing is None or smoothing >= min_smoothing) and min_smoothing >= 0):
            raise ValueError(
                f"smoothing and min_smoothing must be pixel lengths with smoothing >= min_smoothing >= 0, "
                f"got {smoothing!r} and {min_smoothing!r}"
            )
        if not (np.isfinite(self.min_area) and self.min_area >= 0):
            raise ValueError(f"min_area must be a number of square pixels >= 0, got {self.min_area!r}")


#: The level set's step bounds when not given: ``dt_min`` (or ``dt`` when smaller) and ``dt_max``
#: (or ``dt`` when larger), see :meth:`LevelSetOptions.step_bounds`.
_DT_MIN, _DT_MAX = 1.0, 64.0


@dataclasses.dataclass(frozen=True)
class LevelSetOptions:
    """The options of the level-set backend (``segment(..., options={...})``): each field's doc is
    its ``help`` (:func:`option_specs`)."""

    dt: float = option(16.0, (
        "First step, pixels of travel at the typical force, at most half the width of the start's "
        "regions (but not below dt_min)."), typical=(_DT_MIN, _DT_MAX))
    dt_min: float | None = option(None, (
        "Below this ceiling the smoothed-force stages end and the unsmoothed stage runs, with steps "
        "up to dt_min and the force within the band only (no single pixel far from Gamma flips).  "
        f"None (default): {_DT_MIN:g} px, or dt when dt is smaller."))
    dt_max: float | None = option(None, (
        "Largest step (pixels), the ceiling of the first stage.  None (default): "
        f"{_DT_MAX:g} px, or dt when dt is larger.  Bounds given explicitly must satisfy "
        "dt_min <= dt <= dt_max."))
    band: float = option(4.0, (
        "Narrow band: phi is the signed distance up to band pixels from Gamma and is clipped to "
        "+-band beyond.  At least 2."))
    checkerboard_period: float = option(16.0, "Side (pixels) of the squares of the 'checkerboard' start.")
    max_backtracks: int = option(3, (
        "Halvings of the step of the final stage before an iteration counts as stationary."))

    def __post_init__(self):
        for name in ("dt", "dt_min", "dt_max", "band", "checkerboard_period"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise ValueError(f"option {name!r} must be a positive finite number, got {value!r}")
        if self.max_backtracks < 0:
            raise ValueError(f"option 'max_backtracks' must be an integer >= 0, got {self.max_backtracks!r}")
        dt_min, dt_max = self.step_bounds()
        if not dt_min <= self.dt <= dt_max:
            raise ValueError(f"options must satisfy dt_min <= dt <= dt_max, got dt_min={dt_min}, "
                             f"dt={self.dt}, dt_max={dt_max}")
        if self.band < 2.0:
            raise ValueError(f"option 'band' must be at least 2 (pixels), got {self.band}")

    def step_bounds(self):
        """``(dt_min, dt_max)``: as given, or the defaults widened to include ``dt`` (a viewer's
        step slider, say)."""
        dt_min = min(_DT_MIN, self.dt) if self.dt_min is None else self.dt_min
        dt_max = max(_DT_MAX, self.dt) if self.dt_max is None else self.dt_max
        return dt_min, dt_max


@dataclasses.dataclass(frozen=True)
class NoOptions:
    """The options of a solver that takes none (the N-region solvers)."""
