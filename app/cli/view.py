"""``activecontour view IMAGE``: the viewer's window with the command line's settings and init."""

from __future__ import annotations

__all__ = ["run"]


def run(args, settings):
    """Read the image, then open the viewer on it (:func:`app.viewer.launch`); return its exit
    status."""
    from . import starts
    from .errors import UsageError
    from .segment import load_image

    init, _ = starts.load_init(args)
    image = load_image(args.image, args.max_pixels)
    try:
        from ..viewer import launch
    except ModuleNotFoundError as exc:
        if exc.name is None or not exc.name.endswith(".viewer"):
            raise
        raise UsageError("the interactive viewer is not installed") from None
    formats = {} if args.formats is None else {"formats": tuple(args.formats)}
    return launch(args.image, settings, image=image, init=starts.fresh(init), max_pixels=args.max_pixels,
                  **formats)
