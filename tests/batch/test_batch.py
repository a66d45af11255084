"""Many images at once: segment_many equals the serial loop, per-image errors, pickling, find_images."""

import dataclasses
import functools
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

import activecontour as ac
from activecontour import batch, synthetic
from tests.helpers import sigint_as_in_a_terminal

SIZE = (48, 56)


def disk_images(count, *, noise=0.08):
    """Noisy disks of different centres and radii, and their ground truths."""
    images, truths = [], []
    for k in range(count):
        shape = synthetic.disk((22.0 + 1.5 * k, 27.0 - k), 10.0 + 1.3 * k)
        image, truth = synthetic.render(shape, SIZE, inside=0.75, outside=0.25)
        images.append(synthetic.add_noise(image, noise, seed=k))
        truths.append(truth)
    return images, truths


def assert_same_result(a, b):
    """Every field of two SegmentationResults is equal, arrays exactly."""
    assert type(a) is type(b)
    for field in dataclasses.fields(a):
        first, second = getattr(a, field.name), getattr(b, field.name)
        if field.name == "contours":
            assert len(first) == len(second)
            assert all(np.array_equal(p, q) for p, q in zip(first, second, strict=True))
        elif first is None or second is None:
            assert first is None and second is None, field.name
        else:
            assert np.array_equal(first, second), field.name


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_result_and_segment_call_survive_pickling(backend):
    images, _ = disk_images(1)
    result = ac.segment(images[0], backend=backend, max_num_iter=30)
    copy = pickle.loads(pickle.dumps(result))
    assert_same_result(copy, result)
    assert repr(copy) == repr(result)
    # the call itself: the function and a partial of it, as a worker receives them
    call = pickle.loads(pickle.dumps(functools.partial(ac.segment, backend=backend, max_num_iter=30)))
    assert_same_result(call(images[0]), result)
    # a restored result is a valid init, giving what the original gives
    assert_same_result(ac.segment(images[0], copy, max_num_iter=5), ac.segment(images[0], result,
                                                                                 max_num_iter=5))


def test_segment_many_in_spawned_workers_equals_the_serial_loop(tmp_path):
    images, truths = disk_images(4)
    path = tmp_path / "disk.png"
    cv2.imwrite(str(path), np.round(np.clip(images[0], 0, 1) * 255).astype(np.uint8))
    inputs = [*images, path]
    serial = [ac.segment(image, mu=0.1) for image in images] + [ac.segment(ac.load_image(path), mu=0.1)]
    items = list(ac.segment_many(inputs, jobs=2, context="spawn", mu=0.1))
    assert sorted(item.index for item in items) == list(range(len(inputs)))
    for item in items:
        assert item.ok and item.error is None
        assert item.source == (str(path) if item.index == len(images) else None)
        assert_same_result(item.result, serial[item.index])
        if item.index < len(images):
            assert synthetic.dice(item.result.mask, truths[item.index]) > 0.95


def test_one_failing_image_does_not_stop_the_batch(tmp_path):
    images, truths = disk_images(3)
    bad = np.full(SIZE, np.nan)
    inputs = [images[0], bad, tmp_path / "missing.png", images[1], images[2]]
    items = {item.index: item for item in ac.segment_many(inputs, jobs=2, max_num_iter=200)}
    assert sorted(items) == list(range(5))
    assert isinstance(items[1].error, ValueError) and "NaN" in str(items[1].error)
    assert items[1].result is None and not items[1].ok
    assert isinstance(items[2].error, FileNotFoundError) and "missing.png" in str(items[2].error)
    assert items[2].source == str(tmp_path / "missing.png")
    for index, image, truth in zip((0, 3, 4), images, truths, strict=True):
        assert items[index].ok
        assert_same_result(items[index].result, ac.segment(image, max_num_iter=200))
        assert synthetic.dice(items[index].result.mask, truth) > 0.95


def test_jobs_1_runs_in_order_in_this_process():
    images, _ = disk_images(3)
    seen = []

    def generator():  # a generator of arrays, consumed lazily; a closure could not be pickled
        for image in images:
            seen.append(len(seen))
            yield image

    items = list(ac.segment_many(generator(), jobs=1, max_num_iter=20))
    assert [item.index for item in items] == [0, 1, 2] and seen == [0, 1, 2]
    outcomes = list(batch.map_unordered(lambda x: 10 // x, [5, 0, 2], jobs=1))
    assert [index for index, _ in outcomes] == [0, 1, 2]
    assert outcomes[0][1] == (2, None) and outcomes[2][1] == (5, None)
    assert outcomes[1][1][0] is None and isinstance(outcomes[1][1][1], ZeroDivisionError)


def test_a_generator_is_consumed_one_item_per_worker_at_a_time():
    pulled = []

    def numbers():
        for k in range(12):
            pulled.append(k)
            yield k

    outcomes = batch.map_unordered(abs, numbers(), jobs=2)
    first = next(outcomes)
    assert len(pulled) <= 2
    rest = list(outcomes)
    assert sorted([first[0]] + [index for index, _ in rest]) == list(range(12))
    assert all(value == index and error is None for index, (value, error) in [first, *rest])


def _exit_on_three(x):
    if x == 3:
        os._exit(1)  # a worker dying (killed, out of memory) rather than raising
    return x


def _exit_on_one(x):
    if x == 0:
        time.sleep(1.0)  # as a rule in flight when item 1's worker dies
    if x == 1:
        os._exit(1)
    return x


def test_a_dead_worker_fails_only_the_items_in_flight_and_the_rest_go_to_a_new_pool():
    from concurrent.futures.process import BrokenProcessPool

    outcomes = dict(batch.map_unordered(_exit_on_one, range(6), jobs=2))
    assert sorted(outcomes) == list(range(6))
    assert isinstance(outcomes[1][1], BrokenProcessPool)
    failed = {k for k, (_, error) in outcomes.items() if error is not None}
    # at most the two in flight when item 1's worker died: item 0 as a rule, but on a loaded
    # machine item 0 may finish first (a slow worker start) and item 2 be the one in flight
    assert len(failed) <= 2
    assert all(isinstance(outcomes[k][1], BrokenProcessPool) for k in failed)
    assert all(outcomes[k] == (k, None) for k in set(range(6)) - failed)  # the rest: a new pool


def test_a_dead_worker_fails_items_but_not_the_iteration():
    from concurrent.futures.process import BrokenProcessPool

    outcomes = dict(batch.map_unordered(_exit_on_three, range(8), jobs=2))
    assert sorted(outcomes) == list(range(8))
    assert isinstance(outcomes[3][1], BrokenProcessPool)
    for index, (value, error) in outcomes.items():
        assert (value, error) == (index, None) or isinstance(error, BrokenProcessPool)


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        ({"images": "folder"}, TypeError, ["single str", "find_images"]),
        ({"images": np.zeros((3, 8, 8))}, TypeError, ["one ndarray", "list"]),
        ({"images": 3}, TypeError, ["iterable", "int"]),
        ({"jobs": 0}, ValueError, ["jobs", ">= 1"]),
        ({"jobs": 1.5}, ValueError, ["jobs"]),
        ({"context": "threads"}, ValueError, ["context", "spawn"]),
        ({"mux": 0.1}, TypeError, ["mux"]),
        ({"callback": print}, TypeError, ["callback"]),
    ],
)
def test_bad_arguments_are_refused_before_any_work(kwargs, error, words):
    arguments = {"images": [np.zeros(SIZE)], **kwargs}
    with pytest.raises(error) as info:
        ac.segment_many(**arguments)  # raised by the call, not on the first next()
    for word in words:
        assert word in str(info.value)


def write_files(folder, names):
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        (folder / name).write_bytes(b"")
    return folder


def test_image_files_lists_folders_and_expands_patterns(tmp_path):
    folder = write_files(tmp_path / "data", ["b.tif", "a.png", "C.JPG", "notes.txt", "c.png",
                                             "c_mask.png", "c_overlay.png", "lone_mask.png"])
    (folder / "sub").mkdir()
    write_files(folder / "sub", ["d.png"])
    expected = [str(folder / n) for n in ["C.JPG", "a.png", "b.tif", "c.png", "lone_mask.png"]]
    assert batch.find_images(folder) == expected  # sorted, images only, no outputs, not recursive
    assert batch.find_images(str(folder / "*.png")) == [str(folder / n) for n in
                                                        ["a.png", "c.png", "lone_mask.png"]]
    assert batch.find_images(str(tmp_path / "**" / "d.png")) == [str(folder / "sub" / "d.png")]
    # a named file is taken as it is, and a file named twice comes once
    named = folder / "c_mask.png"
    assert batch.find_images(named, folder / "a.png", named) == [str(named), str(folder / "a.png")]
    with pytest.raises(ValueError, match="no file matches"):
        batch.find_images(str(folder / "*.bmp"))
    with pytest.raises(FileNotFoundError, match="missing.png"):
        batch.find_images(folder / "missing.png")
    empty = write_files(tmp_path / "empty", ["readme.txt"])
    with pytest.raises(ValueError, match="no image files"):
        batch.find_images(empty)


def test_a_process_with_threads_is_not_forked():
    import multiprocessing
    import threading

    if multiprocessing.get_start_method() != "fork":
        pytest.skip("the platform does not fork by default")
    assert batch.pool._start_context(None).get_start_method() == (
        "fork" if threading.active_count() == 1 else "forkserver")
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert batch.pool._start_context(None).get_start_method() == "forkserver"
    finally:
        stop.set()
        thread.join()


def test_default_jobs_is_the_usable_cores():
    expected = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert batch.default_jobs() == expected


INTERRUPTED_BATCH = """
import sys, time
import numpy as np
import activecontour as ac
if __name__ == "__main__":
    from activecontour import synthetic
    image, _ = synthetic.render(synthetic.disk((22.0, 27.0), 11.0), (48, 56), inside=0.75, outside=0.25)
    images = [synthetic.add_noise(image, 0.05, seed=k) for k in range(4)]  # tol 0: never converge
    started = time.monotonic()
    print("started", flush=True)
    try:
        list(ac.segment_many(images, jobs=2, context="spawn", max_num_iter=10**6, tol=0))
    except KeyboardInterrupt:
        print(f"interrupted {time.monotonic() - started:.1f}")
"""


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="process groups are POSIX")
def test_ctrl_c_while_spawned_workers_start_stops_them_quietly(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    script = tmp_path / "interrupted.py"
    script.write_text(INTERRUPTED_BATCH)
    root = Path(__file__).resolve().parents[2]
    process = subprocess.Popen([sys.executable, str(script)], cwd=root,
                               env={**os.environ, "PYTHONPATH": str(root)}, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True,
                               preexec_fn=sigint_as_in_a_terminal)
    try:
        assert process.stdout.readline() == "started\n"  # imports done (slow on a loaded machine)
        time.sleep(0.5)  # the parent has started the pool; the workers are still importing
        os.killpg(process.pid, signal.SIGINT)  # Ctrl-C: every process of the group
        stdout, stderr = process.communicate(timeout=60)  # an image alone would take minutes
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert stdout.startswith("interrupted"), (stdout, stderr)
    assert "Traceback" not in stderr, stderr


SLEEPING_BATCH = """
import os, sys, time
from activecontour import batch

def sleep_long(item):
    open(os.path.join(sys.argv[1], str(os.getpid())), "w").close()
    time.sleep(60)
    return item

if __name__ == "__main__":
    started = time.monotonic()
    print("started", flush=True)
    try:
        list(batch.map_unordered(sleep_long, range(4), jobs=2))
    except KeyboardInterrupt:
        print(f"interrupted {time.monotonic() - started:.1f}", flush=True)
"""


def _start_sleeping_batch(tmp_path):
    """A batch whose two workers sleep a minute per item; returns the process and the worker pids."""
    script, pids = tmp_path / "sleeping.py", tmp_path / "pids"
    script.write_text(SLEEPING_BATCH)
    pids.mkdir()
    root = Path(__file__).resolve().parents[2]
    process = subprocess.Popen([sys.executable, str(script), str(pids)], cwd=root,
                               env={**os.environ, "PYTHONPATH": str(root)}, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True,
                               preexec_fn=sigint_as_in_a_terminal)
    assert process.stdout.readline() == "started\n"
    deadline = time.monotonic() + 30
    while len(list(pids.iterdir())) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    return process, [int(p.name) for p in pids.iterdir()]


def _running(pid):
    """True while the process exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="reads /proc")
def test_sigint_to_the_parent_alone_stops_the_workers_promptly(tmp_path):
    process, workers = _start_sleeping_batch(tmp_path)
    try:
        assert len(workers) == 2
        sent = time.monotonic()
        os.kill(process.pid, signal.SIGINT)  # the parent only, not its group: the workers sleep on
        stdout, stderr = process.communicate(timeout=30)  # before: 60 s, the images in flight
        waited = time.monotonic() - sent
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert stdout.startswith("interrupted"), (stdout, stderr)
    assert waited < 10, waited
    assert not any(_running(pid) for pid in workers)


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="reads /proc")
def test_workers_die_with_their_parent_killed_by_sigkill(tmp_path):
    process, workers = _start_sleeping_batch(tmp_path)
    try:
        assert len(workers) == 2
        process.kill()  # kill -9: no cleanup in the parent at all
        process.wait()
        deadline = time.monotonic() + 10
        while any(_running(pid) for pid in workers) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not any(_running(pid) for pid in workers)  # before: a minute, holding the pipes
        assert process.stdout.read() == ""  # the pipe closes: no worker holds it open
    finally:
        for pid in workers:
            if _running(pid):
                os.kill(pid, signal.SIGKILL)
