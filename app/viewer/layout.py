"""The viewer's window layout: the image with its curves, the readouts, the controls.

:func:`build_layout` places every artist and widget in figure coordinates and returns them in a
:class:`Layout`; it connects nothing (:class:`.window.Viewer` wires the behaviour).  The window::

    +------------------------------+  iteration, energy / c_in / c_out / contours
    |                              |  [energy history plot]
    |   image, initial curve       |  mu, omega, lambda_in, lambda_out, step sliders
    |   (dashed), contour (solid)  |  max iter [   ]  tol [   ]
    |                              |  (backend)  (init mode)
    |                              |  [Run] [Step] [Reset]
    |                              |  image     [      ] [Open]
    +------------------------------+  mask file [      ] [Load mask]
                                      save as   [      ] [Save]
    status line (the whole width)
    help line (keyboard shortcuts)

The positions are fractions of the figure, designed so that nothing overlaps at 900 x 600 pixels
(at 100 dpi) with the fixed font sizes; a larger window only adds space.  The texts whose length
varies (the readout, the status and help lines, the sliders' labels) are fitted to their width
by :func:`fit_text`, again whenever the window is resized.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from activecontour.backends import BACKENDS

from .tools import INIT_MODES, TextField

__all__ = ["CONTOUR_COLOR", "DEFAULT_SIZE", "INIT_COLOR", "PREVIEW_COLOR", "SLIDERS", "STEP_OPTIONS",
           "Layout", "build_layout", "contour_color", "fit_text", "refit_texts", "set_slider_value",
           "show_energy", "show_image"]

#: Colour of the current contour on a gray image (on a colour image: :func:`contour_color`).
CONTOUR_COLOR = (1.0, 0.0, 0.0)
#: Colour of the initial curve (dashed) and of the mouse preview.
INIT_COLOR = (0.0, 0.85, 1.0)
PREVIEW_COLOR = (1.0, 0.85, 0.0)

#: (parameter, slider label, lowest, highest, scale) for the functional's weights; the range widens
#: to include a starting value outside it.  The labels are in a user's words; the book's symbols
#: and equations are in the help (key h, :func:`.display.help_text`).  mu is logarithmic: its
#: useful values span 1e-3 (a clean image) to a few units (heavy noise), and the automatic value
#: is often near 0.01; on a log scale every decade gets the same room (mu = 0 shows as the lowest
#: value, 1e-4).
SLIDERS = (
    ("mu", "smoothness", 1e-4, 10.0, "log"),
    ("omega", "shrink / grow", -1.0, 1.0, "linear"),
    ("lambda_in", "object fit", 0.05, 5.0, "linear"),
    ("lambda_out", "background fit", 0.05, 5.0, "linear"),
)



def _step_options():
    """backend -> (option, label, lowest, highest) of its "step" slider: the first number option
    of its options dataclass with typical values (:class:`activecontour.backends.options.OptionSpec`),
    e.g. the polygon flow's largest trial displacement ``max_step`` and the level set's first step
    ``dt``; a backend added to the registry brings its own.  Its starting value is the default."""
    options = {}
    for name, solver in BACKENDS.items():
        tuned = [spec for spec in solver.option_specs() if spec.kind is float and spec.typical is not None]
        if tuned:
            options[name] = (tuned[0].name, tuned[0].name, *tuned[0].typical)
    return options


#: :func:`_step_options` of the registry (:data:`activecontour.backends.BACKENDS`).
STEP_OPTIONS = _step_options()

#: The window's size in inches (at matplotlib's default 100 dpi: 1200 x 740 pixels).
DEFAULT_SIZE = (12.0, 7.4)
_PANEL_X, _PANEL_RIGHT = 0.655, 0.985  # the control panel's edges, figure fraction
_SLIDER_LABEL_WIDTH = 0.1  # a slider's label, left of the slider (figure fraction)
_TEXT_X, _TEXT_RIGHT = 0.01, 0.99  # the status and help lines
_LABEL_SIZE = 8
_SMALLEST_FONT = 6.0  # fit_text shrinks no further, it cuts the text instead

#: What the energy plot says before a run.
ENERGY_PLACEHOLDER = "no run yet: space runs"


@dataclass
class Layout:
    """The artists and widgets of the viewer's window (see the module docstring)."""

    ax_image: object
    init_lines: object
    contour_lines: object
    readout: object
    ax_energy: object
    energy_line: object
    energy_note: object
    sliders: dict
    step_sliders: dict
    slider_labels: dict
    maxiter_box: object
    tol_box: object
    backend_radio: object
    mode_radio: object
    run_button: object
    step_button: object
    reset_button: object
    image_box: object
    image_button: object
    mask_box: object
    mask_button: object
    save_box: object
    save_button: object
    status_text: object
    help_text: object
    help_panel: object

    @property
    def text_boxes(self):
        return (self.maxiter_box, self.tol_box, self.image_box, self.mask_box, self.save_box)

    @property
    def buttons(self):
        return (self.run_button, self.step_button, self.reset_button, self.image_button,
                self.mask_button, self.save_button)

    @property
    def widgets(self):
        return (*self.sliders.values(), *self.step_sliders.values(), *self.text_boxes,
                self.backend_radio, self.mode_radio, *self.buttons)

    def set_fitted_text(self, text, string):
        """Show ``string`` in one of the :attr:`fitted_texts`, fitted to its width."""
        left, right = next((lo, hi) for t, lo, hi in self.fitted_texts if t is text)
        fit_text(text, string, left, right)

    @property
    def fitted_texts(self):
        """(text, left, right): the texts :func:`fit_text` keeps between two figure fractions."""
        labels = tuple((text, _PANEL_X, _PANEL_X + _SLIDER_LABEL_WIDTH)
                       for text in self.slider_labels.values())
        return ((self.readout, _PANEL_X, _PANEL_RIGHT), (self.status_text, _TEXT_X, _TEXT_RIGHT),
                (self.help_text, _TEXT_X, _TEXT_RIGHT), *labels)


def build_layout(fig, display, *, backends, backend, values, step_values, max_num_iter, tol,
                 save_stem, help_line):
    """Place the viewer's artists and widgets on ``fig``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    display : ndarray (M, N, 3) of uint8
        The image as shown (:func:`activecontour.io.pictures.display_rgb`).
    backends : sequence of str
        The backend choices; ``backend`` is selected.
    values : dict
        Starting values of the :data:`SLIDERS` parameters.
    step_values : dict
        backend -> starting value of its step slider (a backend without one gets no slider).
    max_num_iter, tol
        Starting values of the fields.
    save_stem : str
        Starting text of the "save as" field.
    help_line : str
        The keyboard help shown at the bottom.
    """
    ax_image, init_lines, contour_lines = _image_axes(fig, display)
    x0 = _PANEL_X
    readout = fig.text(x0, 0.985, "", fontsize=8.5, family="monospace", va="top")
    ax_energy, energy_line, energy_note = _energy_axes(fig, x0)
    sliders, step_sliders, slider_labels = _sliders(fig, x0, values, step_values)
    maxiter_box, tol_box = _fields(fig, x0, max_num_iter, tol)
    backend_radio, mode_radio = _radios(fig, x0, backends, backend)
    run_button, step_button, reset_button = _run_buttons(fig, x0)
    file_rows = _file_rows(fig, x0, save_stem)
    status_text = fig.text(_TEXT_X, 0.047, "", fontsize=9, color="0.1", va="center")
    help_text = fig.text(_TEXT_X, 0.016, "", fontsize=_LABEL_SIZE, color="0.35", va="center")
    # the help (key h): over the image, hidden until asked for
    help_panel = ax_image.text(0.02, 0.98, "", transform=ax_image.transAxes, fontsize=_LABEL_SIZE, va="top",
                               wrap=True, visible=False, zorder=6,
                               bbox={"boxstyle": "round", "facecolor": "white", "alpha": 0.92})
    layout = Layout(ax_image, init_lines, contour_lines, readout, ax_energy, energy_line,
                    energy_note, sliders, step_sliders, slider_labels, maxiter_box, tol_box,
                    backend_radio, mode_radio, run_button, step_button, reset_button, *file_rows,
                    status_text, help_text, help_panel)
    fit_text(help_text, help_line, _TEXT_X, _TEXT_RIGHT)
    return layout


def new_figure():
    """The viewer's pyplot figure (pyplot, so that ``plt.show`` opens it)."""
    import matplotlib.pyplot as plt

    return plt.figure(figsize=DEFAULT_SIZE)


def fit_text(text, string, left, right, *, size=None):
    """Show ``string`` in the artist ``text``, shrunk (and, if need be, cut with an ellipsis) so
    that it fits between the figure fractions ``left`` and ``right``.

    ``size`` is the wanted font size; by default the one this function was first given, kept on
    the artist, so that a text refitted after a resize grows back.
    """
    if size is None:
        size = getattr(text, "_fit_size", None) or text.get_fontsize()
    text._fit_size, text._fit_string = size, string
    fig = text.get_figure(root=True)
    width = (right - left) * fig.bbox.width
    text.set_text(string)
    text.set_fontsize(size)
    actual = text.get_window_extent().width
    if actual <= width or not string:
        return
    text.set_fontsize(max(_SMALLEST_FONT, size * width / actual * 0.98))
    if text.get_window_extent().width <= width:
        return
    lines = string.split("\n")
    low, high = 0, max(len(line) for line in lines)  # characters kept per line
    while low < high:
        keep = (low + high + 1) // 2
        text.set_text("\n".join(_cut(line, keep) for line in lines))
        if text.get_window_extent().width <= width:
            low = keep
        else:
            high = keep - 1
    text.set_text("\n".join(_cut(line, low) for line in lines))


def refit_texts(layout):
    """Fit the layout's variable texts again (after the window changed size)."""
    for text, left, right in layout.fitted_texts:
        fit_text(text, getattr(text, "_fit_string", text.get_text()), left, right)
    for box in layout.text_boxes:
        box.align_to_fit()


def _cut(line, keep):
    return line if len(line) <= keep else line[:max(keep - 1, 0)] + "\N{HORIZONTAL ELLIPSIS}"


def show_image(ax, display):
    """Show the display image (M, N, 3) uint8 (:func:`activecontour.io.pictures.display_rgb`, as
    the CLI's overlay shows it) on the image axes, replacing the one shown, and reset the view to
    the whole image."""
    for old in list(ax.images):
        old.remove()
    image = ax.imshow(display, interpolation="nearest")
    image.set_mouseover(False)  # the toolbar shows the viewer's format_coord (row, col, value) only
    m, n = display.shape[:2]
    ax.set_xlim(-0.5, n - 0.5)
    ax.set_ylim(m - 0.5, -0.5)
    return image


def show_energy(ax, line, note, history):
    """Plot the energy history (n, 2) of (iteration, energy); an empty history clears the plot
    to its labelled placeholder."""
    from matplotlib.ticker import AutoLocator

    empty = len(history) == 0
    note.set_visible(empty)
    if empty:
        line.set_data([], [])
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.0)
        return
    if not isinstance(ax.xaxis.get_major_locator(), AutoLocator):
        ax.xaxis.set_major_locator(AutoLocator())
        ax.yaxis.set_major_locator(AutoLocator())
    line.set_data(history[:, 0], history[:, 1])
    ax.relim()
    ax.set_autoscale_on(True)  # the placeholder fixed the limits
    ax.autoscale_view()


def contour_color(display):
    """The contour's colour on the display image, as the overlays draw it
    (:func:`activecontour.io.pictures.contrasting_color`: red on gray, one that stands out on
    colour), as matplotlib RGB in [0, 1]."""
    from activecontour.io.pictures import contrasting_color

    return tuple(channel / 255.0 for channel in contrasting_color(display))


def _image_axes(fig, display):
    from matplotlib.collections import LineCollection

    ax = fig.add_axes((0.06, 0.165, 0.575, 0.82))
    show_image(ax, display)
    ax.set_xlabel("col", fontsize=_LABEL_SIZE, labelpad=2)
    ax.set_ylabel("row", fontsize=_LABEL_SIZE, labelpad=2)
    ax.tick_params(labelsize=7)
    init_lines = LineCollection([], colors=[INIT_COLOR], linewidths=1.3, linestyles="--", zorder=3)
    contour_lines = LineCollection([], colors=[contour_color(display)], linewidths=2.0, zorder=4)
    ax.add_collection(init_lines, autolim=False)
    ax.add_collection(contour_lines, autolim=False)
    return ax, init_lines, contour_lines


def _energy_axes(fig, x0):
    ax = fig.add_axes((x0 + 0.055, 0.745, _PANEL_RIGHT - x0 - 0.065, 0.1))
    ax.set_title("energy", fontsize=_LABEL_SIZE, pad=3)
    ax.tick_params(labelsize=7, pad=2)
    ax.set_xlabel("iteration", fontsize=7, labelpad=1)
    ax.yaxis.get_offset_text().set_fontsize(7)
    (line,) = ax.plot([], [], color="0.2", linewidth=1.2)
    note = ax.text(0.5, 0.5, ENERGY_PLACEHOLDER, transform=ax.transAxes, ha="center",
                   va="center", fontsize=_LABEL_SIZE, color="0.45")
    show_energy(ax, line, note, np.empty((0, 2)))
    return ax, line, note


def _sliders(fig, x0, values, step_values):
    from matplotlib.widgets import Slider

    rows = [(name, label, low, high, scale, values[name]) for name, label, low, high, scale in SLIDERS]
    rows += [(backend, label, low, high, "linear", step_values[backend])
             for backend, (_option, label, low, high) in STEP_OPTIONS.items() if backend in step_values]
    sliders, step_sliders, labels = {}, {}, {}
    for row, (name, label, low, high, scale, value) in enumerate(rows):
        y = 0.655 - 0.042 * min(row, len(SLIDERS))  # the step sliders share one row
        if scale == "log":
            value = max(value, low)
        low, high = min(low, value), max(high, value)
        ax = fig.add_axes((x0 + _SLIDER_LABEL_WIDTH + 0.005, y, 0.165, 0.03))
        ax.set_xscale(scale)  # a click's data coordinate is then the value itself
        slider = Slider(ax, "", low, high, valinit=value, valfmt="%.3g")
        ax.set_xlim(low, high)
        slider.valtext.set_fontsize(_LABEL_SIZE)
        text = fig.text(x0, y + 0.015, "", fontsize=_LABEL_SIZE, va="center")
        fit_text(text, label, x0, x0 + _SLIDER_LABEL_WIDTH)
        (step_sliders if name in STEP_OPTIONS else sliders)[name] = slider
        labels[name] = text
    return sliders, step_sliders, labels


def set_slider_value(slider, value):
    """Move a slider to ``value``, widening its range to include it (a log slider's lowest value
    stands for the values below it, 0 included)."""
    if slider.ax.get_xscale() == "log":
        value = max(value, slider.valmin)
    if value > slider.valmax or value < slider.valmin:
        slider.valmin, slider.valmax = min(slider.valmin, value), max(slider.valmax, value)
        slider.ax.set_xlim(slider.valmin, slider.valmax)
    slider.set_val(value)


def _fields(fig, x0, max_num_iter, tol):
    y, height, field_x = 0.43, 0.04, x0 + 0.105
    fig.text(x0, y + height / 2, "max iter", fontsize=_LABEL_SIZE, va="center")
    maxiter_box = TextField(fig.add_axes((field_x, y, 0.075, height)), str(int(max_num_iter)))
    fig.text(x0 + 0.2, y + height / 2, "tol", fontsize=_LABEL_SIZE, va="center")
    tol_box = TextField(fig.add_axes((x0 + 0.235, y, _PANEL_RIGHT - x0 - 0.245, height)), f"{tol:g}")
    return maxiter_box, tol_box


def _radios(fig, x0, backends, backend):
    from matplotlib.widgets import RadioButtons

    y, height, width = 0.3, 0.1, 0.155
    ax = fig.add_axes((x0, y, width, height))
    ax.set_title("backend", fontsize=_LABEL_SIZE, pad=2)
    backend_radio = RadioButtons(ax, list(backends), active=list(backends).index(backend))
    ax = fig.add_axes((_PANEL_RIGHT - width, y, width, height))
    ax.set_title("init (mouse)", fontsize=_LABEL_SIZE, pad=2)
    mode_radio = RadioButtons(ax, list(INIT_MODES), active=0)
    for radio in (backend_radio, mode_radio):
        for text in radio.labels:
            text.set_fontsize(_LABEL_SIZE)
    return backend_radio, mode_radio


def _run_buttons(fig, x0):
    from matplotlib.widgets import Button

    y, height, gap = 0.235, 0.05, 0.01
    width = (_PANEL_RIGHT - x0 - 2 * gap) / 3
    buttons = [Button(fig.add_axes((x0 + (width + gap) * i, y, width, height)), label)
               for i, label in enumerate(("Run", "Step", "Reset"))]
    for button in buttons:
        button.label.set_fontsize(9)
    return buttons


def _file_rows(fig, x0, save_stem):
    """The rows (label, field, button) for opening an image, loading a mask and saving."""
    from matplotlib.widgets import Button

    field_x, button_w, height = x0 + 0.075, 0.1, 0.04
    button_x = _PANEL_RIGHT - button_w
    field_w = button_x - 0.008 - field_x
    widgets = []
    for y, label, initial, action in ((0.18, "image", "", "Open"),
                                      (0.13, "mask file", "", "Load mask"),
                                      (0.08, "save as", save_stem, "Save")):
        fig.text(x0, y + height / 2, label, fontsize=_LABEL_SIZE, va="center")
        box = TextField(fig.add_axes((field_x, y, field_w, height)), initial)
        button = Button(fig.add_axes((button_x, y, button_w, height)), action)
        button.label.set_fontsize(9)
        widgets += [box, button]
    return widgets
