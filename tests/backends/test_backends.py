"""The backend registry and the backends' options dataclasses (one statement of each option)."""

import dataclasses

import numpy as np
import pytest

import activecontour as ac
from activecontour.backends import BACKENDS, SOLVERS
from activecontour.backends import levelset as levelset_package
from activecontour.backends.options import option
from activecontour.geometry.curve import edge_lengths
from app import cli

SHAPE = (64, 64)


def _disk_image(radius=15.0):
    rows, cols = np.indices(SHAPE)
    return ((rows - 32.0) ** 2 + (cols - 32.0) ** 2 <= radius**2).astype(float)


def test_registry_lists_both_backends_with_their_options_and_functions():
    assert set(BACKENDS) == {"polygon", "levelset"}
    from activecontour.backends.polygon import PolygonOptions, segment_polygon

    assert BACKENDS["polygon"].options is PolygonOptions
    assert BACKENDS["polygon"].run is segment_polygon
    assert BACKENDS["levelset"].options is levelset_package.LevelSetOptions
    assert BACKENDS["levelset"].run is levelset_package.segment_levelset
    for backend in BACKENDS.values():
        assert dataclasses.is_dataclass(backend.options)
        with pytest.raises(dataclasses.FrozenInstanceError):
            first = dataclasses.fields(backend.options)[0].name
            setattr(backend.options(), first, None)
        # every option documented, of a kind the CLI and the viewer can show
        for spec in backend.option_specs():
            assert spec.help and spec.kind in (bool, int, float, str)


def test_option_specs_read_types_defaults_and_choices():
    specs = {spec.name: spec for spec in BACKENDS["polygon"].option_specs()}
    smoothing = specs["smoothing"]
    assert (smoothing.kind, smoothing.optional, smoothing.default) == (float, True, None)
    assert specs["velocity"].choices == ("h1", "l2")
    assert (specs["nucleate"].kind, specs["nucleate"].default) == (bool, True)
    levelset = {spec.name: spec for spec in BACKENDS["levelset"].option_specs()}
    assert (levelset["max_backtracks"].kind, levelset["max_backtracks"].optional) == (int, False)
    assert levelset_package.DEFAULT_OPTIONS == {name: spec.default for name, spec in levelset.items()}


def _with_default(options_class, name, default):
    """The options class with one default changed (a subclass: same fields, same order)."""
    return dataclasses.make_dataclass(options_class.__name__, [(name, float, option(default, "changed"))],
                                      bases=(options_class,), frozen=True)


def _change_default(monkeypatch, backend, name, default):
    """The registry's record of ``backend`` with one default of its options changed."""
    record = BACKENDS[backend]
    changed = dataclasses.replace(record, options=_with_default(record.options, name, default))
    monkeypatch.setitem(SOLVERS, record.name, changed)


def test_levelset_reads_its_defaults_from_the_dataclass(monkeypatch):
    # phi is clipped to +-band: the default band is what the backend uses
    image = _disk_image()
    result = ac.segment(image, backend="levelset", max_num_iter=3)
    assert np.max(np.abs(result.phi)) == levelset_package.LevelSetOptions().band
    _change_default(monkeypatch, "levelset", "band", 6.0)
    result = ac.segment(image, backend="levelset", max_num_iter=3)
    assert np.max(np.abs(result.phi)) == 6.0


def test_polygon_reads_its_defaults_from_the_dataclass(monkeypatch):
    # a start's edges longer than 2 spacing are split (a dense start is coarsened only where that
    # lowers the energy, issue 22): from 12 edges of 10.4 px, the default spacing of 1 px gives
    # edges under 2 px and a changed default spacing of 4 px edges over 2 px, without any option
    image = _disk_image()
    init = ac.circle((32.0, 32.0), 20.0, 12)

    def mean_edge():
        result = ac.segment(image, init, max_num_iter=5)
        return np.mean(np.concatenate([edge_lengths(c) for c in result.contours]))

    assert 0.5 < mean_edge() < 2.0  # the default, 1 px
    _change_default(monkeypatch, "polygon", "spacing", 4.0)
    assert 2.0 < mean_edge() < 8.0


@pytest.mark.parametrize("backend", sorted(BACKENDS))
def test_unknown_option_names_the_backend_and_lists_every_field(backend):
    with pytest.raises(TypeError, match=f"unknown option.s. 'bogus' for backend '{backend}'") as info:
        ac.segment(_disk_image(), backend=backend, options={"bogus": 1})
    listed = str(info.value).split("the valid options are ")[1].split(", ")
    assert listed == sorted(field.name for field in dataclasses.fields(BACKENDS[backend].options))


@pytest.mark.parametrize(("backend", "options", "error", "match"), [
    ("polygon", {"nucleate": "yes"}, TypeError, "option 'nucleate' must be True or False.*'polygon'"),
    ("polygon", {"spacing": "1"}, TypeError, "option 'spacing' must be a number"),
    ("polygon", {"smoothing": None}, None, None),  # None is valid: chosen by the backend
    ("polygon", {"velocity": 2}, TypeError, "option 'velocity' must be text"),
    ("levelset", {"max_backtracks": "3"}, TypeError, "option 'max_backtracks' must be an integer"),
    ("levelset", {"dt": None}, TypeError, "option 'dt' must be a number, got None.*'levelset'"),
])
def test_option_types_are_checked_by_the_dataclass(backend, options, error, match):
    if error is None:
        ac.segment(_disk_image(), backend=backend, options=options, max_num_iter=1)
        return
    with pytest.raises(error, match=match):
        ac.segment(_disk_image(), backend=backend, options=options, max_num_iter=1)


def test_cli_help_lists_every_backend_option_from_the_dataclass(capsys):
    assert cli.main(["segment", "--help"]) == 0
    text = capsys.readouterr().out
    for name, backend in BACKENDS.items():
        assert f"--backend {name}:" in text
        for spec in backend.option_specs():
            shown = "automatic" if spec.default is None else str(spec.default).lower() \
                if spec.kind is bool else str(spec.default)
            assert f"    {spec.name}={shown}: " in text
