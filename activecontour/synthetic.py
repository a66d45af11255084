"""Synthetic images with exact ground truth: anti-aliased shapes, noise with fixed seeds, blur.

A shape is a function ``inside(r, c) -> bool array`` of (row, col) coordinates.  :func:`render`
gives an anti-aliased image (each pixel's value is the fraction of its square covered by the shape,
estimated on a ``supersample x supersample`` sub-grid) and the ground-truth mask (pixel centres
inside the shape), the same convention as :func:`activecontour.geometry.raster.rasterize`.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage

__all__ = ["add_noise", "annulus", "coins", "dice", "disk", "disk_image", "disk_sequence", "ellipse",
           "equal_gray_colour", "rectangle", "render", "star", "touching_clumps", "union"]


def disk(center, radius):
    """The closed disk of ``radius`` around ``center`` (row, col)."""
    r0, c0 = center

    def inside(r, c):
        return (r - r0) ** 2 + (c - c0) ** 2 <= radius**2

    return inside


def annulus(center, inner, outer):
    """The ring between radii ``inner`` < ``outer``: one outer boundary and one hole."""
    r0, c0 = center

    def inside(r, c):
        d2 = (r - r0) ** 2 + (c - c0) ** 2
        return (d2 <= outer**2) & (d2 > inner**2)

    return inside


def rectangle(start, end):
    """The axis-aligned rectangle with corners ``start`` and ``end`` (row, col)."""
    r0, r1 = sorted((start[0], end[0]))
    c0, c1 = sorted((start[1], end[1]))
    return lambda r, c: (r >= r0) & (r <= r1) & (c >= c0) & (c <= c1)


def star(center, radius, *, amplitude=0.3, arms=5):
    """A smooth star ``rho(theta) = radius (1 + amplitude cos(arms theta))``."""
    r0, c0 = center

    def inside(r, c):
        theta = np.arctan2(c - c0, r - r0)
        return np.hypot(r - r0, c - c0) <= radius * (1.0 + amplitude * np.cos(arms * theta))

    return inside


def union(*shapes):
    """The union of shapes."""
    return lambda r, c: np.logical_or.reduce([s(r, c) for s in shapes])


def render(shape, size, *, inside=1.0, outside=0.0, supersample=4, values=None):
    """Anti-aliased image of a shape and its ground-truth mask.

    Parameters
    ----------
    shape : callable
        ``inside(r, c)``.
    size : (M, N)
    inside, outside : float
        Intensities of the shape and the background.
    supersample : int
        Sub-samples per pixel side for the coverage fraction.
    values : callable, optional
        ``values(r, c)`` giving the inside intensity pointwise (several objects of different
        intensities); overrides ``inside``.

    Returns
    -------
    image : ndarray (M, N) float64
    truth : ndarray (M, N) bool
    """
    m, n = size
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    image = np.zeros((m, n))
    cols = np.arange(n, dtype=np.float64)
    for start in range(0, m, 64):  # row blocks keep the sub-sample grid small
        rows = np.arange(start, min(m, start + 64), dtype=np.float64)
        r = (rows[:, None] + offsets[None, :]).ravel()[:, None]
        c = (cols[:, None] + offsets[None, :]).ravel()[None, :]
        inner = shape(r, c)
        level = values(r, c) if values is not None else inside
        sub = np.where(inner, level, outside)
        image[start : start + len(rows)] = sub.reshape(
            len(rows), supersample, n, supersample
        ).mean(axis=(1, 3))
    rr, cc = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    return image, shape(rr.astype(np.float64), cc.astype(np.float64))


def disk_image(size, center, radius, *, inside=1.0, outside=0.0):
    """A disk's anti-aliased image and truth at any size, without sub-sampling.

    A pixel's coverage is ``clip(radius - d + 1/2, 0, 1)`` with d the distance of its centre from
    ``center``: exact for a straight edge through the pixel, within ~1/(8 radius) for the circle.
    """
    m, n = (size, size) if np.isscalar(size) else size
    r = np.arange(m)[:, None] - center[0]
    c = np.arange(n)[None, :] - center[1]
    distance = np.hypot(r, c)
    coverage = np.clip(radius - distance + 0.5, 0.0, 1.0)
    return outside + (inside - outside) * coverage, distance <= radius


def add_noise(image, sigma, seed, *, blur=0.0):
    """Gaussian blur of width ``blur`` (pixels) then additive Gaussian noise of std ``sigma``."""
    out = scipy.ndimage.gaussian_filter(image, blur) if blur > 0 else np.array(image, float)
    return out + np.random.default_rng(seed).normal(0.0, sigma, size=out.shape)


def dice(mask, truth):
    """Dice coefficient ``2 |A & B| / (|A| + |B|)`` of two boolean masks."""
    mask, truth = np.asarray(mask, bool), np.asarray(truth, bool)
    total = mask.sum() + truth.sum()
    return 1.0 if total == 0 else 2.0 * np.logical_and(mask, truth).sum() / total


def coins(*, seed=7, noise=0.05):
    """Twelve disks of different intensities (0.55 to 0.95) on a 0.2 background, 128 x 160.

    Returns the noisy image, the ground truth, and the disks' centres.
    """
    rng = np.random.default_rng(seed)
    centers = [(26.0 + 40 * i + rng.uniform(-3, 3), 22.0 + 38 * j + rng.uniform(-3, 3))
               for i in range(3) for j in range(4)]
    radii = rng.uniform(9.0, 14.0, len(centers))
    levels = np.linspace(0.55, 0.95, len(centers))
    shapes = [disk(c, r) for c, r in zip(centers, radii, strict=True)]

    def values(r, c):
        out = np.zeros(np.broadcast(r, c).shape)
        for shape, level in zip(shapes, levels, strict=True):
            out[shape(r, c)] = level
        return out

    image, truth = render(union(*shapes), (128, 160), outside=0.2, values=values)
    return add_noise(image, noise, seed), truth, centers


def equal_gray_colour(*, seed=5, noise=0.05):
    """A reddish disk on a greenish background of the same luminance (rgb2gray weights).

    As gray the image is flat; only the colour channels tell the regions apart.  Returns the
    noisy (128, 128, 3) image and the ground truth.
    """
    object_rgb = np.array([0.8, 0.2, 0.2])
    gray = object_rgb @ [0.2125, 0.7154, 0.0721]
    green = (gray - 0.2125 * 0.2 - 0.0721 * 0.2) / 0.7154
    background_rgb = np.array([0.2, green, 0.2])
    coverage, truth = render(disk((60.3, 66.1), 30.0), (128, 128))
    rgb = coverage[:, :, None] * object_rgb + (1 - coverage[:, :, None]) * background_rgb
    return rgb + np.random.default_rng(seed).normal(0, noise, rgb.shape), truth


def ellipse(center, semi_major, semi_minor, angle=0.0):
    """The closed ellipse with semi-axes ``semi_major`` along the direction ``angle`` (radians from
    the row axis) and ``semi_minor`` across it."""
    r0, c0 = center
    cos, sin = np.cos(angle), np.sin(angle)

    def inside(r, c):
        u = (r - r0) * cos + (c - c0) * sin
        v = -(r - r0) * sin + (c - c0) * cos
        return (u / semi_major) ** 2 + (v / semi_minor) ** 2 <= 1.0

    return inside


def touching_clumps(size=(256, 256), *, n_clumps=10, per_clump=(2, 4), minor=(6.0, 9.0),
                    max_aspect=2.5, max_overlap=1.0 / 3.0, snr=3.0, seed=0):
    """Clumps of touching, slightly overlapping ellipses: an instance segmentation test scene.

    Each clump starts with one ellipse; every further ellipse (semi-minor axis b uniform in
    ``minor``, aspect ratio a / b uniform in [1, ``max_aspect``], random orientation) is placed
    against a random member of its clump, in a random direction, at the distance where their
    support functions touch, then pushed in by an overlap uniform in [0, ``max_overlap``] times the
    smaller minor axis (2 b).  Ellipses of different clumps stay apart.  The image is the
    anti-aliased union (1 on 0) with Gaussian noise of std ``1 / snr``.

    Returns
    -------
    image : ndarray (M, N) float64
    labels : int32 ndarray (M, N)
        The true instances: a pixel centre covered by several ellipses goes to the one it lies
        deepest in (the smallest normalised radius).
    """
    rng = np.random.default_rng(seed)
    m, n = size
    placed = []  # (center, a, b, angle, clump)

    def support(a, b, angle, direction):
        along = direction @ [np.cos(angle), np.sin(angle)]
        across = direction @ [-np.sin(angle), np.cos(angle)]
        return np.sqrt((a * along) ** 2 + (b * across) ** 2)

    def fits(center, a, clump):
        if not (a + 2 <= center[0] <= m - a - 3 and a + 2 <= center[1] <= n - a - 3):
            return False
        return all(np.hypot(*(center - c)) > aa + a + 6 for c, aa, _, _, k in placed if k != clump)

    for clump in range(n_clumps):
        members = []
        for _ in range(200):  # the first ellipse: anywhere with room
            b = rng.uniform(*minor)
            a, angle = b * rng.uniform(1.0, max_aspect), rng.uniform(-np.pi / 2, np.pi / 2)
            center = rng.uniform([0, 0], [m, n])
            if fits(center, a, clump) and all(np.hypot(*(center - c)) > aa + a + 30
                                              for c, aa, *_ in placed):
                members.append((center, a, b, angle, clump))
                placed.append(members[-1])
                break
        count = rng.integers(per_clump[0], per_clump[1] + 1)
        for _ in range(200):
            if not members or len(members) >= count:
                break
            other = members[rng.integers(len(members))]
            b = rng.uniform(*minor)
            a, angle = b * rng.uniform(1.0, max_aspect), rng.uniform(-np.pi / 2, np.pi / 2)
            theta = rng.uniform(0, 2 * np.pi)
            direction = np.array([np.cos(theta), np.sin(theta)])
            gap = support(other[1], other[2], other[3], direction) + support(a, b, angle, direction)
            gap -= rng.uniform(0, max_overlap) * 2 * min(b, other[2])
            center = other[0] + gap * direction
            # touching its anchor only: any other member must be at least as far as support says
            clear = True
            for c, aa, bb, ang, _ in members:
                if c is not other[0]:
                    distance = np.hypot(*(center - c))
                    unit = (center - c) / distance
                    clear &= distance >= support(aa, bb, ang, unit) + support(a, b, angle, -unit)
            if clear and fits(center, a, clump):
                members.append((center, a, b, angle, clump))
                placed.append(members[-1])
    shapes = [ellipse(c, a, b, angle) for c, a, b, angle, _ in placed]
    image, _ = render(union(*shapes), size)
    rr, cc = np.meshgrid(np.arange(m, dtype=np.float64), np.arange(n, dtype=np.float64), indexing="ij")
    depth = np.full((m, n), np.inf)
    labels = np.zeros((m, n), dtype=np.int32)
    for k, (c, a, b, angle, _) in enumerate(placed):
        u = (rr - c[0]) * np.cos(angle) + (cc - c[1]) * np.sin(angle)
        v = -(rr - c[0]) * np.sin(angle) + (cc - c[1]) * np.cos(angle)
        radius = (u / a) ** 2 + (v / b) ** 2
        take = (radius <= 1.0) & (radius < depth)
        labels[take], depth[take] = k + 1, radius[take]
    return add_noise(image, 1.0 / snr, seed), labels


def disk_sequence(size, frames, *, inside=0.75, outside=0.25, sigma=0.0, seed=0):
    """A time-lapse of disks with known identities: the images and the ground-truth label stack.

    Parameters
    ----------
    size : int or (M, N)
    frames : list (one item per frame) of lists of ``(track_id, (row, col), radius)``
        The disks of each frame; a track id > 0 names one object for its whole life.  A disk
        may lie partly or wholly outside the image (an object entering or leaving the field).
    inside, outside : float
        Intensities of the disks and of the background.
    sigma : float
        Standard deviation of the additive Gaussian noise (SNR = (inside - outside) / sigma).
    seed : int
        Noise seed; frame t uses ``seed + t``.

    Returns
    -------
    images : ndarray (T, M, N) float64
        Anti-aliased (:func:`disk_image`; where disks overlap, the larger coverage) plus noise.
    truth : ndarray (T, M, N) int32
        The track id of the disk containing each pixel centre, 0 outside every disk.
    """
    m, n = (size, size) if np.isscalar(size) else size
    images = np.empty((len(frames), m, n))
    truth = np.zeros((len(frames), m, n), dtype=np.int32)
    for t, disks in enumerate(frames):
        coverage = np.zeros((m, n))
        for track_id, center, radius in disks:
            covered, inside_disk = disk_image((m, n), center, radius)
            np.maximum(coverage, covered, out=coverage)
            truth[t][inside_disk] = track_id
        image = outside + (inside - outside) * coverage
        images[t] = add_noise(image, sigma, seed + t) if sigma > 0 else image
    return images, truth
