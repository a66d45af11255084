"""Where the polygon flow's tail goes: what moves after "converged", and how far it may move.

The measurements behind issue 22 item 2 ("converged" is stationary: continuing a result with
``tol / 100`` changes neither J nor the mask by 0.1 %).  Per image, the default polygon run is
recorded through its callback, then continued as ``benchmarks/restart.py`` does.

Columns:

- ``it``: iterations of the default run.
- ``A/L``: the mask's area over the contours' length (px).  A boundary shift of d px flips about
  L d pixels, so 0.1 % of the mask allows a mean shift of about ``1e-3 A/L`` px (``allow``): the
  criterion asks for a sub-pixel precision that scales with the objects' width.
- ``normal``, ``tangent``: over the last ``WINDOW`` iterations of the default run (when they keep
  the vertices), per vertex and per iteration, the mean net displacement along the vertex's
  normal and along its tangent (px); ``n path``, ``t path``: the summed per-iteration
  displacements over the net ones (1: a steady drift, more: back and forth).  The stop rule sees
  the normal one only (the area swept over the length, :class:`activecontour.backends.polygon._Movement`).
- ``>2h``, ``<h/2``: edges longer than twice, shorter than half the spacing (1 px) at the end: the
  vertices' tangential drift leaves long edges on straight runs and clusters at corners.
- ``moved``: the continuation's vertices' distance to the result's contours (px): median, mean and
  99th percentile; ``long``: the share of the normal displacement's power (along the result's
  contours) at wavelengths of 16 px and more.
- ``px %``, ``dJ``: the continuation's mask change (of the mask's area) and relative energy change.

What it showed when written (issue 22 item 2; the numbers in the lead's note): at the stop the
vertices drift along the curve, steadily (``t path`` about 1), several times faster than the
normal movement that the stop rule measures, leaving long edges and clusters of short ones that
the remesh cannot take back (it would raise J); the continuation then shifts the boundary by a
mean of about 0.01-0.03 px on every image, mostly at wavelengths under 16 px (a few images: a lobe
or a whole boundary, at longer ones), and the images that fail are those where that exceeds
``allow`` (thin objects: text, grass, gravel, brick, microaneurysms).

usage (from the project's root):
    python benchmarks/tail.py [--images text,coins,moon]
"""

from __future__ import annotations

import argparse

import numpy as np
import shapely
from restart import DEFAULT_TOL, SAMPLE_IMAGES, load

import activecontour as ac

WINDOW = 5  # iterations of the last block (as the stop rule's)
LONG = 16.0  # px: the wavelength from which a displacement counts as a shape mode


def _closed(curve):
    return np.vstack([curve, curve[:1]])


def _frames(points_list):
    """Unit tangents and normals at the vertices of stacked curves (the mean of the two edges')."""
    tangents = []
    for curve in points_list:
        d = np.roll(curve, -1, axis=0) - curve
        unit = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
        t = unit + np.roll(unit, 1, axis=0)
        tangents.append(t / np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-12)[:, None])
    t = np.vstack(tangents)
    return t, np.column_stack([t[:, 1], -t[:, 0]])


def last_block(states):
    """(normal net, tangential net, normal path/net, tangential path/net) over the recorded
    states (lists of curves with the same vertices), per vertex and iteration; None if they differ."""
    if len(states) < 2 or any([c.shape for c in s] != [c.shape for c in states[0]] for s in states):
        return None
    stacked = [np.vstack(s) for s in states]
    tangent, normal = _frames(states[0])
    out = []
    for frame in (normal, tangent):
        steps = [np.abs(np.einsum("ij,ij->i", b - a, frame)) for a, b in zip(stacked[:-1], stacked[1:],
                                                                              strict=True)]
        net = np.abs(np.einsum("ij,ij->i", stacked[-1] - stacked[0], frame))
        out.append((net.mean() / (len(states) - 1), np.sum(steps) / max(net.sum(), 1e-300)))
    return out[0][0], out[1][0], out[0][1], out[1][1]


def displacement(result, again):
    """The continuation's vertices' distances to the result's contours, and the share of the
    result's normal displacement power (sampled at 1 px along its contours) at wavelengths >= LONG."""
    lines = shapely.MultiLineString([_closed(c) for c in result.contours])
    moved = shapely.distance(shapely.points(np.vstack(again.contours)), lines)
    target = shapely.MultiLineString([_closed(c) for c in again.contours])
    inside = shapely.union_all([shapely.Polygon(c).buffer(0) for c in again.contours])
    power = np.zeros(2)
    for curve in result.contours:
        closed = _closed(curve)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed, axis=0).T))])
        m = int(s[-1])
        if m < 2 * LONG:
            continue
        t = np.linspace(0.0, s[-1], m, endpoint=False)
        samples = shapely.points(np.interp(t, s, closed[:, 0]), np.interp(t, s, closed[:, 1]))
        d = shapely.distance(samples, target) * np.where(shapely.contains(inside, samples), -1.0, 1.0)
        spectrum = np.abs(np.fft.rfft(d)) ** 2
        wavelength = m / np.maximum(np.arange(len(spectrum)), 1e-300)
        power += spectrum[wavelength >= LONG].sum(), spectrum[wavelength < LONG].sum()
    return moved, power[0] / max(power.sum(), 1e-300)


def row(name, image):
    states = []
    result = ac.segment(image, backend="polygon",
                        callback=lambda state: states.append(state.contours) and False)
    block = last_block(states[-WINDOW - 1:])
    again = ac.segment(image, init=result, backend="polygon", tol=DEFAULT_TOL / 100)
    area = max(int(result.mask.sum()), 1)
    length = sum(np.hypot(*np.diff(_closed(c), axis=0).T).sum() for c in result.contours)
    edges = np.concatenate([np.hypot(*np.diff(_closed(c), axis=0).T) for c in result.contours])
    moved, long = displacement(result, again)
    return dict(image=name, it=result.n_iter, width=area / length, block=block,
                long_edges=int(np.count_nonzero(edges > 2.0)), short_edges=int(np.count_nonzero(edges < 0.5)),
                moved=np.quantile(moved, [0.5, 0.99]), mean=moved.mean(), long=long,
                mask=np.count_nonzero(result.mask != again.mask) / area,
                energy=(again.energy - result.energy) / abs(result.energy))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", default=",".join(SAMPLE_IMAGES))
    args = parser.parse_args(argv)
    print(f"{'image':>20} {'it':>4} {'A/L':>5} {'allow':>7} {'normal':>8} {'tangent':>8} {'n path':>6} "
          f"{'t path':>6} {'>2h':>4} {'<h/2':>5} {'moved: median':>13} {'mean':>7} {'99%':>6} {'long':>5} "
          f"{'px %':>6} {'dJ':>9}")
    for name in args.images.split(","):
        r = row(name, load(name))
        block = ("{:8.1e} {:8.1e} {:6.1f} {:6.1f}".format(*r["block"]) if r["block"] is not None
                 else f"{'(remeshed)':>32}")
        print(f"{name:>20} {r['it']:4d} {r['width']:5.2f} {1e-3 * r['width']:7.4f} {block} "
              f"{r['long_edges']:4d} {r['short_edges']:5d} {r['moved'][0]:13.4f} {r['mean']:7.4f} "
              f"{r['moved'][1]:6.3f} {r['long']:5.2f} {100 * r['mask']:6.3f} {r['energy']:+9.2e}", flush=True)


if __name__ == "__main__":
    main()
