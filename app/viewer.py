"""The interactive viewer: ``activecontour view IMAGE``.

A matplotlib window that shows an image with the current contour(s), lets the user set the initial
curve with the mouse (circle, box, polygon) or from a mask file, and runs, pauses and single-steps
the flow of :func:`activecontour.segment` while showing the iteration, the energy (6.38), the
constants c_in, c_out (6.42) and a small plot of the energy history.  Sliders set mu, omega,
lambda_in, lambda_out and the polygon backend's step size; fields set max_num_iter and tol; radio
buttons choose the backend and the init gesture.  Changes apply to the next run.  Another image
can be opened from the window (the "image" field, key i).  Key k chooses the number of regions
(2, 3, 4, 5, 6, auto: ``n_regions`` of :func:`activecontour.segment`) and key l the light
(``fit``: constant or smooth); with more than two regions every region's boundary is drawn in its
own colour (:data:`activecontour.io.pictures.REGION_COLORS`, as the overlays) and a run starts from
the library's start for K regions (the global K-means): a drawn curve outlines two regions.
The result is saved with the CLI's writers (:func:`activecontour.io.save_result`), by default
next to the input image, which is never overwritten.  The toolbar's readout gives the mouse
position as (row, col), the convention of the whole package, and the image's value there.

Without a drawn init the viewer starts from the library's: it passes ``init=None`` (or the named
start given, ``"grid"`` or ``"checkerboard"``) to :func:`activecontour.segment`, and shows as the
dashed initial curve what the library starts from (its result after zero iterations).

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
import os
import sys
import time
from pathlib import Path

import numpy as np

from activecontour._segment import segment
from activecontour.backends import BACKENDS
from activecontour.geometry.curve import length, to_xy
from activecontour.imaging.noise import auto_mu, is_auto
from activecontour.imaging.normalize import normalize_image
from activecontour.initial import initial_curves
from activecontour.io.images import MAX_PIXELS, load_image
from activecontour.io.pictures import REGION_COLORS, display_rgb

from .viewer_layout import (
    CONTOUR_COLOR,
    PREVIEW_COLOR,
    SLIDERS,
    STEP_OPTIONS,
    build_layout,
    contour_color,
    new_figure,
    refit_texts,
    set_slider_value,
    show_energy,
    show_image,
)
from .viewer_tools import INIT_MODES, CurveDrawer

__all__ = ["CONTOUR_COLOR", "NAMED_INITS", "REGION_CHOICES", "SHORTCUTS", "Viewer", "launch"]

#: The library's named starts the viewer passes on as they are (the level set's checkerboard
#: needs ``backend="levelset"``).
NAMED_INITS = ("grid", "checkerboard")

#: The numbers of regions key k cycles through (``n_regions`` of :func:`activecontour.segment`).
REGION_CHOICES = (2, 3, 4, 5, 6, "auto")

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
    ("i", "i", "open image"),
    ("g", "g", "gray/colour"),
    ("k", "k", "regions"),
    ("l", "l", "light fit"),
    ("q", "q", "quit"),
)

_SLIDER_LABELS = {name: label for name, label, *_ in SLIDERS}

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
    init : None, "grid", "checkerboard", path, ndarray (K, 2), list of them, or bool ndarray (M, N)
        The initial curve: None for the library's default, a named start of the library
        (:data:`NAMED_INITS`), a mask file (a path; any other string), or curves or a mask as
        :func:`activecontour.segment` accepts them.
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
    inside : {"auto", "bright", "dark"}
        Which region is the objects (see :func:`activecontour.segment`).  A run started from
        drawn curves is restricted to their neighbourhood (``segment(roi="init")``, see
        :mod:`activecontour.imaging.roi`): drawing around one object gives that object.
    n_regions : int or "auto"
        The number of regions (see :func:`activecontour.segment`); key k cycles through
        :data:`REGION_CHOICES`.
    fit : {"constant", "smooth"}
        The regions' intensities (see :func:`activecontour.segment`); key l switches.

    Attributes
    ----------
    fig : matplotlib.figure.Figure
    layout : viewer_layout.Layout
        The window's artists and widgets, which are also attributes of the viewer
        (``ax_image``, ``sliders``, ``run_button``, ``save_box``, ...).
    init : None, str or list of ndarray (K, 2)
        What the next fresh run passes to :func:`activecontour.segment`: None (the library's
        default), a name from :data:`NAMED_INITS`, or curves (drawn, loaded or given, clipped to
        the image as the library does).
    init_curves : list of ndarray (K, 2)
        The initial curves as shown: the curves of ``init``, or for None and a named init the
        library's start for the selected backend (empty when the library refuses it).
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

    #: The largest image the "image" field opens (:func:`activecontour.load_image`'s limit).
    max_pixels = MAX_PIXELS

    def __init__(self, image, *, image_path=None, backend=None, mu=None, omega=None, lambda_in=None,
                 lambda_out=None, max_num_iter=None, tol=None, init=None, c_in=None, c_out=None,
                 color="gray", formats=("json",), redraw_every=2, live=None, inside="auto",
                 n_regions=2, fit="constant"):
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
        self.inside = inside  # checked by the library on the first run
        self.n_regions, self.fit = n_regions, fit  # checked by the library's start below
        display = display_rgb(self.image)  # validates the image, too
        self.shape = display.shape[:2]
        # mu="auto": the slider shows the value segment(mu="auto") would use, until it is moved
        self._mu_auto = is_auto(settings["mu"])
        if self._mu_auto:
            settings["mu"] = self._auto_mu()
        self.image_path = None if image_path is None else Path(image_path)
        # Save's relative stems start here, wherever the working directory goes later
        self._image_folder = None if image_path is None else Path(os.path.abspath(image_path)).parent
        self.formats = formats
        self.redraw_every = int(redraw_every)
        # a bad init is an error here, before any window exists
        if isinstance(init, (str, os.PathLike)) and init not in NAMED_INITS:
            init = _read_mask_file(init)
        self.init = init if init is None or isinstance(init, str) else initial_curves(init, self.shape)
        self.init_curves = []

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
        help_line = "  ".join(f"{shown} {action}" for _, shown, action in SHORTCUTS)
        with _no_redraw(self.fig.canvas):  # widgets redraw as they are built: once is enough
            layout = build_layout(
                self.fig, display, backends=tuple(BACKENDS), backend=settings["backend"],
                values={name: settings[name] for name, *_ in SLIDERS},
                step_values={k: v for k, v in step_values.items() if v is not None},
                max_num_iter=settings["max_num_iter"], tol=settings["tol"],
                save_stem="" if self.image_path is None else self.image_path.stem,
                help_line=f"keys:  {help_line}")
        self.layout = layout
        vars(self).update(vars(layout))  # its artists and widgets are the viewer's attributes
        self._contour_rgb = contour_color(display)  # of two regions' contours
        self._valid_fields = {"max iter": self.maxiter_box.text, "tol": self.tol_box.text}
        self.drawer = CurveDrawer(self.ax_image, self._on_drawn_curve, self._set_message, self._redraw,
                                  color=PREVIEW_COLOR)
        self.ax_image.format_coord = self.format_coord
        self._show_mu_mode()
        self._show_step_slider(settings["backend"])
        if not self.live:
            for widget in layout.widgets:
                widget.drawon = False
        problem = self._preview_init()
        if problem is not None:
            import matplotlib.pyplot as plt

            plt.close(self.fig)
            raise ValueError(problem)
        self._connect_events()
        self._show_curves()
        self._show_readout(None)
        self._set_message("draw an initial curve with the mouse (or keep the library's start, "
                          "dashed), then press space to run")

    # ------------------------------------------------------------------------------- controls
    def parameters(self):
        """The settings the next run will use: keywords of :func:`activecontour.segment`."""
        backend = self.backend_radio.value_selected
        params = {name: float(self.sliders[name].val) for name, *_ in SLIDERS}
        params.update(backend=backend, max_num_iter=self._max_num_iter, tol=self._tol,
                      color=self.color, inside=self.inside, n_regions=self.n_regions, fit=self.fit,
                      **self.fixed_constants)
        if backend in self.step_sliders and self.n_regions == 2:  # the two-region flows' setting
            option = STEP_OPTIONS[backend][0]
            value = float(self.step_sliders[backend].val)
            if value != _backend_default(backend, option):  # untouched: the backend's own default
                params["options"] = {option: value}
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
        """Where Save writes: the "save as" field, a relative path taken from the input image's
        folder (the working directory when the image came from no file)."""
        text = self.save_box.text.strip()
        if not text:
            return ""
        stem = Path(text).expanduser()
        if not stem.is_absolute() and self.image_path is not None:
            stem = self._image_folder / stem
        return os.fspath(stem)

    def format_coord(self, x, y):
        """The toolbar's readout for the image axes: (row, col) of the mouse and the image's value
        at the nearest pixel centre."""
        row, col = y, x
        text = f"row {row:.1f}, col {col:.1f}"
        i, j = int(np.floor(row + 0.5)), int(np.floor(col + 0.5))
        if 0 <= i < self.shape[0] and 0 <= j < self.shape[1]:
            text += f"  value {_format_constant(self.image[i, j])}"
        return text

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
        """Set the initial curve(s) from anything :func:`activecontour.segment` accepts: None
        (the library's default), a name from :data:`NAMED_INITS`, curves or a mask.

        Returns True when the init was accepted; otherwise the status line says why (for example
        a curve outside the image) and the previous init stays.
        """
        if self.running:
            self._set_message("running: press space to pause before setting a new init")
            return False
        previous = self.init, self.init_curves
        try:
            named = init is None or (isinstance(init, str) and init in NAMED_INITS)
            self.init = init if named else initial_curves(init, self.shape)
        except (ValueError, TypeError) as exc:
            self._set_message(f"init not set: {_one_line(exc)}")
            return False
        problem = self._preview_init()
        if problem is not None:
            self.init, self.init_curves = previous
            self._set_message(f"init not set: {problem}")
            return False
        self._clear_run()
        self._show_curves()
        self._show_readout(None)
        self._set_message(f"init set ({self._describe_init(init)}): press space to run")
        return True

    def open_image(self, path=None):
        """Open another image (a path, or the text of the "image" field) in this window.

        The new image starts afresh: no result, the init back to the library's default (a named
        init such as ``"grid"`` is kept), the save field on the new image's name.  Returns True
        when it was opened; otherwise the status line gives the library's message and the shown
        image stays.
        """
        if self.running:
            self._set_message("running: press space to pause before opening another image")
            return False
        path = self.image_box.text.strip() if path is None else os.fspath(path)
        if not path:
            self._set_message("type an image file's path in the 'image' field, then press i")
            return False
        try:
            image = load_image(Path(path).expanduser(), max_pixels=self.max_pixels)
            display = display_rgb(image)
        except (OSError, ValueError, TypeError) as exc:
            self._set_message(f"image not opened: {_one_line(exc)}")
            return False
        previous = self.image, self.shape, self.init, self.init_curves
        self.image, self.shape = np.asarray(image), display.shape[:2]
        self._refresh_auto_mu()
        if not isinstance(self.init, str):
            self.init = None
        problem = self._preview_init()
        if problem is not None:  # a named init the new image cannot take: the default
            self.init = None
            problem = self._preview_init()
        if problem is not None:
            self.image, self.shape, self.init, self.init_curves = previous
            self._refresh_auto_mu()
            self._set_message(f"image not opened: {problem}")
            return False
        self.image_path = Path(path).expanduser()
        self._image_folder = Path(os.path.abspath(self.image_path)).parent
        self._clear_run()
        self.drawer.cancel()
        show_image(self.ax_image, display)
        self._contour_rgb = contour_color(display)
        self.contour_lines.set_color(self._contour_rgb)
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        if toolbar is not None:
            toolbar.update()  # forget the zoom and pan history of the old image
        self.save_box.set_val(self.image_path.stem)
        self.image_box.set_val("")
        manager = self.fig.canvas.manager
        if manager is not None:
            manager.set_window_title(f"activecontour view: {self.image_path.name}")
        self._show_curves()
        self._show_readout(None)
        m, n = self.shape
        self._set_message(f"opened {self.image_path.name} ({m} x {n}; init: "
                          f"{self._describe_init(self.init)}): press space to run")
        return True

    def load_mask(self, path=None):
        """Use a mask file as the init (path, or the text of the "mask file" field)."""
        path = self.mask_box.text.strip() if path is None else os.fspath(path)
        if not path:
            self._set_message("type a mask file's path in the 'mask file' field, then press m")
            return False
        try:
            mask = _read_mask_file(Path(path).expanduser())
        except (OSError, ValueError) as exc:
            self._set_message(f"mask not loaded: {_one_line(exc)}")
            return False
        return self.set_init(mask)

    def save(self, stem=None):
        """Save mask, overlay and contours with the CLI's writers (and the classes image when the
        number of regions is not 2); returns the paths written.

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
            # K regions: their image too, as the command line writes it
            paths = save_result(self.result, self.image, stem, self.formats, metadata=metadata,
                                protect=protect, objects=("classes",) if self.n_regions != 2 else ())
        except (OSError, ValueError) as exc:
            self._set_message(f"not saved: {_one_line(exc)}")
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
            start = self.result if same_backend or self.n_regions != 2 else self.contours
        else:  # a fresh start from the init (also after a collapse): exactly the library's
            self._clear_run()
            start = self._start()
            if not (start is None or isinstance(start, str)):
                params["roi"] = "init"  # drawing around one object gives that object
        if self.contours and self.result is not None and self.result.roi is not None:
            params["roi"] = self.result.roi  # a continued run stays on its domain
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
                contours = _state_curves(state)
                self._show_contours(contours)
                self._show_readout(state, contours)
                self.fig.canvas.draw_idle()
            if due or now - self._last_flush >= FLUSH_INTERVAL:
                self._last_flush = now
                self.fig.canvas.flush_events()  # draws; pause, close, ... are handled in here
                if due:
                    self._last_draw_end = time.perf_counter()
                    self._draw_cost = self._last_draw_end - now
        return self._stop or self.closed

    def _start(self):
        """What a fresh run starts from: the init, or for more than two regions the library's
        start (a drawn curve or a named start outlines two regions)."""
        return self.init if self.n_regions == 2 else None

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
        canvas.mpl_connect("resize_event", lambda _event: refit_texts(self.layout))
        for slider in (*self.sliders.values(), *self.step_sliders.values()):
            slider.on_changed(self._on_slider)
        self.sliders["mu"].on_changed(self._on_mu_slider)
        self.maxiter_box.on_submit(lambda text: self._on_field("max iter", self.maxiter_box, text))
        self.tol_box.on_submit(lambda text: self._on_field("tol", self.tol_box, text))
        self.backend_radio.on_clicked(self._on_backend_radio)
        self.mode_radio.on_clicked(self._on_mode_radio)
        self.run_button.on_clicked(lambda _event: self.toggle_run())
        self.step_button.on_clicked(lambda _event: self.step())
        self.reset_button.on_clicked(lambda _event: self.reset())
        self.image_button.on_clicked(lambda _event: self.open_image())
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
            "i": self.open_image,
            "g": self.toggle_color,
            "k": self.cycle_regions,
            "l": self.toggle_fit,
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
        if self._start_stale and not self.running:
            self._start_stale = False
            if self.init is None or isinstance(self.init, str):
                problem = self._refresh_named_init()
                if problem:
                    self._set_message(problem.removeprefix("; "))
                else:
                    self._redraw()

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
        self._refresh_auto_mu()
        problem = self._refresh_named_init()
        self._set_message(f"colour: {'each channel (vector)' if self.color == 'vector' else 'gray'}"
                          f"; applies to the next run (space){problem}")

    def cycle_regions(self):
        """The next number of regions of :data:`REGION_CHOICES`; the next run starts afresh (a
        result's regions are no start for another number of them)."""
        if self.running:
            self._set_message("running: press space to pause before changing the regions")
            return
        index = REGION_CHOICES.index(self.n_regions) if self.n_regions in REGION_CHOICES else -1
        self.n_regions = REGION_CHOICES[(index + 1) % len(REGION_CHOICES)]
        self._clear_run()
        problem = self._refresh_start()
        start = ("the init" if self.n_regions == 2 else
                 "the library's start (the global K-means; a drawn curve outlines two regions)")
        self._set_message(f"regions: {self.n_regions}; the next run (space) starts from {start}{problem}")

    def toggle_fit(self):
        """Switch the regions' intensities between constant and smooth (a light field)."""
        self.fit = "smooth" if self.fit == "constant" else "constant"
        problem = self._refresh_named_init()
        light = "each region's constant times a smooth light field" if self.fit == "smooth" else "constant"
        self._set_message(f"light fit: {light}; applies to the next run (space){problem}")

    def _refresh_start(self):
        """Show the start of a fresh run anew (after the number of regions changed)."""
        problem = self._preview_init()
        self._show_curves()
        self._show_readout(None)
        return "" if problem is None else f"; {problem}"

    def _auto_mu(self):
        return auto_mu(normalize_image(self.image, color=self.color))

    def _refresh_auto_mu(self):
        """While mu is automatic, show the value the current image (and colour mode) gets."""
        if self._mu_auto:
            self._mu_auto = False  # set_val below notifies _on_mu_slider, which would clear it
            set_slider_value(self.sliders["mu"], self._auto_mu())
            self._mu_auto = True
            self._show_mu_mode()

    def _show_mu_mode(self):
        self.slider_labels["mu"].set_text("mu (auto)" if self._mu_auto else _SLIDER_LABELS["mu"])

    def _on_mu_slider(self, _value):
        if self._mu_auto:
            self._mu_auto = False  # moved by hand: the value is the user's from now on
            self._show_mu_mode()
        # the library's start depends on mu (specks the length term removes): shown anew once
        # the mouse is released, not for every value a drag passes
        self._start_stale = True

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
            self.slider_labels[name].set_visible(name == backend)

    def _on_backend_radio(self, label):
        self._show_step_slider(label)
        problem = self._refresh_named_init()
        if problem or self.running or self.result is not None:
            self._set_message(f"backend {label}: applies to the next run{problem}")

    def _preview_init(self):
        """Set :attr:`init_curves` to what a fresh run starts from: the init's curves, or for None
        and a named init the library's start (its result after zero iterations, so that the
        viewer never reimplements it).  Returns None, or the library's message refusing it."""
        self._start_stale = False
        init = self._start()
        if not (init is None or isinstance(init, str)):
            self.init_curves = init
            return None
        params = self.parameters()
        params["max_num_iter"] = 0
        try:
            start = segment(self.image, init, **params)
        except (ValueError, TypeError) as exc:
            self.init_curves = []
            return f"init {self._describe_init(self.init)}: {_one_line(exc)}"
        self.init_curves = [np.array(c, dtype=np.float64) for c in start.contours]
        return None

    def _refresh_named_init(self):
        """After a change of backend or colour: show the library's start anew (an empty text, or
        the problem to append to the status line)."""
        init = self._start()
        if self.running or not (init is None or isinstance(init, str)):
            return ""
        problem = self._preview_init()
        self._show_curves()
        return "" if problem is None else f"; {problem}"

    def _describe_init(self, given):
        if self.init is None:
            return "the library's default"
        if isinstance(self.init, str):
            return self.init
        count = len(self.init)
        clipped = given is not None and not _same_curves(self.init, given)
        return f"{count} curve{'s' * (count > 1)}{', clipped to the image' if clipped else ''}"

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
        """The contours; for a result of more than two regions, every region's boundary in its
        own colour (region k in the k-th of :data:`REGION_COLORS`, as the overlays)."""
        regions = self._region_curves(contours)
        if regions is None:
            self.contour_lines.set_segments([_closed_xy(c) for c in contours])
            self.contour_lines.set_color(self._contour_rgb)
            return
        segments, colors = [], []
        for k, curves in enumerate(regions):
            segments += [_closed_xy(c) for c in curves]
            colors += [REGION_COLORS[k % len(REGION_COLORS)]] * len(curves)
        self.contour_lines.set_segments(segments)
        self.contour_lines.set_color(colors or [self._contour_rgb])

    def _region_curves(self, contours):
        """The curves of regions 1..K-1 when ``contours`` are those of a result of K > 2 regions."""
        result = self.result
        if (result is None or contours is not self.contours or result.class_contours is None
                or len(result.class_contours) <= 2):
            return None
        return result.class_contours[1:]

    def _show_readout(self, state, contours=None):
        """Iteration, energy, c_in, c_out of a FlowState or result (None: not run), the contours'
        size, and the energy plot."""
        contours = self.contours if contours is None else contours
        if state is None:
            energy = c_in = c_out = "-"
        else:
            energy = f"{state.energy:.6g}"
            c_in, c_out = _format_constant(state.c_in), _format_constant(state.c_out)
        lines = [f"iteration {self.iteration:<6d} energy {energy}", f"c_in  {c_in}", f"c_out {c_out}"]
        if self.n_regions != 2:  # K regions: how many, and each one's constant (once known)
            constants = getattr(state, "constants", None)
            count = f" (auto: {state.n_regions})" if getattr(state, "n_regions", None) and \
                self.n_regions == "auto" else ""
            shown = "-" if constants is None else _format_constant(np.mean(constants, axis=1))
            lines[1:3] = [f"regions {self.n_regions}{count}, {self.fit} light", f"c_k   {shown}"]
        if contours:
            lines.append(f"{len(contours)} contour{'s' * (len(contours) > 1)}, "
                         f"{sum(len(c) for c in contours)} vertices, "
                         f"{sum(length(c) for c in contours):.1f} px long")
        else:
            lines.append("initial curve (dashed)")
        self.layout.set_fitted_text(self.readout, "\n".join(lines))
        show_energy(self.ax_energy, self.energy_line, self.energy_note, self.energy_history)

    def _set_message(self, text):
        self.message = text
        self.layout.set_fitted_text(self.status_text, text)
        self._redraw()

    def _redraw(self):
        if self.live and not self.closed:
            self.fig.canvas.draw_idle()


def launch(image_path, *, backend=None, mu=None, omega=None, lambda_in=None, lambda_out=None,
           max_num_iter=None, tol=None, init=None, c_in=None, c_out=None, color="gray",
           formats=("json",), inside="auto", max_pixels=MAX_PIXELS, n_regions=2, fit="constant"):
    """Open the viewer's window on an image and return an exit code when it is closed.

    Parameters
    ----------
    image_path : str or os.PathLike
        Any image :func:`activecontour.load_image` reads.
    backend, mu, omega, lambda_in, lambda_out, max_num_iter, tol, init, c_in, c_out, color, formats,
    inside, n_regions, fit
        See :class:`Viewer` (None: the library's default); ``init`` may also be a name from
        :data:`NAMED_INITS` (``"grid"``, ``"checkerboard"``) or a mask file's path.
    max_pixels : int or None
        The largest image opened, this one and those opened later in the window (see
        :func:`activecontour.load_image`).

    Returns
    -------
    int
        0 after the window was closed; 2 for a bad image, init or parameter (one line on
        stderr); 1 when matplotlib has no interactive backend (no display, or ``MPLBACKEND=Agg``).
    """
    import matplotlib.pyplot as plt

    try:
        image = load_image(image_path, max_pixels=max_pixels)
        viewer = Viewer(image, image_path=image_path, backend=backend, mu=mu, omega=omega,
                        lambda_in=lambda_in, lambda_out=lambda_out, max_num_iter=max_num_iter,
                        tol=tol, init=init, c_in=c_in, c_out=c_out, color=color, formats=formats,
                        inside=inside, n_regions=n_regions, fit=fit)
        viewer.max_pixels = max_pixels
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


def _state_curves(state):
    """The curves of a run's state: its contours, or where a backend sends none but a level-set
    function (the N-region label field), the outline of that function's inside."""
    if state.contours or state.phi is None:
        return state.contours
    from activecontour.geometry.raster import mask_to_curves

    return mask_to_curves(state.phi > 0)


def _closed_xy(curve):
    xy = to_xy(curve)
    return np.vstack([xy, xy[:1]])


def _format_constant(value):
    value = np.asarray(value, dtype=np.float64)
    if value.size == 1:
        return f"{float(value.reshape(-1)[0]):.4g}"
    return "(" + ", ".join(f"{v:.3g}" for v in value.reshape(-1)) + ")"


def _one_line(exc):
    """An exception's message on one line (some third-party messages span several)."""
    return " ".join(str(exc).split()) or type(exc).__name__


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
    from activecontour.settings import Settings

    return Settings().keywords()


def _backend_default(backend, option):
    """A backend option's default, from the backend's options dataclass, or None when the backend
    or the option is not there."""
    try:
        default = getattr(BACKENDS[backend].options(), option)
    except (KeyError, ImportError, AttributeError):
        return None
    return None if default is None else float(default)


def _jsonable_parameters(params):
    out = dict(params)
    out.pop("color", None)
    return out
