"""The golden check (benchmarks/golden.py): the outputs of a fixed corpus hash as stored.

By default three of its cheapest cases run here; the whole corpus (about a hundred cases) is
marked slow: ``pytest -m slow tests/api/test_golden.py``, or ``python3 benchmarks/golden.py``.
"""

import importlib.util
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


def test_every_case_is_stored(golden):
    stored = golden.load_golden()
    assert list(stored) == golden.case_names()
    assert len(stored) == len(golden.SAMPLES) * 4 + 1 + len(golden.FILE_CASES)


@pytest.mark.parametrize("name", CHEAP)
def test_cheap_case_is_unchanged(golden, name):
    stored = golden.load_golden()[name]
    name, parts, summary, seconds, error = golden.run_case(name)
    assert error is None, error
    assert golden.compare(name, parts, stored) == "same"


@pytest.mark.slow
def test_whole_corpus_is_unchanged():
    run = subprocess.run([sys.executable, str(SCRIPT), "-j", "2"], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
