"""`activecontour segment` on stacks: a multi-page TIFF or a video is segmented as a sequence."""

import csv
import json

import cv2
import numpy as np
import pytest
import tifffile

from activecontour.synthetic import dice, disk_sequence
from app import cli

SIZE = 128
SPEC = [[(1, (40.0 + 3 * t, 40.0), 22.0), (2, (90.0, 92.0 - 3 * t), 20.0)] for t in range(4)]


def run(capsys, *argv):
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def assert_one_line_error(status, err, *words):
    assert status == 2 and len(err.splitlines()) == 1, err
    assert err.startswith("activecontour: error: ") and "Traceback" not in err
    for word in words:
        assert word in err, err


@pytest.fixture(scope="module")
def movie(tmp_path_factory):
    folder = tmp_path_factory.mktemp("movie")
    images, truth = disk_sequence(SIZE, SPEC, sigma=0.2, seed=4)
    pixels = np.round(np.clip(images, 0, 1) * 65535).astype(np.uint16)
    tifffile.imwrite(folder / "movie.tif", pixels, photometric="minisblack")
    return folder / "movie.tif", pixels, truth


def test_a_stack_is_segmented_as_a_sequence(movie, tmp_path, capsys):
    path, _, truth = movie
    status, out, err = run(capsys, "segment", path, "-o", tmp_path / "out")
    assert status == 0 and err == ""
    assert out.startswith("movie.tif: 4 frames, 2 tracks, 0 divisions")
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["movie_contours.json", "movie_labels.tif", "movie_objects.csv", "movie_overlay.png",
                     "movie_tracks.csv", "movie_tracks.json"]
    labels = tifffile.imread(tmp_path / "out" / "movie_labels.tif")
    assert labels.shape == truth.shape
    for track in (1, 2):  # one id per object in every frame, the objects where the truth has them
        ids = {int(np.bincount(labels[t][truth[t] == track]).argmax()) for t in range(len(truth))}
        assert len(ids) == 1 and 0 not in ids
    assert all(dice(labels[t] > 0, truth[t] > 0) >= 0.98 for t in range(len(truth)))
    with open(tmp_path / "out" / "movie_tracks.csv") as handle:
        tracks = list(csv.DictReader(handle))
    assert len(tracks) == 8 and list(tracks[0]) == ["track_id", "t", "row", "col"]
    first = [row for row in tracks if row["t"] == "0" and float(row["col"]) < 60]
    assert abs(float(first[0]["row"]) - 40.0) < 0.5  # the centroid of disk 1 at frame 0
    with open(tmp_path / "out" / "movie_objects.csv") as handle:
        objects = list(csv.DictReader(handle))
    assert len(objects) == 8 and {"frame", "index", "label", "area"} <= set(objects[0])
    contours = json.loads((tmp_path / "out" / "movie_contours.json").read_text())
    assert [f["frame"] for f in contours["frames"]] == [0, 1, 2, 3]
    assert json.loads((tmp_path / "out" / "movie_tracks.json").read_text()) == {"graph": {}}
    assert cv2.imread(str(tmp_path / "out" / "movie_overlay.png")) is not None


def test_frames_selects_and_axis_names_the_frame_axis(movie, tmp_path, capsys):
    path, pixels, _ = movie
    status, out, _ = run(capsys, "segment", path, "-o", tmp_path / "a", "--frames", "1:3")
    assert status == 0 and "2 frames" in out
    with open(tmp_path / "a" / "movie_objects.csv") as handle:
        assert sorted({row["index"] for row in csv.DictReader(handle)}) == ["1", "2"]
    z_last = tmp_path / "zstack.tif"
    tifffile.imwrite(z_last, np.moveaxis(pixels, 0, -1), photometric="minisblack", planarconfig="contig")
    status, out, err = run(capsys, "segment", z_last, "-o", tmp_path / "b", "--axis", "2", "--frames", "0,3")
    assert status == 0, err
    assert tifffile.imread(tmp_path / "b" / "zstack_labels.tif").shape == (2, SIZE, SIZE)


def test_a_video_is_a_sequence(movie, tmp_path, capsys):
    _, pixels, _ = movie
    video = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 5, (SIZE, SIZE), False)
    for frame in pixels:
        writer.write((frame >> 8).astype(np.uint8))
    writer.release()
    status, out, err = run(capsys, "segment", video, "-o", tmp_path / "out")
    assert status == 0, err
    assert out.startswith("clip.avi: 4 frames, 2 tracks")


def test_two_stacks_with_one_stem_are_refused_before_any_work(movie, tmp_path, capsys):
    """disk.tif and disk.avi would both write disk_labels.tif, ...: refused as two images with one
    stem are (one line, exit 2, nothing written), not segmented one over the other (issue 22)."""
    _, pixels, _ = movie
    tifffile.imwrite(tmp_path / "disk.tif", pixels, photometric="minisblack")
    writer = cv2.VideoWriter(str(tmp_path / "disk.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 5, (SIZE, SIZE),
                             False)
    for frame in pixels:
        writer.write((frame >> 8).astype(np.uint8))
    writer.release()
    status, _, err = run(capsys, "segment", tmp_path / "disk.tif", tmp_path / "disk.avi",
                         "-o", tmp_path / "out")
    assert_one_line_error(status, err, "disk.tif", "disk.avi", "would both write")
    assert not (tmp_path / "out").exists()


def test_bad_frame_selection_writes_nothing(movie, tmp_path, capsys):
    path, _, _ = movie
    status, _, err = run(capsys, "segment", path, "-o", tmp_path / "out", "--frames", "9")
    assert_one_line_error(status, err, "frame index 9", "4 frames")
    assert not (tmp_path / "out").exists()
    status, _, err = run(capsys, "segment", path, "-o", tmp_path / "out", "--frames", "a:b")
    assert_one_line_error(status, err, "--frames")


def test_frames_on_a_single_image_is_refused(tmp_path, capsys):
    image = tmp_path / "one.png"
    cv2.imwrite(str(image), np.zeros((16, 16), np.uint8))
    status, _, err = run(capsys, "segment", image, "--frames", "0:2", "-o", tmp_path / "out")
    assert_one_line_error(status, err, "--frames", "stack")
    assert not (tmp_path / "out").exists()


def test_view_refuses_a_stack_in_one_line(movie, capsys):
    status, _, err = run(capsys, "view", movie[0])
    assert_one_line_error(status, err, "stack of 4 frames", "segment_sequence")


def test_init_options_start_the_first_frame(movie, tmp_path, capsys):
    """--init-circle on a stack is not ignored: with no iteration, frame 0 is that circle."""
    path, _, _ = movie
    status, _, err = run(capsys, "segment", path, "-o", tmp_path / "out", "--init-circle", "60", "64", "30",
                         "--max-iter", "0")
    assert status == 0, err
    first = tifffile.imread(tmp_path / "out" / "movie_labels.tif")[0]
    assert np.unique(first).tolist() == [0, 1]
    assert abs((first > 0).sum() - np.pi * 30**2) < 0.02 * np.pi * 30**2
    rows, cols = np.nonzero(first)
    assert abs(rows.mean() - 60) < 0.5 and abs(cols.mean() - 64) < 0.5
