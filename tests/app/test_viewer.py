"""The interactive viewer, driven headless: Agg canvas, events sent through the figure canvas.

Mouse and key events are built as matplotlib builds them from a GUI toolkit (``MouseEvent``,
``KeyEvent``, ``CloseEvent``) and processed by the canvas, at display positions computed from the
axes' transforms.  Events "during a run" are sent from a ``draw_event`` handler of a canvas made to
behave like a GUI's (:func:`gui_like`): the viewer redraws and processes events from inside the
library's callback, which is where a GUI delivers them.
"""

import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backend_bases import CloseEvent, KeyEvent, MouseEvent, ResizeEvent  # noqa: E402

import activecontour as ac  # noqa: E402
import app.viewer.window as window  # noqa: E402
from activecontour import synthetic  # noqa: E402
from activecontour.geometry.curve import length, signed_area  # noqa: E402
from activecontour.geometry.raster import mask_to_curves  # noqa: E402
from activecontour.io import read_contours, read_mask, write_mask  # noqa: E402
from activecontour.io.pictures import display_rgb  # noqa: E402
from app import viewer as viewer_module  # noqa: E402
from app.viewer import SHORTCUTS, Viewer, launch  # noqa: E402
from app.viewer.display import OBJECT_COLORS, object_colors  # noqa: E402
from app.viewer.layout import DEFAULT_SIZE  # noqa: E402

SIZE = (128, 128)
CENTER, RADIUS = (60.0, 66.0), 30.0


@pytest.fixture(scope="module")
def disk_image():
    clean, truth = synthetic.render(synthetic.disk(CENTER, RADIUS), SIZE)
    return synthetic.add_noise(clean, 0.1, seed=4), truth


@pytest.fixture(scope="module")
def star_image():
    clean, truth = synthetic.render(synthetic.star((64.0, 64.0), 34.0, amplitude=0.35, arms=5), SIZE)
    return synthetic.add_noise(clean, 0.05, seed=5), truth


@pytest.fixture
def make_viewer():
    created = []

    def make(image, **kwargs):
        viewer = Viewer(image, **kwargs)
        viewer.ax_image.apply_aspect()  # place the image axes, as the window's first draw does
        created.append(viewer)
        return viewer

    yield make
    for viewer in created:
        plt.close(viewer.fig)


# ------------------------------------------------------------------------------ event helpers
def _display(ax, x, y):
    return ax.transData.transform((x, y))


def event_resolution(viewer):
    """Image pixels per display pixel: matplotlib rounds event positions to whole display pixels."""
    scale = viewer.ax_image.transData.get_matrix()[0, 0]
    return 1.0 / abs(scale)


def mouse(viewer, name, row, col, *, button=1, dblclick=False):
    """A mouse event at image position (row, col)."""
    x, y = _display(viewer.ax_image, col, row)
    MouseEvent(name, viewer.fig.canvas, x, y, button=button, dblclick=dblclick)._process()


def drag(viewer, start, end, steps=3):
    mouse(viewer, "button_press_event", *start)
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        mouse(viewer, "motion_notify_event", *(np.add(start, t * np.subtract(end, start))))
    mouse(viewer, "button_release_event", *end)


def key(viewer, name):
    KeyEvent("key_press_event", viewer.fig.canvas, name)._process()


def resize(viewer, size):
    """Resize the window to ``size`` inches, as a GUI does (the canvas sends resize_event)."""
    viewer.fig.set_size_inches(*size)
    ResizeEvent("resize_event", viewer.fig.canvas)._process()
    viewer.ax_image.apply_aspect()


def click_axes(viewer, ax, x=None, y=None):
    """Press and release the left button on an axes (its centre, or data position x, y)."""
    if x is None:
        bbox = ax.get_window_extent()
        px, py = (bbox.x0 + bbox.x1) / 2, (bbox.y0 + bbox.y1) / 2
    else:
        px, py = _display(ax, x, y)
    for name in ("button_press_event", "button_release_event"):
        MouseEvent(name, viewer.fig.canvas, px, py, button=1)._process()


def click_radio(viewer, radio, label):
    """Click a radio button's label (the widget accepts clicks on the label or the button)."""
    text = radio.labels[[t.get_text() for t in radio.labels].index(label)]
    bbox = text.get_window_extent()
    px, py = (bbox.x0 + bbox.x1) / 2, (bbox.y0 + bbox.y1) / 2
    for name in ("button_press_event", "button_release_event"):
        MouseEvent(name, viewer.fig.canvas, px, py, button=1)._process()


def set_slider(viewer, slider, value):
    click_axes(viewer, slider.ax, value, 0.5)


def gui_like(viewer):
    """Let the Agg canvas behave as a GUI canvas does: ``draw_idle`` only asks for a draw, and the
    toolkit's event processing (``flush_events``) performs it, sending ``draw_event``."""
    canvas, pending = viewer.fig.canvas, []
    canvas.draw_idle = lambda *args, **kwargs: pending.append(True)

    def flush_events():
        if pending:
            pending.clear()
            canvas.draw()

    canvas.flush_events = flush_events
    viewer.live = True
    return viewer


def during_run(viewer, action, *, at_iteration=1):
    """Call ``action()`` once from the first redraw at or after ``at_iteration`` of a run: as a GUI
    handles a click or a key that arrives during a run."""
    done = []

    def on_draw(_event):
        if viewer.running and not done and viewer.iteration >= at_iteration:
            done.append(viewer.iteration)
            action()

    viewer.fig.canvas.mpl_connect("draw_event", on_draw)
    return done


def assert_same_contours(actual, expected):
    assert len(actual) == len(expected)
    for a, b in zip(actual, expected, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)


# ------------------------------------------------------------------------------------- tests
def test_drag_circle_run_matches_library_and_truth(disk_image, make_viewer):
    image, truth = disk_image
    viewer = make_viewer(image)
    center, radius = (64.0, 62.0), 18.0
    drag(viewer, center, (center[0] + radius, center[1]))
    (init,) = viewer.init_curves
    tolerance = 3 * event_resolution(viewer)
    np.testing.assert_allclose(init.mean(axis=0), center, atol=tolerance)
    np.testing.assert_allclose(np.hypot(*(init - init.mean(axis=0)).T), radius, atol=tolerance)

    key(viewer, " ")
    result = viewer.result
    assert result is not None and result.success
    # the viewer starts at the library's defaults; a drawn curve restricts the run to its
    # neighbourhood (roi="init": drawing around one object gives that object)
    expected = ac.segment(image, viewer.init_curves, roi="init", mu=viewer.parameters()["mu"])
    assert result.n_iter == expected.n_iter
    assert_same_contours(viewer.contours, expected.contours)
    np.testing.assert_array_equal(result.mask, expected.mask)
    assert synthetic.dice(result.mask, truth) >= 0.98
    assert viewer.iteration == result.n_iter
    # the energy plot shows the run's energies, which never increase
    history = viewer.energy_history
    np.testing.assert_array_equal(history[:, 1], expected.energies)
    assert np.all(np.diff(history[:, 1]) <= 0)
    assert f"iteration {result.n_iter}" in viewer.readout.get_text()


def test_run_button_and_default_init_match_library(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image, max_num_iter=200, tol=1e-4)
    click_axes(viewer, viewer.run_button.ax)
    expected = ac.segment(image, None, max_num_iter=200, tol=1e-4)
    assert_same_contours(viewer.contours, expected.contours)
    assert viewer.run_button.label.get_text() == "Run"


def test_larger_mu_from_slider_gives_shorter_contour(star_image, make_viewer):
    image, _ = star_image
    lengths = {}
    for mu in (0.1, 4.0):
        viewer = make_viewer(image)
        set_slider(viewer, viewer.sliders["mu"], mu)
        assert viewer.parameters()["mu"] == pytest.approx(mu, abs=1e-9)
        key(viewer, " ")
        lengths[mu] = sum(length(c) for c in viewer.contours)
    # the slider's value is what the solver got
    expected = ac.segment(image, viewer.init, mu=viewer.parameters()["mu"])
    assert_same_contours(viewer.contours, expected.contours)
    assert lengths[4.0] < lengths[0.1]


def test_fields_reach_the_solver_and_bad_values_are_refused(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    tol = viewer.parameters()["tol"]
    viewer.maxiter_box.set_val("3")
    key(viewer, " ")
    assert viewer.result.n_iter == 3 and viewer.result.status == 1
    viewer.tol_box.set_val("-1")
    assert viewer.parameters()["tol"] == tol
    assert "tol must be" in viewer.message
    viewer.maxiter_box.set_val("many")
    assert viewer.parameters()["max_num_iter"] == 3


def test_box_init_by_drag(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    key(viewer, "b")
    assert viewer.init_mode == "box" and viewer.mode_radio.value_selected == "box"
    drag(viewer, (30.0, 40.0), (90.0, 100.0))
    (init,) = viewer.init_curves
    expected = ac.rectangle((30.0, 40.0), (90.0, 100.0))
    np.testing.assert_allclose(init, expected, atol=2 * event_resolution(viewer))


@pytest.mark.parametrize("closing", ["enter", "right click", "double click"])
def test_polygon_init_by_clicks(disk_image, make_viewer, closing):
    image, _ = disk_image
    viewer = make_viewer(image)
    key(viewer, "p")
    clicked = [(30.0, 40.0), (30.0, 90.0), (95.0, 90.0), (95.0, 40.0)]  # clockwise in (row, col)
    for point in clicked:
        mouse(viewer, "button_press_event", *point)
        mouse(viewer, "button_release_event", *point)
    if closing == "enter":
        key(viewer, "enter")
    elif closing == "right click":
        mouse(viewer, "button_press_event", 60.0, 60.0, button=3)
    else:
        mouse(viewer, "button_press_event", *clicked[-1], dblclick=True)
    (init,) = viewer.init_curves
    assert signed_area(init) > 0  # an outer boundary, whichever way it was clicked
    np.testing.assert_allclose(init, np.array(clicked)[::-1], atol=2 * event_resolution(viewer))


def test_polygon_needs_three_vertices_and_escape_cancels(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    before = [c.copy() for c in viewer.init_curves]
    key(viewer, "p")
    for point in [(30.0, 40.0), (30.0, 90.0)]:
        mouse(viewer, "button_press_event", *point)
    key(viewer, "enter")
    assert "three vertices" in viewer.message
    mouse(viewer, "button_press_event", 50.0, 50.0)
    key(viewer, "escape")
    assert "cancelled" in viewer.message
    assert_same_contours(viewer.init_curves, before)


def test_init_outside_the_image_is_refused_with_a_message(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    before = [c.copy() for c in viewer.init_curves]
    viewer.ax_image.set_xlim(-300, 150)  # zoomed out: the axes now show space beyond the image
    viewer.ax_image.set_ylim(150, -300)
    viewer.ax_image.apply_aspect()
    drag(viewer, (-150.0, -150.0), (-150.0, -130.0))
    assert "init not set" in viewer.message and "outside the image" in viewer.message
    assert_same_contours(viewer.init_curves, before)
    # a click without a drag makes no circle either
    mouse(viewer, "button_press_event", 60.0, 60.0)
    mouse(viewer, "button_release_event", 60.0, 60.0)
    assert "drag" in viewer.message
    assert_same_contours(viewer.init_curves, before)


def test_circle_partly_outside_is_clipped_like_the_library(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    drag(viewer, (10.0, 10.0), (10.0, 40.0))
    assert "clipped" in viewer.message
    (init,) = viewer.init_curves
    assert init[:, 0].min() == -0.5 and init[:, 1].min() == -0.5  # the image domain's edge
    tolerance = 3 * event_resolution(viewer)
    assert init[:, 0].max() == pytest.approx(40.0, abs=tolerance)


def test_save_before_any_run_shows_a_message(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    viewer = make_viewer(image)
    viewer.save_box.set_val(str(tmp_path / "out"))
    key(viewer, "s")
    assert "nothing to save" in viewer.message
    assert list(tmp_path.iterdir()) == []


def test_save_writes_files_the_cli_reader_loads_back(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    viewer = make_viewer(image, formats=("json", "csv"))
    key(viewer, " ")
    stem = tmp_path / "disk"
    viewer.save_box.set_val(str(stem))
    click_axes(viewer, viewer.save_button.ax)
    assert "saved" in viewer.message
    np.testing.assert_array_equal(read_mask(f"{stem}_mask.png"), viewer.result.mask)
    for fmt in ("json", "csv"):
        loaded = read_contours(f"{stem}_contours.{fmt}")
        assert len(loaded) == len(viewer.result.contours)
        for a, b in zip(loaded, viewer.result.contours, strict=True):
            np.testing.assert_array_equal(a, b)
    overlay = plt.imread(f"{stem}_overlay.png")
    assert overlay.shape[:2] == SIZE


def test_save_refuses_to_overwrite_the_image(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    image_path = tmp_path / "x_mask.png"
    write_mask(image_path, image > 0.5)
    viewer = make_viewer(image, image_path=image_path)
    key(viewer, " ")
    viewer.save_box.set_val(str(tmp_path / "x"))
    key(viewer, "s")
    assert "not saved" in viewer.message and "overwrite" in viewer.message
    np.testing.assert_array_equal(read_mask(image_path), image > 0.5)


def test_step_is_one_library_iteration(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    key(viewer, "n")
    first = ac.segment(image, max_num_iter=1)  # no drawn init: the library's default start
    assert viewer.iteration == 1
    assert_same_contours(viewer.contours, first.contours)
    click_axes(viewer, viewer.step_button.ax)
    second = ac.segment(image, first, max_num_iter=1)  # resumed from the result
    assert viewer.iteration == 2
    assert_same_contours(viewer.contours, second.contours)


def test_pause_during_run_then_resume_converges(disk_image, make_viewer):
    image, truth = disk_image
    viewer = gui_like(make_viewer(image, redraw_every=2))
    paused_at = during_run(viewer, lambda: key(viewer, " "), at_iteration=2)
    key(viewer, " ")
    assert paused_at and viewer.result.status == 2
    assert viewer.iteration == paused_at[0]
    assert "paused" in viewer.message and viewer.run_button.label.get_text() == "Run"
    key(viewer, " ")  # resume: from the paused contours, until convergence
    assert viewer.result.success
    assert viewer.iteration == paused_at[0] + viewer.result.n_iter
    assert synthetic.dice(viewer.result.mask, truth) >= 0.98
    assert len(viewer.energy_history) == viewer.iteration + 1


def test_reset_during_run_returns_to_the_init(disk_image, make_viewer):
    image, _ = disk_image
    viewer = gui_like(make_viewer(image))
    init = [c.copy() for c in viewer.init_curves]
    during_run(viewer, lambda: key(viewer, "r"), at_iteration=2)
    key(viewer, " ")
    assert viewer.result is None and viewer.contours == [] and viewer.iteration == 0
    assert_same_contours(viewer.init_curves, init)
    key(viewer, "s")
    assert "nothing to save" in viewer.message


def test_closing_the_window_during_a_run_stops_it(disk_image, make_viewer):
    image, _ = disk_image
    viewer = gui_like(make_viewer(image))
    canvas = viewer.fig.canvas
    during_run(viewer, lambda: CloseEvent("close_event", canvas)._process(), at_iteration=2)
    result = viewer.run()
    assert viewer.closed and not viewer.running
    assert result.status == 2 and result.n_iter == viewer.iteration


def test_quit_key_during_a_run_closes_the_figure(disk_image, make_viewer):
    image, _ = disk_image
    viewer = gui_like(make_viewer(image))
    during_run(viewer, lambda: key(viewer, "q"), at_iteration=2)
    key(viewer, " ")
    assert viewer.closed and not plt.fignum_exists(viewer.fig.number)
    assert viewer.result.status == 2


def test_load_mask_file_as_init(disk_image, make_viewer, tmp_path):
    image, truth = disk_image
    viewer = make_viewer(image)
    path = tmp_path / "init_mask.png"
    write_mask(path, truth)
    viewer.mask_box.set_val(str(path))
    key(viewer, "m")
    assert_same_contours(viewer.init_curves, mask_to_curves(truth))

    write_mask(tmp_path / "small.png", np.ones((10, 10), bool))
    assert not viewer.load_mask(tmp_path / "small.png")
    assert "init not set" in viewer.message and "shape" in viewer.message
    assert_same_contours(viewer.init_curves, mask_to_curves(truth))
    assert not viewer.load_mask(tmp_path / "missing.png")
    assert "mask not loaded" in viewer.message
    viewer.mask_box.set_val("")
    click_axes(viewer, viewer.mask_button.ax)
    assert "type a mask file" in viewer.message


def test_shortcuts_are_off_while_typing_in_a_field(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    viewer.save_box.set_val("")
    click_axes(viewer, viewer.save_box.ax)
    gui_like(viewer)  # draw_idle only asks for a draw, as on a GUI canvas
    draws = []
    real_draw = viewer.fig.canvas.draw
    viewer.fig.canvas.draw = lambda: (draws.append(1), real_draw())
    for name in "s ":  # save, run
        key(viewer, name)
    assert viewer.save_box.text == "s " and viewer.result is None
    assert "saved" not in viewer.message
    assert draws == []  # a key typed asks for a redraw; it does not draw the figure at once
    (cursor,) = viewer.save_box.cursor.get_segments()
    text = viewer.save_box.text_disp
    text.set_text("s")  # the cursor stands after what was typed (the trailing space has a width)
    assert cursor[0, 0] > text.get_window_extent().x1
    text.set_text("s ")
    del viewer.fig.canvas.draw
    key(viewer, "enter")
    assert not viewer.save_box.capturekeystrokes


def test_help_line_lists_every_shortcut(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    help_text = next(t.get_text() for t in viewer.fig.texts if t.get_text().startswith("keys:"))
    for _, shown, action in SHORTCUTS:
        assert f"{shown} {action}" in help_text


def test_backend_radio_selects_the_backend(disk_image, make_viewer):
    image, truth = disk_image
    viewer = make_viewer(image)
    click_radio(viewer, viewer.backend_radio, "levelset")
    assert viewer.parameters()["backend"] == "levelset"
    key(viewer, " ")
    try:
        from activecontour.backends.levelset import DEFAULT_OPTIONS
    except ImportError:
        assert viewer.result is None and "run failed" in viewer.message
        return
    # an untouched step slider leaves the backend's own default (and its rules) in force
    assert viewer.parameters()["options"] is None
    viewer.step_sliders["levelset"].set_val(DEFAULT_OPTIONS["dt"] / 2)
    assert viewer.parameters()["options"] == {"dt": DEFAULT_OPTIONS["dt"] / 2}
    assert viewer.result.backend == "levelset"
    assert synthetic.dice(viewer.result.mask, truth) >= 0.98


def test_screenshot_shows_the_contour_on_the_object_boundary(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    viewer = make_viewer(image)
    key(viewer, " ")
    path = tmp_path / "viewer.png"
    viewer.fig.savefig(path)
    shot = plt.imread(path)[:, :, :3]
    height = shot.shape[0]
    # the one object, in the first of the objects' colours
    contour_rgb = np.array(OBJECT_COLORS[0])
    np.testing.assert_allclose(viewer.contour_lines.get_colors()[0][:3], contour_rgb)

    def near_contour_colour(row, col, reach=2):
        x, y = _display(viewer.ax_image, col, row)
        i, j = int(round(height - y)), int(round(x))
        window = shot[i - reach:i + reach + 1, j - reach:j + reach + 1]
        return np.any(np.abs(window - contour_rgb).max(axis=2) < 0.2)

    angles = np.linspace(0.0, 2.0 * np.pi, 72, endpoint=False)
    on_boundary = [near_contour_colour(CENTER[0] + RADIUS * np.cos(a), CENTER[1] + RADIUS * np.sin(a))
                   for a in angles]
    assert np.mean(on_boundary) >= 0.95
    # nowhere near the object's centre or the image corners
    for row, col in [CENTER, (CENTER[0] + RADIUS / 2, CENTER[1]), (5.0, 5.0), (120.0, 120.0)]:
        assert not near_contour_colour(row, col)


def test_launch_reports_bad_image_and_missing_display(tmp_path, disk_image, capsys):
    assert launch(tmp_path / "missing.png") == 2
    err = capsys.readouterr().err
    assert "not found" in err and err.startswith("activecontour: error: ") and len(err.splitlines()) == 1
    path = tmp_path / "disk.png"
    write_mask(path, disk_image[1])
    figures = plt.get_fignums()
    assert launch(path) == 1  # Agg: no window can be opened
    assert "cannot open a window" in capsys.readouterr().err
    assert plt.get_fignums() == figures


def test_bad_constructor_arguments(disk_image, tmp_path):
    image, _ = disk_image
    figures = plt.get_fignums()
    with pytest.raises(ValueError, match="backend must be one of"):
        Viewer(image, backend="snake")
    with pytest.raises(ValueError, match="mu must be a finite number"):
        Viewer(image, mu=float("nan"))
    with pytest.raises(ValueError, match="max_num_iter must be"):
        Viewer(image, max_num_iter=-1)
    plt.close(Viewer(image, max_num_iter=0).fig)  # as segment allows: the start, no iteration
    with pytest.raises(ValueError, match="formats must be chosen from"):
        Viewer(image, formats=("docx",))
    with pytest.raises(ValueError, match="outside the image"):
        Viewer(image, init=ac.circle((500.0, 500.0), 10.0))
    with pytest.raises(FileNotFoundError):
        Viewer(image, init=tmp_path / "missing_mask.png")
    assert plt.get_fignums() == figures  # no window left behind


def test_colour_key_switches_to_vector_segmentation(make_viewer):
    image, truth = synthetic.equal_gray_colour()
    viewer = make_viewer(image)
    assert viewer.parameters()["color"] == "gray"
    key(viewer, "g")
    assert viewer.parameters()["color"] == "vector"
    key(viewer, " ")
    assert synthetic.dice(viewer.result.mask, truth) >= 0.98  # the regions differ only in hue
    gray_viewer = make_viewer(np.zeros((20, 20)))
    key(gray_viewer, "g")
    assert gray_viewer.parameters()["color"] == "gray" and "gray" in gray_viewer.message


# ------------------------------------------------------------- named inits, CLI and library default
def _write_png(path, image):
    """A gray (M, N) or RGB (M, N, 3) image in [0, 1] as an 8-bit PNG; returns what load_image reads."""
    import cv2

    pixels = np.round(np.clip(image, 0.0, 1.0) * 255).astype(np.uint8)
    cv2.imwrite(str(path), pixels[:, :, ::-1] if pixels.ndim == 3 else pixels)
    return ac.load_image(path)


@pytest.fixture(scope="module")
def coins_image():
    image, truth, _ = synthetic.coins()
    return image, truth


@pytest.fixture
def headless_launch(monkeypatch):
    """``launch`` builds its Viewer as the window would; keep the viewers (Agg cannot show them)."""
    built = []

    class Recorded(Viewer):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            built.append(self)

    monkeypatch.setattr(window, "Viewer", Recorded)
    yield built
    for viewer in built:
        plt.close(viewer.fig)


@pytest.mark.parametrize("argv, init, backend", [
    (["--init-grid"], "grid", "polygon"),
    (["--init-checkerboard", "--backend", "levelset"], "checkerboard", "levelset"),
])
def test_view_command_takes_the_named_inits(coins_image, tmp_path, capsys, headless_launch,
                                            argv, init, backend):
    from app import cli

    path = tmp_path / "coins.png"
    image = _write_png(path, coins_image[0])
    status = cli.main(["view", str(path), "--max-iter", "60", *argv])
    err = capsys.readouterr().err
    assert status == 1 and "cannot open a window" in err  # Agg; not the exit 2 of a refused init
    (viewer,) = headless_launch
    assert viewer.init == init and viewer.parameters()["backend"] == backend
    expected = ac.segment(image, init, backend=backend, max_num_iter=60)
    assert_same_contours(viewer.init_curves, ac.segment(image, init, backend=backend,
                                                        max_num_iter=0).contours)
    viewer.run()
    assert_same_contours(viewer.contours, expected.contours)
    assert synthetic.dice(viewer.result.mask, coins_image[1]) >= 0.95  # every coin, found anywhere


def test_viewer_named_inits_are_the_librarys(coins_image, make_viewer):
    image, truth = coins_image
    for init, backend in (("grid", "polygon"), ("checkerboard", "levelset")):
        viewer = make_viewer(image, init=init, backend=backend, max_num_iter=60)
        key(viewer, " ")
        expected = ac.segment(image, init, backend=backend, max_num_iter=60)
        assert_same_contours(viewer.contours, expected.contours)
        assert synthetic.dice(viewer.result.mask, truth) >= 0.95
    # the polygon backend has no checkerboard: switching to it says so, and a run fails cleanly
    click_radio(viewer, viewer.backend_radio, "polygon")
    assert "checkerboard" in viewer.message and viewer.init_curves == []
    key(viewer, "r")
    key(viewer, " ")
    assert "run failed" in viewer.message and viewer.result is None
    figures = plt.get_fignums()
    with pytest.raises(ValueError, match="checkerboard"):
        Viewer(image, init="checkerboard", backend="polygon")
    assert plt.get_fignums() == figures


def test_without_a_drawn_init_the_viewer_passes_none(disk_image, make_viewer, monkeypatch):
    """The library's default start, whatever it is, not a copy of it."""
    image, _ = disk_image
    calls = []
    real = ac.segment

    def spy(image, init=None, **kwargs):
        calls.append((init, kwargs["max_num_iter"]))
        return real(image, init, **kwargs)

    monkeypatch.setattr(ac, "segment", spy)
    viewer = make_viewer(image, max_num_iter=40)
    assert calls == [(None, 0)]  # what the dashed curve shows: the library's start
    assert_same_contours(viewer.init_curves, real(image, None, max_num_iter=0).contours)
    key(viewer, " ")
    assert calls[-1] == (None, 40)
    assert_same_contours(viewer.contours, real(image, None, max_num_iter=40).contours)
    key(viewer, "r")
    key(viewer, "n")  # a step after a reset starts from the library's default again
    assert calls[-1] == (None, 1)


# ------------------------------------------------------------------------- opening another image
def test_open_another_image_resets_and_runs_on_it(disk_image, star_image, make_viewer, tmp_path):
    first_path, second_path = tmp_path / "disk.png", tmp_path / "wide" / "star_mask.png"
    second_path.parent.mkdir()
    first = _write_png(first_path, disk_image[0])
    wide = np.pad(star_image[0], ((0, 0), (0, 40)))  # (128, 168): a new shape
    second = _write_png(second_path, wide)
    viewer = make_viewer(first, image_path=first_path, max_num_iter=30)
    drag(viewer, (64.0, 62.0), (64.0, 80.0))
    key(viewer, " ")
    assert viewer.result is not None
    viewer.image_box.set_val(str(second_path))
    key(viewer, "i")
    assert viewer.shape == wide.shape and viewer.image_path == second_path
    assert viewer.result is None and viewer.contours == [] and viewer.iteration == 0
    assert viewer.init is None  # the drawn circle belonged to the old image
    assert len(viewer.energy_history) == 0 and np.size(viewer.energy_line.get_xdata()) == 0
    assert viewer.ax_image.get_xlim() == (-0.5, wide.shape[1] - 0.5)
    np.testing.assert_array_equal(viewer.ax_image.images[0].get_array(), display_rgb(second))
    assert "star_mask.png" in viewer.message
    key(viewer, " ")
    assert_same_contours(viewer.contours, ac.segment(second, None, max_num_iter=30).contours)
    # Save now goes next to the new image, and never over it
    assert viewer.save_box.text == "star_mask"
    viewer.save_box.set_val("star")
    key(viewer, "s")
    assert "not saved" in viewer.message and "overwrite" in viewer.message
    np.testing.assert_array_equal(ac.load_image(second_path), second)


def test_a_bad_image_path_keeps_the_shown_image(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    viewer = make_viewer(image, init="grid")
    key(viewer, " ")
    result = viewer.result
    missing, text = tmp_path / "missing.png", tmp_path / "notes.png"
    text.write_text("not an image\n")
    for path in (missing, text, tmp_path):
        with pytest.raises((OSError, ValueError)) as library:
            ac.load_image(path)
        assert not viewer.open_image(path)
        expected = " ".join(str(library.value).split())
        assert viewer.message == f"image not opened: {expected}" and "\n" not in viewer.message
        assert viewer.image is image and viewer.result is result
    viewer.image_box.set_val("")
    click_axes(viewer, viewer.image_button.ax)
    assert "type an image file" in viewer.message
    # a named init is kept for the next image
    other = tmp_path / "other.png"
    _write_png(other, image[:100, :90])
    assert viewer.open_image(other) and viewer.init == "grid"
    assert_same_contours(viewer.init_curves,
                         ac.segment(ac.load_image(other), "grid", max_num_iter=0).contours)


# ------------------------------------------------------------------------ readouts and energy plot
def _visible_tick_labels(ax):
    return [t.get_text() for t in (*ax.get_xticklabels(), *ax.get_yticklabels()) if t.get_text()]


def test_energy_plot_is_labelled_before_a_run_and_cleared_by_a_new_init(disk_image, make_viewer):
    image, _ = disk_image
    viewer = make_viewer(image)
    viewer.fig.canvas.draw()

    def assert_placeholder():
        assert np.size(viewer.energy_line.get_xdata()) == 0
        assert viewer.energy_note.get_visible() and "space" in viewer.energy_note.get_text()
        assert _visible_tick_labels(viewer.ax_energy) == []  # no range of an old run

    assert viewer.ax_energy.get_title() and viewer.ax_energy.get_xlabel() == "iteration"
    assert_placeholder()
    key(viewer, " ")
    viewer.fig.canvas.draw()
    energies = viewer.result.energies
    np.testing.assert_array_equal(viewer.energy_line.get_ydata(), energies)
    assert not viewer.energy_note.get_visible()
    low, high = viewer.ax_energy.get_ylim()
    assert low <= energies.min() and high >= energies.max()
    drag(viewer, (64.0, 62.0), (64.0, 75.0))  # a new init
    viewer.fig.canvas.draw()
    assert_placeholder()
    key(viewer, " ")
    key(viewer, "r")
    assert_placeholder()


def test_colour_constants_fit_the_readout(make_viewer):
    image, _ = synthetic.equal_gray_colour()
    viewer = make_viewer(image, color="vector")
    resize(viewer, (9.0, 6.0))
    key(viewer, " ")
    viewer.fig.canvas.draw()
    text = viewer.readout.get_text()
    for name, words in (("c_in", "object brightness"), ("c_out", "background brightness")):
        line = next(t for t in text.splitlines() if t.startswith(words + " "))
        values = np.atleast_1d(getattr(viewer.result, name))
        assert len(values) == image.shape[2]
        for value in values:
            assert f"{value:.3g}" in line
    assert "\N{HORIZONTAL ELLIPSIS}" not in text and viewer.readout.get_fontsize() >= 8
    panel_right = viewer.ax_energy.get_window_extent().x1
    assert viewer.readout.get_window_extent().x1 <= panel_right + 2.0


def test_toolbar_readout_is_row_col_and_the_pixel_value(make_viewer):
    from matplotlib.backend_bases import NavigationToolbar2

    gray = np.zeros((40, 90))
    gray[30, 70] = 0.625
    viewer = make_viewer(gray)
    assert viewer.ax_image.format_coord(70.2, 29.9) == "row 29.9, col 70.2  value 0.625"
    x, y = _display(viewer.ax_image, 70.0, 30.0)
    event = MouseEvent("motion_notify_event", viewer.fig.canvas, x, y)
    message = NavigationToolbar2._mouse_event_to_message(event)
    assert message.startswith("row 30.0, col 70.0") and message.endswith("value 0.625")
    assert "\n" not in message  # the image's own [value] line would repeat it unlabelled
    assert "value" not in viewer.ax_image.format_coord(95.0, 10.0)  # beyond the last column
    colour = np.zeros((20, 30, 3), np.uint8)
    colour[5, 25] = (255, 128, 7)
    assert make_viewer(colour).ax_image.format_coord(25.0, 5.0).endswith("value (255, 128, 7)")


def test_save_defaults_next_to_the_input_not_the_working_directory(disk_image, make_viewer,
                                                                    tmp_path, monkeypatch):
    image, _ = disk_image
    (tmp_path / "images").mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _write_png(tmp_path / "images" / "disk.png", image)
    monkeypatch.chdir(tmp_path)
    viewer = make_viewer(ac.load_image("images/disk.png"), image_path="images/disk.png")
    monkeypatch.chdir(elsewhere)  # the working directory moves on; the input's folder stays
    key(viewer, " ")
    assert viewer.save_box.text == "disk"
    paths = viewer.save()
    assert {p.parent for p in paths} == {tmp_path / "images"}
    assert (tmp_path / "images" / "disk_mask.png").exists() and list(elsewhere.iterdir()) == []
    viewer.save_box.set_val("second")
    viewer.save()
    assert (tmp_path / "images" / "second_mask.png").exists()
    viewer.save_box.set_val(str(elsewhere / "third"))  # an absolute stem is taken as it is
    viewer.save()
    assert (elsewhere / "third_mask.png").exists()


# ---------------------------------------------------------------------------------------- layout
def _text_boxes(viewer):
    """(text, owner axes or None, window extent) of every text drawn on the viewer's figure,
    except the contents of the text fields (clipped to their field by design)."""
    fig, shown = viewer.fig, []
    field_texts = {box.text_disp for box in viewer.layout.text_boxes}

    def add(text, owner):
        if text.get_visible() and text.get_text().strip() and text not in field_texts:
            shown.append((text, owner, text.get_window_extent()))

    for text in fig.texts:
        add(text, None)
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        for axis in (ax.xaxis, ax.yaxis):
            low, high = sorted(axis.get_view_interval())
            margin = 1e-9 * max(1.0, high - low)
            for tick in axis.get_major_ticks():  # only the ticks in the view are drawn
                if tick.get_visible() and low - margin <= tick.get_loc() <= high + margin:
                    add(tick.label1, ax)
                    add(tick.label2, ax)
            add(axis.label, ax)
            add(axis.get_offset_text(), ax)
        for text in (ax.title, *ax.texts):
            add(text, ax)
    return shown


def _area(a, b):
    width = min(a.x1, b.x1) - max(a.x0, b.x0)
    height = min(a.y1, b.y1) - max(a.y0, b.y0)
    return width * height if width > 0.5 and height > 0.5 else 0.0


# 900 x 550 is a 900 x 600 window less the toolbar of TkAgg
@pytest.mark.parametrize("size", [(9.0, 6.0), (9.0, 5.5), DEFAULT_SIZE, (16.0, 9.0)])
def test_no_text_overlaps_another_or_leaves_the_window(make_viewer, tmp_path, size):
    image, _ = synthetic.equal_gray_colour()
    viewer = make_viewer(image, color="vector", image_path=tmp_path / "a_long_file_name_for_x.png")
    resize(viewer, size)
    key(viewer, " ")
    viewer.set_init_mode("polygon")  # the longest status hint
    viewer.fig.canvas.draw()
    figure = viewer.fig.bbox
    texts = _text_boxes(viewer)
    assert len(texts) > 40  # tick labels, labels, readouts, widgets
    every_axes = [a for a in viewer.fig.axes if a.get_visible()]
    for i, (text, owner, box) in enumerate(texts):
        label = repr(text.get_text()[:30])
        assert box.x0 >= figure.x0 - 0.5 and box.x1 <= figure.x1 + 0.5, f"{label} leaves the window"
        assert box.y0 >= figure.y0 - 0.5 and box.y1 <= figure.y1 + 0.5, f"{label} leaves the window"
        for other, _, other_box in texts[i + 1:]:
            assert _area(box, other_box) == 0.0, f"{label} overlaps {other.get_text()[:30]!r}"
        for ax in every_axes:
            if ax is not owner:
                assert _area(box, ax.get_window_extent()) == 0.0, f"{label} overlaps an axes"
    # a button's label stays inside its button
    for button in viewer.layout.buttons:
        inner, outer = button.label.get_window_extent(), button.ax.get_window_extent()
        assert outer.x0 < inner.x0 and inner.x1 < outer.x1, button.label.get_text()
    # a field's text stays in its field (clipped), showing the end of a long one
    viewer.image_box.set_val(str(tmp_path / "folder" / ("a_long_name_" * 8 + "end.png")))
    viewer.fig.canvas.draw()
    for box in viewer.layout.text_boxes:
        field, shown = box.ax.get_window_extent(), box.text_disp.get_window_extent()
        assert box.text_disp.get_clip_on() and box.text_disp.get_clip_box() is box.ax.bbox
        assert field.x0 < shown.x1 < field.x1, box.text
    shot = tmp_path / f"viewer_{int(size[0] * 100)}x{int(size[1] * 100)}.png"
    viewer.fig.savefig(shot)
    assert plt.imread(shot).shape[:2] == (round(size[1] * 100), round(size[0] * 100))


def test_a_long_status_line_is_fitted_into_the_window(disk_image, make_viewer, tmp_path):
    image, _ = disk_image
    viewer = make_viewer(image)
    resize(viewer, (9.0, 6.0))
    long_path = tmp_path / ("x" * 300 + ".png")
    viewer.open_image(long_path)
    assert str(long_path.name) in viewer.message  # the whole message is kept
    box = viewer.status_text.get_window_extent()
    assert box.x1 <= viewer.fig.bbox.x1
    assert viewer.status_text.get_text().endswith("\N{HORIZONTAL ELLIPSIS}")


def test_automatic_mu_follows_the_image_until_the_slider_is_moved(disk_image, make_viewer,
                                                                 tmp_path):
    noisy = tmp_path / "noisy.png"
    clean = tmp_path / "clean.png"
    first = _write_png(noisy, np.clip(disk_image[0], 0, 1))
    second = _write_png(clean, disk_image[1] * 0.8 + 0.1)
    viewer = make_viewer(first, image_path=noisy, max_num_iter=1)
    mu = viewer.sliders["mu"]
    assert viewer.slider_labels["mu"].get_text() == "smoothness (auto)"
    assert mu.val == pytest.approx(ac.segment(first, max_num_iter=0).mu)
    viewer.open_image(clean)
    assert mu.val == pytest.approx(ac.segment(second, max_num_iter=0).mu)
    assert ac.segment(second, max_num_iter=0).mu != ac.segment(first, max_num_iter=0).mu
    set_slider(viewer, mu, 1.5)
    assert viewer.slider_labels["mu"].get_text() == "smoothness"
    viewer.open_image(noisy)
    assert viewer.parameters()["mu"] == pytest.approx(1.5, abs=1e-9)  # the user's value stays


def test_automatic_mu_shows_the_weight_a_backed_off_run_took(make_viewer):
    # touching ellipses at twice the pixel size: the default weight leaves no object, and the
    # library runs again at MU_BACKOFF of it; the slider, still automatic, shows that weight
    from activecontour import synthetic
    from activecontour.imaging.noise import MU_BACKOFF

    image, _ = synthetic.touching_ellipses(13, pixel=2.0)
    viewer = make_viewer(image, separate=False)
    mu = viewer.sliders["mu"]
    default = mu.val
    click_axes(viewer, viewer.run_button.ax)
    assert mu.val == pytest.approx(MU_BACKOFF * default)
    assert viewer.slider_labels["mu"].get_text() == "smoothness (auto)"
    assert viewer.parameters()["mu"] == "auto"


def test_the_shown_start_follows_mu_as_the_librarys_does(coins_image, make_viewer):
    image, _ = coins_image
    viewer = make_viewer(image)
    mu = viewer.sliders["mu"]
    before = ac.segment(image, max_num_iter=0, mu=mu.val).contours
    assert_same_contours(viewer.init_curves, before)
    set_slider(viewer, mu, 1.0)  # press and release on the slider
    after = ac.segment(image, max_num_iter=0, mu=viewer.parameters()["mu"]).contours
    assert len(after) != len(before)  # on this image the start depends on mu
    assert_same_contours(viewer.init_curves, after)


def test_the_mu_slider_is_logarithmic_and_the_default_sits_inside_it(disk_image, make_viewer):
    viewer = make_viewer(disk_image[0])
    mu = viewer.sliders["mu"]
    assert mu.ax.get_xscale() == "log"
    # the automatic mu (~0.01-0.5) sits well inside, not at the far left of a linear 0..5 scale
    position = (np.log(mu.val) - np.log(mu.valmin)) / (np.log(mu.valmax) - np.log(mu.valmin))
    assert 0.2 < position < 0.9
    for value in (0.003, 0.05, 2.0):  # a click anywhere gives the value under the pointer
        set_slider(viewer, mu, value)
        assert viewer.parameters()["mu"] == pytest.approx(value, rel=1e-6)


def test_drawing_around_one_blob_among_many_gives_that_blob(make_viewer):
    # the viewer's main use: draw around one object, run, get that object (segment's roi="init")
    centers = [(25 + 35 * i, 25 + 35 * j) for i in range(3) for j in range(3)]
    image, _ = synthetic.render(synthetic.union(*[synthetic.disk(c, 11.0) for c in centers]), SIZE)
    image = synthetic.add_noise(image, 0.1, seed=3)
    target = synthetic.render(synthetic.disk(centers[4], 11.0), SIZE)[1]
    others = synthetic.render(synthetic.union(*[synthetic.disk(c, 11.0) for i, c in enumerate(centers)
                                                if i != 4]), SIZE)[1]
    viewer = make_viewer(image)
    drag(viewer, centers[4], (centers[4][0] + 17.0, centers[4][1]))
    key(viewer, " ")
    assert viewer.result is not None and viewer.result.labels.max() == 1
    assert synthetic.dice(viewer.result.mask, target) >= 0.97
    assert not (viewer.result.mask & others).any()


def test_the_contour_stands_out_from_a_red_image_on_screen_too(make_viewer):
    import matplotlib.colors

    red_image = np.zeros((48, 64, 3))
    red_image[..., 0] = 0.8
    red_image[10:30, 20:40, 0] = 0.4  # a darker red square
    viewer = make_viewer(red_image)
    shown = matplotlib.colors.to_rgb(viewer.contour_lines.get_color()[0])
    assert shown != viewer_module.CONTOUR_COLOR  # red would vanish on red
    assert np.linalg.norm(np.subtract(shown, (0.8, 0, 0))) > 0.9


def test_step_sliders_start_at_the_options_dataclass_defaults(disk_image, make_viewer):
    # the slider of each backend is an option of its dataclass, starting at that field's default
    from activecontour.backends import BACKENDS
    from activecontour.backends.polygon import PolygonOptions
    from app.viewer.layout import STEP_OPTIONS

    viewer = make_viewer(disk_image[0])
    assert set(viewer.step_sliders) == set(BACKENDS)
    assert viewer.step_sliders["polygon"].val == PolygonOptions().max_step
    for name, backend in BACKENDS.items():
        option = STEP_OPTIONS[name][0]
        assert viewer.step_sliders[name].val == getattr(backend.options(), option)


def test_a_new_backend_brings_its_step_slider_from_its_options(monkeypatch):
    # a backend added to the registry gets the slider of its first number option with typical
    # values, with that range; one without such an option gets none (the app names no backend)
    import dataclasses

    from activecontour import backends
    from activecontour.backends.options import option
    from app.viewer import layout

    @dataclasses.dataclass(frozen=True)
    class TunedOptions:
        label: str = option("a", "text", choices=("a", "b"))
        rate: float = option(0.5, "a number worth tuning", typical=(0.1, 2.0))
        other: float = option(3.0, "a second one", typical=(1.0, 9.0))

    @dataclasses.dataclass(frozen=True)
    class PlainOptions:
        rate: float = option(0.5, "no typical values")

    added = {"tuned": dataclasses.replace(backends.BACKENDS["polygon"], name="tuned", backend="tuned",
                                          options=TunedOptions),
             "plain": dataclasses.replace(backends.BACKENDS["polygon"], name="plain", backend="plain",
                                          options=PlainOptions)}
    monkeypatch.setattr(layout, "BACKENDS", {**backends.BACKENDS, **added})
    steps = layout._step_options()
    assert steps["tuned"][0] == "rate" and steps["tuned"][2:] == (0.1, 2.0)
    assert "plain" not in steps
    assert steps["polygon"][0] == "max_step" and steps["levelset"][0] == "dt"


# ------------------------------------------------------------------ objects you can see (issue 23, 5)
@pytest.fixture(scope="module")
def touching_image():
    """Three disks, the first two touching (their centres 1.8 radii apart), the third apart."""
    disks = [synthetic.disk((40.0, 40.0), 16.0), synthetic.disk((40.0, 68.8), 16.0),
             synthetic.disk((96.0, 90.0), 14.0)]
    clean, _ = synthetic.render(synthetic.union(*disks), SIZE)
    truths = [synthetic.render(d, SIZE)[1] for d in disks]
    return synthetic.add_noise(clean, 0.1, seed=6), truths


def test_each_object_is_drawn_in_its_own_colour_and_counted(touching_image, make_viewer):
    image, truths = touching_image
    viewer = make_viewer(image)
    key(viewer, " ")
    res = viewer.result
    assert res.labels.max() == len(truths) == 3  # the touching pair split apart
    # every object's outline in its colour, and the two touching objects' colours differ
    first, second = (int(np.bincount(res.labels[t]).argmax()) for t in truths[:2])
    assert first and second and first != second
    wanted = object_colors(res.labels, 3)
    assert wanted[first - 1] != wanted[second - 1]
    drawn = [tuple(np.round(c[:3], 6)) for c in viewer.contour_lines.get_colors()]
    expected = [tuple(np.round(OBJECT_COLORS[wanted[k]], 6)) for k, curves in enumerate(res.object_contours)
                for _ in curves]
    assert drawn == expected and len(set(drawn)) == 3
    assert "3 objects" in viewer.readout.get_text() and "3 objects" in viewer.message


def test_object_colours_differ_wherever_objects_touch():
    """Ids 1..n (n colours) in a row of blocks apart, id n + 1 under id 1: it would cycle back to
    id 1's colour, which it touches, so it takes the first one free; the others keep their own."""
    n = len(OBJECT_COLORS)
    labels = np.zeros((12, 6 * n), np.int32)
    for k in range(n):
        labels[1:5, 6 * k + 1:6 * k + 5] = k + 1
    labels[5:9, 1:5] = n + 1  # touches id 1 only
    colors = object_colors(labels, n + 1)
    assert colors[:n] == list(range(n)) and colors[n] != colors[0]
    assert colors[n] == 1  # the first colour id 1 (its only neighbour) has not taken
    labels[5:9, 1:5] = 0
    labels[7:11, 1:5] = n + 1  # now apart: the next colour round, as every object apart
    assert object_colors(labels, n + 1)[n] == 0


@pytest.mark.parametrize("button", [1, 3])
def test_a_click_on_an_object_shows_its_measurements(touching_image, make_viewer, button):
    image, truths = touching_image
    viewer = make_viewer(image)
    key(viewer, " ")
    res = viewer.result
    label = int(res.labels[96, 90])
    mouse(viewer, "button_press_event", 96, 90, button=button)
    mouse(viewer, "button_release_event", 96, 90, button=button)
    assert viewer.selected == label and viewer.result is res and viewer.init_curves  # no new curve drawn
    row = list(res.objects["label"]).index(label)
    area = res.objects["area"][row]
    assert abs(area - truths[2].sum()) < 0.05 * truths[2].sum()
    assert f"object {label} of 3" in viewer.message and f"area {area:.1f}" in viewer.message
    widths = viewer.contour_lines.get_linewidths()
    index = sum(len(curves) for curves in res.object_contours[:label - 1])
    assert widths[index] > max(np.delete(widths, index))  # the selected object is drawn wider
    mouse(viewer, "button_press_event", 5, 5, button=button)  # the background: nothing to show
    mouse(viewer, "button_release_event", 5, 5, button=button)
    assert viewer.selected == label


def test_controls_speak_a_users_words_and_the_help_gives_the_books(make_viewer, disk_image):
    viewer = make_viewer(disk_image[0])
    words = [t.get_text() for t in viewer.slider_labels.values()] + [viewer.ax_energy.get_title()]
    symbols = ("mu", "omega", "lambda", "c_in", "c_out", "(6.")
    assert not [w for w in words if any(s in w for s in symbols)], words
    assert not any(s in viewer.readout.get_text() for s in ("c_in", "c_out"))
    key(viewer, "h")
    panel = viewer.layout.help_panel
    assert panel.get_visible()
    help_text = panel.get_text()
    for word, symbol in (("smoothness", "mu"), ("object fit", "lambda_in"), ("background fit", "lambda_out"),
                         ("object brightness", "c_in"), ("energy", "(6.38)")):
        entry = next(e for e in re.split(r"\n(?=\S)", help_text) if e.startswith(word + ":"))
        assert symbol in entry, (word, entry)
    key(viewer, "h")
    assert not panel.get_visible()
