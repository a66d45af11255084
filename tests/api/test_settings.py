"""The settings: every rule of segment's keywords stated once, read the same by every front door."""

import dataclasses
import inspect
import subprocess
import sys

import numpy as np
import pytest

import activecontour as ac
from activecontour.backends import BACKENDS, INITS, SOLVERS, solver_for
from activecontour.backends.options import NoOptions, option_specs
from activecontour.settings import KINDS, Settings, setting_specs

IMAGE = np.zeros((40, 50))
IMAGE[10:30, 15:35] = 1.0

CHANNELS = r"a finite number > 0 or one per channel"
CONSTANT = r"None, a finite number or one per channel"
ROI = r"roi must be None, 'init', a bool mask or a box"


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"backend": "snake"}, ValueError, r"backend must be one of \('polygon', 'levelset'\), got 'snake'"),
        ({"mu": -1.0}, ValueError, r"mu must be a finite number >= 0 or 'auto', got -1.0"),
        ({"mu": "big"}, TypeError, r"mu must be a finite number >= 0 or 'auto', got 'big'"),
        ({"mu": np.inf}, ValueError, r"mu must be a finite number >= 0 or 'auto'"),
        ({"omega": np.nan}, ValueError, "omega must be a finite number"),
        ({"omega": "small"}, TypeError, "omega must be a finite number"),
        ({"lambda_in": 0.0}, ValueError, f"lambda_in must be {CHANNELS}"),
        ({"lambda_out": [1.0, -1.0]}, ValueError, f"lambda_out must be {CHANNELS}"),
        ({"lambda_in": [[1.0, 2.0]]}, ValueError, f"lambda_in must be {CHANNELS}"),
        ({"lambda_out": "one"}, TypeError, f"lambda_out must be {CHANNELS}"),
        ({"max_num_iter": 2.5}, TypeError, "max_num_iter must be an integer >= 0"),
        ({"max_num_iter": True}, TypeError, "max_num_iter must be an integer >= 0"),
        ({"max_num_iter": -1}, ValueError, "max_num_iter must be an integer >= 0"),
        ({"tol": -1e-3}, ValueError, "tol must be a finite number >= 0"),
        ({"tol": "tight"}, TypeError, "tol must be a finite number >= 0"),
        ({"c_in": [np.nan]}, ValueError, f"c_in must be {CONSTANT}"),
        ({"c_out": "dark"}, TypeError, f"c_out must be {CONSTANT}"),
        ({"c_in": []}, ValueError, f"c_in must be {CONSTANT}"),
        ({"color": "hsv"}, ValueError, r"color must be one of \('gray', 'vector'\)"),
        ({"normalize": "minmax"}, ValueError, r"normalize must be one of \('range', 'dtype', None\)"),
        ({"n_regions": "Auto"}, ValueError, "n_regions must be an integer >= 2 or 'auto'"),
        ({"n_regions": 1}, ValueError, "n_regions must be an integer >= 2 or 'auto'"),
        ({"n_regions": 2.0}, TypeError, "n_regions must be an integer >= 2 or 'auto'"),
        ({"n_regions": None}, TypeError, "n_regions must be an integer >= 2 or 'auto'"),
        ({"fit": "linear"}, ValueError, r"fit must be one of \('constant', 'smooth'\)"),
        ({"noise": "laplace"}, ValueError, r"noise must be one of \('gaussian', 'poisson'\)"),
        ({"inside": "objects"}, ValueError, r"inside must be one of \('auto', 'bright', 'dark'\)"),
        ({"roi": "everything"}, ValueError, ROI + r" \(r0, c0, r1, c1\), got 'everything'"),
        ({"roi": (1, 2, 3)}, ValueError, ROI),
        ({"roi": np.ones((2, 4, 4), bool)}, ValueError, ROI),
        ({"separate": "yes"}, TypeError, "separate must be True or False"),
        ({"channel_axis": 1.0}, TypeError, "channel_axis must be an integer axis or None"),
        ({"options": [("spacing", 1.0)]}, TypeError, "options must be a dict or None"),
        ({"options": {"bogus": 1}}, TypeError, "unknown option.s. 'bogus' for backend 'polygon'"),
        ({"options": {"spacing": 0.01}}, ValueError, "spacing must be a number of pixels >= 0.1"),
        ({"n_regions": 3, "c_in": 0.5}, ValueError, "c_in and c_out fix the constants of two regions"),
        ({"n_regions": "auto", "c_out": 0.5}, ValueError, "c_in and c_out fix the constants of two regions"),
        ({"n_regions": "auto", "roi": (0, 0, 5, 5)}, ValueError, "roi restricts the two-region model"),
        ({"n_regions": 3, "options": {"nucleate": False}}, TypeError,
         "options are the two-region backends' settings; n_regions=3 takes none"),
    ],
)
def test_each_rule_names_the_keyword_and_the_valid_values(kwargs, error, match):
    with pytest.raises(error, match=match):
        Settings(**kwargs)


def test_an_unknown_keyword_lists_the_valid_ones():
    with pytest.raises(TypeError, match="unknown keyword.s. 'mux' of segment; the valid ones are backend"):
        Settings.of({"mux": 0.1})


@pytest.mark.parametrize(
    "kwargs",
    [
        {"mu": np.float32(0.1), "omega": -0.01, "max_num_iter": np.int64(0), "tol": 0},
        {"lambda_in": [1.0, 2.0, 0.5], "lambda_out": np.array([1.0, 1.0, 1.0]), "c_in": (0.1, 0.2, 0.3)},
        {"n_regions": np.int64(3), "backend": "levelset", "options": {}},
        {"roi": np.ones((4, 4), bool), "separate": np.bool_(False), "channel_axis": 0},
        {"roi": "init", "normalize": None, "color": "vector", "fit": "smooth", "noise": "poisson"},
    ],
)
def test_valid_settings_are_kept_as_given(kwargs):
    settings = Settings(**kwargs)
    for name, value in kwargs.items():
        assert getattr(settings, name) is value


def test_options_are_read_once_into_the_backends_dataclass():
    settings = Settings(options={"spacing": 2, "nucleate": False})
    assert settings.backend_options == BACKENDS["polygon"].options(spacing=2.0, nucleate=False)
    assert isinstance(settings.backend_options.spacing, float)  # the field's kind
    assert Settings(n_regions=3).backend_options == BACKENDS["polygon"].options()


@pytest.mark.parametrize("call", ["segment", "chan_vese_energy", "iter_sequence", "segment_many"])
@pytest.mark.parametrize("kwargs, error, match", [
    ({"mu": -1.0}, ValueError, "mu must be a finite number >= 0 or 'auto'"),
    ({"noise": "laplace"}, ValueError, "noise must be one of"),
    ({"color": 3}, ValueError, r"color must be one of \('gray', 'vector'\)"),
])
def test_every_front_door_refuses_with_the_same_message(call, kwargs, error, match):
    doors = {
        "segment": lambda: ac.segment(IMAGE, **kwargs),
        "chan_vese_energy": lambda: ac.chan_vese_energy(IMAGE, [ac.circle((20.0, 25.0), 8.0)], **kwargs),
        "iter_sequence": lambda: next(ac.iter_sequence(np.stack([IMAGE, IMAGE]), **kwargs)),
        "segment_many": lambda: ac.segment_many([IMAGE], jobs=1, **kwargs),
    }
    with pytest.raises(error, match=match):
        doors[call]()


# --------------------------------------------------------------------------------------------
# One statement of every default


def test_segment_signature_defaults_are_the_settings():
    defaults = Settings()
    parameters = inspect.signature(ac.segment).parameters
    names = [field.name for field in dataclasses.fields(Settings)]
    assert set(names) == set(parameters) - {"image", "init", "callback"}
    for name in names:
        assert parameters[name].default is getattr(defaults, name), name


def test_specs_carry_default_help_kind_and_choices():
    defaults = Settings()
    specs = {spec.name: spec for spec in setting_specs()}
    assert list(specs) == [field.name for field in dataclasses.fields(Settings)]
    for spec in specs.values():
        assert spec.default is getattr(defaults, spec.name)
        assert spec.help and spec.kind in KINDS
        if spec.kind == "choice":
            assert spec.default in spec.choices
    assert specs["backend"].choices == tuple(BACKENDS)
    assert (specs["mu"].auto, specs["n_regions"].auto, specs["omega"].auto) == (True, True, False)


def test_the_command_line_defaults_are_the_settings():
    from app.cli.parser import build_parser

    args = build_parser().parse_args(["segment", "image.png"])
    defaults = Settings()
    shown = [name for name in vars(args) if name in {field.name for field in dataclasses.fields(Settings)}]
    assert len(shown) >= 14
    for name in shown:
        assert getattr(args, name) == getattr(defaults, name), name


def test_backend_option_specs_are_the_dataclass_defaults():
    for solver in SOLVERS.values():
        defaults = solver.options()
        for spec in option_specs(solver.options):
            assert spec.default == getattr(defaults, spec.name)
        for field in dataclasses.fields(solver.options):  # what an option is, not how a viewer shows it
            assert set(field.metadata) <= {"help", "choices", "typical"}
        for spec in option_specs(solver.options):
            if spec.typical is not None:  # values worth trying: valid ones, around the default
                low, high = spec.typical
                assert spec.kind is float and low < high and low <= spec.default <= high
                for value in (low, high):
                    solver.parse({spec.name: value})


# --------------------------------------------------------------------------------------------
# The registry and the dispatch


def test_each_backend_and_number_of_regions_has_one_solver():
    assert solver_for("polygon", 2).name == "polygon" and solver_for("polygon", 3).name == "network"
    assert solver_for("levelset", 2).name == "levelset" and solver_for("levelset", 5).name == "labelfield"
    assert solver_for("levelset", "auto").name == "labelfield"
    assert solver_for("polygon", np.int64(2)).name == "polygon"
    for solver in SOLVERS.values():
        assert solver.backend in BACKENDS and set(solver.inits) <= set(INITS) and solver.help
        assert solver.roi != solver.many_regions
        if solver.many_regions:
            assert solver.options is NoOptions


def test_the_dispatcher_runs_the_registrys_record(monkeypatch):
    # a record's run function is what segment calls: replace one and see segment follow
    calls = []
    record = SOLVERS["labelfield"]

    def recorded(model, init, params, **kwargs):
        calls.append(kwargs["n_regions"])
        return record.run(model, init, params, **kwargs)

    import types
    module = types.SimpleNamespace(segment_labels=recorded)
    monkeypatch.setitem(sys.modules, "recorded_labelfield", module)
    monkeypatch.setitem(SOLVERS, "labelfield", dataclasses.replace(record, module="recorded_labelfield"))
    result = ac.segment(IMAGE, backend="levelset", n_regions=3, max_num_iter=5)
    assert calls == [3] and result.n_regions == 3


# --------------------------------------------------------------------------------------------
# Start-up: the settings and the registry load no solver


HEAVY = ("scipy", "skimage", "cv2", "shapely", "matplotlib")
SOLVER_MODULES = ("activecontour.backends.polygon", "activecontour.backends.network",
                  "activecontour.backends.levelset", "activecontour.backends.labelfield",
                  "activecontour._segment", "activecontour.energy", "activecontour.problem")


def _modules_after(statement):
    code = f"{statement}\nimport sys\nprint('\\n'.join(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return set(out.split())


def test_the_settings_and_the_registry_import_no_solver():
    loaded = _modules_after("import activecontour.settings, activecontour.backends\n"
                            "activecontour.settings.setting_specs()\n"
                            "[b.option_specs() for b in activecontour.backends.BACKENDS.values()]")
    assert not [name for name in loaded if name.split(".")[0] in HEAVY]
    assert not [name for name in loaded if name.startswith(SOLVER_MODULES)]


def test_import_activecontour_is_lazy_and_lists_its_public_names():
    loaded = _modules_after("import activecontour")
    assert {name for name in loaded if name.startswith("activecontour")} == {"activecontour",
                                                                             "activecontour._kernels"}
    assert set(ac.__all__) <= set(dir(ac))
    for name in ac.__all__:
        assert getattr(ac, name).__name__ == name
    with pytest.raises(AttributeError, match="has no attribute 'segmnt'"):
        ac.segmnt  # noqa: B018


def test_no_code_reaches_a_module_through_importlib_by_the_functions_name():
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    for path in [*root.joinpath("activecontour").rglob("*.py"), *root.joinpath("app").rglob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and node.value == "activecontour.segment":
                raise AssertionError(f"{path} names the module activecontour.segment")
