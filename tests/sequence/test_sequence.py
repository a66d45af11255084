"""segment_sequence: warm starts, identities frame by frame, the outputs, the readers, refusals.

Every scene is a :func:`activecontour.synthetic.disk_sequence` with known tracks at SNR 2
(contrast 0.5, noise 0.25); identities are checked frame by frame against the truth's track ids.
"""

import numpy as np
import pytest

import activecontour as ac
from activecontour.synthetic import dice, disk_sequence

SIZE = 160
RADIUS = 26.0  # px: at SNR 2 the boundary error is a small fraction of a pixel, Dice >= 0.99


def run(frames_spec, **kwargs):
    images, truth = disk_sequence(SIZE, frames_spec, sigma=0.25, seed=2)
    return images, truth, ac.segment_sequence(images, **kwargs)


def id_of(labels, truth, track):
    """The id our labels give the pixels of truth track ``track`` (their majority), or None."""
    votes = np.bincount(labels[truth == track])
    votes[0] = 0
    return int(votes.argmax()) if votes.sum() else None


def assert_identities(seq, truth):
    """Every truth track has one id for its whole life, no two tracks share an id, no id is reused."""
    ids = {}
    for t in range(len(truth)):
        for track in np.unique(truth[t][truth[t] > 0]):
            ours = id_of(seq.labels[t], truth[t], track)
            assert ours is not None, f"frame {t}: track {track} not found"
            assert ids.setdefault(int(track), ours) == ours, f"frame {t}: track {track} changed id"
    assert len(set(ids.values())) == len(ids), f"two tracks share an id: {ids}"
    return ids


@pytest.fixture(scope="module")
def drift_and_breathing():
    """Disk 1 drifts 3 px per frame; disk 2 breathes (radius +-15 %)."""
    spec = [[(1, (45.0 + 3 * t, 45.0 + 2 * t), RADIUS),
             (2, (112.0, 110.0), RADIUS * (1 + 0.15 * np.sin(t)))] for t in range(6)]
    return run(spec)


def test_every_frame_is_segmented_and_identities_hold(drift_and_breathing):
    images, truth, seq = drift_and_breathing
    assert seq.labels.shape == truth.shape and seq.labels.dtype == np.int32
    for t in range(len(images)):
        assert dice(seq.labels[t] > 0, truth[t] > 0) >= 0.99, f"frame {t}"
    ids = assert_identities(seq, truth)
    assert sorted(ids.values()) == [1, 2] and seq.graph == {}
    for t, result in enumerate(seq.results):  # each frame's result carries the track ids too
        np.testing.assert_array_equal(result.labels, seq.labels[t])
        assert sorted(result.objects["label"]) == sorted(np.unique(seq.labels[t])[1:])


def test_tracks_and_objects_table(drift_and_breathing):
    images, truth, seq = drift_and_breathing
    ids = assert_identities(seq, truth)
    assert seq.tracks.shape == (2 * len(images), 4)
    # napari's layout: sorted by track, then time; the centroid follows the drifting disk's centre
    drifting = seq.tracks[seq.tracks[:, 0] == ids[1]]
    np.testing.assert_array_equal(drifting[:, 1], np.arange(len(images)))
    centres = np.array([(45.0 + 3 * t, 45.0 + 2 * t) for t in range(len(images))])
    np.testing.assert_allclose(drifting[:, 2:], centres, atol=0.5)
    table = seq.objects
    assert {"frame", "index", "label", "area", "centroid-0", "centroid-1"} <= set(table)
    assert len(table["label"]) == 2 * len(images)
    rows = table["label"] == ids[1]
    np.testing.assert_allclose(table["area"][rows], np.pi * RADIUS**2, rtol=0.03)


def test_warm_frames_follow_the_previous_result(drift_and_breathing):
    """Frames after the first start from the previous contours (or this frame's threshold split,
    whichever is lower in (6.38)): the same answer as a cold start, frame by frame."""
    images, truth, seq = drift_and_breathing
    for t in (1, len(images) - 1):
        cold = ac.segment(images[t])
        assert dice(seq.results[t].mask, cold.mask) >= 0.995
        assert seq.results[t].energy <= cold.energy * (1 + 1e-3)



def test_a_repeated_frame_keeps_the_converged_result(drift_and_breathing):
    """A frame equal to the one before is not segmented again (the result converged on that very
    image: stationary there): the same energies, iterations and ids; a frame that differs by one
    pixel is segmented from the warm start."""
    images = drift_and_breathing[0]
    changed = images[1].copy()
    changed[80, 80] += 0.1
    seq = ac.segment_sequence([images[0], images[1], images[1], changed])
    first, again, other = seq.results[1], seq.results[2], seq.results[3]
    assert first.success
    np.testing.assert_array_equal(again.energies, first.energies)
    assert again.n_iter == first.n_iter and again.energy == first.energy
    np.testing.assert_array_equal(seq.labels[2], seq.labels[1])
    # segmented: the energies of its own run, from its warm start
    assert not np.array_equal(other.energies, first.energies)
    assert dice(other.mask, first.mask) >= 0.99

def test_leaving_and_entering():
    """Disk 1 leaves through the top border (its track ends), disk 2 enters from the left at
    frame 3, 14 px deep (a new id, never one of a finished track)."""
    spec = []
    for t in range(8):
        disks = [(1, (50.0 - 14 * t, 80.0), RADIUS), (3, (120.0, 120.0), RADIUS)]
        if t >= 3:
            disks.append((2, (60.0, -RADIUS + 14 * (t - 2)), RADIUS))
        spec.append(disks)
    images, truth, seq = run(spec)
    ids = assert_identities(seq, truth)
    gone = [t for t in range(8) if not (truth[t] == 1).any()]
    assert gone and all(ids[1] not in seq.labels[t] for t in gone)
    assert ids[2] not in (ids[1], ids[3]) and ids[2] == 3  # the next unused id
    for t in range(8):
        assert dice(seq.labels[t] > 0, truth[t] > 0) >= 0.98  # objects cut by the border included


def test_division_records_the_parent():
    """Disk 1 divides at frame 3 into two daughters of half its area that move apart: the
    parent's track ends and each daughter gets a new id whose parent it is."""
    spec = []
    for t in range(7):
        disks = [(9, (125.0, 30.0), 20.0)]
        if t < 3:
            disks.append((1, (70.0, 80.0), RADIUS))
        else:
            offset = 0.6 * RADIUS + 3.0 * (t - 3)
            disks += [(2, (70.0 - offset, 80.0), 0.72 * RADIUS), (3, (70.0 + offset, 80.0), 0.72 * RADIUS)]
        spec.append(disks)
    images, truth, seq = run(spec)
    first = {track: id_of(seq.labels[t], truth[t], track) for t in (0, 6) for track in (1, 2, 3, 9)
             if (truth[t] == track).any()}
    parent, children = first[1], (first[2], first[3])
    assert len({parent, *children}) == 3
    assert seq.graph == {children[0]: [parent], children[1]: [parent]}
    assert all(parent not in seq.labels[t] for t in range(4, 7))
    assert all(id_of(seq.labels[t], truth[t], 9) == first[9] for t in range(7))  # a bystander


def test_two_objects_passing_close_by_keep_their_ids():
    """Two disks move in opposite directions 4 px apart: no swap, no merge."""
    gap = 4.0
    spec = [[(1, (50.0, 30.0 + 16 * t), 22.0), (2, (50.0 + 44.0 + gap, 130.0 - 16 * t), 22.0)]
            for t in range(7)]
    images, truth, seq = run(spec)
    ids = assert_identities(seq, truth)
    assert ids[1] != ids[2] and seq.graph == {}


def test_callback_progress_and_stop(drift_and_breathing):
    images, _, _ = drift_and_breathing
    seen = []
    seq = ac.segment_sequence(
        images, callback=lambda frame: seen.append((frame.position, frame.n_frames)) or frame.position == 1)
    assert seen == [(0, 6), (1, 6)] and seq.labels.shape == (2, SIZE, SIZE)


def test_iter_sequence_streams(drift_and_breathing):
    images, _, seq = drift_and_breathing
    frames = ac.iter_sequence(iter(images))  # a generator of frames: read once, length unknown
    first = next(frames)
    assert first.index == 0 and first.n_frames is None
    np.testing.assert_array_equal(first.result.labels, seq.labels[0])


def test_select_axis_list_and_streaming_to_tiff(drift_and_breathing, tmp_path):
    images, _, seq = drift_and_breathing
    picked = ac.segment_sequence(images, select=slice(0, None, 2))
    np.testing.assert_array_equal(picked.frame_indices, [0, 2, 4])
    moved = ac.segment_sequence(np.moveaxis(images, 0, -1), axis=-1, select=[0, 1])
    listed = ac.segment_sequence(list(images[:2]))
    np.testing.assert_array_equal(moved.labels, listed.labels)
    np.testing.assert_array_equal(listed.labels, seq.labels[:2])
    streamed = ac.segment_sequence(images[:3], keep_results=False, labels_file=tmp_path / "l.tif")
    assert streamed.results is None
    np.testing.assert_array_equal(streamed.labels, seq.labels[:3])


def test_paths_tiff_folder_and_video(drift_and_breathing, tmp_path):
    import cv2
    import tifffile

    images, _, seq = drift_and_breathing
    pixels = np.round(np.clip(images, 0, 1) * 65535).astype(np.uint16)
    tifffile.imwrite(tmp_path / "movie.tif", pixels[:3], photometric="minisblack")
    from_tiff = ac.segment_sequence(tmp_path / "movie.tif")
    assert from_tiff.labels.shape == (3, SIZE, SIZE)
    assert dice(from_tiff.labels > 0, seq.labels[:3] > 0) >= 0.99
    folder = tmp_path / "frames"
    folder.mkdir()
    for t in (0, 1, 10):  # numbered without padding: frame2 comes before frame10
        cv2.imwrite(str(folder / f"frame{t if t < 2 else 10}.png"), pixels[min(t, 2)])
    from_folder = ac.segment_sequence(folder)
    assert from_folder.n_frames == 3
    assert dice(from_folder.labels[2] > 0, seq.labels[2] > 0) >= 0.99  # frame10 last
    video = tmp_path / "movie.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 5, (SIZE, SIZE), False)
    for t in range(3):
        writer.write((pixels[t] >> 8).astype(np.uint8))
    writer.release()
    from_video = ac.segment_sequence(video, select=[1, 2])
    np.testing.assert_array_equal(from_video.frame_indices, [1, 2])
    assert dice(from_video.labels[0] > 0, seq.labels[1] > 0) >= 0.97  # JPEG-compressed frames


def test_segment_refuses_stacks_with_the_name_of_segment_sequence(drift_and_breathing, tmp_path):
    import tifffile

    images = drift_and_breathing[0]
    with pytest.raises(ValueError, match="stack of 6 frames.*segment_sequence"):
        ac.segment(images)
    with pytest.raises(ValueError, match="ambiguous.*channel_axis=0"):
        ac.segment(images[:3])
    tifffile.imwrite(tmp_path / "movie.tif", images[:4].astype(np.float32), photometric="minisblack")
    with pytest.raises(ValueError, match="stack of 4 frames.*segment_sequence"):
        ac.segment(tmp_path / "movie.tif")


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(frames=np.zeros((8, 8))), ValueError, "stack.*activecontour.segment"),
    (dict(frames=np.zeros((3, 8, 8)), axis=3), ValueError, "axis 3 is out of range"),
    (dict(frames=np.zeros((3, 8, 8)), select=[5]), ValueError, "frame index 5.*3 frames"),
    (dict(frames="/nonexistent/movie.tif"), FileNotFoundError, "frames not found"),
    (dict(frames=42), TypeError, "frames must be"),
    (dict(frames=np.zeros((3, 8, 8)), callback=3), TypeError, "callback"),
])
def test_bad_arguments(kwargs, error, match):
    with pytest.raises(error, match=match):
        ac.segment_sequence(**kwargs)


def test_readme_example_runs(capsys):
    """README's "Time-lapses and stacks" block runs as written: two tracks, one id each."""
    from tests.app.test_readme import python_blocks, run_blocks

    (block,) = [code for code in python_blocks() if "segment_sequence(frames)" in code]
    namespace = run_blocks(block)
    seq, truth = namespace["seq"], namespace["truth"]
    assert_identities(seq, truth)
    assert seq.tracks.shape == (10, 4)
    assert len(capsys.readouterr().out.splitlines()) == 5
