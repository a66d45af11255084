"""The ``activecontour`` parser, built from the library's settings and registries.

Each setting of :func:`activecontour.segment` that a command line can give is one option: its
name, default, choices and help come from the library (:func:`setting_fields`), so a new choice of
backend, model or noise shows here without an edit.  Parsing turns text into values only; the
library checks them, once, when the run's settings are made (:func:`settings_from`).

``--help`` wraps at 100 columns and answers without importing a backend or the image libraries.
"""

from __future__ import annotations

import argparse
import shutil

from . import stacks, starts
from .errors import EXIT_USAGE, PROG

__all__ = ["build_parser", "option_name", "settings_from"]

#: The settings' options spelled otherwise than ``--name-with-dashes``.
SPELLING = {"max_num_iter": "--max-iter", "n_regions": "--regions"}
#: The settings listed first; the others go to "less common options" at the end of --help.
COMMON = ("backend", "mu", "n_regions", "inside", "fit", "noise")
#: Help lines wrap at this many columns at most.
WIDTH = 100


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (no usage block), exit status 2."""

    def error(self, message):
        self.exit(EXIT_USAGE, f"{PROG}: error: {message} (see '{self.prog} --help')\n")


class _Formatter(argparse.HelpFormatter):
    """Help at most :data:`WIDTH` columns wide (narrower on a narrower terminal); descriptions keep
    their line breaks, each line wrapped with its own indent."""

    def __init__(self, prog):
        width = min(WIDTH, shutil.get_terminal_size((WIDTH, 24)).columns)
        super().__init__(prog, width=width, max_help_position=32)

    def _fill_text(self, text, width, indent):
        import textwrap

        lines = []
        for line in text.splitlines():
            inner = indent + line[:len(line) - len(line.lstrip())]
            lines.append(textwrap.fill(line.strip(), width, initial_indent=inner,
                                       subsequent_indent=inner + "    ") if line.strip() else "")
        return "\n".join(lines)


def build_parser():
    """The argparse parser with the ``segment`` and ``view`` subcommands."""
    parser = _Parser(prog=PROG, formatter_class=_Formatter,
                     description="Find the outlines of objects in images (Chan-Vese active contours).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _segment_parser(commands)
    _view_parser(commands)
    return parser


def _segment_parser(commands):
    from pathlib import Path

    segment = commands.add_parser(
        "segment", formatter_class=_Formatter, usage="%(prog)s [options] IMAGE [IMAGE ...]",
        help="segment images and write mask, overlay and contour files",
        description="Segment each IMAGE and write <name>_mask.png (the objects in white), "
        "<name>_overlay.png (the outlines drawn on the image) and <name>_contours.json next to it, "
        "or into --output.  A multi-page TIFF or a video is segmented as a sequence, its objects "
        "tracked from frame to frame.")
    segment.add_argument("images", nargs="+", metavar="IMAGE",
                         help="image files, folders (the images in them) or quoted patterns such as "
                         "'data/*.tif'")
    segment.add_argument("-o", "--output", metavar="DIR", type=Path,
                         help="write here, made if missing (default: next to each image)")
    segment.add_argument("-j", "--jobs", type=_int_at_least(1), default=None, metavar="N",
                         help="segment N images at a time (default: one per core)")
    segment.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    _output_options(segment, rare=False)
    _settings_options(segment, rare=False)
    starts.add_options(segment)
    rare = segment.add_argument_group("less common options")
    _settings_options(rare, rare=True)
    _output_options(rare, rare=True)
    stacks.add_options(rare)
    segment.epilog = _backend_options_listing()
    segment.set_defaults(run="segment")


def _view_parser(commands):
    view = commands.add_parser(
        "view", formatter_class=_Formatter, usage="%(prog)s [options] IMAGE",
        help="open the interactive viewer on one image",
        description="Watch the outline move on IMAGE; draw the start with the mouse and change "
        "the settings while it runs.")
    view.add_argument("image", metavar="IMAGE", help="an image file")
    view.add_argument("--format", dest="formats", type=_formats, default=None, metavar="FMT[,FMT...]",
                      help="the contour files the viewer's Save writes (default: json)")
    _settings_options(view, rare=False)
    starts.add_options(view)
    rare = view.add_argument_group("less common options")
    _settings_options(rare, rare=True, backend_options=False)
    _max_pixels(rare)
    view.set_defaults(run="view")


def _output_options(parser, *, rare):
    """The options of ``segment``'s files: the common ones, or (``rare``) the others."""
    from activecontour.io.contours import CONTOUR_FORMATS
    from activecontour.io.objects import OBJECT_FORMATS

    if not rare:
        parser.add_argument("--format", dest="formats", type=_formats, default=["json"],
                            metavar="FMT[,FMT...]",
                            help=f"contour files, any of {', '.join(CONTOUR_FORMATS)} (default: json)")
        parser.add_argument("--objects", type=_object_formats, default=[], metavar="FMT[,FMT...]",
                            help=f"files with one id per object, any of {', '.join(OBJECT_FORMATS)} "
                            "(default: none)")
        return
    parser.add_argument("--line-color", "--overlay-color", dest="line_color", type=_line_color,
                        default="auto", metavar="COLOR",
                        help="the outline's colour in the overlay: a name such as red or cyan, "
                        "R,G,B in 0..255, or auto: one that stands out from the image (default: auto)")
    parser.add_argument("--line-width", type=_line_width, default="auto", metavar="PX",
                        help="the outline's width in the overlay, in pixels, or auto: 1 px per "
                        "1024 px of the overlay's longer side (default: auto)")
    _max_pixels(parser)


def _max_pixels(parser):
    from activecontour.io.images import MAX_PIXELS

    parser.add_argument("--max-pixels", type=_int_at_least(1), default=MAX_PIXELS, metavar="N",
                        help="refuse images of more pixels (about 30 bytes of memory each) and "
                        "contour files of more vertices (default: %(default)s = 2**27)")


def _settings_options(parser, *, rare, backend_options=True):
    """One option per setting of :func:`activecontour.segment` (the common ones, or the others)."""
    for field in setting_fields():
        if (field.name in COMMON) == rare:
            continue
        kwargs = {"dest": field.name, "default": field.default, "help": field.help}
        if field.choices is not None:
            kwargs.update(choices=field.choices, metavar="{" + ",".join(map(str, field.choices)) + "}")
        else:
            kwargs.update(type=field.parse, metavar=field.metavar)
        parser.add_argument(option_name(field.name), **kwargs)
    if rare and backend_options:
        parser.add_argument("--option", dest="options", action="append", type=_key_value, default=None,
                            metavar="KEY=VALUE", help=_backend_options_help())


def option_name(name):
    """The command-line option of the setting ``name``."""
    return SPELLING.get(name, "--" + name.replace("_", "-"))


def settings_from(args):
    """The run's settings from the parsed arguments, checked by the library: one line naming the
    option when it refuses them."""
    from ..messages import one_line
    from .errors import UsageError

    given = {field.name: getattr(args, field.name) for field in setting_fields()}
    if getattr(args, "options", None):
        given["options"] = dict(args.options)
    try:
        return make_settings(given)
    except (ValueError, TypeError) as exc:
        raise UsageError(with_option_names(one_line(exc))) from None


def with_option_names(message):
    """A library message about ``lambda_in`` etc., with the option's spelling in front."""
    for field in setting_fields():
        if message.startswith((field.name + " ", field.name + ",", field.name + ":")):
            return f"{option_name(field.name)}: {message}"
    if message.startswith("option "):
        return f"--option {message.removeprefix('option ')}"
    return message


def _backend_options_help():
    return "a setting of the backend (listed below), e.g. max_step=2; repeatable"


def _backend_options_listing():
    """Every backend's ``--option`` settings, from its options dataclass: name, default and the
    first sentence of its help."""
    import re

    from activecontour.backends import BACKENDS

    lines = ["backend options (--option KEY=VALUE):"]
    for name, backend in BACKENDS.items():
        lines.append(f"  --backend {name}:")
        for spec in backend.option_specs():
            default = "automatic" if spec.default is None else str(spec.default).lower() \
                if spec.kind is bool else spec.default
            first = re.sub(r" \([^()]*\)", "", spec.help.split(".  ")[0]).rstrip(".")  # no asides
            line = f"    {spec.name}={default}: {first}"
            lines.append(line if len(line) <= WIDTH else line[:WIDTH - 1] + "\N{HORIZONTAL ELLIPSIS}")
    return "\n".join(lines)


def _version():
    import activecontour

    return activecontour.__version__


# ------------------------------------------------------------------------------ text to values
def _key_value(text):
    """``--option`` KEY=VALUE: the value read as an int, a float, true/false, or else kept as text."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip().isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    return key.strip(), value_of(value.strip())


def value_of(text):
    """A number (int or float), true/false, or the text itself."""
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def _formats(text):
    from activecontour.io.contours import CONTOUR_FORMATS

    return _listed(text, CONTOUR_FORMATS, "format", lambda f: f.lower().lstrip("."))


def _object_formats(text):
    from activecontour.io.objects import OBJECT_FORMATS

    return _listed(text, OBJECT_FORMATS, "object format", str.lower)


def _listed(text, choices, what, normal):
    formats = [normal(f.strip()) for f in text.split(",") if f.strip()]
    unknown = [f for f in formats if f not in choices]
    if not formats or unknown:
        raise argparse.ArgumentTypeError(
            f"unknown {what} {(unknown or [text])[0]!r}; choose from {', '.join(choices)}")
    return list(dict.fromkeys(formats))


def _line_color(text):
    """``--line-color``: "auto", a colour name or R,G,B in 0..255."""
    from activecontour.io.pictures import COLORS

    if text.lower() in ("auto", *COLORS):
        return text.lower()
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(0 <= v <= 255 for v in values):
        raise argparse.ArgumentTypeError(
            f"must be auto, one of {', '.join(COLORS)} or R,G,B in 0..255, got {text!r}")
    return values


def _line_width(text):
    return text if text == "auto" else _int_at_least(1)(text)


def _int_at_least(low):
    """An argparse type: an integer >= ``low``."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < low:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}")
        return value

    parse.__name__ = f"integer >= {low}"
    return parse


# --------------------------------------------------------------------------- interim: the fields
class _Field:
    def __init__(self, name, default, help, choices=None, parse=None, metavar=None):
        self.name, self.default, self.help, self.choices = name, default, help, choices
        self.parse, self.metavar = parse, metavar


def setting_fields():
    """Interim, until ``activecontour.settings`` lands: the settings a command line gives."""
    import inspect

    from activecontour._segment import FITS, INSIDE, segment
    from activecontour.backends import BACKENDS
    from activecontour.models import NOISES

    defaults = {n: p.default for n, p in inspect.signature(segment).parameters.items()}

    def number(text):
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None

    def number_or_auto(text):
        return text if text == "auto" else number(text)

    def integer(text):
        try:
            return int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None

    def regions(text):
        if text == "auto":
            return text
        try:
            return int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= 2 or 'auto', got {text!r}") from None

    def numbers(text):
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number or comma-separated numbers, got {text!r}") \
                from None
        return values[0] if len(values) == 1 else values

    fields = [
        _Field("backend", defaults["backend"], "polygon: sub-pixel outlines; levelset: outlines on the "
               "pixel grid that split and merge freely (default: %(default)s)", tuple(BACKENDS)),
        _Field("mu", defaults["mu"], "how smooth the outline is: larger removes more detail and "
               "noise; auto: from the image's noise (default: %(default)s)", None, number_or_auto, "MU|auto"),
        _Field("omega", defaults["omega"], "> 0 shrinks, < 0 grows the objects (default: %(default)s)",
               None, number, "OMEGA"),
        _Field("lambda_in", defaults["lambda_in"], "weight of the objects' fit, > 0 (default: %(default)s)",
               None, number, "L"),
        _Field("lambda_out", defaults["lambda_out"], "weight of the background's fit, > 0 "
               "(default: %(default)s)", None, number, "L"),
        _Field("max_num_iter", defaults["max_num_iter"], "stop after N iterations (default: %(default)s)",
               None, integer, "N"),
        _Field("tol", defaults["tol"], "stop when the outline moves less than this many pixels per "
               "iteration (default: %(default)s)", None, number, "TOL"),
        _Field("c_in", None, "the objects' intensity, held fixed: a number, or one per channel "
               "separated by commas (default: found)", None, numbers, "C"),
        _Field("c_out", None, "the background's intensity, held fixed (default: found)", None, numbers, "C"),
        _Field("color", defaults["color"], "colour images: as gray, or every channel (default: %(default)s)",
               ("gray", "vector")),
        _Field("inside", defaults["inside"], "which region is the objects: auto (the one touching less "
               "of the border), bright or dark (default: %(default)s)", INSIDE),
        _Field("n_regions", defaults["n_regions"], "the number of intensity classes, 2 or more, or auto; "
               "not 2: <name>_classes.png too (default: %(default)s)", None, regions, "K|auto"),
        _Field("fit", defaults["fit"], "smooth: for uneven light, a smooth light field times each "
               "region's intensity (default: %(default)s)", FITS),
        _Field("noise", defaults["noise"], "poisson: for photon counts such as fluorescence "
               "(default: %(default)s)", NOISES),
    ]
    return fields


class _Settings(dict):
    def __getattr__(self, name):
        return self[name]

    def keywords(self):
        return dict(self)


def make_settings(given):
    """Interim, until ``activecontour.settings`` lands: the settings, checked as segment checks them."""
    import math

    from activecontour.backends import BACKENDS
    from activecontour.models import ChanVeseParameters

    settings = _Settings(given)
    if settings["max_num_iter"] < 0:
        raise ValueError(f"max_num_iter must be >= 0, got {settings['max_num_iter']}")
    if not (math.isfinite(settings["tol"]) and settings["tol"] >= 0):
        raise ValueError(f"tol must be a finite number >= 0, got {settings['tol']!r}")
    if settings["n_regions"] != "auto" and settings["n_regions"] < 2:
        raise ValueError(f"n_regions must be an integer >= 2 or 'auto', got {settings['n_regions']!r}")
    if "options" in settings:
        specs = {spec.name: spec for spec in BACKENDS[settings["backend"]].option_specs()}
        for key, value in settings["options"].items():
            if key in specs:
                specs[key].check(value, settings["backend"])
    ChanVeseParameters(0.0 if settings["mu"] == "auto" else settings["mu"], settings["omega"],
                       settings["lambda_in"], settings["lambda_out"], settings["c_in"], settings["c_out"])
    return settings
