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
           "equal_gray_colour", "FAMILIES", "rectangle", "render", "render_instances", "singles", "star",
           "touching_disks", "touching_ellipses", "union"]


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


# ---- families of scenes for touching objects (issue 23) ----------------------------------------
#
# A scene is drawn from a seed in a continuous frame whose unit is the nominal pixel; ``pixel`` is
# the pixel size in that unit (0.5: twice as many pixels a side, 2: half as many), so the same
# scene can be rendered at several resolutions.  Pixel (i, j) covers [i p, (i + 1) p) x
# [j p, (j + 1) p) and its centre is ((i + 1/2) p, (j + 1/2) p).

#: The touching families' object radii (equal-area radius sqrt(a b), nominal pixels): a scene's
#: radii lie in [r0, 1.5 r0] with r0 log-uniform in ``FAMILY_RADII`` (so 6-40 over the seeds).
FAMILY_RADII = (6.0, 40.0 / 1.5)
#: Signal-to-noise ratio (contrast / noise sigma) and Gaussian blur (nominal pixels) of a scene.
FAMILY_SNR = (2.0, 5.0)
FAMILY_BLUR = (0.0, 1.5)
#: Objects per clump, and the largest overlap: the depth by which a new object is pushed into its
#: anchor, as a fraction of the smaller minor axis (2 b).
FAMILY_CLUMP = (2, 8)
FAMILY_OVERLAP = 1.0 / 3.0
#: Clumps drawn per scene (fewer when there is no room).
FAMILY_CLUMPS = 4


class _Ellipse:
    """An ellipse in the scene frame: ``depth(r, c)`` is its normalised radius (<= 1 inside)."""

    def __init__(self, center, a, b, angle):
        self.center, self.a, self.b, self.angle = np.asarray(center, float), a, b, angle
        half = np.hypot(a * np.cos(angle), b * np.sin(angle)), np.hypot(a * np.sin(angle), b * np.cos(angle))
        self.box = (self.center[0] - half[0], self.center[1] - half[1],
                    self.center[0] + half[0], self.center[1] + half[1])

    def depth(self, r, c):
        cos, sin = np.cos(self.angle), np.sin(self.angle)
        u = (r - self.center[0]) * cos + (c - self.center[1]) * sin
        v = -(r - self.center[0]) * sin + (c - self.center[1]) * cos
        return (u / self.a) ** 2 + (v / self.b) ** 2

    def support(self, direction):
        """The largest projection of the ellipse on a unit direction, from its centre."""
        along = direction @ [np.cos(self.angle), np.sin(self.angle)]
        across = direction @ [-np.sin(self.angle), np.cos(self.angle)]
        return np.sqrt((self.a * along) ** 2 + (self.b * across) ** 2)


class _Shape:
    """A shape given by a signed function ``level(r, c)`` (> 0 inside) and a bounding box."""

    def __init__(self, level, box):
        self.level, self.box = level, box

    def depth(self, r, c):
        return np.where(self.level(r, c) > 0, 0.0, np.inf)


def render_instances(shapes, extent, *, pixel=1.0, snr=np.inf, blur=0.0, seed=0, supersample=4):
    """The anti-aliased image of a union of shapes and its true label image, at a pixel size.

    Parameters
    ----------
    shapes : list
        Objects with ``box = (r0, c0, r1, c1)`` and ``depth(r, c)`` (<= 1 inside; where shapes
        overlap, a pixel centre belongs to the one it lies deepest in), in the scene frame.
    extent : (H, W)
        The scene's size in nominal pixels; the image has ``round(H / pixel) x round(W / pixel)``
        pixels.
    pixel : float
        The pixel size in nominal pixels.
    snr, blur, seed :
        The objects are 1 on 0, blurred by a Gaussian of ``blur`` nominal pixels, plus Gaussian
        noise of sigma ``1 / snr`` (per pixel, at any pixel size).

    Returns
    -------
    image : ndarray (M, N) float64
        Each pixel: the fraction of its square covered (``supersample`` x ``supersample``
        sub-samples; only each shape's box is sampled), blurred, plus noise.
    labels : int32 ndarray (M, N)
        Shape k + 1 at the pixel centres inside shape k.
    """
    m, n = int(round(extent[0] / pixel)), int(round(extent[1] / pixel))
    s = supersample
    covered = np.zeros((m * s, n * s), dtype=bool)
    labels = np.zeros((m, n), dtype=np.int32)
    deepest = np.full((m, n), np.inf)
    offsets = (np.arange(s) + 0.5) / s
    for k, shape in enumerate(shapes):
        r0, c0, r1, c1 = shape.box
        i0, j0 = max(int(np.floor(r0 / pixel)) - 1, 0), max(int(np.floor(c0 / pixel)) - 1, 0)
        i1, j1 = min(int(np.ceil(r1 / pixel)) + 2, m), min(int(np.ceil(c1 / pixel)) + 2, n)
        if i1 <= i0 or j1 <= j0:
            continue
        rows = ((np.arange(i0, i1)[:, None] + offsets).ravel() * pixel)[:, None]
        cols = ((np.arange(j0, j1)[:, None] + offsets).ravel() * pixel)[None, :]
        covered[i0 * s:i1 * s, j0 * s:j1 * s] |= shape.depth(rows, cols) <= 1.0
        depth = shape.depth((np.arange(i0, i1)[:, None] + 0.5) * pixel,
                            (np.arange(j0, j1)[None, :] + 0.5) * pixel)
        window = deepest[i0:i1, j0:j1]
        take = (depth <= 1.0) & (depth < window)
        labels[i0:i1, j0:j1][take], window[take] = k + 1, depth[take]
    image = covered.reshape(m, s, n, s).mean(axis=(1, 3))
    sigma = 0.0 if not np.isfinite(snr) else 1.0 / snr
    return add_noise(image, sigma, seed, blur=blur / pixel) if sigma > 0 or blur > 0 else image, labels


def _clumps(rng, extent, radius, aspect, count):
    """Clumps of touching ellipses (equal-area radius uniform in ``radius``, aspect ratio a / b
    uniform in ``aspect``, any angle): each clump starts with one ellipse anywhere with room, and
    every further one is placed against a random member, in a random direction, at the distance
    where their support functions meet, then pushed in by an overlap uniform in
    [0, ``FAMILY_OVERLAP``] times the smaller minor axis.  It must clear every other member of its
    clump (support functions) and every ellipse of the other clumps by 6 px."""
    h, w = extent
    placed, clump_of = [], []

    def draw():
        r, ratio = rng.uniform(*radius), rng.uniform(*aspect)
        return r * np.sqrt(ratio), r / np.sqrt(ratio), rng.uniform(-np.pi / 2, np.pi / 2)

    def room(e, clump):
        r0, c0, r1, c1 = e.box
        if r0 < 3 or c0 < 3 or r1 > h - 3 or c1 > w - 3:
            return False
        return all(np.hypot(*(e.center - o.center)) > e.a + o.a + 6
                   for o, k in zip(placed, clump_of, strict=True) if k != clump)

    for clump in range(FAMILY_CLUMPS):
        members = []
        for _ in range(200):
            a, b, angle = draw()
            first = _Ellipse(rng.uniform([0, 0], [h, w]), a, b, angle)
            if room(first, clump) and all(np.hypot(*(first.center - o.center)) > first.a + o.a + 4 * b
                                          for o in placed):
                members.append(first)
                placed.append(first)
                clump_of.append(clump)
                break
        size = rng.integers(count[0], count[1] + 1)
        for _ in range(300):
            if not members or len(members) >= size:
                break
            anchor = members[rng.integers(len(members))]
            a, b, angle = draw()
            theta = rng.uniform(0, 2 * np.pi)
            direction = np.array([np.cos(theta), np.sin(theta)])
            probe = _Ellipse((0.0, 0.0), a, b, angle)
            gap = anchor.support(direction) + probe.support(-direction)
            gap -= rng.uniform(0, FAMILY_OVERLAP) * 2 * min(b, anchor.b)
            new = _Ellipse(anchor.center + gap * direction, a, b, angle)
            clear = True
            for other in members:
                if other is not anchor:
                    distance = np.hypot(*(new.center - other.center))
                    unit = (new.center - other.center) / distance
                    clear &= distance >= other.support(unit) + new.support(unit)
            if clear and room(new, clump):
                members.append(new)
                placed.append(new)
                clump_of.append(clump)
    return placed


def _scene_settings(rng):
    """A scene's base radius r0, SNR and blur, and its extent (room for its clumps)."""
    r0 = float(np.exp(rng.uniform(*np.log(FAMILY_RADII))))
    side = float(np.clip(18 * r0, 160, 560))
    return r0, rng.uniform(*FAMILY_SNR), rng.uniform(*FAMILY_BLUR), (side, side)


def touching_ellipses(seed, *, pixel=1.0):
    """A scene of the touching-ellipse family: clumps of 2-8 ellipses of aspect 1-3 at any angle,
    overlapping by up to a third of the minor axis; radii in [r0, 1.5 r0], r0 in 6-27 px, SNR 2-5,
    blur 0-1.5 px (module constants ``FAMILY_*``).

    Returns the image and the true labels (:func:`render_instances`; a pixel centre in an overlap
    belongs to the ellipse it lies deepest in)."""
    rng = np.random.default_rng([23, 1, seed])
    r0, snr, blur, extent = _scene_settings(rng)
    shapes = _clumps(rng, extent, (r0, 1.5 * r0), (1.0, 3.0), FAMILY_CLUMP)
    return render_instances(shapes, extent, pixel=pixel, snr=snr, blur=blur, seed=seed)


def touching_disks(seed, *, pixel=1.0):
    """A scene of the touching-disk family: as :func:`touching_ellipses` with aspect 1."""
    rng = np.random.default_rng([23, 2, seed])
    r0, snr, blur, extent = _scene_settings(rng)
    shapes = _clumps(rng, extent, (r0, 1.5 * r0), (1.0, 1.0), FAMILY_CLUMP)
    return render_instances(shapes, extent, pixel=pixel, snr=snr, blur=blur, seed=seed)


def _polyline_distance(points, r, c):
    """The distance from (r, c) (broadcast arrays) to a polyline (P, 2)."""
    best = np.full(np.broadcast(r, c).shape, np.inf)
    for (ar, ac_), (br, bc) in zip(points[:-1], points[1:], strict=True):
        dr, dc = br - ar, bc - ac_
        t = np.clip(((r - ar) * dr + (c - ac_) * dc) / max(dr * dr + dc * dc, 1e-12), 0.0, 1.0)
        best = np.minimum(best, np.hypot(r - ar - t * dr, c - ac_ - t * dc))
    return best


def _tube(points, half_width):
    """The points within ``half_width`` of a polyline: a stroke, a rod with round ends."""
    low, high = points.min(axis=0) - half_width, points.max(axis=0) + half_width
    return _Shape(lambda r, c: half_width - _polyline_distance(points, r, c), (*low, *high))


def _walk(rng, start, length, turn, step=2.0):
    """A smooth random path: ``length`` px in steps of ``step``, its heading turning by a random
    amount (std ``turn`` radians per step, smoothed) at each step."""
    steps = max(int(length / step), 2)
    turns = scipy.ndimage.gaussian_filter1d(rng.normal(0.0, turn, steps), 3.0) * 3.0
    heading = rng.uniform(0, 2 * np.pi) + np.cumsum(turns)
    moves = step * np.column_stack([np.cos(heading), np.sin(heading)])
    return np.asarray(start, float) + np.vstack([[0.0, 0.0], np.cumsum(moves, axis=0)])


_HORSE = None


def _horse_level():
    """skimage's horse silhouette as a smooth signed distance (px; > 0 inside), and its size."""
    global _HORSE
    if _HORSE is None:
        import skimage.data

        horse = ~skimage.data.horse()
        level = (scipy.ndimage.distance_transform_edt(horse) - scipy.ndimage.distance_transform_edt(~horse))
        _HORSE = scipy.ndimage.gaussian_filter(level, 1.0)
    return _HORSE


def _horse(center, height, angle, mirror):
    """The horse silhouette of ``height`` px (its image's rows), turned by ``angle``."""
    level = _horse_level()
    scale = level.shape[0] / height
    cos, sin = np.cos(angle), np.sin(angle)
    half = 0.5 * np.hypot(*level.shape) / scale

    def signed(r, c):
        r, c = np.broadcast_arrays(r - center[0], c - center[1])
        u = (r * cos + c * sin) * scale + level.shape[0] / 2
        v = (-r * sin + c * cos) * scale * (-1 if mirror else 1) + level.shape[1] / 2
        return scipy.ndimage.map_coordinates(level, [u, v], order=1, cval=-1.0)

    return _Shape(signed, (center[0] - half, center[1] - half, center[0] + half, center[1] + half))


def _single(kind, rng, r0):
    """One shape of the singles family around (0, 0): its level function and box."""
    if kind == "horse":
        return _horse((0.0, 0.0), float(np.clip(rng.uniform(6, 9) * r0, 60, 220)),
                      rng.uniform(-np.pi, np.pi), bool(rng.integers(2)))
    if kind == "ring":
        outer = rng.uniform(1.2, 2.0) * r0
        inner = outer - max(rng.uniform(0.25, 0.5) * outer, 4.0)
        return _Shape(lambda r, c: np.minimum(outer - np.hypot(r, c), np.hypot(r, c) - inner),
                      (-outer, -outer, outer, outer))
    if kind == "stroke":
        return _tube(_walk(rng, (0.0, 0.0), rng.uniform(8, 16) * max(r0, 6.0), 0.15), 1.5)
    if kind == "bent rod":
        width = max(rng.uniform(0.8, 1.4) * r0, 6.0)
        arm = rng.uniform(1.5, 3.0) * width
        bend = rng.uniform(np.pi / 6, 2 * np.pi / 3)
        heading = rng.uniform(0, 2 * np.pi)
        if rng.integers(2):  # a polyline with one bend
            points = np.array([[0.0, 0.0], [np.cos(heading), np.sin(heading)]]) * arm
            points = np.vstack([points, points[1] + arm * np.array([np.cos(heading + bend),
                                                                    np.sin(heading + bend)])])
        else:  # an arc turning by ``bend``
            t = np.linspace(0, 1, 24)[:, None]
            radius = 2 * arm / bend
            points = radius * np.hstack([np.sin(t * bend), 1 - np.cos(t * bend)])
            turn = np.array([[np.cos(heading), np.sin(heading)], [-np.sin(heading), np.cos(heading)]])
            points = points @ turn
        return _tube(points - points.mean(axis=0), width / 2)
    if kind == "star":
        radius, amplitude, arms = rng.uniform(1.2, 2.0) * r0, rng.uniform(0.15, 0.35), int(rng.integers(4, 8))
        turn = rng.uniform(0, 2 * np.pi)
        reach = radius * (1 + amplitude)
        return _Shape(lambda r, c: radius * (1 + amplitude * np.cos(arms * np.arctan2(c, r) + turn))
                      - np.hypot(r, c), (-reach, -reach, reach, reach))
    # an ellipse of aspect 3
    radius = rng.uniform(1.0, 1.5) * r0
    e = _Ellipse((0.0, 0.0), radius * np.sqrt(3), radius / np.sqrt(3), rng.uniform(-np.pi / 2, np.pi / 2))
    return _Shape(lambda r, c: 1.0 - e.depth(r, c), e.box)


#: The kinds of the singles family, one of each per scene.
SINGLE_KINDS = ("horse", "ring", "stroke", "bent rod", "star", "ellipse aspect 3")


def singles(seed, *, pixel=1.0):
    """A scene of the singles family: one horse silhouette (skimage's), ring, 3 px stroke, bent
    rod (one bend or an arc), star (4-7 arms) and ellipse of aspect 3 (``SINGLE_KINDS``), apart
    from each other, at the touching families' sizes, SNR and blur.  None may be split.

    Returns the image and the true labels (shape k + 1 is ``SINGLE_KINDS[k]``)."""
    rng = np.random.default_rng([23, 3, seed])
    r0, snr, blur, _ = _scene_settings(rng)
    shapes = [_single(kind, rng, r0) for kind in SINGLE_KINDS]
    sizes = [max(s.box[2] - s.box[0], s.box[3] - s.box[1]) + 8 for s in shapes]
    # a row of cells, each as large as its shape
    columns = 3
    rows = range(0, len(shapes), columns)
    height = [max(sizes[i:i + columns]) for i in rows]
    width = max(sum(sizes[i:i + columns]) for i in rows)
    placed, top = [], 0.0
    for row, start in enumerate(rows):
        left = 0.0
        for k in range(start, min(start + columns, len(shapes))):
            placed.append(_shifted(shapes[k], (top + height[row] / 2, left + sizes[k] / 2)))
            left += sizes[k]
        top += height[row]
    return render_instances(placed, (np.ceil(top), np.ceil(width)), pixel=pixel, snr=snr, blur=blur,
                            seed=seed)


def _shifted(shape, centre):
    """The shape moved so that its box is centred on ``centre``."""
    r0, c0, r1, c1 = shape.box
    shift = np.asarray(centre) - [(r0 + r1) / 2, (c0 + c1) / 2]
    return _Shape(lambda r, c: shape.level(r - shift[0], c - shift[1]),
                  (r0 + shift[0], c0 + shift[1], r1 + shift[0], c1 + shift[1]))


#: The families of issue 23 by name: ``FAMILIES[name](seed, pixel=1.0) -> (image, labels)``.
FAMILIES = {"disks": touching_disks, "ellipses": touching_ellipses, "singles": singles}


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
