"""The viewer's input: keyboard shortcuts, the mouse on the image, and the widgets' callbacks.

:func:`connect` wires the figure's canvas and widgets to a :class:`~.window.Viewer`.  The
shortcuts (:data:`SHORTCUTS`) replace matplotlib's default keys that clash (s save figure, r/h
home, p pan, c back, q quit); the other default keys (o zoom, g grid, f fullscreen, ...) keep
working.  While a text field is being edited the shortcuts are off.
"""

from __future__ import annotations

from .layout import refit_texts

__all__ = ["SHORTCUTS", "connect"]

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
    ("h", "h", "help"),
    ("q", "q", "quit"),
)


def help_line():
    """The window's bottom line: every shortcut."""
    return "keys:  " + "  ".join(f"{shown} {action}" for _, shown, action in SHORTCUTS)


def connect(viewer):
    """Wire the viewer's canvas events and widgets to its actions; returns the handlers, which the
    viewer keeps (the canvas holds its callbacks' methods weakly)."""
    return _Events(viewer)


class _Events:
    """The handlers of one viewer's events."""

    def __init__(self, viewer):
        self.viewer = viewer
        layout, controls = viewer.layout, viewer.controls
        canvas = viewer.fig.canvas
        manager = canvas.manager
        self.default_keys = False
        if manager is not None and getattr(manager, "key_press_handler_id", None) is not None:
            # our shortcuts replace matplotlib's clashing keys; the others are passed on
            canvas.mpl_disconnect(manager.key_press_handler_id)
            manager.key_press_handler_id = None
            self.default_keys = True
        canvas.mpl_connect("key_press_event", self.on_key)
        canvas.mpl_connect("button_press_event", self.on_press)
        canvas.mpl_connect("motion_notify_event", self.on_motion)
        canvas.mpl_connect("button_release_event", self.on_release)
        canvas.mpl_connect("close_event", self.on_close)
        canvas.mpl_connect("resize_event", lambda _event: refit_texts(layout))
        for slider in (*layout.sliders.values(), *layout.step_sliders.values()):
            slider.on_changed(controls.on_slider)
        layout.sliders["mu"].on_changed(controls.on_mu_slider)
        layout.maxiter_box.on_submit(lambda text: controls.on_field("max iter", layout.maxiter_box, text))
        layout.tol_box.on_submit(lambda text: controls.on_field("tol", layout.tol_box, text))
        layout.backend_radio.on_clicked(viewer.set_backend)
        layout.mode_radio.on_clicked(viewer.on_mode)
        layout.run_button.on_clicked(lambda _event: viewer.toggle_run())
        layout.step_button.on_clicked(lambda _event: viewer.step())
        layout.reset_button.on_clicked(lambda _event: viewer.reset())
        layout.image_button.on_clicked(lambda _event: viewer.open_image())
        layout.mask_button.on_clicked(lambda _event: viewer.load_mask())
        layout.save_button.on_clicked(lambda _event: viewer.save())
        actions = {
            "run/pause": viewer.toggle_run,
            "step": viewer.step,
            "reset": viewer.reset,
            "save": viewer.save,
            "circle": lambda: viewer.set_init_mode("circle"),
            "box": lambda: viewer.set_init_mode("box"),
            "polygon": lambda: viewer.set_init_mode("polygon"),
            "load mask": viewer.load_mask,
            "open image": viewer.open_image,
            "gray/colour": viewer.toggle_color,
            "regions": viewer.cycle_regions,
            "light fit": viewer.toggle_fit,
            "help": viewer.toggle_help,
            "quit": viewer.quit,
        }
        self.keys = {key: actions[action] for key, _, action in SHORTCUTS}

    def on_key(self, event):
        viewer = self.viewer
        if any(box.capturekeystrokes for box in viewer.layout.text_boxes):
            return  # typing into a field
        if not viewer.running and viewer.drawer.key(event.key):
            return
        action = self.keys.get(event.key)
        if action is not None:
            action()
        elif self.default_keys:
            from matplotlib.backend_bases import key_press_handler

            key_press_handler(event, viewer.fig.canvas)

    def on_press(self, event):
        viewer = self.viewer
        if event.inaxes is not viewer.ax_image or self._toolbar_active():
            return
        if viewer.running:
            viewer.say("running: press space to pause before drawing a new init")
            return
        viewer.drawer.press(event)

    def on_motion(self, event):
        if not self.viewer.running and self.viewer.drawer.busy:
            self.viewer.drawer.motion(event)

    def on_release(self, event):
        viewer = self.viewer
        if not viewer.running and viewer.drawer.busy:
            viewer.drawer.release(event)
        if viewer.controls.start_stale and not viewer.running:
            viewer.controls.start_stale = False
            problem = viewer.refresh_named_start()
            if problem:
                viewer.say(problem.removeprefix("; "))
            else:
                viewer.redraw()

    def on_close(self, _event):
        self.viewer.closed = True

    def _toolbar_active(self):
        toolbar = getattr(self.viewer.fig.canvas, "toolbar", None)
        return bool(getattr(toolbar, "mode", ""))  # pan or zoom owns the mouse
