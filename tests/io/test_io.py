"""Writers and readers: masks, overlays, contour files, and the all-or-nothing group write."""

import json
import os
import xml.etree.ElementTree as ElementTree

import cv2
import numpy as np
import pytest

import activecontour as ac
from activecontour import io
from activecontour.geometry.curve import orient, signed_area
from activecontour.geometry.raster import rasterize
from activecontour.io.pictures import render_overlay
from activecontour.result import SegmentationResult

SHAPE = (60, 80)


def shoelace_xy(ring):
    """Signed area of a ring of (x, y) positions (closing position allowed), counterclockwise > 0."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


@pytest.fixture
def curves():
    """An island first, then a hole, then the outer boundary containing that hole: not grouped."""
    rng = np.random.default_rng(3)
    outer = ac.circle((25.3, 30.7), 18.2, n=29) + rng.normal(0, 0.1, (29, 2))
    hole = orient(ac.circle((25.1, 31.2), 6.3, n=13), hole=True)
    island = ac.circle((48.7, 65.1), 7.9, n=17)
    return [island, hole, outer]


@pytest.fixture
def result(curves):
    return SegmentationResult(
        mask=rasterize(curves, SHAPE), contours=curves, c_in=0.8125, c_out=np.float64(0.1875),
        energy=12.5, energies=[14.0, 12.5], n_iter=7, status=0, backend="polygon",
    )


@pytest.mark.parametrize("fmt", io.CONTOUR_FORMATS)
def test_contours_round_trip_exactly_in_order(tmp_path, curves, result, fmt):
    path = io.write_contours(tmp_path / f"c.{fmt}", result, metadata={"image": "x.png"})
    back = io.read_contours(path)
    assert len(back) == len(curves)
    for written, read in zip(curves, back, strict=True):
        assert read.dtype == np.float64 and read.shape == written.shape
        assert np.array_equal(read, written)
    meta = io.read_metadata(path)
    assert meta["image_shape"] == list(SHAPE)
    assert meta["c_in"] == 0.8125 and meta["c_out"] == 0.1875
    assert meta["n_iter"] == 7 and meta["energy"] == 12.5 and meta["backend"] == "polygon"
    assert meta["image"] == "x.png"


@pytest.mark.parametrize("fmt", io.CONTOUR_FORMATS)
def test_a_list_of_curves_and_an_empty_list_round_trip(tmp_path, curves, fmt):
    path = io.write_contours(tmp_path / f"c.{fmt}", curves[:1], image_shape=SHAPE)
    assert np.array_equal(io.read_contours(path)[0], curves[0])
    empty = io.write_contours(tmp_path / f"e.{fmt}", [], image_shape=SHAPE)
    assert io.read_contours(empty) == []


def test_a_repeated_closing_vertex_is_stored_once(tmp_path, curves):
    closed = np.vstack([curves[0], curves[0][:1]])
    path = io.write_contours(tmp_path / "c.json", [closed])
    assert np.array_equal(io.read_contours(path)[0], curves[0])


def test_vector_constants_are_stored_per_channel(tmp_path, result):
    result.c_in = np.array([0.25, 0.5, 0.75])
    meta = io.read_metadata(io.write_contours(tmp_path / "c.json", result))
    assert meta["c_in"] == [0.25, 0.5, 0.75]


def test_geojson_is_image_xy_closed_right_hand_rule_and_groups_holes(tmp_path, curves, result):
    island, hole, outer = curves
    path = io.write_contours(tmp_path / "c.geojson", result)
    document = json.loads(path.read_text())
    geometry = document["features"][0]["geometry"]
    assert geometry["type"] == "MultiPolygon"
    polygons = [[np.array(ring) for ring in polygon] for polygon in geometry["coordinates"]]
    by_size = sorted(polygons, key=len)
    assert [len(p) for p in by_size] == [1, 2]  # the island alone; the outer ring with its hole
    for polygon in polygons:
        for k, ring in enumerate(polygon):
            assert np.array_equal(ring[0], ring[-1])  # closed, RFC 7946
            assert (shoelace_xy(ring) > 0) == (k == 0)  # outer counterclockwise in (x, y)
    # x = col, y = row: the same vertex set as the (row, col) curves, swapped
    for ring, curve in ((by_size[0][0], island), (by_size[1][0], outer), (by_size[1][1], hole)):
        assert sorted(map(tuple, ring[:-1])) == sorted(zip(curve[:, 1], curve[:, 0], strict=True))


def test_geojson_from_elsewhere_is_oriented_on_reading(tmp_path):
    # a Polygon written by another tool with the opposite winding and no contour_index
    outer = [[0.0, 0.0], [0.0, 10.0], [10.0, 10.0], [10.0, 0.0], [0.0, 0.0]]  # (x, y) clockwise
    hole = [[2.0, 2.0], [5.0, 2.0], [5.0, 5.0], [2.0, 5.0], [2.0, 2.0]]
    geometry = {"type": "Polygon", "coordinates": [outer, hole]}
    path = tmp_path / "other.geojson"
    path.write_text(json.dumps({"type": "Feature", "properties": {}, "geometry": geometry}))
    read_outer, read_hole = io.read_contours(path)
    assert signed_area(read_outer) == pytest.approx(100.0)
    assert signed_area(read_hole) == pytest.approx(-9.0)
    assert sorted(map(tuple, read_outer)) == sorted((y, x) for x, y in outer[:-1])


def test_svg_has_the_image_size_and_one_nonzero_path_per_outer_ring(tmp_path, result):
    path = io.write_contours(tmp_path / "c.svg", result)
    root = ElementTree.parse(path).getroot()
    assert (root.get("width"), root.get("height")) == (str(SHAPE[1]), str(SHAPE[0]))
    paths = root.findall("{http://www.w3.org/2000/svg}path")
    assert len(paths) == 2
    assert all(p.get("fill-rule") == "nonzero" for p in paths)
    assert sorted(p.get("d").count("M") for p in paths) == [1, 2]


@pytest.mark.parametrize("dtype", [bool, np.uint8, np.float32])
def test_mask_png_is_0_255_and_reads_back(tmp_path, dtype):
    mask = rasterize([ac.circle((20.0, 30.0), 11.5)], (40, 50))
    path = io.write_mask(tmp_path / "m.png", mask.astype(dtype))
    stored = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert stored.dtype == np.uint8 and stored.shape == mask.shape
    assert set(np.unique(stored)) == {0, 255}
    assert np.array_equal(io.read_mask(path), mask)


def test_read_mask_of_colour_images_is_nonzero_in_any_channel(tmp_path):
    rgba = np.zeros((10, 12, 4), np.uint8)
    rgba[..., 3] = 255  # opaque everywhere: the alpha channel does not count
    rgba[2, 3, 1] = 7
    rgba[5, 6, 2] = 200
    cv2.imwrite(str(tmp_path / "m.png"), rgba)
    expected = np.zeros((10, 12), bool)
    expected[2, 3] = expected[5, 6] = True
    assert np.array_equal(io.read_mask(tmp_path / "m.png"), expected)


def test_read_mask_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        io.read_mask(tmp_path / "missing.png")
    (tmp_path / "text.png").write_text("not an image")
    with pytest.raises(ValueError, match="cannot read image"):
        io.read_mask(tmp_path / "text.png")


def test_overlay_draws_the_colour_on_the_circle_and_nothing_elsewhere(tmp_path):
    center, radius = np.array([31.5, 30.25]), 20.0
    image = np.zeros((64, 64), np.uint8)
    path = io.write_overlay(tmp_path / "o.png", image, [ac.circle(center, radius, n=256)],
                            color=(0, 255, 0))
    rgb = cv2.imread(str(path), cv2.IMREAD_COLOR)[:, :, ::-1]
    assert rgb.shape == (64, 64, 3)
    angles = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    on_circle = np.round(center + radius * np.column_stack([np.cos(angles), np.sin(angles)]))
    for row, col in on_circle.astype(int):
        assert rgb[row, col, 1] >= 100  # the pixel nearest the curve is mostly green
        assert rgb[row, col, 0] == 0 and rgb[row, col, 2] == 0
    rows, cols = np.mgrid[:64, :64]
    far = np.abs(np.hypot(rows - center[0], cols - center[1]) - radius) > 2.5
    assert not rgb[far].any()


def test_overlay_background_is_normalised_like_the_library(tmp_path):
    image = np.full((16, 16), 32768, np.uint16)  # half of the uint16 range
    rgb = cv2.imread(str(io.write_overlay(tmp_path / "o.png", image, [])), cv2.IMREAD_COLOR)
    assert np.all(rgb == round(32768 / 65535 * 255))


def test_8_bit_images_are_displayed_as_their_float_values(tmp_path):
    # display_rgb maps an 8-bit image through a table of its levels: the same bytes as the float
    # values dtype normalisation gives (a hot pixel stretches by the percentiles, not the range)
    rng = np.random.default_rng(4)
    gray = rng.integers(40, 200, size=(300, 200), dtype=np.uint8)
    gray[7, 9] = 255
    for image in (gray, np.dstack([gray, gray[::-1], gray[:, ::-1]])):
        shown = io.display_rgb(image)
        assert shown.dtype == np.uint8 and shown.shape == (300, 200, 3)
        assert shown.tobytes() == io.display_rgb(image / 255.0).tobytes()
    assert shown[..., 0].max() == 255 and shown[..., 0].min() == 0
    mask = gray > 128
    assert io.read_mask(io.write_mask(tmp_path / "m.png", mask)).tobytes() == mask.tobytes()


def test_overlay_keeps_the_colours_of_an_rgb_image(tmp_path):
    image = np.empty((20, 24, 3), np.uint8)
    image[...] = (10, 120, 250)
    path = io.write_overlay(tmp_path / "o.png", image, [ac.circle((9.5, 11.5), 5.0)], color="red")
    rgb = cv2.imread(str(path), cv2.IMREAD_COLOR)[:, :, ::-1]
    assert tuple(rgb[0, 0]) == (10, 120, 250) and tuple(rgb[9, 11]) == (10, 120, 250)
    assert rgb[9, 16, 0] > 128 and rgb[9, 16, 2] < 250  # (9, 16) is on the circle: reddened


def test_save_result_writes_the_group(tmp_path, result):
    image = np.zeros(SHAPE)
    paths = io.save_result(result, image, tmp_path / "img", ["json", "csv"])
    names = [p.name for p in paths]
    assert names == ["img_mask.png", "img_overlay.png", "img_contours.json", "img_contours.csv"]
    assert sorted(os.listdir(tmp_path)) == sorted(names)  # no temporary file left
    assert np.array_equal(io.read_mask(paths[0]), result.mask)


def test_save_result_is_all_or_nothing(tmp_path, result, no_space_for_contours):
    old_mask = tmp_path / "img_mask.png"
    old_mask.write_bytes(b"previous run")
    with pytest.raises(OSError, match="No space"):
        io.save_result(result, np.zeros(SHAPE), tmp_path / "img", ["json"])
    assert sorted(os.listdir(tmp_path)) == ["img_mask.png"]
    assert old_mask.read_bytes() == b"previous run"


def test_save_result_never_overwrites_a_protected_file(tmp_path, result):
    source = tmp_path / "img_mask.png"
    source.write_bytes(b"the input")
    with pytest.raises(ValueError, match="overwrite"):
        io.save_result(result, np.zeros(SHAPE), tmp_path / "img", protect=[source])
    assert source.read_bytes() == b"the input"
    assert os.listdir(tmp_path) == ["img_mask.png"]


def test_save_result_rejects_an_image_of_another_shape(tmp_path, result):
    with pytest.raises(ValueError, match="shape"):
        io.save_result(result, np.zeros((5, 5)), tmp_path / "img")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("channels, shape", [(2, (40, 50)), (3, (40, 50)), (4, (40, 50)), (3, (40, 3))])
def test_save_result_takes_the_channel_first_image_segment_took(tmp_path, channels, shape):
    """segment(image, channel_axis=0) reads a (C, M, N) image; save_result writes it (the overlay
    from the same pixels as the channel-last image's), where it refused 2 channels or a side of 3."""
    image = np.zeros((channels, *shape))
    image[:, 10:30, 1:2] = 1.0
    result = ac.segment(image, channel_axis=0)
    first = io.save_result(result, image, tmp_path / "first")
    last = io.save_result(result, np.moveaxis(image, 0, -1), tmp_path / "last")
    assert [p.name for p in first] == [p.name.replace("last", "first") for p in last]
    for a, b in zip(first, last, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name


@pytest.mark.parametrize(
    "contours, name, match",
    [
        ([np.array([[0.0, 0.0], [1.0, np.nan], [2.0, 0.0]])], "c.json", "NaN"),
        ([np.zeros((4, 3))], "c.json", r"shape \(K, 2\)"),
        ([np.zeros((2, 2))], "c.json", "at least 3"),
        ([ac.circle((5.0, 5.0), 3.0)], "c.txt", "must end in"),
        ([orient(ac.circle((5.0, 5.0), 3.0), hole=True)], "c.geojson", "inside no outer"),
    ],
)
def test_write_contours_rejects_bad_input_and_writes_nothing(tmp_path, contours, name, match):
    with pytest.raises(ValueError, match=match):
        io.write_contours(tmp_path / name, contours)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name, text", [("c.json", "{not json"), ("c.csv", "a,b\n1,2\n"),
                                        ("c.npz", "not a zip"), ("c.svg", "<svg")])
def test_read_contours_rejects_invalid_files(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    with pytest.raises(ValueError, match="not a valid"):
        io.read_contours(tmp_path / name)


def test_read_contours_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        io.read_contours(tmp_path / "missing.json")


def test_svg_coordinates_are_x_col_y_row(tmp_path):
    curve = ac.circle((10.25, 20.5), 4.0, n=8)  # first vertex (row, col) = (14.25, 20.5)
    path = io.write_contours(tmp_path / "c.svg", [curve], image_shape=(30, 40))
    d = ElementTree.parse(path).getroot().find("{http://www.w3.org/2000/svg}path").get("d")
    x, y = (float(v) for v in d.split()[1].split(","))
    assert (x, y) == (20.5, 14.25)


def test_a_large_overlay_is_shrunk_with_its_contours():
    image = np.full((600, 400), 0.5)
    circle = ac.circle((299.5, 199.5), 100.0)
    rgb = render_overlay(image, [circle], color="red", max_side=300)
    assert rgb.shape == (300, 200, 3)
    red = (rgb[:, :, 0] > 200) & (rgb[:, :, 1] < 100)
    rows, cols = np.nonzero(red)
    # pixel centres map by x' = (x + 1/2) / 2 - 1/2: the circle lands at (149.5, 99.5), radius 50
    radius = np.hypot(rows - 149.5, cols - 99.5)
    assert red.sum() > 2 * np.pi * 50 * 0.8 and np.all(np.abs(radius - 50.0) < 1.5)
    assert rgb[150, 100, 0] == rgb[150, 100, 1] == 128  # the gray image, shrunk, unchanged
    full = render_overlay(image, [circle], color="red")
    assert full.shape == (600, 400, 3)


@pytest.mark.parametrize("name, stem", [
    ("x.png", "x"), ("my image.tif", "my image"), ("a.b.png", "a.b"),
    ("..png", "__png"), ("...png", "___png"), (".hidden.png", "_hidden"), (".hidden", "_hidden"),
    ("a/../../x.png", "x"), ("../..", "__"), ("", "image"), ("new\nline.png", "new_line"),
    ("\x1b[31mred.png", "_[31mred"), ("back\\slash.png", "slash"),
])
def test_output_stem_stays_in_the_folder_whatever_the_name(tmp_path, name, stem):
    path = io.output_stem(tmp_path / "out", name)
    assert path == tmp_path / "out" / stem
    for output in io.output_paths(path, io.CONTOUR_FORMATS):
        assert output.parent == tmp_path / "out" and not output.name.startswith(".")
        assert os.path.realpath(output).startswith(os.path.realpath(tmp_path / "out") + os.sep)


def test_sweep_removes_only_orphaned_temporaries(tmp_path):
    import subprocess
    import sys

    from activecontour.io import atomic

    io.save_result(ac.segment(np.pad(np.ones((8, 8)), 8)), np.pad(np.ones((8, 8)), 8), tmp_path / "a")
    assert not list(tmp_path.glob(".*"))  # a finished write leaves no temporary
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    orphan = tmp_path / f".a_mask.png.{dead}-{atomic._host()}.x1y2z3w4.part"
    mine = tmp_path / f".a_mask.png.{os.getpid()}-{atomic._host()}.x1y2z3w4.part"
    elsewhere = tmp_path / f".a_mask.png.{dead}-00000000.x1y2z3w4.part"  # another machine's
    old = tmp_path / f".a_mask.png.{dead}-00000000.q1y2z3w4.part"
    for path in (orphan, mine, elsewhere, old):
        path.write_bytes(b"half")
    os.utime(old, (0, 0))  # 1970: older than STALE_AFTER_S
    assert sorted(io.sweep_temporaries(tmp_path)) == sorted([orphan, old])
    assert mine.exists() and elsewhere.exists()


def test_display_uses_the_image_s_own_range():
    from activecontour.io.pictures import display_rgb

    image = np.where(np.add.outer(np.arange(32), np.arange(32)) > 31, 200, 20).astype(np.uint16)
    shown = display_rgb(image)
    assert shown.shape == (32, 32, 3) and shown.dtype == np.uint8
    # 20 -> black, 200 -> white (by the dtype's range both would be 0: 200 / 65535 * 255 < 1)
    np.testing.assert_array_equal(shown[:, :, 0], np.where(image == 200, 255, 0))
    # a few hot pixels do not darken the image (the percentiles 0.01, 99.99 of the values)
    hot = np.random.default_rng(1).integers(0, 60000, (512, 512)).astype(np.uint16) // 1000
    hot[0, :2] = 65535
    assert display_rgb(hot).max() == 255 and np.median(display_rgb(hot)) > 100


def test_auto_line_width_follows_the_saved_size():
    from activecontour.io.pictures import line_width

    assert [line_width((m, m)) for m in (256, 1024, 2048, 4096)] == [1, 1, 2, 4]
    image = np.full((2048, 1024), 0.5)
    circle = ac.circle((1023.5, 511.5), 400.0)
    thick = render_overlay(image, [circle], color="red")
    thin = render_overlay(image, [circle], color="red", thickness=1)
    red = lambda rgb: int(((rgb[:, :, 0] > 200) & (rgb[:, :, 1] < 100)).sum())  # noqa: E731
    assert red(thick) > 1.6 * red(thin)  # a 2 px line where the saved image is 2048 px high
    shrunk = render_overlay(image, [circle], color="red", max_side=512)
    assert line_width(shrunk.shape) == 1  # the width follows the size written, not the input's


@pytest.mark.parametrize("name", ["coffee", "retina"])
def test_auto_colour_stands_out_from_a_red_image(name, tmp_path):
    import skimage.data

    from activecontour.io.pictures import COLORS, contrasting_color, display_rgb

    image = getattr(skimage.data, name)()
    shown = display_rgb(image)
    chosen = contrasting_color(shown)
    assert chosen != COLORS["red"]
    sample = shown.reshape(-1, 3)[::5].astype(float)
    distance = lambda color: np.percentile(np.linalg.norm(sample - color, axis=1), 5)  # noqa: E731
    assert distance(chosen) > 1.5 * distance(COLORS["red"])
    assert contrasting_color(display_rgb(np.full((8, 8), 0.3))) == COLORS["red"]  # gray: red
