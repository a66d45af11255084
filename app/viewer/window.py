"""The viewer's window: :class:`Viewer`, its state and its actions.

The window's parts live beside it: the layout (:mod:`.layout`), the mouse tools (:mod:`.tools`),
the controls that set the next run (:mod:`.controls`), what is shown of a run (:mod:`.display`),
the runs since the last init (:mod:`.session`), the starts (:mod:`.starts`) and the input events
(:mod:`.events`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import time
from pathlib import Path

import numpy as np

from activecontour.backends import BACKENDS
from activecontour.initial import initial_curves
from activecontour.io.images import MAX_PIXELS, load_image
from activecontour.io.pictures import display_rgb

from ..messages import one_line
from . import display, events, starts
from .controls import Controls, slider_values, step_values
from .layout import PREVIEW_COLOR, build_layout, contour_color, new_figure, show_image
from .session import Session
from .tools import INIT_MODES, CurveDrawer

__all__ = ["FLUSH_INTERVAL", "Viewer"]

#: Seconds between two calls of ``flush_events`` during a run: the GUI answers within this time
#: plus one iteration.
FLUSH_INTERVAL = 0.03


class Viewer:
    """The viewer's figure, widgets and actions, without showing a window.

    Parameters
    ----------
    image : ndarray of shape (M, N) or (M, N, C)
        The image, as :func:`activecontour.load_image` returns it.
    settings : Settings, optional
        The starting settings (:class:`activecontour.settings.Settings`); by default the library's.
    image_path : str or os.PathLike, optional
        Where the image came from: the window title, the default save stem (``<dir>/<stem>``), and
        a file the writers must not overwrite.
    init : None, "grid", "checkerboard", path, ndarray (K, 2), list of them, or bool ndarray (M, N)
        The initial curve: None for the library's default, a named start of the library
        (:data:`~.starts.NAMED_INITS`), a mask file (a path; any other string), or curves or a mask
        as :func:`activecontour.segment` accepts them.
    formats : sequence of str
        Contour formats written by Save, from :data:`activecontour.io.CONTOUR_FORMATS`.
    redraw_every : int
        During a run, redraw the contour every this many iterations.
    live : bool, optional
        Draw during runs and after each action; by default True on an interactive canvas and
        False on a non-interactive one (Agg), where nothing is drawn until the figure is drawn or
        saved (``savefig``).
    **keywords
        Settings that differ from ``settings``, keywords of :func:`activecontour.segment`
        (``backend``, ``mu``, ``max_num_iter``, ``n_regions``, ...), checked by the library.  A run
        started from drawn curves is restricted to their neighbourhood (``roi="init"``, see
        :mod:`activecontour.imaging.roi`): drawing around one object gives that object.

    Attributes
    ----------
    fig : matplotlib.figure.Figure
    layout : layout.Layout
        The window's artists and widgets, which are also attributes of the viewer
        (``ax_image``, ``sliders``, ``run_button``, ``save_box``, ...).
    controls : controls.Controls
        The next run's settings as the widgets and keys set them (:meth:`parameters`).
    init : None, str or list of ndarray (K, 2)
        What the next fresh run passes to :func:`activecontour.segment`: None (the library's
        default), a name from :data:`~.starts.NAMED_INITS`, or curves (drawn, loaded or given,
        clipped to the image as the library does).
    init_curves : list of ndarray (K, 2)
        The initial curves as shown: the curves of ``init``, or for None and a named init the
        library's start for the selected backend (empty when the library refuses it).
    session : session.Session
        The runs since the init was set or reset: ``result``, ``contours``, ``iteration`` and
        ``energy_history`` (also the viewer's attributes).
    message : str
        The status line.
    running, closed : bool
    """

    #: The largest image the "image" field opens (:func:`activecontour.load_image`'s limit).
    max_pixels = MAX_PIXELS

    def __init__(self, image, settings=None, *, image_path=None, init=None, formats=("json",), redraw_every=2,
                 live=None, **keywords):
        from activecontour.settings import Settings

        settings = Settings.of(keywords) if settings is None else dataclasses.replace(settings, **keywords)
        if isinstance(redraw_every, bool) or not isinstance(redraw_every, (int, np.integer)) \
                or redraw_every < 1:
            raise ValueError(f"redraw_every must be an integer >= 1, got {redraw_every!r}")
        from activecontour.io import CONTOUR_FORMATS

        formats = (formats,) if isinstance(formats, str) else tuple(formats)
        for fmt in formats:
            if fmt not in CONTOUR_FORMATS:
                raise ValueError(f"formats must be chosen from {CONTOUR_FORMATS}, got {fmt!r}")
        self.image = np.asarray(image)
        display_image = display_rgb(self.image)  # validates the image, too
        self.shape = display_image.shape[:2]
        self.image_path = None if image_path is None else Path(image_path)
        # Save's relative stems start here, wherever the working directory goes later
        self._image_folder = None if image_path is None else Path(os.path.abspath(image_path)).parent
        self.formats = formats
        self.redraw_every = int(redraw_every)
        # a bad init is an error here, before any window exists
        if isinstance(init, (str, os.PathLike)) and init not in starts.NAMED_INITS:
            from activecontour.io import read_mask

            init = read_mask(init)
        self.init = init if starts.is_named(init) else initial_curves(init, self.shape)
        self.init_curves = []
        self.session = Session()
        self.message = ""
        self.running = False
        self.closed = False
        self._stop = False  # the callback returns True at the next iteration
        self._after_run = None  # "reset" or "quit", deferred until the run has stopped
        self._last_flush = self._last_draw_end = -np.inf
        self._last_draw_iteration, self._draw_cost = 0, 0.0

        self.fig = new_figure()
        manager = self.fig.canvas.manager
        if manager is not None:
            manager.set_window_title("activecontour view" + (f": {self.image_path.name}" if self.image_path
                                                              else ""))
        self.live = (self.fig.canvas.required_interactive_framework is not None) if live is None \
            else bool(live)
        with _no_redraw(self.fig.canvas):  # widgets redraw as they are built: once is enough
            self.layout = build_layout(
                self.fig, display_image, backends=tuple(BACKENDS), backend=settings.backend,
                values=slider_values(settings, self.image), step_values=step_values(),
                max_num_iter=settings.max_num_iter, tol=settings.tol,
                save_stem="" if self.image_path is None else self.image_path.stem,
                help_line=events.help_line())
            vars(self).update(vars(self.layout))  # its artists and widgets are the viewer's attributes
            self.controls = Controls(self.layout, settings, say=self.say,
                                     has_run=lambda: self.running or self.result is not None)
        self._contour_rgb = contour_color(display_image)  # of two regions' contours
        self.drawer = CurveDrawer(self.ax_image, lambda curve: self.set_init([curve]), self.say, self.redraw,
                                  color=PREVIEW_COLOR, on_click=self.select)
        self.selected = None  # the id of the object whose measurements are shown
        self.ax_image.format_coord = lambda x, y: display.format_coord(self.image, self.shape, x, y)
        if not self.live:
            for widget in self.layout.widgets:
                widget.drawon = False
        problem = self._preview_start()
        if problem is not None:
            import matplotlib.pyplot as plt

            plt.close(self.fig)
            raise ValueError(problem)
        self._events = events.connect(self)
        self._show(None)
        self.say("draw an initial curve with the mouse (or keep the library's start, dashed), then "
                 "press space to run")

    # ----------------------------------------------------------------------------- the state
    def parameters(self):
        """The settings the next run will use, as keywords of :func:`activecontour.segment`
        (:meth:`.controls.Controls.settings`)."""
        return self.controls.settings().keywords()

    @property
    def result(self):
        """The last run's result; None before any run and after a new init or a reset."""
        return self.session.result

    @property
    def contours(self):
        """The current contours (empty before the first run and after a reset)."""
        return self.session.contours

    @property
    def iteration(self):
        """Iterations since the init was set or reset."""
        return self.session.iteration

    @property
    def energy_history(self):
        """(iteration, energy) since the init was set or reset: (n, 2)."""
        return self.session.energy_history

    @property
    def init_mode(self):
        return self.drawer.mode

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

    # ------------------------------------------------------------------------------- the runs
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
        return self._run(self.session.iterations_for(self.controls.max_num_iter()))

    def step(self):
        """One iteration from the current contours (or the init)."""
        if self.running:
            self.say("running: press space to pause before stepping")
            return None
        return self._run(self.session.iterations_for(self.controls.max_num_iter(), step=True))

    def reset(self):
        """Back to the initial curve: forget the contours, the result and the energy history."""
        if self.running:
            self._stop, self._after_run = True, "reset"
            return
        self.session.clear()
        self._show(None)
        self.say("reset to the initial curve")

    def _run(self, n_iter):
        import activecontour

        params = self.parameters()
        params["max_num_iter"] = n_iter
        result = self.result
        if self.contours:  # continue: the last result carries the level set's phi, too
            same_backend = result is not None and result.backend == params["backend"]
            start = result if same_backend or self.controls.n_regions != 2 else self.contours
            if result is not None and result.roi is not None:
                params["roi"] = result.roi  # a continued run stays on its domain
        else:  # a fresh start from the init (also after a collapse): exactly the library's
            self.session.clear()
            start = self._start()
            if not starts.is_named(start):
                params["roi"] = "init"  # drawing around one object gives that object
        self.drawer.cancel()
        self.running, self._stop, self._after_run = True, False, None
        self.session.begin()
        self._last_flush = self._last_draw_end = -np.inf
        self._last_draw_iteration = 0
        self.run_button.label.set_text("Pause")
        self.say(f"running {params['backend']} (space pauses)")
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
            self.session.end()
            self.run_button.label.set_text("Run")
        if result is not None:
            self.session.accept(result, self.controls.max_num_iter())
            self.controls.show_run_mu(result.mu)
        after, self._after_run = self._after_run, None
        if self.closed:
            return result
        if after == "quit":
            self.quit()
        elif after == "reset":
            self.reset()
        else:
            self._show(self.result)
            self.say(failure or self.session.describe(result))
        return result

    def _on_iteration(self, state):
        """The library's callback: show the state now and then, keep the GUI alive, stop on request."""
        self.session.record(state)
        if self.closed:
            return True
        if self.live and state.max_num_iter > 1:  # a single step leaves queued keys for later
            now = time.perf_counter()
            due = (state.iteration - self._last_draw_iteration >= self.redraw_every
                   and now - self._last_draw_end >= self._draw_cost)
            if due:
                self._last_draw_iteration = state.iteration
                contours = display.state_curves(state)
                display.show_contours(self.layout, contours, None, self._contour_rgb)
                self._show_readout(state, contours)
                self.fig.canvas.draw_idle()
            if due or now - self._last_flush >= FLUSH_INTERVAL:
                self._last_flush = now
                self.fig.canvas.flush_events()  # draws; pause, close, ... are handled in here
                if due:
                    self._last_draw_end = time.perf_counter()
                    self._draw_cost = self._last_draw_end - now
        return self._stop or self.closed

    # ---------------------------------------------------------------------------- the start
    def set_init(self, init):
        """Set the initial curve(s) from anything :func:`activecontour.segment` accepts: None
        (the library's default), a name from :data:`~.starts.NAMED_INITS`, curves or a mask.

        Returns True when the init was accepted; otherwise the status line says why (for example
        a curve outside the image) and the previous init stays.
        """
        if self.running:
            self.say("running: press space to pause before setting a new init")
            return False
        previous = self.init, self.init_curves
        try:
            self.init = init if starts.is_named(init) else initial_curves(init, self.shape)
        except (ValueError, TypeError) as exc:
            self.say(f"init not set: {one_line(exc)}")
            return False
        problem = self._preview_start()
        if problem is not None:
            self.init, self.init_curves = previous
            self.say(f"init not set: {problem}")
            return False
        self.session.clear()
        self._show(None)
        self.say(f"init set ({starts.describe(self.init, init)}): press space to run")
        return True

    def set_init_mode(self, mode):
        """Choose the mouse gesture for the next init: "circle", "box" or "polygon"."""
        index = INIT_MODES.index(mode) if mode in INIT_MODES else None
        if index is None:
            raise ValueError(f"init mode must be one of {INIT_MODES}, got {mode!r}")
        if self.mode_radio.value_selected != mode:
            self.mode_radio.set_active(index)  # calls on_mode
        else:
            self.on_mode(mode)

    def on_mode(self, label):
        """The init mode radio button: the gesture of the next drawn init."""
        self.drawer.set_mode(label)
        hint = {"circle": "press at the centre and drag to the radius",
                "box": "press at a corner and drag to the opposite corner",
                "polygon": "click the vertices; enter, double or right click closes"}[label]
        self.say(f"init mode {label}: {hint}")

    def load_mask(self, path=None):
        """Use a mask file as the init (path, or the text of the "mask file" field)."""
        from activecontour.io import read_mask

        path = self.mask_box.text.strip() if path is None else os.fspath(path)
        if not path:
            self.say("type a mask file's path in the 'mask file' field, then press m")
            return False
        try:
            mask = read_mask(Path(path).expanduser())
        except (OSError, ValueError) as exc:
            self.say(f"mask not loaded: {one_line(exc)}")
            return False
        return self.set_init(mask)

    def _start(self):
        """What a fresh run starts from: the init, or for more than two regions the library's
        start (a drawn curve or a named start outlines two regions)."""
        return self.init if self.controls.n_regions == 2 else None

    def _preview_start(self):
        """Set :attr:`init_curves` to what a fresh run starts from: the init's curves, or for None
        and a named init the library's start.  Returns None, or the library's message refusing it."""
        self.controls.start_stale = False
        init = self._start()
        if not starts.is_named(init):
            self.init_curves = init
            return None
        try:
            self.init_curves = starts.library_start(self.image, init, self.parameters())
        except (ValueError, TypeError) as exc:
            self.init_curves = []
            return f"init {starts.describe(self.init, None)}: {one_line(exc)}"
        return None

    def refresh_named_start(self):
        """After a setting changed: show the library's start anew (an empty text, or the problem
        to append to the status line)."""
        if self.running or not starts.is_named(self._start()):
            return ""
        problem = self._preview_start()
        self._show_curves()
        return "" if problem is None else f"; {problem}"

    # ------------------------------------------------------------------------------ settings
    def set_backend(self, label):
        """The backend radio button: the backend of the next run."""
        self.controls.show_step_slider(label)
        problem = self.refresh_named_start()
        if problem or self.running or self.result is not None:
            self.say(f"backend {label}: applies to the next run{problem}")

    def toggle_color(self):
        """Switch a colour image between gray and vector-valued (per-channel) segmentation."""
        if self.image.ndim != 3:
            self.say("the image is gray: there is no colour to switch to")
            return
        self.controls.toggle_color()
        self.controls.refresh_auto_mu(self.image)
        problem = self.refresh_named_start()
        color = self.controls.color
        self.say(f"colour: {'each channel (vector)' if color == 'vector' else 'gray'}; applies to the "
                 f"next run (space){problem}")

    def cycle_regions(self):
        """The next number of regions of :data:`~.controls.REGION_CHOICES`; the next run starts
        afresh (a result's regions are no start for another number of them)."""
        if self.running:
            self.say("running: press space to pause before changing the regions")
            return
        self.controls.next_regions()
        self.session.clear()
        problem = self._preview_start()
        self._show(None)
        n_regions = self.controls.n_regions
        start = ("the init" if n_regions == 2 else
                 "the library's start (the global K-means; a drawn curve outlines two regions)")
        suffix = "" if problem is None else f"; {problem}"
        self.say(f"regions: {n_regions}; the next run (space) starts from {start}{suffix}")

    def toggle_fit(self):
        """Switch the regions' intensities between constant and smooth (a light field)."""
        self.controls.toggle_fit()
        problem = self.refresh_named_start()
        light = ("each region's constant times a smooth light field" if self.controls.fit == "smooth"
                 else "constant")
        self.say(f"light fit: {light}; applies to the next run (space){problem}")

    # ------------------------------------------------------------------------------ files
    def open_image(self, path=None):
        """Open another image (a path, or the text of the "image" field) in this window.

        The new image starts afresh: no result, the init back to the library's default (a named
        init such as ``"grid"`` is kept), the save field on the new image's name.  Returns True
        when it was opened; otherwise the status line gives the library's message and the shown
        image stays.
        """
        if self.running:
            self.say("running: press space to pause before opening another image")
            return False
        path = self.image_box.text.strip() if path is None else os.fspath(path)
        if not path:
            self.say("type an image file's path in the 'image' field, then press i")
            return False
        try:
            image = load_image(Path(path).expanduser(), max_pixels=self.max_pixels)
            display_image = display_rgb(image)
        except (OSError, ValueError, TypeError) as exc:
            self.say(f"image not opened: {one_line(exc)}")
            return False
        previous = self.image, self.shape, self.init, self.init_curves
        self.image, self.shape = np.asarray(image), display_image.shape[:2]
        self.controls.refresh_auto_mu(self.image)
        if not isinstance(self.init, str):
            self.init = None
        problem = self._preview_start()
        if problem is not None:  # a named init the new image cannot take: the default
            self.init = None
            problem = self._preview_start()
        if problem is not None:
            self.image, self.shape, self.init, self.init_curves = previous
            self.controls.refresh_auto_mu(self.image)
            self.say(f"image not opened: {problem}")
            return False
        self.image_path = Path(path).expanduser()
        self._image_folder = Path(os.path.abspath(self.image_path)).parent
        self.session.clear()
        self.drawer.cancel()
        show_image(self.ax_image, display_image)
        self._contour_rgb = contour_color(display_image)
        self.contour_lines.set_color(self._contour_rgb)
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        if toolbar is not None:
            toolbar.update()  # forget the zoom and pan history of the old image
        self.save_box.set_val(self.image_path.stem)
        self.image_box.set_val("")
        manager = self.fig.canvas.manager
        if manager is not None:
            manager.set_window_title(f"activecontour view: {self.image_path.name}")
        self._show(None)
        m, n = self.shape
        self.say(f"opened {self.image_path.name} ({m} x {n}; init: {starts.describe(self.init, None)}): "
                 "press space to run")
        return True

    def save(self, stem=None):
        """Save mask, overlay and contours with the CLI's writers (and the classes image when the
        number of regions is not 2); returns the paths written.

        Before any run, or while running, the status line says so and nothing is written.
        """
        if self.running:
            self.say("running: press space to pause before saving")
            return None
        if self.result is None:
            self.say("nothing to save yet: run the flow first (space)")
            return None
        stem = self.output_stem if stem is None else os.fspath(stem)
        if not stem:
            self.say("type an output stem in the 'save as' field, then press s")
            return None
        from activecontour.io import save_result

        protect = [self.image_path] if self.image_path is not None else []
        metadata = {"parameters": self.parameters()}
        if self.image_path is not None:
            metadata["image"] = os.fspath(self.image_path)
        try:
            # K regions: their image too, as the command line writes it
            paths = save_result(self.result, self.image, stem, self.formats, metadata=metadata,
                                protect=protect, objects=("classes",) if self.controls.n_regions != 2 else ())
        except (OSError, ValueError) as exc:
            self.say(f"not saved: {one_line(exc)}")
            return None
        folder = os.path.dirname(os.path.abspath(paths[0]))
        self.say(f"saved {', '.join(p.name for p in paths)} in {folder}")
        return paths

    def quit(self):
        """Close the window (after stopping a run in progress)."""
        if self.running:
            self._stop, self._after_run = True, "quit"
            return
        import matplotlib.pyplot as plt

        plt.close(self.fig)
        self.closed = True  # not every backend sends close_event for plt.close

    # ---------------------------------------------------------------------------- drawing
    def _show(self, state):
        """The curves and the readout of ``state`` (a result, or None: not run); no object
        selected."""
        self.selected = None
        self._show_curves()
        self._show_readout(state)

    def _show_curves(self):
        display.show_curves(self.layout, self.init_curves, self.contours, self._region_curves(),
                            self._contour_rgb, self.result, self.selected)

    def select(self, point):
        """Show the measurements of the object of the last result at ``point`` (row, col) and draw
        it wider; returns False when no object is there."""
        result = self.result
        if result is None or result.labels is None or self.running:
            return False
        row, col = (int(np.floor(v + 0.5)) for v in point)
        if not (0 <= row < self.shape[0] and 0 <= col < self.shape[1]) or not result.labels[row, col]:
            return False
        self.selected = int(result.labels[row, col])
        self._show_curves()
        self.say(display.object_summary(result, self.selected))
        return True

    def toggle_help(self):
        """Show or hide the help: the controls and the readout in a user's words, with the book's
        symbols and equation numbers (:func:`.display.help_text`)."""
        panel = self.layout.help_panel
        if not panel.get_text():
            panel.set_text(display.help_text())
        panel.set_visible(not panel.get_visible())
        self.say("help shown: h hides it" if panel.get_visible() else "help hidden: h shows it")

    def _region_curves(self):
        """The curves of regions 1..K-1 when the contours are those of a result of K > 2 regions."""
        result = self.result
        if result is None or result.class_contours is None or len(result.class_contours) <= 2:
            return None
        return result.class_contours[1:]

    def _show_readout(self, state, contours=None):
        display.show_readout(self.layout, state, iteration=self.iteration,
                             contours=self.contours if contours is None else contours,
                             n_regions=self.controls.n_regions, fit=self.controls.fit,
                             history=self.energy_history)

    def say(self, text):
        """Show ``text`` on the status line."""
        self.message = text
        self.layout.set_fitted_text(self.status_text, text)
        self.redraw()

    def redraw(self):
        if self.live and not self.closed:
            self.fig.canvas.draw_idle()


@contextlib.contextmanager
def _no_redraw(canvas):
    """Suppress ``draw_idle`` (which Agg, unlike a GUI canvas, performs at once) for a while."""
    canvas.draw_idle = lambda *args, **kwargs: None
    try:
        yield
    finally:
        del canvas.draw_idle
