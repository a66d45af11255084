"""Packaging: the wheel installs the library and the front ends under the project's names only."""

from pathlib import Path

import pytest

import app.cli

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def test_the_front_ends_install_as_activecontour_app_not_app():
    config = tomllib.loads(PYPROJECT.read_text())
    setuptools = config["tool"]["setuptools"]
    packages = setuptools["packages"]
    assert {"activecontour", "activecontour_app"} <= set(packages)
    assert all(name.split(".")[0] in ("activecontour", "activecontour_app") for name in packages)
    # every sub-package of the library is listed, or the wheel would leave it out
    library = PYPROJECT.parent / "activecontour"
    found = {".".join(path.parent.relative_to(PYPROJECT.parent).parts)
             for path in library.rglob("__init__.py") if "build" not in path.parts}
    assert found <= set(packages), found - set(packages)
    assert setuptools["package-dir"] == {"activecontour_app": "app"}
    # and every sub-package of the front ends, under the installed name
    front_ends = {"activecontour_app." + ".".join(path.parent.relative_to(PYPROJECT.parent / "app").parts)
                  for path in (PYPROJECT.parent / "app").rglob("*/__init__.py")}
    assert front_ends and front_ends <= set(packages), front_ends - set(packages)
    module, function = config["project"]["scripts"]["activecontour"].split(":")
    assert module == "activecontour_app.cli"
    assert callable(getattr(app.cli, function))  # the folder app/ is that package


def test_the_front_ends_import_each_other_relatively():
    # absolute "app." imports would break under the installed name activecontour_app
    for path in Path(app.__file__).parent.rglob("*.py"):
        text = path.read_text()
        assert "from app" not in text and "import app" not in text, path.name
