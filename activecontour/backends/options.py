"""Backend options: every backend states its settings once, as a frozen dataclass.

A backend's options class (:class:`activecontour.backends.polygon.PolygonOptions`,
:class:`activecontour.backends.levelset.LevelSetOptions`) is the one place of each setting's name,
type, default and documentation (``field(metadata={"help": ...})``, made by :func:`option`).  The
backend builds it from the ``options`` of :func:`activecontour.segment` with
:func:`parse_options`; the CLI (``--option KEY=VALUE`` and its help) and the viewer (its sliders'
defaults) read the same fields through :func:`option_specs`.
"""

from __future__ import annotations

import dataclasses
import types
import typing

import numpy as np

__all__ = ["OptionSpec", "option", "option_specs", "parse_options"]

#: The kinds of option values: a field's type, None allowed where it is ``T | None``.
_KINDS = (bool, int, float, str)


def option(default, help, choices=None, slider=None):
    """A field of an options dataclass: its default, its documentation, for text its choices, and
    for the backend's "step" option the viewer's slider ``(label, lowest, highest)``."""
    metadata = {"help": help}
    if choices is not None:
        metadata["choices"] = tuple(choices)
    if slider is not None:
        metadata["slider"] = tuple(slider)
    return dataclasses.field(default=default, metadata=metadata)


@dataclasses.dataclass(frozen=True)
class OptionSpec:
    """One option of a backend, as the CLI and the viewer show it.

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
    slider : tuple or None
        ``(label, lowest, highest)`` of the viewer's slider of this option (one per backend).
    """

    name: str
    kind: type
    default: object
    help: str
    optional: bool = False
    choices: tuple | None = None
    slider: tuple | None = None

    def check(self, value, backend):
        """Raise TypeError (ValueError for a fractional integer or a text not among the choices)
        naming the option and the backend when ``value`` is not of this option's kind."""
        if value is None and self.optional:
            return
        where, of = f"option {self.name!r}", f" (backend {backend!r})"
        number = isinstance(value, (int, float, np.integer, np.floating)) \
            and not isinstance(value, (bool, np.bool_))
        if self.kind is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{where} must be True or False, got {value!r}{of}")
        elif self.kind is int:
            if not number:
                raise TypeError(f"{where} must be an integer, got {value!r}{of}")
            if not float(value).is_integer():
                raise ValueError(f"{where} must be an integer, got {value!r}{of}")
        elif self.kind is float:
            if not number:
                raise TypeError(f"{where} must be a number{' or None' if self.optional else ''}, "
                                f"got {value!r}{of}")
        elif not isinstance(value, str):
            raise TypeError(f"{where} must be text, got {value!r}{of}")
        elif self.choices is not None and value not in self.choices:
            raise ValueError(f"{self.name} must be one of {self.choices}, got {value!r}{of}")


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
                                slider=field.metadata.get("slider")))
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
        Option name -> value; the others keep their defaults.

    Returns
    -------
    options_class instance

    Raises
    ------
    TypeError
        For an unknown option (one message naming the backend and listing the valid options) or
        a value of the wrong type.
    ValueError
        For a text option not among its choices or a fractional integer.
    """
    specs = {spec.name: spec for spec in option_specs(options_class)}
    unknown = sorted(set(options) - set(specs))
    if unknown:
        raise TypeError(f"unknown option(s) {', '.join(map(repr, unknown))} for backend {backend!r}; "
                        f"the valid options are {', '.join(sorted(specs))}")
    for name, value in options.items():
        specs[name].check(value, backend)
    return options_class(**options)

