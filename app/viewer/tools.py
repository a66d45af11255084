"""The viewer's input tools: drawing an initial curve with the mouse, and a text field.

:class:`TextField` is matplotlib's ``TextBox`` with fixes that matter for a tool: Enter ends the
editing (so the keyboard shortcuts work again); neither a key typed nor a click elsewhere draws the
whole figure at once (``TextBox`` redraws synchronously on every key, and once per field on every
click anywhere), they ask for a redraw; setting the text from code neither shows a cursor nor
forces a redraw; and a text longer than the field stays inside it, showing its end (where a path
has its file name and where one types).

:class:`CurveDrawer` is a small state machine fed with matplotlib mouse and key events; it shows a
dashed preview while the user drags or clicks, and hands the finished curve, in (row, col), to a
callback.  It knows nothing about the solver: the viewer validates the curve with the library's
:func:`activecontour.initial.initial_curves` and reports problems (a curve outside the image).

Gestures
--------
circle   press at the centre, drag to the radius, release.
box      press at one corner, drag to the opposite corner, release.
polygon  click the vertices; Enter, a double click or a right click closes it (three vertices at
         least); Backspace removes the last vertex; Escape cancels.  Clicked in either direction,
         the polygon is an outer boundary (positively oriented).
click    (circle and box: a click without a drag; any mode: a right click with no polygon begun)
         hands the point to ``on_click``, e.g. to show the object there.
"""

from __future__ import annotations

import numpy as np
from matplotlib.widgets import TextBox

from activecontour.geometry.curve import from_xy, orient, to_xy
from activecontour.initial import circle, rectangle

__all__ = ["INIT_MODES", "MIN_DRAG", "CurveDrawer", "TextField"]

#: The drawing modes, in the order the viewer lists them.
INIT_MODES = ("circle", "box", "polygon")

#: A press and release closer than this (pixels of the image) is a click, not a drag: too small
#: for a circle or a box.
MIN_DRAG = 1.0


class CurveDrawer:
    """Turn mouse gestures on an image axes into a closed curve (row, col).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes showing the image, with data coordinates x = col, y = row.
    on_curve : callable
        ``on_curve(curve)`` with an (K, 2) array once a gesture is complete.
    on_message : callable
        ``on_message(text)`` for hints (a click too small for a circle, a polygon with too few
        vertices).
    redraw : callable
        ``redraw()`` asks for the canvas to be redrawn (the viewer coalesces these).
    color : str
        Colour of the dashed preview.
    on_click : callable, optional
        ``on_click(point)`` with the (row, col) of a click that draws nothing (see the module);
        it returns whether it used it (else a click too small for a circle or box says so).
    """

    def __init__(self, ax, on_curve, on_message, redraw, *, color="yellow", on_click=None):
        self.ax = ax
        self._redraw = redraw
        self.mode = INIT_MODES[0]
        self._on_curve = on_curve
        self._on_message = on_message
        self._on_click = on_click
        self._anchor = None  # (row, col) of the press of a circle or box drag
        self._vertices = []  # polygon vertices clicked so far, (row, col)
        (self.preview,) = ax.plot([], [], linestyle="--", linewidth=1.5, color=color,
                                  marker=None, zorder=5)

    @property
    def busy(self):
        """True while a gesture is in progress (a drag, or a polygon not yet closed)."""
        return self._anchor is not None or bool(self._vertices)

    def set_mode(self, mode):
        if mode not in INIT_MODES:
            raise ValueError(f"init mode must be one of {INIT_MODES}, got {mode!r}")
        self.cancel()
        self.mode = mode

    def cancel(self):
        self._anchor = None
        self._vertices = []
        self._show([])

    def point(self, event):
        """The event's position in image (row, col), also outside the axes (drags may leave it)."""
        xy = self.ax.transData.inverted().transform((event.x, event.y))
        return from_xy(xy)

    # --- events -------------------------------------------------------------------------------
    def press(self, event):
        """A button press inside the image axes; returns True when it was used."""
        point = self.point(event)
        if event.button == 3 and not self._vertices and self._on_click is not None:
            return bool(self._on_click(point))
        if self.mode == "polygon":
            return self._polygon_press(event, point)
        if event.button != 1:
            return False
        self._anchor = point
        self._show(self._shape(point, point))
        return True

    def motion(self, event):
        if self._anchor is not None:
            self._show(self._shape(self._anchor, self.point(event)))
        elif self._vertices:
            self._show(self._vertices + [self.point(event)], closed=False)

    def release(self, event):
        if self._anchor is None or event.button != 1:
            return
        anchor, point = self._anchor, self.point(event)
        self.cancel()
        if np.hypot(*(point - anchor)) < MIN_DRAG:
            if self._on_click is not None and self._on_click(anchor):
                return
            noun = "radius" if self.mode == "circle" else "opposite corner"
            self._on_message(f"{self.mode}: press and drag to the {noun}")
            return
        if self.mode == "circle":
            curve = circle(anchor, float(np.hypot(*(point - anchor))))
        else:
            curve = rectangle(anchor, point)
        self._on_curve(curve)

    def key(self, key):
        """Enter, Backspace and Escape while a polygon is drawn; returns True when used."""
        if not self._vertices:
            return False
        if key == "enter":
            self._close_polygon()
        elif key == "backspace":
            self._vertices.pop()
            self._show(self._vertices, closed=False)
        elif key == "escape":
            self.cancel()
            self._on_message("polygon cancelled")
        else:
            return False
        return True

    # --- helpers ------------------------------------------------------------------------------
    def _polygon_press(self, event, point):
        if event.button == 3 or (event.button == 1 and event.dblclick):
            # the first click of a double click has already added the last vertex
            self._close_polygon()
            return True
        if event.button != 1:
            return False
        self._vertices.append(point)
        self._show(self._vertices, closed=False)
        self._on_message(f"polygon: {len(self._vertices)} vertices; Enter, double or right click closes")
        return True

    def _close_polygon(self):
        vertices = np.array(self._vertices, dtype=np.float64).reshape(-1, 2)
        self.cancel()
        if len(vertices) < 3:
            self._on_message("polygon: click at least three vertices before closing it")
            return
        self._on_curve(orient(vertices))  # clicked either way round, it is an outer boundary

    def _shape(self, anchor, point):
        if self.mode == "circle":
            radius = float(np.hypot(*(point - anchor)))
            angle = np.linspace(0.0, 2.0 * np.pi, 73)
            return list(anchor + radius * np.column_stack([np.cos(angle), np.sin(angle)]))
        (r0, c0), (r1, c1) = anchor, point
        return [np.array(p) for p in ((r0, c0), (r1, c0), (r1, c1), (r0, c1))]

    def _show(self, points, *, closed=True):
        points = np.array(points, dtype=np.float64).reshape(-1, 2)
        if closed and len(points):
            points = np.vstack([points, points[:1]])
        xy = to_xy(points)
        self.preview.set_data(xy[:, 0], xy[:, 1])
        self.preview.set_marker("o" if self.mode == "polygon" else "")  # the clicked vertices
        self.preview.set_markersize(3)
        self._redraw()


class TextField(TextBox):
    """A ``TextBox`` that stops editing on Enter and redraws only when something changes."""

    def __init__(self, ax, initial=""):
        super().__init__(ax, "", initial)
        self.text_disp.set_fontsize(8)
        for artist in (self.text_disp, self.cursor):
            artist.set_clip_box(ax.bbox)
            artist.set_clip_on(True)
        self.on_submit(self._end_editing)
        self.align_to_fit()

    def align_to_fit(self):
        """Left-aligned when the text fits the field, else right-aligned (its end shown)."""
        self.text_disp.set_horizontalalignment("left")
        self.text_disp.set_x(0.05)
        if self.text_disp.get_window_extent().width > 0.9 * self.ax.bbox.width:
            self.text_disp.set_horizontalalignment("right")
            self.text_disp.set_x(0.95)

    def _rendercursor(self):
        """Place the cursor after the text before ``cursor_index``, as ``TextBox`` does, but ask
        for a redraw instead of drawing the whole figure at once on every key typed."""
        self.align_to_fit()
        text, shown = self.text_disp.get_text(), self.text_disp.get_window_extent()
        self.text_disp.set_text(text[:self.cursor_index] or ",")
        before = self.text_disp.get_window_extent()
        self.text_disp.set_text(text)
        if shown.y0 == shown.y1:  # no text: the height of a comma
            shown.y0, shown.y1 = shown.y0 - before.height / 2, shown.y1 + before.height / 2
        x = shown.x0 + (before.width if text[:self.cursor_index] else 0.0)
        self.cursor.set(segments=[[(x, shown.y0), (x, shown.y1)]], visible=True)
        self.ax.get_figure(root=True).canvas.draw_idle()

    def stop_typing(self):
        if self.capturekeystrokes or self.cursor.get_visible():
            super().stop_typing()

    def set_val(self, val):
        """Set the text and notify as ``TextBox`` does; outside editing, without showing a cursor
        and with an idle redraw instead of a synchronous one."""
        if self.capturekeystrokes:
            super().set_val(val)
            return
        text = str(val)
        if self.text == text:
            return
        self.text_disp.set_text(text)
        self.align_to_fit()
        if self.drawon:
            self.ax.get_figure(root=True).canvas.draw_idle()
        if self.eventson:
            self._observers.process("change", self.text)
            self._observers.process("submit", self.text)

    def _end_editing(self, _text):
        if self.capturekeystrokes:
            self.stop_typing()  # submits once more; submit handlers must be idempotent
