"""The viewer's controls: sliders, fields, radio buttons and keys that set the next run's settings.

:class:`Controls` reads the widgets of the window's :class:`~.layout.Layout` and the settings that
keys switch (colour, regions, light), and gives the keyword arguments of
:func:`activecontour.segment` for the next run (:meth:`Controls.parameters`).  It checks nothing
itself: a value typed into a field is kept only when the library accepts it.
"""

from __future__ import annotations

from activecontour.imaging.noise import auto_mu, is_auto
from activecontour.imaging.normalize import normalize_image

from ..messages import one_line
from .layout import SLIDERS, STEP_OPTIONS, set_slider_value

__all__ = ["REGION_CHOICES", "Controls", "backend_default", "slider_values", "starting_settings",
           "step_values"]

#: The numbers of regions key k cycles through (``n_regions`` of :func:`activecontour.segment`).
REGION_CHOICES = (2, 3, 4, 5, 6, "auto")

_SLIDER_LABELS = {name: label for name, label, *_ in SLIDERS}


class Controls:
    """The next run's settings, as the window's widgets and keys set them.

    Parameters
    ----------
    layout : Layout
        The window's widgets (sliders, step sliders, fields, backend radio).
    settings : dict
        The starting settings (keywords of :func:`activecontour.segment`); ``mu="auto"`` shows
        the value the image gets, until the slider is moved.
    image : ndarray
        The image, for the automatic mu.
    say : callable
        ``say(text)`` shows a status message.
    has_run : callable
        ``has_run()``: whether a run is going on or has a result (changes then apply to the next).
    """

    def __init__(self, layout, settings, image, *, say, has_run):
        self.layout = layout
        self.say, self.has_run = say, has_run
        self.fixed = {name: settings[name] for name in ("c_in", "c_out", "inside", "noise")}
        self.color, self.n_regions, self.fit = settings["color"], settings["n_regions"], settings["fit"]
        self.mu_auto = is_auto(settings["mu"])
        #: the library's start depends on mu: shown anew once the mouse is released
        self.start_stale = False
        self._valid = {"max iter": layout.maxiter_box.text, "tol": layout.tol_box.text}
        self._show_mu_mode()
        self.show_step_slider(self.backend)

    @property
    def backend(self):
        return self.layout.backend_radio.value_selected

    def parameters(self):
        """The settings the next run will use: keywords of :func:`activecontour.segment`."""
        backend = self.backend
        params = {name: float(self.layout.sliders[name].val) for name, *_ in SLIDERS}
        params.update(backend=backend, max_num_iter=self.max_num_iter(),
                      tol=float(self.layout.tol_box.text), color=self.color, inside=self.fixed["inside"],
                      n_regions=self.n_regions, fit=self.fit, noise=self.fixed["noise"],
                      c_in=self.fixed["c_in"], c_out=self.fixed["c_out"])
        if backend in self.layout.step_sliders and self.n_regions == 2:  # the two-region flows' setting
            option = STEP_OPTIONS[backend][0]
            value = float(self.layout.step_sliders[backend].val)
            if value != backend_default(backend, option):  # untouched: the backend's own default
                params["options"] = {option: value}
        return params

    def max_num_iter(self):
        return int(self.layout.maxiter_box.text)

    # ---------------------------------------------------------------------- keys
    def toggle_color(self):
        self.color = "vector" if self.color == "gray" else "gray"

    def next_regions(self):
        index = REGION_CHOICES.index(self.n_regions) if self.n_regions in REGION_CHOICES else -1
        self.n_regions = REGION_CHOICES[(index + 1) % len(REGION_CHOICES)]

    def toggle_fit(self):
        self.fit = "smooth" if self.fit == "constant" else "constant"

    # ---------------------------------------------------------------------- mu
    def refresh_auto_mu(self, image):
        """While mu is automatic, show the value the image (and colour mode) gets."""
        if self.mu_auto:
            self.mu_auto = False  # set_val below notifies on_mu_slider, which would clear it
            set_slider_value(self.layout.sliders["mu"], automatic_mu(image, self.color))
            self.mu_auto = True
            self._show_mu_mode()

    def on_mu_slider(self, _value):
        if self.mu_auto:
            self.mu_auto = False  # moved by hand: the value is the user's from now on
            self._show_mu_mode()
        # the library's start depends on mu (specks the length term removes): shown anew once
        # the mouse is released, not for every value a drag passes
        self.start_stale = True

    def _show_mu_mode(self):
        self.layout.slider_labels["mu"].set_text("mu (auto)" if self.mu_auto else _SLIDER_LABELS["mu"])

    # ---------------------------------------------------------------------- widgets
    def on_slider(self, _value):
        if self.has_run():
            self.say("changed settings apply to the next run (space)")

    def on_field(self, name, box, text):
        """A value typed into the "max iter" or "tol" field: kept if it is a valid setting, else
        the field shows its last valid value again."""
        try:
            value = int(text.strip()) if name == "max iter" else float(text.strip())
        except ValueError:
            problem = f"{name} must be {'an integer' if name == 'max iter' else 'a number'}, got {text!r}"
        else:
            try:
                _check(name, value)
                problem = None
            except (ValueError, TypeError) as exc:
                problem = one_line(exc)
        if problem is not None:
            box.set_val(self._valid[name])
            self.say(f"{problem}; kept {self._valid[name]}")
            return
        if text.strip() == self._valid[name]:
            return
        self._valid[name] = text.strip()
        if self.has_run():
            self.say(f"{name} = {value:g}: applies to the next run")

    def show_step_slider(self, backend):
        for name, slider in self.layout.step_sliders.items():
            slider.ax.set_visible(name == backend)
            slider.set_active(name == backend)
            self.layout.slider_labels[name].set_visible(name == backend)


def slider_values(settings, image):
    """The sliders' starting values: the settings', mu="auto" as the value the image gets."""
    values = {name: settings[name] for name, *_ in SLIDERS}
    if is_auto(values["mu"]):
        values["mu"] = automatic_mu(image, settings["color"])
    return values


def automatic_mu(image, color):
    """The mu that ``segment(image, mu="auto", color=color)`` uses."""
    return auto_mu(normalize_image(image, color=color))


def step_values():
    """backend -> the starting value of its step slider: the option's default."""
    values = {name: backend_default(name, option) for name, (option, *_) in STEP_OPTIONS.items()}
    return {name: value for name, value in values.items() if value is not None}


def starting_settings(given):
    """Interim: the starting settings, the given ones checked and the library's defaults for the others."""
    import importlib
    import inspect

    import numpy as np

    from activecontour.backends import BACKENDS

    segment = importlib.import_module("activecontour._segment").segment
    settings = {name: parameter.default for name, parameter in inspect.signature(segment).parameters.items()
                if parameter.default is not inspect.Parameter.empty}
    unknown = sorted(set(given) - set(settings))
    if unknown:
        raise TypeError(f"unknown setting(s) {', '.join(unknown)}")
    settings.update({name: value for name, value in given.items() if value is not None})
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
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"max_num_iter must be an integer >= 0, got {value!r}")
    return settings


def _check(name, value):
    """Interim: the field's rule, as :func:`activecontour.segment` states it."""
    if name == "max iter" and value < 0:
        raise ValueError(f"max_num_iter must be >= 0, got {value}")
    if name == "tol" and not (value == value and abs(value) != float("inf") and value >= 0):
        raise ValueError(f"tol must be a finite number >= 0, got {value!r}")


def backend_default(backend, option):
    """A backend option's default, from the backend's options dataclass, or None when the backend
    or the option is not there."""
    from activecontour.backends import BACKENDS

    try:
        default = getattr(BACKENDS[backend].options(), option)
    except (KeyError, ImportError, AttributeError):
        return None
    return None if default is None else float(default)
