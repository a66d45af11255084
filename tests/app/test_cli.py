"""The command line end to end: outputs, summary, progress, and one-line errors with exit status 2."""

import json
import os
import re
import shutil
import subprocess
import sys
import types
from pathlib import Path

import cv2
import numpy as np
import pytest
import scipy.ndimage

import app
from activecontour import io, synthetic
from app import cli
from app.cli.progress import ImageProgress
from tests.helpers import sigint_as_in_a_terminal

SAMPLES = Path(__file__).resolve().parents[2] / "sample_images"
SIZE = (48, 64)
CENTER, RADIUS = (23.0, 33.5), 13.0


@pytest.fixture
def small(tmp_path):
    """A small noisy disk image (PNG) in its own folder, and its ground truth."""
    image, truth = synthetic.render(synthetic.disk(CENTER, RADIUS), SIZE, inside=0.75, outside=0.25)
    image = synthetic.add_noise(image, 0.05, seed=5)
    folder = tmp_path / "in"
    folder.mkdir()
    path = folder / "disk.png"
    cv2.imwrite(str(path), np.round(np.clip(image, 0, 1) * 255).astype(np.uint8))
    return path, truth


def run(capsys, *argv):
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def summary_fields(line):
    return dict(re.findall(r"(\w+)=(\S+)", line))


def assert_one_line_error(status, err, *words):
    assert status == 2
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("activecontour: error: ")
    assert "Traceback" not in err
    for word in words:
        assert word.lower() in lines[0].lower(), lines[0]


def test_segment_sample_image_end_to_end(tmp_path, capsys):
    out = tmp_path / "out"
    image = SAMPLES / "disk_noisy.png"
    status, stdout, stderr = run(capsys, "segment", image, "-o", out, "--format", "json,geojson")
    assert status == 0 and stderr == ""
    expected = ["disk_noisy_contours.geojson", "disk_noisy_contours.json", "disk_noisy_mask.png",
                "disk_noisy_overlay.png"]
    assert sorted(os.listdir(out)) == expected
    (line,) = stdout.splitlines()
    assert line.startswith("disk_noisy.png: ")
    fields = summary_fields(line)
    meta = io.read_metadata(out / "disk_noisy_contours.json")
    assert int(fields["iterations"]) == meta["n_iter"]
    assert float(fields["c_in"]) == pytest.approx(meta["c_in"], rel=1e-3)
    assert fields["success"] == "True" and fields["time"].endswith("s")
    mask = io.read_mask(out / "disk_noisy_mask.png")
    assert synthetic.dice(mask, io.read_mask(SAMPLES / "disk_noisy_truth.png")) > 0.95
    overlay = cv2.imread(str(out / "disk_noisy_overlay.png"))
    assert overlay.shape == mask.shape + (3,)
    contours = io.read_contours(out / "disk_noisy_contours.geojson")
    assert all(np.array_equal(a, b) for a, b in
               zip(contours, io.read_contours(out / "disk_noisy_contours.json"), strict=True))


def test_summary_counts_the_objects(tmp_path, capsys):
    """objects= is the count of result.labels' ids: three disks, two of them touching, are three."""
    disks = [synthetic.disk((40.0, 40.0), 16.0), synthetic.disk((40.0, 68.8), 16.0),
             synthetic.disk((96.0, 90.0), 14.0)]
    clean, truth = synthetic.render(synthetic.union(*disks), (128, 128))
    path = tmp_path / "three.png"
    noisy = np.clip(synthetic.add_noise(clean, 0.1, seed=6), 0, 1)
    cv2.imwrite(str(path), np.round(noisy * 255).astype(np.uint8))
    status, stdout, _ = run(capsys, "segment", path, "-o", tmp_path / "out", "--objects", "labels")
    assert status == 0
    labels = cv2.imread(str(tmp_path / "out" / "three_labels.png"), cv2.IMREAD_UNCHANGED)
    assert int(summary_fields(stdout)["objects"]) == len(np.unique(labels[labels > 0])) == len(disks)
    assert scipy.ndimage.label(truth)[1] == 2  # the touching pair is one piece of the mask


def test_default_output_is_next_to_the_image_and_quiet_prints_nothing(small, capsys):
    path, truth = small
    status, stdout, stderr = run(capsys, "segment", path, "--quiet", "--mu", "0.2")
    assert (status, stdout, stderr) == (0, "", "")
    assert sorted(os.listdir(path.parent)) == ["disk.png", "disk_contours.json", "disk_mask.png",
                                               "disk_overlay.png"]
    assert synthetic.dice(io.read_mask(path.parent / "disk_mask.png"), truth) > 0.95
    meta = io.read_metadata(path.parent / "disk_contours.json")
    assert meta["parameters"]["mu"] == 0.2 and meta["image"] == str(path)


@pytest.mark.parametrize("init", ["circle", "rect", "mask", "contours"])
def test_each_kind_of_initial_curve(small, tmp_path, capsys, init):
    path, truth = small
    if init == "circle":
        options = ["--init-circle", 20, 30, 8]
    elif init == "rect":
        options = ["--init-rect", 5, 5, 42, 60]
    elif init == "mask":
        io.write_mask(tmp_path / "init.png", synthetic.render(synthetic.disk(CENTER, 8.0), SIZE)[1])
        options = ["--init-mask", tmp_path / "init.png"]
    else:
        io.write_contours(tmp_path / "init.json", [np.array([[10.0, 20.0], [35.0, 20.0], [35.0, 45.0]])],
                          image_shape=SIZE)
        options = ["--init-contours", tmp_path / "init.json"]
    status, _, stderr = run(capsys, "segment", path, "-o", tmp_path / "out", *options)
    assert status == 0, stderr
    assert synthetic.dice(io.read_mask(tmp_path / "out" / "disk_mask.png"), truth) > 0.95


def test_the_same_image_named_twice_is_segmented_once(small, tmp_path, capsys):
    path, _ = small
    same = path.parent / ".." / path.parent.name / path.name
    status, stdout, _ = run(capsys, "segment", path, same, "-o", tmp_path / "out")
    assert status == 0 and len(stdout.splitlines()) == 1


def test_progress_bar_only_on_a_terminal(small, tmp_path, capsys, monkeypatch):
    path, _ = small
    monkeypatch.setattr("app.cli.segment.is_terminal", lambda stream: True)
    status, stdout, stderr = run(capsys, "segment", path, "-o", tmp_path / "a", "--max-iter", 3)
    assert status == 0
    assert "\r" in stderr and "iteration 3 energy" in stderr
    assert "[1/1] disk.png: loading" in stderr and f"setting up ({SIZE[0]} x {SIZE[1]})" in stderr
    assert len(stdout.splitlines()) == 1
    status, stdout, stderr = run(capsys, "segment", path, "-o", tmp_path / "b", "--quiet")
    assert (status, stdout, stderr) == (0, "", "")


def bad_text_image(folder):
    path = folder / "text.png"
    path.write_text("this is not an image\n")
    return path


@pytest.mark.parametrize(
    "case, words",
    [
        ("missing file", ["not found", "missing.png"]),
        ("unreadable file", ["cannot read", "text.png"]),
        ("init mask of the wrong shape", ["shape"]),
        ("negative mu", ["--mu", ">= 0"]),
        ("nan parameter", ["omega", "finite"]),
        ("init circle outside", ["outside the image"]),
        ("zero radius", ["radius"]),
        ("unknown format", ["unknown format", "xml"]),
        ("negative max-iter", ["--max-iter"]),
        ("output is a file", ["not a directory"]),
        ("output under a file", ["not a directory"]),
        ("good then missing", ["not found"]),
        ("same output twice", ["both write"]),
        ("output overwrites an input", ["overwrite"]),
        ("no image", ["required"]),
        ("missing init mask", ["--init-mask", "not found"]),
        ("c_in per channel of a gray image", ["--c-in", "2 values"]),
        ("a one-column image", ["(100, 1)", "2 x 2"]),  # its own shape, not a corner's
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(small, tmp_path, capsys, case, words):
    path, _ = small
    out = tmp_path / "out"
    argv = ["segment", path, "-o", out]
    if case == "missing file":
        argv[1] = tmp_path / "missing.png"
    elif case == "unreadable file":
        argv[1] = bad_text_image(tmp_path)
    elif case == "init mask of the wrong shape":
        io.write_mask(tmp_path / "m.png", np.ones((SIZE[0] + 1, SIZE[1]), bool))
        argv += ["--init-mask", tmp_path / "m.png"]
    elif case == "negative mu":
        argv += ["--mu", "-1"]
    elif case == "nan parameter":
        argv += ["--omega", "nan"]
    elif case == "init circle outside":
        argv += ["--init-circle", 500, 500, 10]
    elif case == "zero radius":
        argv += ["--init-circle", 20, 20, 0]
    elif case == "unknown format":
        argv += ["--format", "json,xml"]
    elif case == "negative max-iter":
        argv += ["--max-iter", "-3"]
    elif case == "output is a file":
        out.write_text("a file where the directory should be")
    elif case == "output under a file":
        (tmp_path / "file").write_text("")
        argv[3] = out = tmp_path / "file" / "out"
    elif case == "good then missing":
        argv.insert(2, tmp_path / "missing.png")
    elif case == "same output twice":
        other = tmp_path / "other"
        other.mkdir()
        shutil.copy(path, other / "disk.png")
        argv.insert(2, other / "disk.png")
    elif case == "output overwrites an input":
        shutil.copy(path, path.parent / "disk_mask.png")
        argv = ["segment", path, path.parent / "disk_mask.png"]
    elif case == "no image":
        argv = ["segment"]
    elif case == "missing init mask":
        argv += ["--init-mask", tmp_path / "nope.png"]
    elif case == "c_in per channel of a gray image":
        argv += ["--c-in", "0.2,0.3"]
    elif case == "a one-column image":
        argv[1] = tmp_path / "column.png"
        cv2.imwrite(str(argv[1]), np.arange(100, dtype=np.uint8)[:, None])
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    status, stdout, stderr = run(capsys, *argv)
    assert_one_line_error(status, stderr, *words)
    assert stdout == ""
    after = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before  # nothing written, nothing overwritten
    assert not out.is_dir()


@pytest.mark.parametrize("stage", ["segment", "write"])
def test_a_failure_while_running_leaves_no_file_and_no_new_directory(small, tmp_path, capsys,
                                                                      monkeypatch, request, stage):
    path, _ = small
    if stage == "segment":
        def failing_segment(*args, **kwargs):
            raise ValueError("the flow found a problem")

        monkeypatch.setattr("activecontour.segment", failing_segment)
    else:
        request.getfixturevalue("no_space_for_contours")
    status, stdout, stderr = run(capsys, "segment", path, "-o", tmp_path / "new" / "deeper")
    assert_one_line_error(status, stderr, "problem" if stage == "segment" else "no space")
    assert stdout == ""
    assert not (tmp_path / "new").exists()


def test_help_exits_0(capsys):
    status, stdout, _ = run(capsys, "segment", "--help")
    assert status == 0 and "--init-circle" in stdout and "--lambda-in" in stdout


def test_view_passes_the_settings_to_the_viewer(small, capsys, monkeypatch):
    path, _ = small
    calls = []

    def launch(image_path, settings, *, image=None, init=None, max_pixels=None):
        calls.append(dict(image_path=image_path, image=image, init=init, **settings.keywords()))
        return 0

    viewer = types.ModuleType("app.viewer")
    viewer.launch = launch
    monkeypatch.setitem(sys.modules, "app.viewer", viewer)
    monkeypatch.setattr(app, "viewer", viewer, raising=False)
    status, _, stderr = run(capsys, "view", path, "--mu", "0.25", "--max-iter", "40",
                            "--init-circle", 20, 30, 8)
    assert status == 0, stderr
    (call,) = calls
    assert call["image_path"] == str(path) and call["mu"] == 0.25 and call["max_num_iter"] == 40
    assert call["image"].shape == SIZE  # read once, by the command line
    assert np.allclose(np.hypot(call["init"][:, 0] - 20, call["init"][:, 1] - 30), 8.0)
    # every setting the view command takes reaches the viewer, none is silently dropped
    status, _, stderr = run(capsys, "view", path, "--c-in", "0.5", "--noise", "poisson")
    assert status == 0, stderr
    assert calls[-1]["c_in"] == 0.5 and calls[-1]["noise"] == "poisson"
    status, _, stderr = run(capsys, "view", path.parent / "missing.png")
    assert_one_line_error(status, stderr, "not found")
    assert len(calls) == 2


def test_the_executable_turns_numpys_huge_pages_off_unless_told(monkeypatch):
    seen = []
    monkeypatch.setattr(cli, "main", lambda: seen.append(os.environ.get("NUMPY_MADVISE_HUGEPAGE")) or 0)
    monkeypatch.setattr(cli, "reuse_freed_memory", lambda: None)  # not in the test process
    monkeypatch.delenv("NUMPY_MADVISE_HUGEPAGE", raising=False)
    assert cli.console_script() == 0
    monkeypatch.setenv("NUMPY_MADVISE_HUGEPAGE", "1")  # the caller's environment wins
    assert cli.console_script() == 0
    assert seen == ["0", "1"]


_FAULTS = """
import resource
import numpy as np
from app import cli

def faults():  # the page faults of each of three 64 MB arrays, made and freed in turn
    counts = []
    for _ in range(3):
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        array = np.ones(64 << 20, dtype=np.uint8)
        del array
        counts.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
    return counts

default = faults()
cli.reuse_freed_memory()
print(*default, *faults())
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_the_executable_reuses_the_memory_of_freed_arrays():
    """After the first, a 64 MB array that replaces a freed one faults in no fresh pages."""
    import resource

    completed = subprocess.run([sys.executable, "-c", _FAULTS], capture_output=True, text=True, check=True,
                               cwd=Path(__file__).resolve().parents[2], timeout=60,
                               env={**os.environ, "NUMPY_MADVISE_HUGEPAGE": "0"})
    counts = [int(count) for count in completed.stdout.split()]
    pages = (64 << 20) // resource.getpagesize()
    if min(counts[1:3]) < pages / 2:
        pytest.skip("this malloc reuses freed arrays already")
    assert max(counts[4:]) < pages / 100


def test_installed_console_script(small, tmp_path):
    executable = shutil.which("activecontour")
    if executable is None:
        pytest.skip("the activecontour console script is not installed (pip install -e .)")
    path, truth = small
    completed = subprocess.run(
        [executable, "segment", str(path), "-o", str(tmp_path / "out"), "--format", "csv"],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout.startswith("disk.png: ") and len(completed.stdout.splitlines()) == 1
    assert sorted(os.listdir(tmp_path / "out")) == ["disk_contours.csv", "disk_mask.png",
                                                    "disk_overlay.png"]
    assert synthetic.dice(io.read_mask(tmp_path / "out" / "disk_mask.png"), truth) > 0.95
    csv_rows = (tmp_path / "out" / "disk_contours.csv").read_text().splitlines()
    meta = json.loads(csv_rows[1].split(":", 1)[1])
    assert meta["image_shape"] == list(SIZE)


@pytest.mark.parametrize("backend, init", [("polygon", "--init-grid"), ("levelset", "--init-grid"),
                                           ("levelset", "--init-checkerboard")])
def test_grid_and_checkerboard_starts(small, tmp_path, capsys, backend, init):
    path, truth = small
    status, _, stderr = run(capsys, "segment", path, "-o", tmp_path / "out", "--backend", backend, init)
    assert status == 0, stderr
    assert synthetic.dice(io.read_mask(tmp_path / "out" / "disk_mask.png"), truth) > 0.95


def test_backend_options_reach_the_solver(small, tmp_path, capsys):
    path, _ = small
    status, stdout, stderr = run(capsys, "segment", path, "-o", tmp_path / "a", "--option", "max_step=0.5",
                                 "--option", "nucleate=false", "--max-iter", 2)
    assert status == 0, stderr
    assert summary_fields(stdout)["iterations"] == "2"
    for argv, words in (
        (["--option", "bogus=1"], ["unknown option", "bogus", "max_step"]),
        (["--option", "bogus"], ["KEY=VALUE"]),
        (["--init-checkerboard"], ["--backend levelset"]),
    ):
        status, _, stderr = run(capsys, "segment", path, "-o", tmp_path / "b", *argv)
        assert_one_line_error(status, stderr, *words)
        assert not (tmp_path / "b").exists()


def test_a_failing_image_is_reported_and_the_batch_goes_on(small, tmp_path, capsys):
    path, truth = small
    second = tmp_path / "in" / "second.png"
    shutil.copy(path, second)
    text = bad_text_image(tmp_path / "in")
    out = tmp_path / "out"
    status, stdout, stderr = run(capsys, "segment", path, text, second, "-o", out)
    assert status == 2
    errors = stderr.splitlines()
    assert errors == [f"activecontour: error: cannot read image {str(text)!r}: the file holds text, "
                      "not an image",
                      "activecontour: error: 1 of 3 images failed; the others were written"]
    # with --jobs (every core by default) the summary lines come in the order the images finish
    assert sorted(line.split(":")[0] for line in stdout.splitlines()) == ["disk.png", "second.png"]
    assert sorted(os.listdir(out)) == sorted(
        f"{stem}_{kind}" for stem in ("disk", "second")
        for kind in ("mask.png", "overlay.png", "contours.json"))
    assert synthetic.dice(io.read_mask(out / "second_mask.png"), truth) > 0.95


def test_an_image_whose_files_cannot_be_written_does_not_stop_the_next(small, tmp_path, capsys,
                                                                        monkeypatch):
    path, _ = small
    second = tmp_path / "in" / "second.png"
    shutil.copy(path, second)
    real_replace = os.replace

    def full_disk_for_disk_png(src, dst):
        if os.path.basename(dst) == "disk_contours.json":
            raise OSError(28, "No space left on device", str(dst))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", full_disk_for_disk_png)
    # --jobs 1: the patched os.replace is this process's; the workers of --jobs 2 would have it only
    # when forked, not from a fork server (chosen once this process runs threads, as under
    # pytest-xdist). Workers that fail to write: test_cli_batch's failing-images test.
    status, stdout, stderr = run(capsys, "segment", path, second, "-o", tmp_path / "out", "--jobs", "1")
    assert status == 2
    assert stderr.splitlines()[0].endswith(f"No space left on device: "
                                           f"{str(tmp_path / 'out' / 'disk_contours.json')!r}")
    assert sorted(os.listdir(tmp_path / "out")) == ["second_contours.json", "second_mask.png",
                                                    "second_overlay.png"]
    assert stdout.startswith("second.png: ")


@pytest.mark.parametrize(
    "option, message",
    [
        # the library's message (the options dataclass states each rule once), the option named
        ("smoothing=abc", "--option smoothing: option 'smoothing' must be a number or None, got 'abc' "
                          "(backend 'polygon')"),
        ("smoothing=inf", "--option smoothing: smoothing and min_smoothing must be pixel lengths with "
                          "smoothing >= min_smoothing >= 0, got inf and 1.0"),
        ("nucleate=3", "--option nucleate: option 'nucleate' must be True or False, got 3 (backend "
                       "'polygon')"),
        ("velocity=1", "--option velocity: option 'velocity' must be text, got 1 (backend 'polygon')"),
    ],
)
def test_backend_option_of_the_wrong_kind_gets_one_true_line(small, tmp_path, capsys, option, message):
    path, _ = small
    status, stdout, stderr = run(capsys, "segment", path, "-o", tmp_path / "out", "--option", option)
    assert (status, stdout, stderr) == (2, "", f"activecontour: error: {message}\n")
    assert not (tmp_path / "out").exists()


def test_summary_of_an_unconverged_run_says_why(small, tmp_path, capsys):
    from activecontour.result import STATUS_MESSAGES

    path, _ = small
    status, stdout, _ = run(capsys, "segment", path, "-o", tmp_path / "out", "--max-iter", 2)
    assert status == 0
    assert f"success=False ({STATUS_MESSAGES[1].rstrip('.')}) output=" in stdout


def test_progress_shows_file_k_of_n_elapsed_and_time_left():
    import io as stdio

    now = [0.0]
    stream = stdio.StringIO()
    progress = ImageProgress(3, stream=stream, clock=lambda: now[0])
    progress.start(1, "/data/a.png")
    assert "[1/3] a.png: loading" in stream.getvalue() and "elapsed 0:00 left ?" in stream.getvalue()
    now[0] = 4.0
    progress(types.SimpleNamespace(iteration=5, max_num_iter=10, energy=1.5))
    assert stream.getvalue().endswith("iteration 5 energy 1.5         elapsed 0:04 left ?")
    now[0] = 10.0
    progress.start(2, "/data/b.png")  # a.png took 10 s: b.png and c.png should take 20 s more
    assert stream.getvalue().endswith("[2/3] b.png: loading elapsed 0:10 left ~0:20")
    now[0] = 13.0
    progress(types.SimpleNamespace(iteration=1, max_num_iter=10, energy=2.0))
    assert stream.getvalue().endswith("elapsed 0:13 left ~0:17")
    progress.clear()
    assert stream.getvalue().endswith("\r\033[K")


def test_progress_of_a_single_image_shows_no_time_left_and_no_bar_scaled_to_max_num_iter():
    # a run stops on tol long before max_num_iter: a bar and a bound scaled to it never moved and
    # said "left 8:43" at iteration 2 of a run that ended after 8 s (issue 22)
    import io as stdio

    now = [0.0]
    stream = stdio.StringIO()
    progress = ImageProgress(1, stream=stream, clock=lambda: now[0])
    progress.start(1, "/data/a.png")
    assert stream.getvalue().endswith("[1/1] a.png: loading elapsed 0:00")
    now[0] = 2.0
    progress(types.SimpleNamespace(iteration=1, max_num_iter=500, energy=3.0))
    now[0] = 6.0
    progress(types.SimpleNamespace(iteration=21, max_num_iter=500, energy=2.0))
    assert stream.getvalue().endswith("[1/1] a.png: iteration 21 energy 2           elapsed 0:06")
    assert "left" not in stream.getvalue() and "#" not in stream.getvalue() and "500" not in stream.getvalue()


def test_interrupt_while_writing_restores_everything(small, tmp_path, capsys, monkeypatch):
    path, _ = small
    out = tmp_path / "out"
    real_replace = os.replace

    def interrupted_replace(src, dst):
        if str(dst).endswith("_overlay.png"):
            raise KeyboardInterrupt
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", interrupted_replace)
    status, stdout, stderr = run(capsys, "segment", path, "-o", out)
    assert (status, stdout, stderr) == (130, "", "activecontour: interrupted\n")
    assert not out.exists()


_SLOW_SEGMENT = """
import sys
import numpy as np
from app import cli
import activecontour
from activecontour import _kernels

def slow_segment(*args, **kwargs):
    # a compiled loop that never looks at signals: 10^11 point-edge tests in winding()
    points = np.random.default_rng(0).random((300_000, 2))
    next_index = np.roll(np.arange(len(points)), -1)
    print("segmenting", file=sys.stderr, flush=True)
    _kernels.winding(points, next_index, points, np.zeros(len(points), dtype=np.int64))

activecontour.segment = slow_segment
sys.argv[0] = "activecontour"
sys.exit(cli.console_script())
"""


def test_ctrl_c_during_a_compiled_kernel_ends_the_run_within_a_second(small, tmp_path):
    import signal
    import time

    path, _ = small
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-c", _SLOW_SEGMENT, "segment", str(path), "-o", str(out)],
        cwd=Path(__file__).resolve().parents[2], stderr=subprocess.PIPE, text=True,
        preexec_fn=sigint_as_in_a_terminal,
    )
    try:
        assert process.stderr.readline() == "segmenting\n"
        time.sleep(0.2)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        process.wait(timeout=30)
        answered = time.monotonic() - sent
    finally:
        process.kill()
        process.wait()
    assert process.returncode in (-signal.SIGINT, 130)
    assert answered < 1.0
    assert not out.exists()


@pytest.mark.parametrize("command", ["segment", "view"])
def test_help_says_what_the_default_start_is(command, capsys):
    import activecontour as ac

    status, out, _ = run(capsys, command, "--help")
    assert status == 0
    text = " ".join(out.split())
    assert "centred circle" not in text and "default_init" in text and "two-means" in text
    assert "centred circle" not in ac.segment.__doc__ and "default_init" in ac.segment.__doc__


_IMPORTED_BY_HELP = """
import contextlib, io, sys
from app import cli
for argv in (["--help"], ["segment", "--help"], ["view", "--help"], ["--version"],
             ["segment", "x.png", "--mu", "-1"]):
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        cli.main(argv)
print(" ".join(sorted(sys.modules)))
"""


def test_help_and_argument_errors_import_no_backend_and_no_image_library():
    completed = subprocess.run([sys.executable, "-c", _IMPORTED_BY_HELP], capture_output=True, text=True,
                               cwd=Path(__file__).resolve().parents[2], check=True)
    modules = set(completed.stdout.split())
    assert "app.cli.parser" in modules and "activecontour.settings" in modules  # it did build the parser
    heavy = {"scipy", "cv2", "skimage", "matplotlib", "shapely", "tifffile", "roifile"}
    assert not {name for name in modules if name.split(".")[0] in heavy}
    solvers = {"activecontour.backends." + name for name in ("polygon", "network", "labelfield", "levelset")}
    assert not modules & solvers
