"""``io.save_sequence``: a segmented sequence's files, written as the frames come, all or none."""

import csv
import json
import os

import numpy as np
import pytest
import tifffile

import activecontour as ac
from activecontour import io
from activecontour.io.sequences import SEQUENCE_SUFFIXES, SHEET_FRAMES, contact_sheet
from activecontour.synthetic import disk_sequence

SIZE = 64
SPEC = [[(1, (20.0 + 2 * t, 20.0), 10.0), (2, (44.0, 46.0 - 2 * t), 9.0)] for t in range(3)]


@pytest.fixture(scope="module")
def frames():
    images, truth = disk_sequence(SIZE, SPEC, sigma=0.05, seed=2)
    return images, truth


def _save(frames, stem, **kwargs):
    with io.save_sequence(stem, source="movie.tif", n_frames=len(frames), **kwargs) as writer:
        seq = ac.segment_sequence(frames, callback=writer.add, keep_results=False,
                                  labels_file=writer.labels_file)
        return seq, writer.finish(seq)


def test_the_files_of_a_sequence(frames, tmp_path):
    images, truth = frames
    seq, paths = _save(images, tmp_path / "movie")
    assert paths == io.sequence_paths(tmp_path / "movie")
    assert sorted(os.listdir(tmp_path)) == sorted(f"movie{suffix}" for suffix in SEQUENCE_SUFFIXES)
    labels = tifffile.imread(tmp_path / "movie_labels.tif")
    assert labels.shape == truth.shape and labels.dtype == np.int32
    for track in (1, 2):  # each disk one id in every frame
        assert len({int(np.bincount(labels[t][truth[t] == track]).argmax()) for t in range(3)}) == 1
    with open(tmp_path / "movie_tracks.csv") as handle:
        tracks = list(csv.DictReader(handle))
    assert list(tracks[0]) == ["track_id", "t", "row", "col"] and len(tracks) == 2 * len(SPEC)
    disk_1 = [row for row in tracks if float(row["col"]) < 32]
    # the centroid of disk 1 moves 2 px down per frame from row 20
    assert [round(float(row["row"])) for row in disk_1] == [20, 22, 24]
    with open(tmp_path / "movie_objects.csv") as handle:
        assert len(list(csv.DictReader(handle))) == 2 * len(SPEC)
    contours = json.loads((tmp_path / "movie_contours.json").read_text())
    assert contours["source"] == "movie.tif" and [f["frame"] for f in contours["frames"]] == [0, 1, 2]
    assert [len(f["objects"]) for f in contours["frames"]] == [2, 2, 2]
    assert json.loads((tmp_path / "movie_tracks.json").read_text()) == {"graph": {}}
    sheet = ac.load_image(tmp_path / "movie_overlay.png")
    assert sheet.shape == (2 * SIZE, 2 * SIZE, 3)  # three tiles on a 2 x 2 grid


def test_a_run_that_fails_leaves_no_file(frames, tmp_path):
    images, _ = frames

    def fail_at_the_second_frame(frame):
        writer.add(frame)
        if frame.position == 1:
            raise ValueError("stop")

    with pytest.raises(ValueError, match="stop"):
        with io.save_sequence(tmp_path / "movie", n_frames=3) as writer:
            ac.segment_sequence(images, callback=fail_at_the_second_frame, labels_file=writer.labels_file)
    assert os.listdir(tmp_path) == []  # no output, no temporary


def test_a_failed_write_of_the_group_leaves_no_file(frames, tmp_path, monkeypatch):
    images, _ = frames
    real_replace = os.replace

    def no_space_for_the_objects(src, dst):
        if os.fspath(dst).endswith("_contours.json"):
            raise OSError(28, "No space left on device", os.fspath(dst))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", no_space_for_the_objects)
    with pytest.raises(OSError, match="No space"):
        _save(images, tmp_path / "movie")
    assert os.listdir(tmp_path) == []


def test_an_output_that_is_the_input_is_refused(tmp_path):
    source = tmp_path / "x_labels.tif"
    source.write_bytes(b"")
    with pytest.raises(ValueError, match="overwrite the input"):
        io.save_sequence(tmp_path / "x", protect=[source])


def test_the_sheet_shows_evenly_spaced_frames():
    writer = io.save_sequence("unused", n_frames=100)
    assert len(writer.shown) == SHEET_FRAMES and min(writer.shown) == 0 and max(writer.shown) == 99
    assert io.save_sequence("unused").shown == set(range(SHEET_FRAMES))  # length unknown: the first
    tiles = [np.full((4, 6, 3), k, np.uint8) for k in range(5)]
    sheet = contact_sheet(tiles)  # five tiles: three columns, two rows
    assert sheet.shape == (8, 18, 3) and sheet[4, 6, 0] == 4 and sheet[4, 12:].max() == 0
