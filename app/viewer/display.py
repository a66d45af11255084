"""What the viewer shows of a run: the curves on the image, the readout and the energy plot.

Functions of the window's :class:`~.layout.Layout` and the values shown; they hold no state.
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry.curve import length, to_xy
from activecontour.io.pictures import REGION_COLORS

from .layout import show_energy

__all__ = ["closed_xy", "format_constant", "format_coord", "show_contours", "show_curves",
           "show_readout", "state_curves"]


def show_curves(layout, init_curves, contours, regions, contour_rgb):
    """The initial curves (dashed, faded once a run has contours) and the contours."""
    layout.init_lines.set_segments([closed_xy(c) for c in init_curves])
    layout.init_lines.set_alpha(0.55 if contours else 1.0)
    show_contours(layout, contours, regions, contour_rgb)


def show_contours(layout, contours, regions, contour_rgb):
    """The contours; ``regions`` (the curves of regions 1..K-1 of a result of K > 2 regions, or
    None): every region's boundary in its own colour (region k in the k-th of
    :data:`~activecontour.io.pictures.REGION_COLORS`, as the overlays)."""
    if regions is None:
        layout.contour_lines.set_segments([closed_xy(c) for c in contours])
        layout.contour_lines.set_color(contour_rgb)
        return
    segments, colors = [], []
    for k, curves in enumerate(regions):
        segments += [closed_xy(c) for c in curves]
        colors += [REGION_COLORS[k % len(REGION_COLORS)]] * len(curves)
    layout.contour_lines.set_segments(segments)
    layout.contour_lines.set_color(colors or [contour_rgb])


def show_readout(layout, state, *, iteration, contours, n_regions, fit, history):
    """Iteration, energy, c_in, c_out of a FlowState or result (None: not run), the contours'
    size, and the energy plot of ``history`` ((n, 2): iteration, energy)."""
    if state is None:
        energy = c_in = c_out = "-"
    else:
        energy = f"{state.energy:.6g}"
        c_in, c_out = format_constant(state.c_in), format_constant(state.c_out)
    lines = [f"iteration {iteration:<6d} energy {energy}", f"c_in  {c_in}", f"c_out {c_out}"]
    if n_regions != 2:  # K regions: how many, and each one's constant (once known)
        constants = getattr(state, "constants", None)
        count = f" (auto: {state.n_regions})" if getattr(state, "n_regions", None) and \
            n_regions == "auto" else ""
        shown = "-" if constants is None else format_constant(np.mean(constants, axis=1))
        lines[1:3] = [f"regions {n_regions}{count}, {fit} light", f"c_k   {shown}"]
    if contours:
        lines.append(f"{len(contours)} contour{'s' * (len(contours) > 1)}, "
                     f"{sum(len(c) for c in contours)} vertices, "
                     f"{sum(length(c) for c in contours):.1f} px long")
    else:
        lines.append("initial curve (dashed)")
    layout.set_fitted_text(layout.readout, "\n".join(lines))
    show_energy(layout.ax_energy, layout.energy_line, layout.energy_note, history)


def format_coord(image, shape, x, y):
    """The toolbar's readout for the image axes: (row, col) of the mouse and the image's value
    at the nearest pixel centre."""
    row, col = y, x
    text = f"row {row:.1f}, col {col:.1f}"
    i, j = int(np.floor(row + 0.5)), int(np.floor(col + 0.5))
    if 0 <= i < shape[0] and 0 <= j < shape[1]:
        text += f"  value {format_constant(image[i, j])}"
    return text


def state_curves(state):
    """The curves of a run's state: its contours, or where a backend sends none but a level-set
    function (the N-region label field), the outline of that function's inside."""
    if state.contours or state.phi is None:
        return state.contours
    from activecontour.geometry.raster import mask_to_curves

    return mask_to_curves(state.phi > 0)


def closed_xy(curve):
    """A closed curve (row, col) as matplotlib's (x, y) polyline, its first vertex repeated."""
    xy = to_xy(curve)
    return np.vstack([xy, xy[:1]])


def format_constant(value):
    """A number, or a tuple of them (colour channels), in a few digits."""
    value = np.asarray(value, dtype=np.float64)
    if value.size == 1:
        return f"{float(value.reshape(-1)[0]):.4g}"
    return "(" + ", ".join(f"{v:.3g}" for v in value.reshape(-1)) + ")"
