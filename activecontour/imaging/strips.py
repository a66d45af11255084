"""Images made a strip of rows at a time: the 2 x 2 block means and the Gaussian blur the
default start (:mod:`activecontour.initial`) scans, exactly as the whole image's, never held whole."""

from __future__ import annotations

import numpy as np

__all__ = ["STRIP_ROWS", "Kept", "Rows", "block_means", "block_means_of", "blurred", "blurred_rows", "strip"]

#: Rows of a :class:`Rows` made at once (with a blur's margins): the default start never holds
#: a whole blurred image.  At 8192^2 a float64 one is 512 MB of fresh memory, and on the 2-core
#: machine the first touch of fresh memory cost 6x the blur's own arithmetic (1.27 s CPU, 1.2 s
#: of it the kernel's, against 0.19 s into memory the process had); strips are reused memory.
STRIP_ROWS = 256


class Rows:
    """An image (M, N, C) whose rows are made on demand, a strip at a time: the 2 x 2 block means
    (:func:`block_means`) or a blur (:func:`blurred_rows`) of another.  ``rows[key]`` and
    ``rows[key, columns]``, ``key`` a slice or sorted row indices, are exactly those rows of the
    whole image, which is never held.

    ``make(a, b)`` makes rows ``a`` to ``b - 1`` (possibly in memory it reuses: valid until the
    next ``make``; ``rows[key]`` copies); ``reach`` is how far beyond them it reads (a blur's
    margin): wanted rows closer than twice that are made in one strip.
    """

    def __init__(self, shape, make, reach=0):
        self.shape, self.make, self.reach = tuple(shape), make, reach

    def __getitem__(self, key):
        rows, columns = key if isinstance(key, tuple) else (key, slice(None))
        wanted = np.arange(self.shape[0])[rows]
        if wanted.size == 0:
            return np.empty((0, *self.shape[1:]))[:, columns]
        # strips: runs of wanted rows with gaps up to 2 reach, spanning at most STRIP_ROWS rows
        breaks = (np.diff(wanted) > 2 * self.reach + 1) | (np.diff(wanted // STRIP_ROWS) != 0)
        parts = []
        for piece in np.split(wanted, np.flatnonzero(breaks) + 1):
            made = self.make(piece[0], piece[-1] + 1)
            parts.append(made[piece - piece[0], columns])
        return parts[0] if len(parts) == 1 else np.concatenate(parts)


class Kept:
    """Some rows of an image (an array or :class:`Rows`), made once and served as its rows:
    ``kept[key]``, ``kept[key, columns]`` as the image's (only the kept rows)."""

    def __init__(self, image, rows):
        self.shape, self.rows, self.held = image.shape, rows, image[rows]

    def __getitem__(self, key):
        rows, columns = key if isinstance(key, tuple) else (key, slice(None))
        wanted = np.arange(self.shape[0])[rows]
        where = np.minimum(np.searchsorted(self.rows, wanted), len(self.rows) - 1)
        if not np.array_equal(self.rows[where], wanted):
            raise IndexError("rows that were not kept")
        return self.held[where, columns]


def strip(image, a, b):
    """Rows ``a`` to ``b - 1`` of an array (a view) or of :class:`Rows` (valid until its next strip)."""
    return image.make(a, b) if isinstance(image, Rows) else image[a:b]


def block_means(values):
    """The image reduced by 2 x 2 block means, (M // 2, N // 2, C) (a last odd row or column
    dropped), as :class:`Rows`."""
    shape = (values.shape[0] // 2, values.shape[1] // 2, values.shape[2])
    return Rows(shape, lambda a, b: block_means_of(values[2 * a:2 * b]))


def block_means_of(values):
    """The image reduced by 2 x 2 block means, (M // 2, N // 2, C) (a last odd row or column
    dropped).  Gray: the four strided planes added as ``(a + b) + (c + d)``, the order numpy's
    mean over the blocks takes, without its reshaped temporaries (3x faster at 4096^2)."""
    m, n = values.shape[0] // 2 * 2, values.shape[1] // 2 * 2
    if values.shape[2] != 1:
        return values[:m, :n].reshape(m // 2, 2, n // 2, 2, -1).mean(axis=(1, 3))
    plane = values[:m, :n, 0]
    total = plane[0::2, 0::2] + plane[0::2, 1::2]
    total += plane[1::2, 0::2] + plane[1::2, 1::2]
    total *= 0.25
    return total[:, :, np.newaxis]


def blurred_rows(values, blur):
    """:func:`blurred` of ``values`` (an array or :class:`Rows`), as :class:`Rows`: each strip
    is blurred with the rows of its kernel's reach around it, which gives exactly the rows of
    the whole image's blur (OpenCV filters the rows of a strip as those of the whole image; the
    reflected border is reached only at the image's own top and bottom)."""
    # OpenCV's kernel for a float image has round(8 blur + 1) | 1 taps: its reach is half that
    reach, m = (int(np.rint(8.0 * blur + 1.0)) | 1) // 2, values.shape[0]

    reused = []  # a gray strip's blur is written over the last one's

    def make(a, b):
        low, high = max(0, a - reach), min(m, b + reach)
        return blurred(strip(values, low, high), blur, reused)[a - low:b - low]

    return Rows(values.shape, make, reach)


def blurred(values, blur, reused=None):
    """The image blurred by ``blur`` px, (M, N, C).

    ``reused``: a list holding (or to hold) a buffer a gray image's blur is written into, when it
    has the rows: the returned array is then a view of it."""
    import cv2  # not scipy.ndimage: it costs ~0.2 s to import on every cold start

    m, n, channels = values.shape
    if reused is not None and channels == 1 and not (reused and reused[0].shape[0] >= m):
        reused[:] = [np.empty((m, n))]
    out = reused[0][:m] if reused and channels == 1 else None
    # scipy.ndimage.gaussian_filter(values, (b, b, 0)): the same sampled kernel (4 sigma), reflected
    planes = [cv2.GaussianBlur(np.ascontiguousarray(values[:, :, ch]), (0, 0), blur, dst=out,
                               borderType=cv2.BORDER_REFLECT) for ch in range(channels)]
    return planes[0][:, :, np.newaxis] if len(planes) == 1 else np.stack(planes, axis=-1)
