"""Opening the viewer's window: what ``activecontour view IMAGE`` calls."""

from __future__ import annotations

import sys

from activecontour.io.images import MAX_PIXELS

from ..messages import one_line

__all__ = ["launch"]


def launch(image_path, settings=None, *, image=None, init=None, formats=("json",), max_pixels=MAX_PIXELS,
           **keywords):
    """Open the viewer's window on an image and return an exit code when it is closed.

    Parameters
    ----------
    image_path : str or os.PathLike
        Any image :func:`activecontour.load_image` reads.
    image : ndarray, optional
        The image of ``image_path`` when it has been read already.
    settings, init, formats, **keywords
        See :class:`~.window.Viewer`; ``init`` may also be a name from
        :data:`~.starts.NAMED_INITS` (``"grid"``, ``"checkerboard"``) or a mask file's path.
    max_pixels : int or None
        The largest image opened, this one and those opened later in the window (see
        :func:`activecontour.load_image`).

    Returns
    -------
    int
        0 after the window was closed; 2 for a bad image, init or parameter; 1 when matplotlib
        has no interactive backend (no display, or ``MPLBACKEND=Agg``).  A problem is one line on
        stderr, ``activecontour: error: ...`` as the command line's.
    """
    import matplotlib.pyplot as plt
    import numpy as np

    from activecontour import load_image, segment

    from . import window

    try:
        if image is None:
            image = load_image(image_path, max_pixels=max_pixels)
        viewer = window.Viewer(image, settings, image_path=image_path, init=init, formats=formats, **keywords)
        viewer.max_pixels = max_pixels
    except (OSError, ValueError, TypeError) as exc:
        print(f"activecontour: error: {one_line(exc)}", file=sys.stderr)
        return 2
    if viewer.fig.canvas.required_interactive_framework is None:
        plt.close(viewer.fig)
        print(f"activecontour: error: matplotlib backend {plt.get_backend()!r} cannot open a window "
              "(no display?); set MPLBACKEND to an interactive backend such as TkAgg or QtAgg",
              file=sys.stderr)
        return 1
    # The library's compiled kernels load (or, once after installing, compile) on their first
    # call: do that now, before the window opens, rather than freeze it during the first run.
    segment(np.eye(8), max_num_iter=1)
    plt.show()
    return 0
