"""Packaging: the wheel installs the library and the front ends under the project's names only."""

from pathlib import Path

import pytest

import app.cli

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"


def test_the_front_ends_install_as_activecontour_app_not_app():
    config = tomllib.loads(PYPROJECT.read_text())
    setuptools = config["tool"]["setuptools"]
    library = Path(__file__).resolve().parents[1] / "activecontour"
    sub_packages = sorted(".".join(("activecontour",) + init.parent.relative_to(library).parts)
                          for init in library.rglob("__init__.py"))
    assert sorted(setuptools["packages"]) == sorted(sub_packages + ["activecontour_app"])
    assert setuptools["package-dir"] == {"activecontour_app": "app"}
    module, function = config["project"]["scripts"]["activecontour"].split(":")
    assert module == "activecontour_app.cli"
    assert callable(getattr(app.cli, function))  # the folder app/ is that package


def test_the_front_ends_import_each_other_relatively():
    # absolute "app." imports would break under the installed name activecontour_app
    for path in Path(app.__file__).parent.glob("*.py"):
        text = path.read_text()
        assert "from app" not in text and "import app" not in text, path.name
