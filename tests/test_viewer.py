"""The interactive viewer, driven headless: Agg canvas, events sent through the figure canvas.

Mouse and key events are built as matplotlib builds them from a GUI toolkit (``MouseEvent``,
``KeyEvent``, ``CloseEvent``) and processed by the canvas, at display positions computed from the
axes' transforms.  Events "during a run" are sent from a ``draw_event`` handler of a canvas made to
behave like a GUI's (:func:`gui_like`): the viewer redraws and processes events from inside the
library's callback, which is where a GUI delivers them.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backend_bases import CloseEvent, KeyEvent, MouseEvent  # noqa: E402

import activecontour as ac  # noqa: E402
from activecontour import synthetic  # noqa: E402
from activecontour.curve import length, signed_area  # noqa: E402
from activecontour.io import read_contours, read_mask, write_mask  # noqa: E402
from activecontour.raster import mask_to_curves  # noqa: E402
from app import viewer as viewer_module  # noqa: E402
from app.viewer import SHORTCUTS, Viewer, launch  # noqa: E402

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
    expected = ac.segment(image, viewer.init_curves)  # the viewer starts at the library's defaults
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
    expected = ac.segment(image, viewer.init_curves, mu=viewer.parameters()["mu"])
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
    first = ac.segment(image, viewer.init_curves, max_num_iter=1)
    assert viewer.iteration == 1
    assert_same_contours(viewer.contours, first.contours)
    click_axes(viewer, viewer.step_button.ax)
    second = ac.segment(image, first.contours, max_num_iter=1)
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
    for name in "s ":  # save, run
        key(viewer, name)
    assert viewer.save_box.text == "s " and viewer.result is None
    assert "saved" not in viewer.message
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
        from activecontour.levelset import DEFAULT_OPTIONS
    except ImportError:
        assert viewer.result is None and "run failed" in viewer.message
        return
    assert viewer.parameters()["options"] == {"dt": DEFAULT_OPTIONS["dt"]}  # the step slider
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
    contour_rgb = np.array(viewer_module.CONTOUR_COLOR)

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
    assert "not found" in capsys.readouterr().err
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
    with pytest.raises(ValueError, match="max_num_iter must be an integer"):
        Viewer(image, max_num_iter=0)
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
