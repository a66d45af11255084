"""README's Python examples run as written, in order, and do what their comments say."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_examples_run(tmp_path, monkeypatch):
    segmenting, saving = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(segmenting, "README.md", "exec"), namespace)  # noqa: S102 - our own documentation
    from activecontour import synthetic

    assert synthetic.dice(namespace["res"].mask, namespace["truth"]) >= 0.98  # README says ~0.99
    exec(compile(saving, "README.md", "exec"), namespace)  # noqa: S102
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == ["disk_contours.geojson", "disk_contours.json", "disk_contours.npz",
                       "disk_contours.svg", "disk_mask.png", "disk_overlay.png"]
    res = namespace["res"]
    assert all(np.array_equal(a, b) for a, b in zip(namespace["curves"], res.contours, strict=True))
    assert namespace["meta"]["image_shape"] == list(res.mask.shape)
    assert (tmp_path / "disk.geojson").is_file() and (tmp_path / "disk_mask.png").is_file()
