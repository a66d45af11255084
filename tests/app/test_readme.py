"""README's and the docs pages' Python examples run as written, in order, and do what their comments say."""

import re
from pathlib import Path

import numpy as np
import pytest

from activecontour import synthetic

README = Path(__file__).resolve().parents[2] / "README.md"
#: The pages README links, in the order a reader meets them.
PAGES = [README] + [README.parent / "docs" / f"{name}.md" for name in (
    "python", "command-line", "formats", "objects", "many-images", "sequences", "scikit-image", "method",
    "performance")]


def python_blocks():
    """Every ```python block of README and its pages, in reading order."""
    return [block for page in PAGES
            for block in re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)]


def test_every_page_readme_links_exists_and_is_listed_here():
    linked = re.findall(r"\]\((docs/[^)#]+\.md)\)", README.read_text())
    assert sorted(README.parent / link for link in linked if "gallery" not in link) == sorted(PAGES[1:])


def run_blocks(*codes, namespace=None):
    namespace = {"__name__": "__main__"} if namespace is None else namespace
    for code in codes:  # the examples' `if __name__ == "__main__":` parts run too
        exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - our own documentation
    return namespace


def test_readme_python_examples_run(tmp_path, monkeypatch):
    (segmenting,) = [code for code in python_blocks() if "synthetic.add_noise(image, 0.25" in code]
    (saving,) = [code for code in python_blocks() if "io.save_result(res, image, \"out/disk\")" in code]
    monkeypatch.chdir(tmp_path)
    namespace = run_blocks(segmenting)
    assert synthetic.dice(namespace["res"].mask, namespace["truth"]) >= 0.98  # README says ~0.99
    run_blocks(saving, namespace=namespace)
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == ["disk_contours.geojson", "disk_contours.json", "disk_contours.npz",
                       "disk_contours.svg", "disk_mask.png", "disk_overlay.png"]
    res = namespace["res"]
    assert all(np.array_equal(a, b) for a, b in zip(namespace["curves"], res.contours, strict=True))
    assert namespace["meta"]["image_shape"] == list(res.mask.shape)
    assert (tmp_path / "disk.geojson").is_file() and (tmp_path / "disk_mask.png").is_file()


@pytest.mark.xdist_group("dask")  # beside tests/batch/test_dask.py's cluster, never at the same time
def test_readme_batch_examples_run(restore_environ):
    (many,) = [code for code in python_blocks() if "segment_many(" in code]
    namespace = run_blocks(many)
    assert sorted(namespace["dice"]) == [0, 1, 2, 3]
    assert all(value >= 0.98 for value in namespace["dice"].values())  # README says about 0.99
    pytest.importorskip("distributed")
    (on_dask,) = [code for code in python_blocks() if "segment_dask(" in code]
    namespace = run_blocks(on_dask, namespace=namespace)  # "continues the example above"
    assert sorted(namespace["masks"]) == [0, 1, 2, 3]
    for index, mask in namespace["masks"].items():
        assert synthetic.dice(mask, namespace["scenes"][index][1]) >= 0.98


def test_readme_summary_line_is_what_the_first_command_prints(tmp_path, monkeypatch, capsys):
    import shutil

    from app import cli

    text = README.read_text()
    (command,) = re.findall(r"&& (activecontour segment \S+ -o \S+)\n", text)
    (line,) = [ln for ln in re.findall(r"```text\n(.*?)```", text, flags=re.S)[0].splitlines() if ln]
    (tmp_path / "sample_images").mkdir()
    shutil.copy(README.parent / "sample_images" / "disk_noisy.png", tmp_path / "sample_images")
    monkeypatch.chdir(tmp_path)
    assert cli.main(command.split()[1:]) == 0
    printed = capsys.readouterr().out.strip()
    timing = r"time=\d+\.\d\ds"
    assert re.sub(timing, "time=", printed) == re.sub(timing, "time=", line), (
        f"README's summary line should read:\n{printed}")


def test_the_gallery_page_shows_figures_the_script_wrote():
    docs = README.parent / "docs"
    assert "docs/gallery.md" in README.read_text() and "docs/gallery/" in README.read_text()
    page = (docs / "gallery.md").read_text()
    figures = re.findall(r"!\[[^\]]*\]\((gallery/[^)]+\.png)\)", page)
    assert len(figures) >= 10 and all((docs / figure).is_file() for figure in figures)
    assert sum((docs / figure).stat().st_size for figure in figures) < 3e6
    assert "nuclei" in page and "make_gallery.py" in page


def test_readme_objects_example_runs():
    (objects,) = [code for code in python_blocks() if "res.labels" in code and "roi=" in code]
    namespace = run_blocks(objects)
    assert namespace["score"]["f1"] >= 0.95  # README says ~0.98
    res, one, truth = namespace["res"], namespace["one"], namespace["truth"]
    assert len(res.objects["area"]) == res.labels.max()
    assert one.labels.max() == 1 and not (one.mask & ~one.roi).any()
    # the drawn disk covers a clump: the object holding most of the disk comes back alone
    row, col, radius = map(float, re.search(r"ac\.circle\(\((\d+), (\d+)\), (\d+)\)", objects).groups())
    rows, cols = np.indices(truth.shape)
    disk = np.hypot(rows - row, cols - col) <= radius
    held = np.bincount(truth[disk], minlength=truth.max() + 1)[1:]
    assert np.sort(held)[-2] > 0  # the disk does hold two objects
    pointed = truth == held.argmax() + 1
    assert synthetic.dice(one.mask, pointed) >= 0.95 and not (one.mask & (truth > 0) & ~pointed).any()
