"""The viewer's models, driven headless: key k (the number of regions), key l (the light fit), each
region's boundary in its own colour, and the view command passing --regions and --fit."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.colors as mcolors  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import activecontour as ac  # noqa: E402
from activecontour.io.pictures import REGION_COLORS  # noqa: E402
from app.viewer import REGION_CHOICES  # noqa: E402
from app.viewer.display import OBJECT_COLORS, object_colors  # noqa: E402
from tests.app import test_viewer  # noqa: E402
from tests.app.test_viewer import drag, key  # noqa: E402

# the viewer tests' fixtures: a headless viewer, closed afterwards; launch's viewers recorded
make_viewer, headless_launch = test_viewer.make_viewer, test_viewer.headless_launch


@pytest.fixture(scope="module")
def rings():
    """Three nested classes (levels 0, 0.5, 1) at SNR 3, and the true classes."""
    m = 96
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - 48, cols - 48)
    truth = (radius < 38).astype(int) + (radius < 20)
    return truth / 2.0 + np.random.default_rng(40).normal(0, 0.5 / 3, truth.shape), truth


def _dice(found, truth, k):
    return 2 * np.sum((found == k) & (truth == k)) / (np.sum(found == k) + np.sum(truth == k))


def test_key_k_cycles_the_regions_and_a_run_draws_each_region_in_its_colour(rings, make_viewer):
    image, truth = rings
    viewer = make_viewer(image)
    assert viewer.parameters()["n_regions"] == 2
    key(viewer, "k")
    assert viewer.parameters()["n_regions"] == 3 and "regions: 3" in viewer.message
    # more regions take no backend options (the registry's solver for K > 2): no step slider
    assert not viewer.step_sliders["polygon"].ax.get_visible() and viewer.parameters()["options"] is None
    key(viewer, " ")
    res = viewer.result
    assert res.n_regions == 3
    assert all(_dice(res.classes, truth, k) > 0.97 for k in range(3))
    # the run is the library's, from its start for three regions
    expected = ac.segment(image, n_regions=3, **{k: v for k, v in viewer.parameters().items()
                                                 if k != "n_regions"})
    assert np.array_equal(res.classes, expected.classes)
    # every curve of regions 1 and 2, in the first and second region colours
    segments = viewer.contour_lines.get_segments()
    colors = [mcolors.to_hex(c) for c in viewer.contour_lines.get_colors()]
    wanted = [mcolors.to_hex(REGION_COLORS[k - 1]) for k in (1, 2) for _ in res.class_contours[k]]
    assert len(segments) == len(wanted) and colors == wanted
    assert "regions 3" in viewer.readout.get_text()


def test_auto_regions_from_the_viewer(rings, make_viewer):
    image, _ = rings
    viewer = make_viewer(image)
    for _ in range(REGION_CHOICES.index("auto")):
        key(viewer, "k")
    assert viewer.parameters()["n_regions"] == "auto"
    key(viewer, " ")
    assert viewer.result.n_regions == 3
    assert "(auto: 3)" in viewer.readout.get_text()
    key(viewer, "k")  # and round again to two regions: the objects' colours, the drawn init applies again
    assert viewer.parameters()["n_regions"] == 2 and viewer.result is None
    drag(viewer, (48, 48), (48, 80))
    key(viewer, " ")
    res = viewer.result
    assert res.n_regions == 2
    colors = [mcolors.to_hex(c) for c in viewer.contour_lines.get_colors()]
    wanted = object_colors(res.labels, len(res.object_contours))
    assert colors == [mcolors.to_hex(OBJECT_COLORS[wanted[k]]) for k, curves in enumerate(res.object_contours)
                      for _ in curves]


def test_a_drawn_curve_is_no_start_for_more_regions(rings, make_viewer):
    image, truth = rings
    viewer = make_viewer(image)
    drag(viewer, (48, 48), (48, 60))  # a circle inside the disc: two regions' init
    key(viewer, "k")
    assert "global K-means" in viewer.message
    key(viewer, " ")
    assert viewer.result is not None and viewer.result.n_regions == 3
    assert all(_dice(viewer.result.classes, truth, k) > 0.97 for k in range(3))


def test_key_l_switches_the_light_fit(make_viewer):
    # a disc under a strong light gradient: the constant fit follows the light, the smooth one the disc
    rows, cols = np.mgrid[:96, :96]
    truth = np.hypot(rows - 48, cols - 40) < 20
    light = 0.4 + 1.2 * cols / 96
    image = (0.3 + 0.15 * truth) * light + np.random.default_rng(41).normal(0, 0.01, truth.shape)
    viewer = make_viewer(image)
    key(viewer, "l")
    assert viewer.parameters()["fit"] == "smooth" and "smooth light field" in viewer.message
    key(viewer, " ")
    smooth = viewer.result
    assert smooth.light is not None
    assert 2 * np.sum(smooth.mask & truth) / (smooth.mask.sum() + truth.sum()) > 0.95
    key(viewer, "l")
    assert viewer.parameters()["fit"] == "constant"


def test_view_command_passes_regions_and_fit(rings, tmp_path, headless_launch):
    import cv2

    from app import cli

    image, _ = rings
    path = tmp_path / "rings.png"
    cv2.imwrite(str(path), np.round(255 * (image - image.min()) / np.ptp(image)).astype(np.uint8))
    status = cli.main(["view", str(path), "--regions", "auto", "--fit", "smooth"])
    assert status == 1  # Agg cannot open a window: the viewer was built, then refused to show
    (viewer,) = headless_launch
    assert viewer.parameters()["n_regions"] == "auto" and viewer.parameters()["fit"] == "smooth"


def test_save_writes_the_classes_image_as_the_command_line_does(rings, make_viewer, tmp_path):
    from activecontour.io.objects import read_label_image

    image, _ = rings
    viewer = make_viewer(image)
    key(viewer, "k")
    key(viewer, " ")
    paths = viewer.save(tmp_path / "rings")
    assert sorted(p.name for p in paths) == ["rings_classes.png", "rings_contours.json", "rings_mask.png",
                                             "rings_overlay.png"]
    assert np.array_equal(read_label_image(tmp_path / "rings_classes.png"), viewer.result.classes)


def test_a_label_field_run_is_drawn_while_it_runs(rings, make_viewer):
    from tests.app.test_viewer import during_run, gui_like

    image, _ = rings
    viewer = gui_like(make_viewer(image, backend="levelset", redraw_every=1))
    key(viewer, "k")
    shown = []
    during_run(viewer, lambda: shown.append(len(viewer.contour_lines.get_segments())), at_iteration=1)
    key(viewer, " ")
    # the label field sends no contours, only the inside's indicator: its outline is drawn
    assert shown and shown[0] > 0
    assert viewer.result.n_regions == 3
