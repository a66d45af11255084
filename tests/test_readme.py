"""README's Python examples run as written and do what their comments say."""

import re
from pathlib import Path

import pytest

from activecontour import synthetic

README = Path(__file__).resolve().parents[1] / "README.md"


def python_blocks():
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def run_blocks(*codes):
    namespace = {"__name__": "__main__"}  # the examples' `if __name__ == "__main__":` parts run too
    for code in codes:
        exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - our own documentation
    return namespace


def test_readme_python_example_runs():
    namespace = run_blocks(python_blocks()[0])
    assert synthetic.dice(namespace["res"].mask, namespace["truth"]) >= 0.98  # README says ~0.99


def test_readme_batch_examples_run():
    (many,) = [code for code in python_blocks() if "segment_many(" in code]
    namespace = run_blocks(many)
    assert sorted(namespace["dice"]) == [0, 1, 2, 3]
    assert all(value >= 0.98 for value in namespace["dice"].values())  # README says about 0.99
    pytest.importorskip("distributed")
    (on_dask,) = [code for code in python_blocks() if "segment_dask(" in code]
    namespace = run_blocks(many, on_dask)
    assert sorted(namespace["masks"]) == [0, 1, 2, 3]
    for index, mask in namespace["masks"].items():
        assert synthetic.dice(mask, namespace["scenes"][index][1]) >= 0.98
