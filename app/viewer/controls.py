"""The viewer's controls: sliders, fields, radio buttons and keys that set the next run's settings.

:class:`Controls` holds the starting :class:`~activecontour.settings.Settings` and gives the next
run's (:meth:`Controls.settings`): the starting ones with what the widgets of the window's
:class:`~.layout.Layout` and the keys (colour, regions, light) set.  It checks nothing itself: a
value typed into a field is kept only when the library's settings accept it.  The step sliders are
options of the backends' options dataclasses (:data:`~.layout.STEP_OPTIONS`), shown for the
backend selected and applied where its solver takes options (two regions).
"""

from __future__ import annotations

import dataclasses

from ..messages import one_line
from .layout import SLIDERS, STEP_OPTIONS, set_slider_value

__all__ = ["REGION_CHOICES", "Controls", "automatic_mu", "slider_values", "step_values"]

#: The numbers of regions key k cycles through (``n_regions`` of :func:`activecontour.segment`).
REGION_CHOICES = (2, 3, 4, 5, 6, "auto")

_SLIDER_LABELS = {name: label for name, label, *_ in SLIDERS}
#: The fields' labels -> the setting each holds and the field's name in the layout.
_FIELDS = {"max iter": ("max_num_iter", "maxiter_box"), "tol": ("tol", "tol_box")}


class Controls:
    """The next run's settings, as the window's widgets and keys set them.

    Parameters
    ----------
    layout : Layout
        The window's widgets (sliders, step sliders, fields, backend radio).
    settings : Settings
        The starting settings; ``mu="auto"`` shows the value the image gets, until the slider is
        moved.
    say : callable
        ``say(text)`` shows a status message.
    has_run : callable
        ``has_run()``: whether a run is going on or has a result (changes then apply to the next).
    """

    def __init__(self, layout, settings, *, say, has_run):
        self.layout = layout
        self.start = settings
        self.say, self.has_run = say, has_run
        self.color, self.n_regions, self.fit = settings.color, settings.n_regions, settings.fit
        self.mu_auto = settings.mu == "auto"
        #: the library's start depends on mu: shown anew once the mouse is released
        self.start_stale = False
        self._valid = {label: getattr(layout, box).text for label, (_, box) in _FIELDS.items()}
        self._show_mu_mode()
        self.show_step_slider(self.backend)

    @property
    def backend(self):
        return self.layout.backend_radio.value_selected

    def settings(self, **changes):
        """The settings of the next run (with ``changes``), checked by the library; mu stays
        ``"auto"`` while it is automatic, so that a run takes the library's own rule (the weight
        it backs off to where the image's leaves no object), not the value the slider shows."""
        values = {name: float(self.layout.sliders[name].val) for name, *_ in SLIDERS}
        if self.mu_auto:
            values["mu"] = "auto"
        values.update(backend=self.backend, max_num_iter=int(self.layout.maxiter_box.text),
                      tol=float(self.layout.tol_box.text), color=self.color, n_regions=self.n_regions,
                      fit=self.fit, options=self._options())
        return dataclasses.replace(self.start, **{**values, **changes})

    def max_num_iter(self):
        return int(self.layout.maxiter_box.text)

    def _options(self):
        """The starting options, and the step slider's value when it was moved (untouched: the
        backend's own default and its rules stay in force) and the solver takes options."""
        options = dict(self.start.options or {})
        slider = self.layout.step_sliders.get(self.backend)
        if slider is not None and slider.get_active():  # shown: the solver takes it
            option = STEP_OPTIONS[self.backend][0]
            if float(slider.val) != backend_default(self.backend, option):
                options[option] = float(slider.val)
        return options or None

    # ---------------------------------------------------------------------- keys
    def toggle_color(self):
        self.color = "vector" if self.color == "gray" else "gray"

    def next_regions(self):
        index = REGION_CHOICES.index(self.n_regions) if self.n_regions in REGION_CHOICES else -1
        self.n_regions = REGION_CHOICES[(index + 1) % len(REGION_CHOICES)]
        self.show_step_slider()

    def toggle_fit(self):
        self.fit = "smooth" if self.fit == "constant" else "constant"

    # ---------------------------------------------------------------------- mu
    def refresh_auto_mu(self, image):
        """While mu is automatic, show the value the image (and colour mode) gets."""
        if self.mu_auto:
            self.mu_auto = False  # set_val below notifies on_mu_slider, which would clear it
            set_slider_value(self.layout.sliders["mu"], automatic_mu(image, self.settings(mu="auto")))
            self.mu_auto = True
            self._show_mu_mode()

    def show_run_mu(self, mu):
        """While mu is automatic, show the weight a run took: ``result.mu``, which is half the
        image's automatic value where that value left no object
        (:data:`activecontour.imaging.noise.MU_BACKOFF`)."""
        if self.mu_auto:
            self.mu_auto = False  # as in refresh_auto_mu: set_val would clear the automatic mode
            set_slider_value(self.layout.sliders["mu"], mu)
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
        label = _SLIDER_LABELS["mu"]
        shown = f"{label} (auto)" if self.mu_auto else label
        self.layout.set_fitted_text(self.layout.slider_labels["mu"], shown)

    # ---------------------------------------------------------------------- widgets
    def on_slider(self, _value):
        if self.has_run():
            self.say("changed settings apply to the next run (space)")

    def on_field(self, label, box, text):
        """A value typed into the "max iter" or "tol" field: kept if the library's settings take
        it, else the field shows its last valid value again."""
        name = _FIELDS[label][0]
        try:
            value = int(text.strip()) if name == "max_num_iter" else float(text.strip())
        except ValueError:
            value = text.strip()  # the library says what it must be
        try:
            self.settings(**{name: value})
        except (ValueError, TypeError) as exc:
            box.set_val(self._valid[label])
            self.say(f"{one_line(exc)}; kept {self._valid[label]}")
            return
        if text.strip() == self._valid[label]:
            return
        self._valid[label] = text.strip()
        if self.has_run():
            self.say(f"{label} = {value:g}: applies to the next run")

    def show_step_slider(self, backend=None):
        """Show the step slider of the backend (the one selected by default) where its solver for
        the number of regions takes that option."""
        from activecontour.backends import solver_for

        backend = self.backend if backend is None else backend
        takes = {spec.name for spec in solver_for(backend, self.n_regions).option_specs()}
        for name, slider in self.layout.step_sliders.items():
            shown = name == backend and STEP_OPTIONS[name][0] in takes
            slider.ax.set_visible(shown)
            slider.set_active(shown)
            self.layout.slider_labels[name].set_visible(shown)


def slider_values(settings, image):
    """The sliders' starting values: the settings', mu="auto" as the value the image gets."""
    values = {name: getattr(settings, name) for name, *_ in SLIDERS}
    if values["mu"] == "auto":
        values["mu"] = automatic_mu(image, settings)
    return values


def automatic_mu(image, settings):
    """The mu that :func:`activecontour.segment` uses for ``mu="auto"`` on ``image`` with these
    settings (the library's preparation, :attr:`activecontour.problem.Problem.mu`)."""
    from activecontour.problem import prepare

    return prepare(image, settings).mu


def step_values():
    """backend -> the starting value of its step slider: the option's default."""
    values = {name: backend_default(name, option) for name, (option, *_) in STEP_OPTIONS.items()}
    return {name: value for name, value in values.items() if value is not None}


def backend_default(backend, option):
    """A backend option's default, from the backend's options dataclass (None when the backend
    or the option is not there, or chosen by the backend)."""
    from activecontour.backends import BACKENDS

    try:
        default = getattr(BACKENDS[backend].options(), option)
    except (KeyError, AttributeError):
        return None
    return None if default is None else float(default)
