"""The command line's models: ``--regions K|auto``, ``--fit`` and ``--noise``, and the classes image
they write."""

import json
import os

import cv2
import numpy as np
import pytest

from activecontour import io
from activecontour.io.objects import read_label_image
from tests.app.test_cli import assert_one_line_error, run, summary_fields


@pytest.fixture
def nested(tmp_path):
    """Three nested classes (levels 0, 0.5, 1 at SNR 3) as an 8-bit PNG, and the true classes."""
    m = 96
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - m / 2, cols - m / 2)
    truth = (radius < 38).astype(int) + (radius < 20)
    image = truth / 2.0 + np.random.default_rng(30).normal(0, 0.5 / 3, truth.shape)
    image = (image - image.min()) / np.ptp(image)
    folder = tmp_path / "in"
    folder.mkdir()
    path = folder / "rings.png"
    cv2.imwrite(str(path), np.round(image * 255).astype(np.uint8))
    return path, truth


def _dice(found, truth, k):
    return 2 * np.sum((found == k) & (truth == k)) / (np.sum(found == k) + np.sum(truth == k))


@pytest.mark.parametrize("regions", ["3", "auto"])
def test_regions_write_the_classes_image(nested, tmp_path, capsys, regions):
    path, truth = nested
    out = tmp_path / "out"
    status, stdout, stderr = run(capsys, "segment", path, "-o", out, "--backend", "levelset",
                                 "--regions", regions, "--format", "json")
    assert status == 0, stderr
    assert sorted(os.listdir(out)) == ["rings_classes.png", "rings_contours.json", "rings_mask.png",
                                       "rings_overlay.png"]
    classes = read_label_image(out / "rings_classes.png")
    # 0 = the background (on the border), then by mean intensity: the truth's own numbering
    assert all(_dice(classes, truth, k) > 0.97 for k in range(3))
    mask = cv2.imread(str(out / "rings_mask.png"), cv2.IMREAD_GRAYSCALE)
    assert np.array_equal(mask > 0, classes > 0)  # the mask: every region but the background
    (line,) = stdout.splitlines()
    assert summary_fields(line)["regions"] == "3"
    meta = io.read_metadata(out / "rings_contours.json")
    assert meta["n_regions"] == 3 and np.shape(meta["constants"]) == (3, 1)
    assert meta["parameters"]["n_regions"] == (3 if regions == "3" else "auto")
    levels = np.array(meta["constants"])[:, 0]
    assert np.all(np.diff(levels[1:]) > 0)  # the regions by increasing mean intensity


def test_two_regions_by_default_write_no_classes_image_and_say_nothing(nested, tmp_path, capsys):
    path, _ = nested
    out = tmp_path / "out"
    status, stdout, stderr = run(capsys, "segment", path, "-o", out)
    assert status == 0, stderr
    assert "rings_classes.png" not in os.listdir(out)
    assert "regions" not in summary_fields(stdout)
    # asked for, the two-region classes are the mask
    status, _, stderr = run(capsys, "segment", path, "-o", out, "--objects", "classes")
    assert status == 0, stderr
    mask = cv2.imread(str(out / "rings_mask.png"), cv2.IMREAD_GRAYSCALE)
    assert np.array_equal(read_label_image(out / "rings_classes.png"), (mask > 0).astype(int))


@pytest.mark.parametrize("option, name, value", [("--fit", "fit", "smooth"), ("--noise", "noise", "poisson")])
def test_model_options_reach_the_library(nested, tmp_path, capsys, option, name, value):
    path, _ = nested
    out = tmp_path / "out"
    status, _, stderr = run(capsys, "segment", path, "-o", out, option, value)
    assert status == 0, stderr
    meta = json.loads((out / "rings_contours.json").read_text())["metadata"]
    assert meta["parameters"][name] == value


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--regions", "1"], ["--regions", "integer >= 2 or 'auto'"]),
        (["--regions", "2.5"], ["--regions", "integer >= 2 or 'auto'"]),
        (["--regions", "many"], ["--regions", "integer >= 2 or 'auto'"]),
        (["--fit", "linear"], ["--fit", "constant", "smooth"]),
        (["--noise", "laplace"], ["--noise", "gaussian", "poisson"]),
        (["--regions", "3", "--backend", "levelset", "--c-in", "0.5"], ["c_in", "n_regions=3"]),
        (["--regions", "auto", "--backend", "levelset", "--c-out", "0.5"], ["c_out"]),
    ],
)
def test_bad_regions_or_fit_exit_2_with_one_line_and_write_nothing(nested, tmp_path, capsys, argv, words):
    path, _ = nested
    out = tmp_path / "out"
    status, _, stderr = run(capsys, "segment", path, "-o", out, *argv)
    assert_one_line_error(status, stderr, *words)
    assert not out.exists()


def test_help_lists_regions_and_fit(capsys):
    status, stdout, _ = run(capsys, "segment", "--help")
    assert status == 0
    assert "--regions K|auto" in stdout and "--fit {constant,smooth}" in stdout
    assert "--noise {gaussian,poisson}" in stdout



def test_the_overlay_draws_each_region_in_its_own_colour(nested, tmp_path, capsys):
    from activecontour.io.pictures import COLORS, REGION_COLORS

    path, truth = nested
    out = tmp_path / "out"
    status, _, stderr = run(capsys, "segment", path, "-o", out, "--regions", "3")
    assert status == 0, stderr
    overlay = cv2.imread(str(out / "rings_overlay.png"))[:, :, ::-1].astype(int)

    def colour_near(row, col, name):
        """Whether a pixel next to (row, col) has the hue of the colour (its full channels 100
        above its empty ones: a gray image's pixel has none, an anti-aliased line's does)."""
        patch = overlay[row - 1:row + 2, col - 1:col + 2].reshape(-1, 3)
        full = np.array(COLORS[name]) == 255
        return bool(np.any(patch[:, full].min(axis=1) - patch[:, ~full].max(axis=1) > 100))

    # the background/ring interface (radius 38) in region 1's colour, the ring/disc one (radius 20)
    # in region 2's, on the four axes through the centre (48, 48); the middle of the ring has none
    for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0)):
        assert colour_near(48 + round(37.5 * dr), 48 + round(37.5 * dc), REGION_COLORS[0])
        assert colour_near(48 + round(19.5 * dr), 48 + round(19.5 * dc), REGION_COLORS[1])
        assert not colour_near(48 + 29 * dr, 48 + 29 * dc, REGION_COLORS[0])
        assert not colour_near(48 + 29 * dr, 48 + 29 * dc, REGION_COLORS[1])
