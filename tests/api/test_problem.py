"""prepare(image, settings): the one preparation of segment, the evaluator, sequences and auto K."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.imaging.noise import auto_mu
from activecontour.models.modes import choose_regions
from activecontour.problem import prepare
from activecontour.result import SegmentationResult
from activecontour.settings import Settings


def _scene(seed=0):
    image, _ = synthetic.disk_image(64, (30.0, 34.0), 14.0, inside=0.7, outside=0.3)
    return synthetic.add_noise(image, 0.05, seed)


def test_units_map_the_normalised_values_back_to_the_input():
    image = 40.0 + 900.0 * _scene()
    problem = prepare(image)
    assert problem.normalised.min() == 0.0 and problem.normalised.max() == 1.0
    offset, scale = problem.units
    np.testing.assert_allclose(offset + scale * problem.normalised[..., 0], image, rtol=1e-12)
    assert problem.frame == (0.0, 1.0) and not problem.framed  # [0, 1] is the working frame


def test_the_working_frame_spans_unit_range_and_carries_mu():
    image = 1000.0 + 250.0 * _scene()
    problem = prepare(image, Settings(normalize=None, mu="auto"))
    low, span = problem.frame
    assert (low, span) == (image.min(), image.max() - image.min())
    assert problem.values.min() == 0.0 and problem.values.max() == pytest.approx(1.0, rel=1e-15)
    # mu is in the caller's units, the working frame's mu is it over the span squared
    assert problem.mu == pytest.approx(auto_mu(problem.values) * span**2, rel=1e-15)
    assert problem.framed and problem.working.mu == pytest.approx(problem.mu / span**2, rel=1e-15)
    fixed = prepare(image, Settings(normalize=None, mu=5.0, omega=2.0))
    assert (fixed.mu, fixed.working.mu, fixed.working.omega) == (5.0, 5.0 / span**2, 2.0 / span**2)


def test_a_crop_is_a_problem_of_its_own():
    image = 10.0 + 100.0 * _scene()
    problem = prepare(image)
    box = (5, 8, 40, 50)
    crop = problem.restricted(box, None)
    assert crop.shape == (35, 42) and crop.box == box and crop.domain is None
    # the crop by its own range, and the units still map onto the input's intensities
    assert crop.normalised.min() == 0.0 and crop.normalised.max() == 1.0
    offset, scale = crop.units
    np.testing.assert_allclose(offset + scale * crop.normalised[..., 0], image[5:40, 8:50], rtol=1e-12)



def test_a_reweighted_problem_shares_the_values_and_is_prepared_as_anew():
    """Problem.reweighted: the same values, frame and noise level (the same arrays, not copies),
    the parameters of a fresh preparation with the new settings; changes that would change the
    values are refused."""
    image = 1000.0 + 250.0 * _scene()
    problem = prepare(image, Settings(normalize=None))
    values, mu = problem.values, problem.mu
    other = problem.reweighted(mu=0.5 * mu, c_in=1100.0, noise="poisson")
    fresh = prepare(image, Settings(normalize=None, mu=0.5 * mu, c_in=1100.0, noise="poisson"))
    assert other.values is values and other.frame == fresh.frame
    np.testing.assert_array_equal(fresh.values, values)
    assert other.working == fresh.working and other.working.mu == pytest.approx(0.5 * problem.working.mu)
    assert other.auto_mu == problem.auto_mu and problem.settings.noise == "gaussian"
    (model, params), (expected_model, expected_params) = other.model(), fresh.model()
    assert type(params) is type(expected_params) and params == expected_params
    np.testing.assert_array_equal(model.image, expected_model.image)
    assert problem.model()[0] is problem.model()[0]  # the uniform model is built once
    with pytest.raises(ValueError, match="normalize"):
        problem.reweighted(normalize="range")

def test_a_path_is_read_as_segment_reads_it(tmp_path):
    import imageio.v3 as iio

    image = np.round(255 * _scene()).clip(0, 255).astype(np.uint8)
    iio.imwrite(tmp_path / "scene.png", image)
    np.testing.assert_array_equal(prepare(tmp_path / "scene.png").normalised, prepare(image).normalised)


def test_auto_regions_are_the_modes_at_the_noise_the_length_weight_assumes():
    rng = np.random.default_rng(1)
    truth = np.zeros((96, 96), int)
    truth[20:60, 10:50], truth[40:80, 50:90] = 1, 2
    image = truth / 2 + rng.normal(0, 0.05, truth.shape)
    problem = prepare(image, Settings(n_regions="auto"))
    assert problem.n_regions == 3 == choose_regions(problem.values, problem.auto_mu)
    # a length weight far above the noise's merges the levels (regions told apart at its noise)
    assert prepare(image, Settings(n_regions="auto", mu=5.0)).n_regions == 2


@pytest.mark.parametrize("noise", ["gaussian", "poisson"])
def test_the_model_is_the_noise_models(noise):
    from activecontour.models import noise_model

    problem = prepare(_scene(), Settings(noise=noise))
    model, params = problem.model()
    expected_model, expected_params = noise_model(noise)[0](problem.values, None, problem.working)
    assert type(model) is type(expected_model) and type(params) is type(expected_params)
    np.testing.assert_array_equal(model.image, expected_model.image)


def test_segment_the_evaluator_and_prepare_agree_on_mu_and_energy():
    image = _scene(3)
    result = ac.segment(image, max_num_iter=30)
    assert result.mu == prepare(image).mu
    assert ac.chan_vese_energy(image, result.contours) == pytest.approx(result.energy, rel=1e-12)


@pytest.mark.parametrize("kwargs", [
    {}, {"n_regions": 3}, {"roi": (4, 4, 60, 60)}, {"fit": "smooth", "inside": "bright"},
    {"backend": "levelset", "normalize": None},
])
def test_segment_builds_its_result_once(monkeypatch, kwargs):
    """No field of a SegmentationResult is set after it was constructed."""
    patched = []
    post_init = SegmentationResult.__post_init__

    def recording_post_init(self):
        post_init(self)
        vars(self)["_constructed"] = True

    def recording_setattr(self, name, value):
        if vars(self).get("_constructed"):
            patched.append(name)
        object.__setattr__(self, name, value)

    monkeypatch.setattr(SegmentationResult, "__post_init__", recording_post_init)
    monkeypatch.setattr(SegmentationResult, "__setattr__", recording_setattr)
    image = 3.0 * _scene(4) - 1.0
    result = ac.segment(image, max_num_iter=20, **kwargs)
    frames = list(ac.iter_sequence(np.stack([image, np.roll(image, 2, axis=1)]), max_num_iter=10))
    assert patched == []
    assert result.mu is not None and result.classes is not None and result.labels is not None
    assert all(frame.result.labels is not None for frame in frames)


def test_the_smooth_fits_light_is_reported_when_the_inside_is_the_complement():
    # inside="bright" may take the complement of the run's result: the light the energy was
    # computed with is still the result's light (res.energy == chan_vese_energy(..., light=res.light))
    image, _ = synthetic.disk_image(96, (40.0, 50.0), 20.0, inside=0.3, outside=0.7)
    ramp = np.linspace(0.6, 1.4, 96)[None, :]
    image = synthetic.add_noise(image * ramp, 0.02, 5)
    for inside in ("bright", "dark"):
        result = ac.segment(image, fit="smooth", inside=inside, max_num_iter=60)
        energy = ac.chan_vese_energy(image, result.contours, mu=result.mu, light=result.light)
        assert energy == pytest.approx(result.energy, rel=1e-9), inside
