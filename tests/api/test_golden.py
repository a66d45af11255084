"""The golden check (benchmarks/golden.py): the outputs of a fixed corpus hash as stored.

By default three of its cheapest cases run here; the whole corpus (about a hundred cases) is
marked slow: ``pytest -m slow tests/api/test_golden.py``, or ``python3 benchmarks/golden.py``.
"""

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "golden.py"

#: Three of the fastest stored cases (0.2-0.3 s of CPU each): both backends, K = 2 and 3.
CHEAP = ["segment/cell/polygon/K2", "segment/colorwheel/polygon/K2", "segment/checkerboard/levelset/K3"]


def load_golden():
    spec = importlib.util.spec_from_file_location("golden_check", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def golden():
    return load_golden()


def test_loading_the_script_leaves_the_environment_alone(monkeypatch):
    """The pin is the script's: a test process that loads it keeps its environment, so the workers
    it starts run its kernels (a pinned environment made segment_many's spawned workers compute
    other last bits than the test process, and a batch test failed after this file's tests)."""
    for name in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "OPENCV_CPU_DISABLE"):
        monkeypatch.delenv(name, raising=False)
    before = dict(os.environ)
    load_golden()
    assert dict(os.environ) == before


def test_every_case_is_stored(golden):
    stored = golden.load_golden()
    assert list(stored) == golden.case_names()
    assert len(stored) == len(golden.SAMPLES) * 4 + 1 + len(golden.FILE_CASES)


def test_cheap_cases_are_unchanged():
    """In a fresh process: golden.py pins the BLAS, numpy and OpenCV kernels before numpy is imported
    (its PINNED), which this process, numpy loaded, cannot do; in here the objects table of cell
    hashed differently on an AMD EPYC than on the machine that stored it."""
    only = [arg for name in CHEAP for arg in ("--only", name)]
    run = subprocess.run([sys.executable, str(SCRIPT), "-j", "1", *only], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
    assert sum(line.endswith(" same") for line in run.stdout.splitlines()) == len(CHEAP), run.stdout


def test_the_kernels_are_pinned_before_numpy_loads():
    code = (f"import runpy, sys; sys.argv = ['golden.py', '--list']\n"
            f"try: runpy.run_path({str(SCRIPT)!r}, run_name='__main__')\n"
            "except SystemExit: pass\n"
            "import numpy as np; info = np.lib.introspect.opt_func_info('exp', 'float64'); "
            "print(info['exp']['dd']['current'])")
    env = {key: value for key, value in os.environ.items()
           if key not in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "OPENCV_CPU_DISABLE")}
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert "V4" not in run.stdout and "AVX512" not in run.stdout, run.stdout


@pytest.mark.slow
def test_whole_corpus_is_unchanged():
    run = subprocess.run([sys.executable, str(SCRIPT), "-j", "2"], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
