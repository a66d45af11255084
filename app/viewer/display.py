"""What the viewer shows of a run: the curves on the image, the readout and the energy plot.

Functions of the window's :class:`~.layout.Layout` and the values shown; they hold no state.
"""

from __future__ import annotations

import numpy as np

from activecontour.geometry.curve import length, to_xy
from activecontour.io.pictures import REGION_COLORS

from .layout import SLIDERS, STEP_OPTIONS, show_energy

__all__ = ["OBJECT_COLORS", "READOUT_HELP", "closed_xy", "format_constant", "format_coord", "help_text",
           "object_colors", "object_summary", "show_contours", "show_curves", "show_objects", "show_readout",
           "state_curves"]

#: The objects' colours (matplotlib's tab10 less its gray, which vanishes on a gray image):
#: objects that touch get different ones (:func:`object_colors`).
OBJECT_COLORS = ((0.12, 0.47, 0.71), (1.0, 0.5, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16),
                 (0.58, 0.4, 0.74), (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.74, 0.74, 0.13),
                 (0.09, 0.75, 0.81))

#: The readout's words, and what they are in the book (shown by the help, key h).
READOUT_HELP = (
    ("energy", "the value of the Chan-Vese functional (6.38) that a run lowers: how far the image is "
               "from its object and background brightness, plus smoothness times the contour length "
               "(mu |Gamma|), plus shrink / grow times the objects' area (omega |Omega_i|)"),
    ("object brightness", "the mean intensity inside the contours, c_in of (6.42) (one per colour "
                          "channel); with more regions, each region's, c_k"),
    ("background brightness", "the mean intensity outside the contours, c_out of (6.42)"),
    ("objects", "the connected pieces of the inside, touching ones apart (segment's labels), each "
                "in its own colour; click one (or right-click it) for its measurements"),
)


def show_curves(layout, init_curves, contours, regions, contour_rgb, result=None, selected=None):
    """The initial curves (dashed, faded once a run has contours) and the contours: a two-region
    ``result``'s objects each in its own colour (:func:`show_objects`), else the contours."""
    layout.init_lines.set_segments([closed_xy(c) for c in init_curves])
    layout.init_lines.set_alpha(0.55 if contours else 1.0)
    if regions is None and contours and getattr(result, "object_contours", None) is not None:
        show_objects(layout, result, selected)
    else:
        show_contours(layout, contours, regions, contour_rgb)


def show_contours(layout, contours, regions, contour_rgb):
    """The contours; ``regions`` (the curves of regions 1..K-1 of a result of K > 2 regions, or
    None): every region's boundary in its own colour (region k in the k-th of
    :data:`~activecontour.io.pictures.REGION_COLORS`, as the overlays)."""
    layout.contour_lines.set_linewidths(2.0)
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
    """Iteration, energy, the object and background brightness (c_in, c_out) of a FlowState or
    result (None: not run), the count of a result's objects and the contours' size, and the
    energy plot of ``history`` ((n, 2): iteration, energy)."""
    if state is None:
        energy = c_in = c_out = "-"
    else:
        energy = f"{state.energy:.6g}"
        c_in, c_out = format_constant(state.c_in, bare=True), format_constant(state.c_out, bare=True)
    lines = [f"iteration {iteration:<6d} energy {energy}", f"object brightness {c_in}",
             f"background brightness {c_out}"]
    if n_regions != 2:  # K regions: how many, and each one's brightness (once known)
        constants = getattr(state, "constants", None)
        count = f" (auto: {state.n_regions})" if getattr(state, "n_regions", None) and \
            n_regions == "auto" else ""
        shown = "-" if constants is None else format_constant(np.mean(constants, axis=1))
        lines[1:3] = [f"regions {n_regions}{count}, {fit} light", f"region brightness {shown}"]
    if contours:
        size = (f"{len(contours)} contour{'s' * (len(contours) > 1)}, "
                f"{sum(length(c) for c in contours):.1f} px long")
        objects = getattr(state, "objects", None)
        if objects is not None:  # a result: its objects
            count = len(objects["label"])
            size = f"{count} object{'s' * (count != 1)}, {size}"
        lines.append(size)
    else:
        lines.append("initial curve (dashed)")
    layout.set_fitted_text(layout.readout, "\n".join(lines))
    show_energy(layout.ax_energy, layout.energy_line, layout.energy_note, history)


def show_objects(layout, result, selected=None):
    """A result's objects, each outline in its own colour (:func:`object_colors`); the
    ``selected`` id's drawn wider."""
    colors = object_colors(result.labels, len(result.object_contours))
    segments, segment_colors, widths = [], [], []
    for k, curves in enumerate(result.object_contours):
        segments += [closed_xy(c) for c in curves]
        segment_colors += [OBJECT_COLORS[colors[k]]] * len(curves)
        widths += [3.5 if k + 1 == selected else 2.0] * len(curves)
    layout.contour_lines.set_segments(segments)
    layout.contour_lines.set_color(segment_colors)
    layout.contour_lines.set_linewidths(widths)


def object_colors(labels, count):
    """The index into :data:`OBJECT_COLORS` of objects 1..count of a label image: in id order,
    object k takes colour k - 1 (cycling), or where an object it touches (8-neighbour pixels) of a
    lower id has that one, the first colour none of them has."""
    pairs = set()
    for a, b in ((labels[:, :-1], labels[:, 1:]), (labels[:-1], labels[1:]),
                 (labels[:-1, :-1], labels[1:, 1:]), (labels[:-1, 1:], labels[1:, :-1])):
        touching = (a != b) & (a > 0) & (b > 0)
        pairs.update(zip(a[touching].tolist(), b[touching].tolist(), strict=True))
    neighbours = {}
    for a, b in pairs:
        neighbours.setdefault(a, set()).add(b)
        neighbours.setdefault(b, set()).add(a)
    colors = []
    for label in range(1, count + 1):
        taken = {colors[other - 1] for other in neighbours.get(label, ()) if other < label}
        own = (label - 1) % len(OBJECT_COLORS)
        free = [c for c in range(len(OBJECT_COLORS)) if c not in taken]
        colors.append(own if own not in taken or not free else free[0])
    return colors


def object_summary(result, label):
    """One line of an object's measurements (``result.objects``, the row of id ``label``)."""
    table = result.objects
    row = int(np.flatnonzero(np.asarray(table["label"]) == label)[0])
    brightness = "intensity_mean" if "intensity_mean" in table else None
    text = (f"object {label} of {len(table['label'])}: area {table['area'][row]:.1f} px^2, perimeter "
            f"{table['perimeter'][row]:.1f} px, centre (row {table['centroid-0'][row]:.1f}, col "
            f"{table['centroid-1'][row]:.1f}), eccentricity {table['eccentricity'][row]:.2f}, solidity "
            f"{table['solidity'][row]:.2f}")
    if brightness is None:  # colour: one mean per channel
        means = [table[name][row] for name in sorted(table) if name.startswith("intensity_mean-")]
        return text + (f", brightness {format_constant(means)}" if means else "")
    return text + f", brightness {format_constant(table[brightness][row])}"


def help_text(width=96):
    """The help (key h): every control and readout in a user's words, with the book's symbols and
    equation numbers (the settings' own help, :func:`activecontour.settings.setting_specs`)."""
    import textwrap

    from activecontour.backends import BACKENDS
    from activecontour.settings import setting_specs

    specs = {spec.name: spec.help for spec in setting_specs()}
    entries = [(label, specs[name]) for name, label, *_ in SLIDERS]
    for backend, (option, label, *_) in STEP_OPTIONS.items():
        if backend in BACKENDS:
            helps = {spec.name: spec.help for spec in BACKENDS[backend].option_specs()}
            entries.append((f"{label} ({backend})", helps.get(option, "")))
    entries += [("max iter", specs["max_num_iter"]), ("tol", specs["tol"]), ("backend", specs["backend"]),
                *READOUT_HELP]
    return "\n".join(textwrap.fill(f"{label}: {text}", width, subsequent_indent="    ")
                     for label, text in entries)


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


def format_constant(value, *, bare=False):
    """A number, or a tuple of them (colour channels), in a few digits; ``bare``: the channels
    apart by spaces, without parentheses (the readout's narrow lines)."""
    value = np.asarray(value, dtype=np.float64)
    if value.size == 1:
        return f"{float(value.reshape(-1)[0]):.4g}"
    channels = [f"{v:.3g}" for v in value.reshape(-1)]
    return " ".join(channels) if bare else "(" + ", ".join(channels) + ")"
