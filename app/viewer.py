"""The interactive viewer: ``activecontour view IMAGE``.

A matplotlib window that shows an image with the current contour(s), lets the user set the initial
curve with the mouse (circle, box, polygon) or from a mask file, and runs, pauses and single-steps
the flow of :func:`activecontour.segment` while showing the iteration, the energy (6.38), the
constants c_in, c_out (6.42) and a small plot of the energy history.  Sliders set mu, omega,
lambda_in, lambda_out and the polygon backend's step size; fields set max_num_iter and tol; radio
buttons choose the backend and the init gesture.  Changes apply to the next run.  The result is
saved with the CLI's writers (:func:`activecontour.io.save_result`).

The viewer holds no solver logic: every iteration is the library's, seen through its callback.

Responsiveness
--------------
A run is one call of :func:`activecontour.segment` in the GUI (main) thread.  Its callback, called
once per iteration, updates the contour, the readouts and the energy plot every ``redraw_every``
iterations (``canvas.draw_idle``), but no sooner than the last redraw took after the end of that
redraw, so drawing never takes more than about half of a run's time; and it lets the GUI toolkit
process pending events (``canvas.flush_events``) every ``FLUSH_INTERVAL`` seconds, or after every
iteration when iterations are slower than that.  Clicks and keys are therefore handled *during*
the run: pause (space, the Run/Pause button), quit, reset and closing the window only set a flag,
and the callback returns True at the next iteration, which ends the run with status 2 ("stopped by
the callback").  Resuming calls ``segment`` again with the last result as init (its contours; the
level set also takes its phi), and the constants c are re-estimated from it; a single step is a
run with ``max_num_iter=1`` from there.  A run that is never paused is therefore exactly the
library's ``segment(image, init, ...)`` with the same parameters.

This needs no threads (matplotlib artists are not thread-safe) and no timers (which never fire on a
non-interactive canvas): with the Agg backend the same code runs headless and a run simply goes to
its end unless a callback of the test stops it, which is how the tests drive the viewer.  On a
non-interactive canvas nothing is drawn during a run (``live=False``); ``savefig`` draws the final
state.

Keyboard shortcuts (listed in the window's help line): see :data:`SHORTCUTS`.  They replace
matplotlib's default keys that clash (s save figure, r/h home, p pan, c back, q quit); the other
default keys (o zoom, g grid, f fullscreen, ...) keep working.  While a text field is being edited
the shortcuts are off.
"""

from __future__ import annotations

import contextlib
import inspect
import os
import sys
import time
from pathlib import Path

import numpy as np

from activecontour.curve import length, to_xy
from activecontour.image import load_image, normalize_image
from activecontour.initial import default_init, initial_curves
from activecontour.noise import auto_mu, is_auto
from activecontour.segment import BACKENDS, segment
from app.viewer_layout import (
    CONTOUR_COLOR,
    PREVIEW_COLOR,
    SLIDERS,
    STEP_OPTIONS,
    build_layout,
    new_figure,
)
from app.viewer_tools import INIT_MODES, CurveDrawer

__all__ = ["CONTOUR_COLOR", "SHORTCUTS", "Viewer", "launch"]

#: Seconds between two calls of ``flush_events`` during a run: the GUI answers within this time
#: plus one iteration.
FLUSH_INTERVAL = 0.03

#: (key as matplotlib names it, what the help line shows, action name)
SHORTCUTS = (
    (" ", "space", "run/pause"),
    ("n", "n", "step"),
    ("r", "r", "reset"),
    ("s", "s", "save"),
    ("c", "c", "circle"),
    ("b", "b", "box"),
    ("p", "p", "polygon"),
    ("m", "m", "load mask"),
    ("g", "g", "gray/colour"),
    ("q", "q", "quit"),
)

_STATUS_WORDS = {0: "converged", 1: "max_num_iter reached", 2: "paused", 3: "collapsed",
                 4: "stationary"}


class Viewer:
    """The viewer's figure, widgets and actions, without showing a window.

    Parameters
    ----------
    image : ndarray of shape (M, N) or (M, N, C)
        The image, as :func:`activecontour.load_image` returns it.
    image_path : str or os.PathLike, optional
        Where the image came from: the window title, the default save stem (``<dir>/<stem>``), and
        a file the writers must not overwrite.
    backend, mu, omega, lambda_in, lambda_out, max_num_iter, tol
        Starting values of the controls, as in :func:`activecontour.segment`; None takes the
        library's default.
    c_in, c_out : float or sequence, optional
        Hold the region constants fixed (passed to :func:`activecontour.segment`; no control).
    init : None, path, ndarray (K, 2), list of them, or bool ndarray (M, N)
        The initial curve: a mask file (path), anything :func:`activecontour.segment` accepts, or
        None for the library's default (a centred circle).
    color : {"gray", "vector"}
        How colour images are segmented (see :func:`activecontour.segment`).
    formats : sequence of str
        Contour formats written by Save, from :data:`activecontour.io.CONTOUR_FORMATS`.
    redraw_every : int
        During a run, redraw the contour every this many iterations.
    live : bool, optional
        Draw during runs and after each action; by default True on an interactive canvas and
        False on a non-interactive one (Agg), where nothing is drawn until the figure is drawn or
        saved (``savefig``).

    Attributes
    ----------
    fig : matplotlib.figure.Figure
    layout : app.viewer_layout.Layout
        The window's artists and widgets, which are also attributes of the viewer
        (``ax_image``, ``sliders``, ``run_button``, ``save_box``, ...).
    init_curves : list of ndarray (K, 2)
        The initial curves, clipped to the image as the library does.
    contours : list of ndarray (K, 2)
        The current contours (empty before the first run and after a reset).
    result : SegmentationResult or None
        The last run's result; None before any run and after a new init or a reset.
    iteration : int
        Iterations since the init was set or reset.
    energy_history : ndarray of shape (n, 2)
        (iteration, energy) since the init was set or reset.
    message : str
        The status line.
    running, closed : bool
    """

    def __init__(self, image, *, image_path=None, backend=None, mu=None, omega=None, lambda_in=None,
                 lambda_out=None, max_num_iter=None, tol=None, init=None, c_in=None, c_out=None,
                 color="gray", formats=("json",), redraw_every=2, live=None):
        settings = _settings(backend=backend, mu=mu, omega=omega, lambda_in=lambda_in,
                             lambda_out=lambda_out, max_num_iter=max_num_iter, tol=tol)
        if isinstance(redraw_every, bool) or not isinstance(redraw_every, (int, np.integer)) \
                or redraw_every < 1:
            raise ValueError(f"redraw_every must be an integer >= 1, got {redraw_every!r}")
        if color not in ("gray", "vector"):
            raise ValueError(f"color must be one of ('gray', 'vector'), got {color!r}")
        from activecontour.io import CONTOUR_FORMATS

        formats = (formats,) if isinstance(formats, str) else tuple(formats)
        for fmt in formats:
            if fmt not in CONTOUR_FORMATS:
                raise ValueError(f"formats must be chosen from {CONTOUR_FORMATS}, got {fmt!r}")
        self.image = np.asarray(image)
        self.color = color
        self.fixed_constants = {"c_in": c_in, "c_out": c_out}
        display = normalize_image(self.image, color="vector")  # validates the image, too
        self.shape = display.shape[:2]
        values = normalize_image(self.image, color=color)
        if is_auto(settings["mu"]):  # the slider starts at the value segment(mu="auto") would use
            settings["mu"] = auto_mu(values)
        self.image_path = None if image_path is None else Path(image_path)
        self.formats = formats
        self.redraw_every = int(redraw_every)
        self.init_curves = default_init(self.shape, values, settings["mu"])  # segment's init=None
        if init is not None:  # a bad init is an error here, before any window exists
            if isinstance(init, (str, os.PathLike)):
                init = _read_mask_file(init)
            self.init_curves = initial_curves(init, self.shape)

        self.result = None
        self.contours = []
        self.iteration = 0
        self.message = ""
        self.running = False
        self.closed = False
        self._history = []  # (iteration, energy) of finished runs
        self._live_history = []  # of the run in progress
        self._session_iterations = 0  # iterations counted against max_num_iter
        self._session_open = True  # a run may continue the current session (after pause or step)
        self._stop = False  # the callback returns True at the next iteration
        self._after_run = None  # "reset" or "quit", deferred until the run has stopped
        self._run_offset = 0
        self._last_flush = self._last_draw_end = -np.inf
        self._last_draw_iteration, self._draw_cost = 0, 0.0

        self.fig = new_figure()
        title = "activecontour view" + (f": {self.image_path.name}" if self.image_path else "")
        manager = self.fig.canvas.manager
        if manager is not None:
            manager.set_window_title(title)
        self.live = (self.fig.canvas.required_interactive_framework is not None) if live is None \
            else bool(live)
        step_values = {name: _backend_default(name, option) for name, (option, *_) in STEP_OPTIONS.items()}
        help_line = "   ".join(f"{shown} {action}" for _, shown, action in SHORTCUTS)
        with _no_redraw(self.fig.canvas):  # widgets redraw as they are built: once is enough
            layout = build_layout(
                self.fig, display, backends=tuple(BACKENDS), backend=settings["backend"],
                values={name: settings[name] for name, *_ in SLIDERS},
                step_values={k: v for k, v in step_values.items() if v is not None},
                max_num_iter=settings["max_num_iter"], tol=settings["tol"],
                save_stem="" if self.image_path is None else os.fspath(self.image_path.with_suffix("")),
                help_line=f"keys: {help_line}   |   polygon: click vertices, enter closes, esc cancels")
        self.layout = layout
        vars(self).update(vars(layout))  # its artists and widgets are the viewer's attributes
        self._valid_fields = {"max iter": self.maxiter_box.text, "tol": self.tol_box.text}
        self.drawer = CurveDrawer(self.ax_image, self._on_drawn_curve, self._set_message, self._redraw,
                                  color=PREVIEW_COLOR)
        self._show_step_slider(settings["backend"])
        if not self.live:
            for widget in layout.widgets:
                widget.drawon = False
        self._connect_events()
        self._show_curves()
        self._show_readout(None)
        self._set_message("draw an initial curve with the mouse (or keep the default circle), "
                          "then press space to run")

    # ------------------------------------------------------------------------------- controls
    def parameters(self):
        """The settings the next run will use: keywords of :func:`activecontour.segment`."""
        backend = self.backend_radio.value_selected
        params = {name: float(self.sliders[name].val) for name, *_ in SLIDERS}
        params.update(backend=backend, max_num_iter=self._max_num_iter, tol=self._tol,
                      color=self.color, **self.fixed_constants)
        if backend in self.step_sliders:
            params["options"] = {STEP_OPTIONS[backend][0]: float(self.step_sliders[backend].val)}
        return params

    @property
    def init_mode(self):
        return self.drawer.mode

    def set_init_mode(self, mode):
        """Choose the mouse gesture for the next init: "circle", "box" or "polygon"."""
        index = INIT_MODES.index(mode) if mode in INIT_MODES else None
        if index is None:
            raise ValueError(f"init mode must be one of {INIT_MODES}, got {mode!r}")
        if self.mode_radio.value_selected != mode:
            self.mode_radio.set_active(index)  # calls _on_mode_radio
        else:
            self._on_mode_radio(mode)

    @property
    def output_stem(self):
        return self.save_box.text.strip()

    # -------------------------------------------------------------------------------- actions
    def toggle_run(self):
        """Run, or pause the run in progress."""
        if self.running:
            self._stop = True
            return None
        return self.run()

    def run(self):
        """Run the flow from the current contours (or the init) until it stops; returns the result."""
        if self.running:
            return None
        budget = self._max_num_iter - self._session_iterations
        if not self._session_open or budget <= 0:
            self._session_open, self._session_iterations = True, 0
            budget = self._max_num_iter
        return self._run(budget)

    def step(self):
        """One iteration from the current contours (or the init)."""
        if self.running:
            self._set_message("running: press space to pause before stepping")
            return None
        if not self._session_open or self._session_iterations >= self._max_num_iter:
            self._session_open, self._session_iterations = True, 0
        return self._run(1)

    def reset(self):
        """Back to the initial curve: forget the contours, the result and the energy history."""
        if self.running:
            self._stop, self._after_run = True, "reset"
            return
        self._clear_run()
        self._show_curves()
        self._show_readout(None)
        self._set_message("reset to the initial curve")

    def set_init(self, init):
        """Set the initial curve(s) from anything :func:`activecontour.segment` accepts.

        Returns True when the init was accepted; otherwise the status line says why (for example
        a curve outside the image) and the previous init stays.
        """
        if self.running:
            self._set_message("running: press space to pause before setting a new init")
            return False
        try:
            curves = initial_curves(init, self.shape)
        except (ValueError, TypeError) as exc:
            self._set_message(f"init not set: {exc}")
            return False
        self.init_curves = curves
        self._clear_run()
        self._show_curves()
        self._show_readout(None)
        clipped = not _same_curves(curves, init)
        self._set_message(f"init set ({len(curves)} curve{'s' * (len(curves) > 1)}"
                          f"{', clipped to the image' if clipped else ''}): press space to run")
        return True

    def load_mask(self, path=None):
        """Use a mask file as the init (path, or the text of the "mask file" field)."""
        path = self.mask_box.text.strip() if path is None else os.fspath(path)
        if not path:
            self._set_message("type a mask file's path in the 'mask file' field, then press m")
            return False
        try:
            mask = _read_mask_file(path)
        except (OSError, ValueError) as exc:
            self._set_message(f"mask not loaded: {exc}")
            return False
        return self.set_init(mask)

    def save(self, stem=None):
        """Save mask, overlay and contours with the CLI's writers; returns the paths written.

        Before any run, or while running, the status line says so and nothing is written.
        """
        if self.running:
            self._set_message("running: press space to pause before saving")
            return None
        if self.result is None:
            self._set_message("nothing to save yet: run the flow first (space)")
            return None
        stem = self.output_stem if stem is None else os.fspath(stem)
        if not stem:
            self._set_message("type an output stem in the 'save as' field, then press s")
            return None
        from activecontour.io import save_result

        protect = [self.image_path] if self.image_path is not None else []
        metadata = {"parameters": _jsonable_parameters(self.parameters())}
        if self.image_path is not None:
            metadata["image"] = os.fspath(self.image_path)
        try:
            paths = save_result(self.result, self.image, stem, self.formats, metadata=metadata,
                                protect=protect)
        except (OSError, ValueError) as exc:
            self._set_message(f"not saved: {exc}")
            return None
        folder = os.path.dirname(os.path.abspath(paths[0]))
        self._set_message(f"saved {', '.join(p.name for p in paths)} in {folder}")
        return paths

    def quit(self):
        """Close the window (after stopping a run in progress)."""
        if self.running:
            self._stop, self._after_run = True, "quit"
            return
        import matplotlib.pyplot as plt

        plt.close(self.fig)
        self.closed = True  # not every backend sends close_event for plt.close

    # ------------------------------------------------------------------------------ the run
    def _run(self, n_iter):
        import activecontour

        params = self.parameters()
        params["max_num_iter"] = n_iter
        if self.contours:  # continue: the last result carries the level set's phi, too
            same_backend = self.result is not None and self.result.backend == params["backend"]
            start = self.result if same_backend else self.contours
        else:  # a fresh start from the init (also after a collapse)
            self._clear_run()
            start = self.init_curves
        self.drawer.cancel()
        self.running, self._stop, self._after_run = True, False, None
        self._run_offset = self.iteration
        self._live_history = []
        self._last_flush = self._last_draw_end = -np.inf
        self._last_draw_iteration = 0
        self.run_button.label.set_text("Pause")
        self._set_message(f"running {params['backend']} (space pauses)")
        if self.live and n_iter > 1:
            self.fig.canvas.flush_events()  # show "Pause" now: the first iteration may take a while
        result, failure = None, None
        try:
            result = activecontour.segment(self.image, start, callback=self._on_iteration, **params)
        except (ValueError, TypeError, ImportError, NotImplementedError) as exc:
            # the library's clear errors (and a backend that is not there) are not fatal here
            failure = f"run failed: {exc}"
        finally:  # also for an unexpected error, which propagates to matplotlib's event loop
            self.running = False
            self._live_history = []
            self.run_button.label.set_text("Run")
        if result is not None:
            self._accept(result)
        after, self._after_run = self._after_run, None
        if self.closed:
            return result
        if after == "quit":
            self.quit()
        elif after == "reset":
            self.reset()
        else:
            self._finish_ui(failure or self._describe(result))
        return result

    def _on_iteration(self, state):
        """The library's callback: show the state now and then, keep the GUI alive, stop on request."""
        self.iteration = self._run_offset + state.iteration
        self._live_history.append((self.iteration, float(state.energy)))
        if self.closed:
            return True
        if self.live and state.max_num_iter > 1:  # a single step leaves queued keys for later
            now = time.perf_counter()
            due = (state.iteration - self._last_draw_iteration >= self.redraw_every
                   and now - self._last_draw_end >= self._draw_cost)
            if due:
                self._last_draw_iteration = state.iteration
                self._show_contours(state.contours)
                self._show_readout(state, state.contours)
                self.fig.canvas.draw_idle()
            if due or now - self._last_flush >= FLUSH_INTERVAL:
                self._last_flush = now
                self.fig.canvas.flush_events()  # draws; pause, close, ... are handled in here
                if due:
                    self._last_draw_end = time.perf_counter()
                    self._draw_cost = self._last_draw_end - now
        return self._stop or self.closed

    def _accept(self, result):
        self.result = result
        self.contours = [np.array(c, dtype=np.float64) for c in result.contours]
        self.iteration = self._run_offset + result.n_iter
        self._session_iterations += result.n_iter
        energies = np.asarray(result.energies, dtype=np.float64)
        points = list(zip(range(self._run_offset, self._run_offset + len(energies)), energies,
                          strict=True))
        self._history += points[1:] if self._history else points
        self._live_history = []
        paused = result.status == 2 or (result.status == 1 and
                                        self._session_iterations < self._max_num_iter)
        self._session_open = paused and bool(self.contours)  # after a collapse: the init again

    def _describe(self, result):
        word = _STATUS_WORDS.get(result.status, result.message)
        if result.status == 2:
            return f"paused at iteration {self.iteration}: space resumes, n steps, s saves"
        if result.status == 1 and self._session_open:
            return f"iteration {self.iteration}: n steps, space runs on"
        if result.status == 3:
            return f"{word} after {self.iteration} iterations: try a smaller mu or another init (r resets)"
        return f"{word} after {self.iteration} iterations"

    def _finish_ui(self, message):
        self._show_curves()
        self._show_readout(self.result)
        self._set_message(message)

    def _clear_run(self):
        self.result = None
        self.contours = []
        self.iteration = 0
        self._history, self._live_history = [], []
        self._session_open, self._session_iterations = True, 0

    @property
    def energy_history(self):
        return np.array(self._history + self._live_history, dtype=np.float64).reshape(-1, 2)

    @property
    def _max_num_iter(self):
        return int(self.maxiter_box.text)

    @property
    def _tol(self):
        return float(self.tol_box.text)

    def _connect_events(self):
        canvas = self.fig.canvas
        manager = canvas.manager
        self._default_key_handler = None
        if manager is not None and getattr(manager, "key_press_handler_id", None) is not None:
            # our shortcuts replace matplotlib's clashing keys; the others are passed on
            canvas.mpl_disconnect(manager.key_press_handler_id)
            manager.key_press_handler_id = None
            self._default_key_handler = True
        canvas.mpl_connect("key_press_event", self._on_key)
        canvas.mpl_connect("button_press_event", self._on_press)
        canvas.mpl_connect("motion_notify_event", self._on_motion)
        canvas.mpl_connect("button_release_event", self._on_release)
        canvas.mpl_connect("close_event", self._on_close)
        for slider in (*self.sliders.values(), *self.step_sliders.values()):
            slider.on_changed(self._on_slider)
        self.maxiter_box.on_submit(lambda text: self._on_field("max iter", self.maxiter_box, text))
        self.tol_box.on_submit(lambda text: self._on_field("tol", self.tol_box, text))
        self.backend_radio.on_clicked(self._on_backend_radio)
        self.mode_radio.on_clicked(self._on_mode_radio)
        self.run_button.on_clicked(lambda _event: self.toggle_run())
        self.step_button.on_clicked(lambda _event: self.step())
        self.reset_button.on_clicked(lambda _event: self.reset())
        self.mask_button.on_clicked(lambda _event: self.load_mask())
        self.save_button.on_clicked(lambda _event: self.save())
        self._key_actions = {
            " ": self.toggle_run,
            "n": self.step,
            "r": self.reset,
            "s": self.save,
            "c": lambda: self.set_init_mode("circle"),
            "b": lambda: self.set_init_mode("box"),
            "p": lambda: self.set_init_mode("polygon"),
            "m": self.load_mask,
            "g": self.toggle_color,
            "q": self.quit,
        }

    # ------------------------------------------------------------------------- event handlers
    def _on_key(self, event):
        if any(box.capturekeystrokes for box in self.layout.text_boxes):
            return  # typing into a field
        if not self.running and self.drawer.key(event.key):
            return
        action = self._key_actions.get(event.key)
        if action is not None:
            action()
        elif self._default_key_handler:
            from matplotlib.backend_bases import key_press_handler

            key_press_handler(event, self.fig.canvas)

    def _on_press(self, event):
        if event.inaxes is not self.ax_image or self._toolbar_active():
            return
        if self.running:
            self._set_message("running: press space to pause before drawing a new init")
            return
        self.drawer.press(event)

    def _on_motion(self, event):
        if not self.running and self.drawer.busy:
            self.drawer.motion(event)

    def _on_release(self, event):
        if not self.running and self.drawer.busy:
            self.drawer.release(event)

    def _on_close(self, _event):
        self.closed = True
        self._stop = True

    def _on_drawn_curve(self, curve):
        self.set_init([curve])

    def toggle_color(self):
        """Switch a colour image between gray and vector-valued (per-channel) segmentation."""
        if self.image.ndim != 3:
            self._set_message("the image is gray: there is no colour to switch to")
            return
        self.color = "vector" if self.color == "gray" else "gray"
        self._set_message(f"colour: {'each channel (vector)' if self.color == 'vector' else 'gray'}"
                          "; applies to the next run (space)")

    def _on_slider(self, _value):
        if self.running or self.result is not None:
            self._set_message("changed settings apply to the next run (space)")

    def _on_field(self, name, box, text):
        try:
            if name == "max iter":
                value = int(text.strip())
                if value < 1:
                    raise ValueError
            else:
                value = float(text.strip())
                if not (np.isfinite(value) and value >= 0):
                    raise ValueError
        except ValueError:
            need = "an integer >= 1" if name == "max iter" else "a number >= 0"
            box.set_val(self._valid_fields[name])
            self._set_message(f"{name} must be {need}, got {text!r}; kept {self._valid_fields[name]}")
            return
        if text.strip() == self._valid_fields[name]:
            return
        self._valid_fields[name] = text.strip()
        if self.running or self.result is not None:
            self._set_message(f"{name} = {value:g}: applies to the next run")

    def _show_step_slider(self, backend):
        for name, slider in self.step_sliders.items():
            slider.ax.set_visible(name == backend)
            slider.set_active(name == backend)
            self.step_labels[name].set_visible(name == backend)

    def _on_backend_radio(self, label):
        self._show_step_slider(label)
        if self.running or self.result is not None:
            self._set_message(f"backend {label}: applies to the next run")

    def _on_mode_radio(self, label):
        self.drawer.set_mode(label)
        hint = {"circle": "press at the centre and drag to the radius",
                "box": "press at a corner and drag to the opposite corner",
                "polygon": "click the vertices; enter, double or right click closes"}[label]
        self._set_message(f"init mode {label}: {hint}")

    def _toolbar_active(self):
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        return bool(getattr(toolbar, "mode", ""))  # pan or zoom owns the mouse

    # ------------------------------------------------------------------------------- drawing
    def _show_curves(self):
        self.init_lines.set_segments([_closed_xy(c) for c in self.init_curves])
        self.init_lines.set_alpha(0.55 if self.contours else 1.0)
        self._show_contours(self.contours)

    def _show_contours(self, contours):
        self.contour_lines.set_segments([_closed_xy(c) for c in contours])

    def _show_readout(self, state, contours=None):
        """Iteration, energy, c_in, c_out of a FlowState or result (None: not run), the contours'
        size, and the energy plot."""
        contours = self.contours if contours is None else contours
        if state is None:
            energy = c_in = c_out = "-"
        else:
            energy = f"{state.energy:.6g}"
            c_in, c_out = _format_constant(state.c_in), _format_constant(state.c_out)
        lines = [f"iteration {self.iteration:<7d} energy {energy}",
                 f"c_in {c_in:<12}   c_out {c_out}"]
        if contours:
            lines.append(f"{len(contours)} contour(s), {sum(len(c) for c in contours)} "
                         f"vertices, length {sum(length(c) for c in contours):.1f} px")
        else:
            lines.append("initial curve (dashed)")
        self.readout.set_text("\n".join(lines))
        history = self.energy_history
        self.energy_line.set_data(history[:, 0], history[:, 1])
        self.ax_energy.relim()
        self.ax_energy.autoscale_view()

    def _set_message(self, text):
        self.message = text
        self.status_text.set_text(text)
        self._redraw()

    def _redraw(self):
        if self.live and not self.closed:
            self.fig.canvas.draw_idle()


def launch(image_path, *, backend=None, mu=None, omega=None, lambda_in=None, lambda_out=None,
           max_num_iter=None, tol=None, init=None, c_in=None, c_out=None, color="gray",
           formats=("json",)):
    """Open the viewer's window on an image and return an exit code when it is closed.

    Parameters
    ----------
    image_path : str or os.PathLike
        Any image :func:`activecontour.load_image` reads.
    backend, mu, omega, lambda_in, lambda_out, max_num_iter, tol, init, c_in, c_out, color, formats
        See :class:`Viewer` (None: the library's default); ``init`` may be a mask file's path.

    Returns
    -------
    int
        0 after the window was closed; 2 for a bad image, init or parameter (one line on
        stderr); 1 when matplotlib has no interactive backend (no display, or ``MPLBACKEND=Agg``).
    """
    import matplotlib.pyplot as plt

    try:
        image = load_image(image_path)
        viewer = Viewer(image, image_path=image_path, backend=backend, mu=mu, omega=omega,
                        lambda_in=lambda_in, lambda_out=lambda_out, max_num_iter=max_num_iter,
                        tol=tol, init=init, c_in=c_in, c_out=c_out, color=color, formats=formats)
    except (OSError, ValueError, TypeError) as exc:
        print(f"activecontour view: {exc}", file=sys.stderr)
        return 2
    if viewer.fig.canvas.required_interactive_framework is None:
        plt.close(viewer.fig)
        print(f"activecontour view: matplotlib backend {plt.get_backend()!r} cannot open a window "
              "(no display?); set MPLBACKEND to an interactive backend such as TkAgg or QtAgg",
              file=sys.stderr)
        return 1
    # The library's compiled kernels load (or, once after installing, compile) on their first
    # call: do that now, before the window opens, rather than freeze it during the first run.
    segment(np.eye(8), max_num_iter=1)
    plt.show()
    return 0


# ----------------------------------------------------------------------------------- helpers
@contextlib.contextmanager
def _no_redraw(canvas):
    """Suppress ``draw_idle`` (which Agg, unlike a GUI canvas, performs at once) for a while."""
    canvas.draw_idle = lambda *args, **kwargs: None
    try:
        yield
    finally:
        del canvas.draw_idle


def _closed_xy(curve):
    xy = to_xy(curve)
    return np.vstack([xy, xy[:1]])


def _format_constant(value):
    value = np.asarray(value, dtype=np.float64)
    if value.size == 1:
        return f"{float(value.reshape(-1)[0]):.4g}"
    return "(" + ", ".join(f"{v:.3g}" for v in value.reshape(-1)) + ")"


def _same_curves(curves, init):
    """Whether the curves are the init as given (not clipped); a mask init counts as unchanged."""
    if isinstance(init, np.ndarray) and init.dtype == bool:
        return True
    try:
        given = [np.asarray(c, dtype=np.float64) for c in init]
    except (TypeError, ValueError):
        return True
    return len(given) == len(curves) and all(
        g.shape == c.shape and np.array_equal(g, c) for g, c in zip(given, curves, strict=True))


def _read_mask_file(path):
    from activecontour.io import read_mask

    return read_mask(path)


def _settings(**given):
    """The starting settings: the given ones, checked, and the library's defaults for None."""
    defaults = _library_defaults()
    settings = {name: defaults[name] if value is None else value for name, value in given.items()}
    if settings["backend"] not in BACKENDS:
        raise ValueError(f"backend must be one of {tuple(BACKENDS)}, got {settings['backend']!r}")
    for name in ("mu", "omega", "lambda_in", "lambda_out", "tol"):
        value = settings[name]
        if name == "mu" and is_auto(value):
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
                or not np.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value!r}")
    value = settings["max_num_iter"]
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"max_num_iter must be an integer >= 1, got {value!r}")
    return settings


def _library_defaults():
    """The defaults of :func:`activecontour.segment`, so the viewer starts where the library does."""
    import importlib

    segment = importlib.import_module("activecontour.segment").segment
    return {name: parameter.default for name, parameter in inspect.signature(segment).parameters.items()
            if parameter.default is not inspect.Parameter.empty}


def _backend_default(backend, option):
    """A backend option's default (its module's ``DEFAULT_OPTIONS`` or the function's signature),
    or None when the backend or the option is not there."""
    import importlib

    module_name, function_name = BACKENDS[backend].split(":")
    try:
        module = importlib.import_module(module_name)
        defaults = getattr(module, "DEFAULT_OPTIONS", {})
        if option in defaults:
            return float(defaults[option])
        default = inspect.signature(getattr(module, function_name)).parameters[option].default
    except (ImportError, AttributeError, KeyError):
        return None
    return None if default is inspect.Parameter.empty else float(default)


def _jsonable_parameters(params):
    out = dict(params)
    out.pop("color", None)
    return out
