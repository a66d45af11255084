"""The interactive viewer: ``activecontour view IMAGE``.

A matplotlib window that shows an image with the current contour(s), lets the user set the initial
curve with the mouse (circle, box, polygon) or from a mask file, and runs, pauses and single-steps
the flow of :func:`activecontour.segment` while showing the iteration, the energy (6.38), the
object and background brightness (c_in, c_out of (6.42)) and a small plot of the energy history.
After a run each object (``result.labels``: touching ones apart) is drawn in its own colour, the
readout counts them, and a click on one (or a right click) shows its measurements
(``result.objects``) on the status line.  Sliders set smoothness (mu), shrink / grow (omega),
object fit and background fit (lambda_in, lambda_out) and the backend's step size; fields set
max_num_iter and tol; radio buttons choose the backend and the init gesture.  The controls speak
a user's words; key h shows the help, where each is given with the book's symbol and equation
number.  Changes apply to the next run.  Another image
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
dashed initial curve what the library starts from.

The viewer holds no solver logic: every iteration is the library's, seen through its callback.

Parts
-----
window     :class:`Viewer`: the state and the actions
layout     where every artist and widget sits
controls   the sliders, fields, radio buttons and keys that set the next run's settings
events     keyboard shortcuts, the mouse on the image, the widgets' callbacks
tools      drawing an initial curve with the mouse; the text field
display    the curves, the readout and the energy plot of a run
session    the runs since the last init: result, iterations, energy history
starts     the initial curves, as the library makes them
launch     :func:`launch`: the window of ``activecontour view``

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

Keyboard shortcuts (listed in the window's help line): see :data:`SHORTCUTS`.
"""

from .controls import REGION_CHOICES
from .events import SHORTCUTS
from .launch import launch
from .layout import CONTOUR_COLOR
from .starts import NAMED_INITS
from .window import Viewer

__all__ = ["CONTOUR_COLOR", "NAMED_INITS", "REGION_CHOICES", "SHORTCUTS", "Viewer", "launch"]
