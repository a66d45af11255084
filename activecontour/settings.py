"""The settings of :func:`activecontour.segment`: its keywords, their defaults and their checks.

:class:`Settings` is a frozen dataclass with one field per keyword of ``segment`` but the image,
the init and the callback.  Every rule is stated once, here, with one message naming the keyword
and its valid values (TypeError for a value of the wrong type, ValueError for one out of range);
rules that need the image (its shape, its channels, the parameters' range in its intensity frame)
are checked where the image is read (:mod:`activecontour.problem`).  ``segment``, the evaluator,
sequences, batches, compat and the front ends read the defaults, the choices and the help from
here (:func:`setting_specs`); nothing inspects a signature.

This module imports numpy and the backends' registry only (no solver), so a front end's help
answers fast.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from activecontour.backends import BACKENDS, solver_for
from activecontour.models import NOISE_MODELS

__all__ = ["COLOR_MODES", "FITS", "INSIDE", "KINDS", "NOISES", "NORMALIZATIONS", "SettingSpec", "Settings",
           "setting_specs"]

#: ``color``: colour images converted to gray, or their channels kept (vector-valued (6.38)).
COLOR_MODES = ("gray", "vector")
#: ``normalize``: the image's own range onto [0, 1] (default), its dtype's range, or as given.
NORMALIZATIONS = ("range", "dtype", None)
#: ``fit``: the models of the regions' intensities.
FITS = ("constant", "smooth")
#: ``noise``: the fit term, (6.38)'s squared error or the likelihood of photon counts.
NOISES = tuple(NOISE_MODELS)
#: ``inside``: which region holds the objects.
INSIDE = ("auto", "bright", "dark")

#: The kinds of settings (:attr:`SettingSpec.kind`), for a front end that reads them from text:
#: one of ``choices``; a number; an integer; True or False; a number or one per channel (None
#: too where that is the default); a region of interest; an axis (or None); a backend's options
#: (a dict, see :mod:`activecontour.backends.options`).
KINDS = ("choice", "number", "integer", "flag", "channels", "roi", "axis", "options")


def _setting(default, help, kind, choices=None, auto=False):
    """A field of :class:`Settings`: its default and its metadata for the front ends."""
    return dataclasses.field(default=default, metadata={
        "help": help, "kind": kind, "choices": None if choices is None else tuple(choices), "auto": auto})


@dataclasses.dataclass(frozen=True, eq=False)
class Settings:
    """The keywords of :func:`activecontour.segment` (all but image, init and callback), checked.

    Construct it with keywords; a bad value raises at once, naming the keyword and its valid
    values.  :meth:`keywords` gives them back as ``segment``'s keyword arguments.  The fields'
    meanings are ``segment``'s (its docstring), in short in each field's ``help``
    (:func:`setting_specs`).

    Attributes
    ----------
    backend_options : dataclass instance
        ``options`` read into the options dataclass of the backend's two-region solver
        (:mod:`activecontour.backends.options`), once; its defaults when ``n_regions`` is not 2
        (more regions take no options).

    Raises
    ------
    TypeError
        For a value of the wrong type, or backend options that the chosen solver does not take.
    ValueError
        For a value out of range, or settings that do not go together (``c_in``/``c_out`` or
        ``roi`` with more than two regions).
    """

    backend: str = _setting(
        "polygon", "how the contour is represented: polygon (sub-pixel curves moved by the book's "
        "gradient flow) or levelset (a function on the pixel grid: objects split and merge freely)",
        "choice", BACKENDS)
    mu: object = _setting(
        "auto", "how much contour length costs: larger gives smoother, shorter outlines and "
        "removes small specks; auto sets it from the image's noise (mu of (6.38))", "number", auto=True)
    omega: float = _setting(
        0.0, "cost of the inside's area: positive shrinks the objects, negative grows them "
        "(omega)", "number")
    lambda_in: object = _setting(
        1.0, "weight of how closely the inside matches its intensity, > 0, one number or one per "
        "channel (lambda_in of (6.38))", "channels")
    lambda_out: object = _setting(
        1.0, "weight of how closely the outside matches its intensity, > 0, one number or one per "
        "channel (lambda_out of (6.38))", "channels")
    max_num_iter: int = _setting(
        500, "the most iterations to run (0: the start as it is)", "integer")
    tol: float = _setting(
        5e-4, "stop when the contour moves less than this many pixels per iteration", "number")
    c_in: object = _setting(
        None, "hold the objects' intensity at this value, one number or one per channel "
        "(default: fitted, (6.42))", "channels")
    c_out: object = _setting(
        None, "hold the background's intensity at this value, one number or one per channel "
        "(default: fitted, (6.42))", "channels")
    color: str = _setting(
        "gray", "colour images: gray (their brightness) or vector (every channel)", "choice", COLOR_MODES)
    normalize: object = _setting(
        "range", "intensity scale: range (the image's own darkest to brightest onto 0..1), dtype "
        "(its type's range) or None (as given)", "choice", NORMALIZATIONS)
    n_regions: object = _setting(
        2, "how many kinds of region: 2 (objects and background), more, or auto (counted from the "
        "image's intensities, 2..6)", "integer", auto=True)
    fit: str = _setting(
        "constant", "the regions' intensities: constant, or smooth (for uneven light: each region's "
        "intensity times a smooth light field shared by all)", "choice", FITS)
    noise: str = _setting(
        "gaussian", "the image's noise: gaussian (the squared error of (6.38)) or poisson (photon "
        "counts, as in fluorescence)", "choice", NOISES)
    inside: str = _setting(
        "auto", "which region is the objects: auto (the one touching less of the image border), "
        "bright or dark", "choice", INSIDE)
    roi: object = _setting(
        None, "where to look: a box (r0, c0, r1, c1), a mask, or init (around the start); "
        "default: the whole image", "roi")
    separate: bool = _setting(
        True, "give touching objects their own ids", "flag")
    min_size: object = _setting(
        "auto", "objects smaller than this many square pixels are left out of the objects (the "
        "contours keep them); auto: the size the length term removes, from mu and the regions' "
        "contrast", "number", auto=True)
    channel_axis: object = _setting(
        None, "the axis of a 3-D array that holds the colour channels (default: the last, when it "
        "has 1-4 entries)", "axis")
    options: object = _setting(
        None, "the backend's own settings (see the backends' options)", "options")

    def __post_init__(self):
        for field in dataclasses.fields(self):
            _CHECKS[field.name](field.name, getattr(self, field.name))
        self._check_regions()
        # read once, here: the run takes this instance
        object.__setattr__(self, "backend_options", solver_for(self.backend, 2).parse(self.options or {}))

    def _check_regions(self):
        """The rules between settings: what the solver of ``n_regions`` takes."""
        solver = self.solver
        if not solver.many_regions:
            return
        if self.c_in is not None or self.c_out is not None:
            raise ValueError("c_in and c_out fix the constants of two regions; leave them None for "
                             f"n_regions={self.n_regions}")
        if self.roi is not None and not solver.roi:
            raise ValueError(f"roi restricts the two-region model; it is not available with "
                             f"n_regions={self.n_regions}")
        if self.options:
            raise TypeError(f"options are the two-region backends' settings; n_regions={self.n_regions} "
                            "takes none")

    @property
    def solver(self):
        """The registry's record of the solver these settings run
        (:func:`activecontour.backends.solver_for`; ``n_regions="auto"`` as more than two)."""
        return solver_for(self.backend, self.n_regions)

    @classmethod
    def of(cls, keywords):
        """The settings of keyword arguments of :func:`activecontour.segment` (a sequence's, a
        batch's ``**segment_kwargs``).

        Raises
        ------
        TypeError
            For a keyword that is not a setting (one message listing the valid ones), and as the
            constructor.
        """
        unknown = sorted(set(keywords) - set(_FIELDS))
        if unknown:
            raise TypeError(f"unknown keyword(s) {', '.join(map(repr, unknown))} of segment; the valid "
                            f"ones are {', '.join(_FIELDS)}")
        return cls(**keywords)

    def keywords(self):
        """The settings as keyword arguments of :func:`activecontour.segment`."""
        return {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}


@dataclasses.dataclass(frozen=True)
class SettingSpec:
    """One setting, as a front end shows it.

    Attributes
    ----------
    name : str
    kind : str
        One of :data:`KINDS`.
    default : object
    help : str
        What it does, in a user's words (the book's symbols in parentheses).
    choices : tuple or None
        The valid values of a ``"choice"`` setting.
    auto : bool
        Whether ``"auto"`` is a valid value too.
    """

    name: str
    kind: str
    default: object
    help: str
    choices: tuple | None
    auto: bool


def setting_specs():
    """The settings in the order of :class:`Settings`' fields.

    Returns
    -------
    tuple of SettingSpec
    """
    return tuple(SettingSpec(field.name, field.metadata["kind"], field.default, field.metadata["help"],
                             field.metadata["choices"], field.metadata["auto"])
                 for field in dataclasses.fields(Settings))


# --------------------------------------------------------------------------------------------
# The rules, one per setting


def _is_number(value):
    return (isinstance(value, (int, float, np.integer, np.floating))
            and not isinstance(value, (bool, np.bool_)))


def _is_auto(value):
    return isinstance(value, str) and value == "auto"


def _number(rule, test):
    """A rule for a number: TypeError when ``value`` is not one, ValueError when ``test`` fails."""
    def check(name, value):
        if not _is_number(value):
            raise TypeError(f"{name} must be {rule}, got {value!r}")
        if not (np.isfinite(value) and test(value)):
            raise ValueError(f"{name} must be {rule}, got {value!r}")
    return check


def _choice(name, value):
    choices = _FIELDS[name].metadata["choices"]
    if not (isinstance(value, (str, type(None))) and value in choices):
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")


def _auto_or_at_least_zero(name, value):
    if not _is_auto(value):
        _number("a finite number >= 0 or 'auto'", lambda v: v >= 0)(name, value)


def _per_channel(rule, allow_none, test):
    """A rule for a number or one number per channel (a 1-D sequence)."""
    def check(name, value):
        if value is None and allow_none:
            return
        if isinstance(value, (bool, np.bool_, str)):
            raise TypeError(f"{name} must be {rule}, got {value!r}")
        try:
            array = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be {rule}, got {value!r}") from None
        if array.ndim > 1 or array.size == 0 or not np.all(np.isfinite(array)) or not np.all(test(array)):
            raise ValueError(f"{name} must be {rule}, got {value!r}")
    return check


def _integer(rule, test):
    def check(name, value):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"{name} must be {rule}, got {value!r}")
        if not test(value):
            raise ValueError(f"{name} must be {rule}, got {value!r}")
    return check


def _n_regions(name, value):
    rule = "an integer >= 2 or 'auto'"
    if isinstance(value, str):
        if not _is_auto(value):
            raise ValueError(f"{name} must be {rule}, got {value!r}")
        return
    _integer(rule, lambda v: v >= 2)(name, value)


def _roi(name, value):
    rule = "None, 'init', a bool mask or a box (r0, c0, r1, c1)"
    if value is None:
        return
    if isinstance(value, str):
        if value != "init":
            raise ValueError(f"{name} must be {rule}, got {value!r}")
        return
    array = np.asarray(value)
    if array.dtype == bool:
        if array.ndim != 2:
            raise ValueError(f"{name} must be {rule}, got a bool array of shape {array.shape}")
        return
    if array.shape != (4,) or not np.issubdtype(array.dtype, np.number):
        raise ValueError(f"{name} must be {rule}, got {value!r}")


def _flag(name, value):
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r}")


def _axis(name, value):
    if value is None:
        return
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer axis or None, got {value!r}")


def _options(name, value):
    if value is not None and not isinstance(value, dict):
        raise TypeError(f"{name} must be a dict or None, got {type(value).__name__}")


_FIELDS = {field.name: field for field in dataclasses.fields(Settings)}
_CHECKS = {
    "backend": _choice,
    "mu": _auto_or_at_least_zero,
    "omega": _number("a finite number", lambda v: True),
    "lambda_in": _per_channel("a finite number > 0 or one per channel", False, lambda a: a > 0),
    "lambda_out": _per_channel("a finite number > 0 or one per channel", False, lambda a: a > 0),
    "max_num_iter": _integer("an integer >= 0", lambda v: v >= 0),
    "tol": _number("a finite number >= 0", lambda v: v >= 0),
    "c_in": _per_channel("None, a finite number or one per channel", True, lambda a: True),
    "c_out": _per_channel("None, a finite number or one per channel", True, lambda a: True),
    "color": _choice,
    "normalize": _choice,
    "n_regions": _n_regions,
    "fit": _choice,
    "noise": _choice,
    "inside": _choice,
    "roi": _roi,
    "separate": _flag,
    "min_size": _auto_or_at_least_zero,
    "channel_axis": _axis,
    "options": _options,
}
