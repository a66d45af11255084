"""The viewer's window layout: the image with its curves, the readouts, the controls.

:func:`build_layout` places every artist and widget in figure coordinates and returns them in a
:class:`Layout`; it connects nothing (:class:`app.viewer.Viewer` wires the behaviour).  The window::

    +------------------------------+  iteration, energy, c_in, c_out, contours
    |                              |  [energy history plot]
    |   image, initial curve       |  mu, omega, lambda_in, lambda_out, step sliders
    |   (dashed), contour (solid)  |  max iter [   ]  tol [   ]
    |                              |  (backend)  (init mode)
    |                              |  [Run] [Step] [Reset]
    +------------------------------+  mask file [      ] [Load mask]
    status line                       save as   [      ] [Save]
    help line (keyboard shortcuts)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.viewer_tools import INIT_MODES, TextField

__all__ = ["CONTOUR_COLOR", "INIT_COLOR", "PREVIEW_COLOR", "SLIDERS", "STEP_OPTIONS", "Layout",
           "build_layout"]

#: Colour of the current contour: the default overlay colour of :func:`activecontour.io.save_result`.
CONTOUR_COLOR = (1.0, 0.0, 0.0)
#: Colour of the initial curve (dashed) and of the mouse preview.
INIT_COLOR = (0.0, 0.85, 1.0)
PREVIEW_COLOR = (1.0, 0.85, 0.0)

#: (parameter, slider label, lowest, highest) for the functional's weights; the range widens to
#: include a starting value outside it.
SLIDERS = (
    ("mu", "mu (length)", 0.0, 5.0),
    ("omega", "omega (area)", -1.0, 1.0),
    ("lambda_in", "lambda_in", 0.05, 5.0),
    ("lambda_out", "lambda_out", 0.05, 5.0),
)

#: backend -> (option, label, lowest, highest) of the "step" slider: the polygon flow's largest
#: first trial displacement in pixels (:func:`activecontour.flow.segment_polygon`), the level set's
#: initial time step (:func:`activecontour.levelset.segment_levelset`).  Its starting value is the
#: backend's own default.
STEP_OPTIONS = {
    "polygon": ("max_step", "step (px)", 0.25, 10.0),
    "levelset": ("dt", "first step dt", 4.0, 256.0),
}

_FIGSIZE = (12.0, 7.4)
_PANEL_X = 0.665  # left edge of the control panel, figure fraction
_LABEL_SIZE = 8


@dataclass
class Layout:
    """The artists and widgets of the viewer's window (see the module docstring)."""

    ax_image: object
    init_lines: object
    contour_lines: object
    readout: object
    ax_energy: object
    energy_line: object
    sliders: dict
    step_sliders: dict
    step_labels: dict
    maxiter_box: object
    tol_box: object
    backend_radio: object
    mode_radio: object
    run_button: object
    step_button: object
    reset_button: object
    mask_box: object
    mask_button: object
    save_box: object
    save_button: object
    status_text: object
    help_text: object

    @property
    def text_boxes(self):
        return (self.maxiter_box, self.tol_box, self.mask_box, self.save_box)

    @property
    def buttons(self):
        return (self.run_button, self.step_button, self.reset_button, self.mask_button,
                self.save_button)

    @property
    def widgets(self):
        return (*self.sliders.values(), *self.step_sliders.values(), *self.text_boxes,
                self.backend_radio, self.mode_radio, *self.buttons)


def build_layout(fig, display, *, backends, backend, values, step_values, max_num_iter, tol,
                 save_stem, help_line):
    """Place the viewer's artists and widgets on ``fig``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    display : ndarray (M, N, C)
        The normalised image (:func:`activecontour.image.normalize_image` with ``color="vector"``).
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
    readout = fig.text(x0, 0.965, "", fontsize=9, family="monospace", va="top")
    ax_energy, energy_line = _energy_axes(fig, x0)
    sliders, step_sliders, step_labels = _sliders(fig, x0, values, step_values)
    maxiter_box, tol_box = _fields(fig, x0, max_num_iter, tol)
    backend_radio, mode_radio = _radios(fig, x0, backends, backend)
    run_button, step_button, reset_button = _run_buttons(fig, x0)
    mask_box, mask_button, save_box, save_button = _file_rows(fig, x0, save_stem)
    status_text = fig.text(0.035, 0.045, "", fontsize=9, color="0.1", va="center")
    help_text = fig.text(0.035, 0.014, help_line, fontsize=_LABEL_SIZE, color="0.35", va="center")
    return Layout(ax_image, init_lines, contour_lines, readout, ax_energy, energy_line, sliders,
                  step_sliders, step_labels, maxiter_box, tol_box, backend_radio, mode_radio,
                  run_button, step_button, reset_button, mask_box, mask_button, save_box,
                  save_button, status_text, help_text)


def new_figure():
    """The viewer's pyplot figure (pyplot, so that ``plt.show`` opens it)."""
    import matplotlib.pyplot as plt

    return plt.figure(figsize=_FIGSIZE)


def _image_axes(fig, display):
    from matplotlib.collections import LineCollection

    ax = fig.add_axes((0.035, 0.12, 0.58, 0.84))
    if display.shape[2] == 1:
        values = display[:, :, 0]
        # as the CLI's overlay shows it: [0, 1], widened to the image's range when it exceeds it
        ax.imshow(values, cmap="gray", interpolation="nearest",
                  vmin=min(0.0, values.min()), vmax=max(1.0, values.max()))
    else:
        low, high = display.min(), display.max()
        if low < 0.0 or high > 1.0:
            display = (display - low) / (high - low) if high > low else display * 0.0
        ax.imshow(np.clip(display, 0.0, 1.0), interpolation="nearest")
    ax.set_xlabel("col", fontsize=_LABEL_SIZE)
    ax.set_ylabel("row", fontsize=_LABEL_SIZE)
    ax.tick_params(labelsize=7)
    init_lines = LineCollection([], colors=[INIT_COLOR], linewidths=1.3, linestyles="--", zorder=3)
    contour_lines = LineCollection([], colors=[CONTOUR_COLOR], linewidths=2.0, zorder=4)
    ax.add_collection(init_lines)
    ax.add_collection(contour_lines)
    return ax, init_lines, contour_lines


def _energy_axes(fig, x0):
    ax = fig.add_axes((x0 + 0.045, 0.71, 0.26, 0.15))
    ax.set_title("energy (6.38)", fontsize=_LABEL_SIZE, pad=3)
    ax.tick_params(labelsize=7)
    ax.set_xlabel("iteration", fontsize=7, labelpad=1)
    (line,) = ax.plot([], [], color="0.2", linewidth=1.2)
    return ax, line


def _sliders(fig, x0, values, step_values):
    from matplotlib.widgets import Slider

    rows = [(name, label, low, high, values[name]) for name, label, low, high in SLIDERS]
    rows += [(backend, label, low, high, step_values[backend])
             for backend, (_option, label, low, high) in STEP_OPTIONS.items() if backend in step_values]
    sliders, step_sliders, step_labels = {}, {}, {}
    for row, (name, label, low, high, value) in enumerate(rows):
        y = 0.615 - 0.042 * min(row, len(SLIDERS))  # the step sliders share one row
        low, high = min(low, value), max(high, value)
        slider = Slider(fig.add_axes((x0 + 0.095, y, 0.16, 0.026)), "", low, high, valinit=value,
                        valfmt="%.3g")
        slider.valtext.set_fontsize(_LABEL_SIZE)
        text = fig.text(x0, y + 0.013, label, fontsize=_LABEL_SIZE, va="center")
        if name in STEP_OPTIONS:
            step_sliders[name], step_labels[name] = slider, text
        else:
            sliders[name] = slider
    return sliders, step_sliders, step_labels


def _fields(fig, x0, max_num_iter, tol):
    y, field_x = 0.375, x0 + 0.095
    fig.text(x0, y + 0.0175, "max iter", fontsize=_LABEL_SIZE, va="center")
    maxiter_box = TextField(fig.add_axes((field_x, y, 0.07, 0.035)), str(int(max_num_iter)))
    fig.text(field_x + 0.085, y + 0.0175, "tol", fontsize=_LABEL_SIZE, va="center")
    tol_box = TextField(fig.add_axes((field_x + 0.11, y, 0.05, 0.035)), f"{tol:g}")
    return maxiter_box, tol_box


def _radios(fig, x0, backends, backend):
    from matplotlib.widgets import RadioButtons

    y, height = 0.235, 0.115
    ax = fig.add_axes((x0, y, 0.145, height))
    ax.set_title("backend", fontsize=_LABEL_SIZE, pad=2)
    backend_radio = RadioButtons(ax, list(backends), active=list(backends).index(backend))
    ax = fig.add_axes((x0 + 0.16, y, 0.155, height))
    ax.set_title("init (mouse)", fontsize=_LABEL_SIZE, pad=2)
    mode_radio = RadioButtons(ax, list(INIT_MODES), active=0)
    for radio in (backend_radio, mode_radio):
        for text in radio.labels:
            text.set_fontsize(_LABEL_SIZE)
    return backend_radio, mode_radio


def _run_buttons(fig, x0):
    from matplotlib.widgets import Button

    y, width, height = 0.165, 0.095, 0.045
    buttons = [Button(fig.add_axes((x0 + 0.11 * i, y, width, height)), label)
               for i, label in enumerate(("Run", "Step", "Reset"))]
    for button in buttons:
        button.label.set_fontsize(9)
    return buttons


def _file_rows(fig, x0, save_stem):
    from matplotlib.widgets import Button

    field_x, field_w, button_w, height = x0 + 0.075, 0.155, 0.075, 0.04
    button_x = field_x + field_w + 0.01
    fig.text(x0, 0.12, "mask file", fontsize=_LABEL_SIZE, va="center")
    mask_box = TextField(fig.add_axes((field_x, 0.1, field_w, height)))
    mask_button = Button(fig.add_axes((button_x, 0.1, button_w, height)), "Load mask")
    fig.text(x0, 0.06, "save as", fontsize=_LABEL_SIZE, va="center")
    save_box = TextField(fig.add_axes((field_x, 0.04, field_w, height)), save_stem)
    save_button = Button(fig.add_axes((button_x, 0.04, button_w, height)), "Save")
    for button in (mask_button, save_button):
        button.label.set_fontsize(9)
    return mask_box, mask_button, save_box, save_button
