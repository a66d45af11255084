"""The ``activecontour`` parser, built from the library's settings and registries.

Each setting of :func:`activecontour.segment` that the command line gives (:data:`OPTIONS`) is one
option whose default, choices, help and kind come from the library
(:func:`activecontour.settings.setting_specs`), so a new choice of backend, model or noise shows
here without an edit; ``--option`` lists every backend's options from its options dataclass.
Parsing turns text into values only; the library checks them, once, when the run's settings are
made (:func:`settings_from`), and its refusal is one line naming the option.

``--help`` wraps at 100 columns and answers without importing a backend or the image libraries.
"""

from __future__ import annotations

import argparse
import shutil

from . import stacks, starts
from .errors import EXIT_USAGE, PROG

__all__ = ["OPTIONS", "build_parser", "recorded", "settings_from", "with_option_names"]

#: The settings the command line gives, and their options, in the order the contour files record
#: them (:func:`recorded`).
OPTIONS = {
    "backend": "--backend",
    "mu": "--mu",
    "omega": "--omega",
    "lambda_in": "--lambda-in",
    "lambda_out": "--lambda-out",
    "max_num_iter": "--max-iter",
    "tol": "--tol",
    "c_in": "--c-in",
    "c_out": "--c-out",
    "color": "--color",
    "inside": "--inside",
    "n_regions": "--regions",
    "fit": "--fit",
    "noise": "--noise",
}
#: The settings listed first; the others go to "less common options" at the end of --help.
COMMON = ("backend", "mu", "n_regions", "inside", "fit", "noise")
#: The placeholders of the options that are not ``--name NAME``.
METAVARS = {"max_num_iter": "N", "n_regions": "K", "c_in": "C", "c_out": "C", "lambda_in": "L",
            "lambda_out": "L"}
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
            lines.append(textwrap.fill(line.strip(), width, initial_indent=inner, subsequent_indent=inner)
                         if line.strip() else "")
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
        "tracked from frame to frame.",
        epilog=_backend_options_listing())
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
    """One option per setting of :data:`OPTIONS` (the common ones, or the others)."""
    from activecontour.settings import setting_specs

    for spec in setting_specs():
        if spec.name not in OPTIONS or (spec.name in COMMON) == rare:
            continue
        shown = "" if "default" in spec.help else " (default: %(default)s)"  # unless it says its own
        kwargs = {"dest": spec.name, "default": spec.default, "help": spec.help + shown}
        if spec.choices is not None:
            kwargs.update(choices=spec.choices)
        else:
            metavar = METAVARS.get(spec.name, OPTIONS[spec.name].lstrip("-").upper())
            kwargs.update(type=_TEXT_TO_VALUE[spec.kind](spec.auto), metavar=metavar + "|auto" * spec.auto)
        parser.add_argument(OPTIONS[spec.name], **kwargs)
    if rare and backend_options:
        parser.add_argument("--option", dest="options", action="append", type=_key_value, default=None,
                            metavar="KEY=VALUE",
                            help="a setting of the backend (listed below), e.g. max_step=2; repeatable")


def settings_from(args):
    """The run's :class:`~activecontour.settings.Settings` from the parsed arguments: one line
    naming the option when the library refuses them."""
    from activecontour.settings import Settings

    from ..messages import one_line
    from .errors import UsageError

    given = {name: getattr(args, name) for name in OPTIONS}
    if getattr(args, "options", None):
        given["options"] = dict(args.options)
    try:
        return Settings(**given)
    except (ValueError, TypeError) as exc:
        raise UsageError(with_option_names(one_line(exc))) from None


def recorded(settings):
    """The settings as the contour files record them: those of :data:`OPTIONS`, and the backend's
    options when given."""
    values = {name: getattr(settings, name) for name in OPTIONS}
    if settings.options:
        values["options"] = settings.options
    return values


def with_option_names(message):
    """A library message about ``lambda_in``, or about a backend's option, with the option's
    spelling in front."""
    import re

    for name, option in OPTIONS.items():
        if message.startswith((name + " ", name + ",", name + ":")):
            return f"{option}: {message}"
    named = re.match(r"option '(\w+)'|(\w+) (?:and \w+ )?must be", message)
    if named:
        from activecontour.backends import BACKENDS

        key = named.group(1) or named.group(2)
        if named.group(1) or any(key == spec.name for backend in BACKENDS.values()
                                 for spec in backend.option_specs()):
            return f"--option {key}: {message}"
    return message


def _backend_options_listing():
    """Every backend's ``--option`` settings, from its options dataclass: name, default and the
    first sentence of its help, without its asides, on one line."""
    import re

    from activecontour.backends import BACKENDS

    lines = ["backend options (--option KEY=VALUE):"]
    for name, backend in BACKENDS.items():
        lines.append(f"  --backend {name}:")
        for spec in backend.option_specs():
            default = "automatic" if spec.default is None else str(spec.default).lower() \
                if spec.kind is bool else spec.default
            first = re.sub(r" \([^()]*\)", "", spec.help.split(".  ")[0]).rstrip(".")
            line = f"    {spec.name}={default}: {first}"
            lines.append(line if len(line) <= WIDTH else line[:WIDTH - 3] + "...")
    return "\n".join(lines)


def _version():
    import activecontour

    return activecontour.__version__


# ------------------------------------------------------------------------------ text to values
def _number(auto):
    """A setting of kind "number": a float ("auto" where it may be); other text as it is, for the
    library to refuse in its words."""
    def parse(text):
        if auto and text == "auto":
            return text
        try:
            return float(text)
        except ValueError:
            return text
    return parse


def _integer(auto):
    """A setting of kind "integer": an int where the text is one, else a number or the text."""
    return value_of


def _channels(auto):
    """A setting of kind "channels": a number, or numbers separated by commas (one per channel)."""
    def parse(text):
        values = [_number(False)(part) for part in text.split(",")]
        return values[0] if len(values) == 1 else values
    return parse


def _flag(auto):
    return lambda text: {"true": True, "false": False}.get(text.lower(), text)


#: How a setting of each kind (:data:`activecontour.settings.KINDS`) is read from text.
_TEXT_TO_VALUE = {"number": _number, "integer": _integer, "channels": _channels, "flag": _flag}


def value_of(text):
    """A number (int or float), true/false, or the text itself."""
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def _key_value(text):
    """``--option`` KEY=VALUE, the value read by :func:`value_of`."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip().isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    return key.strip(), value_of(value.strip())


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
    """``--line-color``: "auto", or a colour of the overlays (a name, or R,G,B in 0..255) as the
    library reads it (:func:`activecontour.io.pictures.rgb_color`)."""
    from activecontour.io.pictures import rgb_color

    if text.lower() == "auto":
        return "auto"
    try:
        parts = text.split(",")
        return rgb_color(text.lower() if len(parts) == 1 else tuple(int(p) for p in parts))
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"expected auto, a colour name or R,G,B: {exc}") from None


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
