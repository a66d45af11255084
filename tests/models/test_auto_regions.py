"""``n_regions="auto"``: the number of regions read off the modes of the flat pixels' intensities
(:mod:`activecontour.models.modes`), on scenes whose number of regions is known by construction."""

import numpy as np
import pytest
import skimage.data

import activecontour as ac
from activecontour.models.modes import MAX_REGIONS, count_regions, intensity_modes


def _auto(image, **kwargs):
    return ac.segment(image, n_regions="auto", backend="levelset", separate=False, **kwargs)


def _dice(found, truth, n_classes):
    return np.array([2 * np.sum((found == k) & (truth == k)) / (np.sum(found == k) + np.sum(truth == k))
                     for k in range(n_classes)])


def test_pure_noise_is_two_regions():
    image = np.random.default_rng(10).normal(0.5, 0.1, (128, 128))
    res = _auto(image)
    assert res.n_regions == 2
    assert res.constants.shape == (2, 1)
    assert set(np.unique(res.classes)) <= {0, 1}


def test_two_flat_regions_at_snr_3():
    truth = np.zeros((128, 128), dtype=int)
    truth[:, 64:] = 1
    image = truth + np.random.default_rng(11).normal(0, 1 / 3, truth.shape)
    res = _auto(image)
    assert res.n_regions == 2
    # both halves touch the border as much: either may be the background
    assert max(np.min(_dice(res.classes, truth, 2)), np.min(_dice(1 - res.classes, truth, 2))) > 0.98


def test_three_nested_classes_at_snr_3():
    m = 192
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - m / 2, cols - m / 2)
    truth = (radius < 75).astype(int) + (radius < 40)
    image = truth / 2.0 + np.random.default_rng(12).normal(0, 0.5 / 3, truth.shape)
    res = _auto(image)
    assert res.n_regions == 3
    assert res.constants.shape == (3, 1)
    assert np.all(_dice(res.classes, truth, 3) > 0.99)
    # the same as asking for three
    assert np.array_equal(res.classes, ac.segment(image, n_regions=3, backend="levelset",
                                                  separate=False).classes)


def test_shepp_logan_six_levels():
    phantom = skimage.data.shepp_logan_phantom()
    levels = np.array([0.0, 0.098, 0.2, 0.298, 0.4, 1.0])
    truth = np.argmin(np.abs(phantom[..., None] - levels), axis=-1)
    assert sorted(np.bincount(truth.ravel()))[:2] < [250, 250]  # two levels under 250 px
    image = phantom + np.random.default_rng(13).normal(0, 0.02, phantom.shape)
    modes = intensity_modes(image, 0.02)
    assert len(modes) == 6
    # each mode is one of the levels, to within the histogram's resolution and the noise
    span = image.max() - image.min()
    np.testing.assert_allclose(modes, levels, atol=span / 256 + 0.02)


@pytest.mark.parametrize("width", [160, 256])
@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_a_ramp_has_no_regions_of_its_own(noise, width):
    image = np.tile(np.linspace(0.0, 1.0, width), (120, 1))
    image = image + np.random.default_rng(14).normal(0, noise, image.shape) if noise else image
    assert _auto(image).n_regions == 2


def test_a_vignetted_object_is_two_regions():
    rows, cols = np.mgrid[:200, :200]
    light = 1.0 - 0.5 * ((rows - 100.0) ** 2 + (cols - 100.0) ** 2) / 100.0**2
    truth = np.hypot(rows - 90.0, cols - 110.0) < 40
    image = (0.3 + 0.4 * truth) * light + np.random.default_rng(19).normal(0, 0.02, light.shape)
    assert _auto(image).n_regions == 2


@pytest.mark.parametrize("n_levels", [2, 3, 4, 5, 6, 8])
def test_flat_steps_are_counted_up_to_the_limit(n_levels):
    # vertical bands of n_levels intensities in shuffled order, noise 0.02 of the span
    order = np.random.default_rng(15).permutation(n_levels)
    image = np.repeat(order / (n_levels - 1), 24)[None, :].repeat(60, axis=0)
    image = image + np.random.default_rng(16).normal(0, 0.02, image.shape)
    values = image[..., None]
    assert count_regions(values, 0.02) == min(n_levels, MAX_REGIONS)
    assert count_regions(values, 0.02, max_regions=3) == min(n_levels, 3)


def test_a_larger_mu_merges_close_levels():
    # four levels 0.1 apart on a span of 1 (a bright patch sets the span): told apart at the
    # default resolution (sigma 0.03), merged when mu assumes a noise of sigma = 0.2 (mu = 10 * 0.04)
    image = np.repeat(np.array([0.0, 0.1, 0.2, 0.3]), 40)[None, :].repeat(80, axis=0)
    image[30:50, 60:100] = 1.0
    image = image + np.random.default_rng(17).normal(0, 0.005, image.shape)
    assert _auto(image).n_regions == 5
    assert _auto(image, mu=0.4).n_regions < 5


def test_colour_regions_of_equal_gray_need_the_channels():
    rgb = np.array([[0.2, 0.5, 0.9], [0.6, 0.45, 0.3], [0.35, 0.5, 0.2]])
    gray = rgb @ np.array([0.2125, 0.7154, 0.0721])
    rgb[1:] *= (gray[0] / gray[1:])[:, None]
    truth = np.zeros((90, 120), dtype=int)
    truth[20:70, 15:55] = 1
    truth[30:80, 70:110] = 2
    image = rgb[truth] + np.random.default_rng(18).normal(0, 0.05, truth.shape + (3,))
    assert _auto(image, color="vector").n_regions == 3
    assert _auto(image).n_regions == 2  # one gray level: gray sees one region


def test_given_regions_are_reported():
    image = np.zeros((40, 40))
    image[10:30, 12:28] = 1.0
    assert ac.segment(image).n_regions == 2
    assert ac.segment(image, n_regions=3, backend="levelset").n_regions == 3


@pytest.mark.parametrize(
    "kwargs, error",
    [
        ({"n_regions": "Auto"}, ValueError),
        ({"n_regions": "three"}, ValueError),
        ({"n_regions": 1}, ValueError),
        ({"n_regions": 2.0}, TypeError),
        ({"n_regions": None}, TypeError),
    ],
)
def test_bad_regions_list_the_choices(kwargs, error):
    with pytest.raises(error, match=r"n_regions must be an integer >= 2 or 'auto'"):
        ac.segment(np.zeros((10, 10)), backend="levelset", **kwargs)


@pytest.mark.parametrize("kwargs, match", [({"c_in": 0.5}, "c_in"), ({"roi": (0, 0, 5, 5)}, "roi")])
def test_auto_takes_the_settings_of_more_than_two_regions(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ac.segment(np.zeros((10, 10)), **{"backend": "levelset", "n_regions": "auto", **kwargs})


@pytest.mark.parametrize("convert", [
    lambda im: im * 1000.0 + 5.0,
    lambda im: im.astype(np.float32),
    lambda im: np.round(255 * (im - im.min()) / np.ptp(im)).astype(np.uint8),
])
def test_the_count_does_not_depend_on_scale_or_dtype(convert):
    m = 128
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - m / 2, cols - m / 2)
    truth = (radius < 50).astype(int) + (radius < 25)
    image = truth / 2.0 + np.random.default_rng(20).normal(0, 0.5 / 3, truth.shape)
    assert _auto(convert(image), max_num_iter=0).n_regions == 3


def test_a_sequence_chooses_once_and_follows_the_classes():
    m = 96
    rows, cols = np.mgrid[:m, :m]
    truths, frames = [], []
    for t in range(4):  # the inner disc moves 3 px per frame inside the ring's disc
        disc = np.hypot(rows - 48, cols - 40 - 3 * t) < 15
        truth = (np.hypot(rows - 48, cols - 48) < 38).astype(int) + disc
        truths.append(truth)
        frames.append(truth / 2.0 + np.random.default_rng(21 + t).normal(0, 0.5 / 3, truth.shape))
    seq = ac.segment_sequence(np.array(frames), n_regions="auto", backend="levelset")
    for res, truth in zip(seq.results, truths, strict=True):
        assert res.n_regions == 3
        assert np.all(_dice(res.classes, truth, 3) > 0.97)


def test_auto_on_the_polygon_backend():
    m = 128
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - m / 2, cols - m / 2)
    truth = (radius < 50).astype(int) + (radius < 25)
    image = truth / 2.0 + np.random.default_rng(22).normal(0, 0.5 / 3, truth.shape)
    res = ac.segment(image, n_regions="auto", separate=False)
    assert res.n_regions == 3 and res.backend == "polygon"
    assert np.all(_dice(res.classes, truth, 3) > 0.98)


def test_an_image_without_flat_pixels_has_no_mode():
    # a steep ramp: 0.05 per pixel, above the flat limit 3.03 tau = 3.03 * 0.159 * 0.03 = 0.015
    steep = np.tile(np.linspace(0.0, 1.0, 21), (30, 1))
    assert len(intensity_modes(steep, 0.03)) == 0
    assert _auto(steep, max_num_iter=0).n_regions == 2


def test_any_small_image_gets_a_count_in_range_and_a_consistent_result():
    """Fuzz: random small images of every dtype and scene of tests/api/test_fuzz.py, every mu and
    normalisation: K in 2..MAX_REGIONS, classes in 0..K-1, K constants, the common evaluator's
    energy."""
    hypothesis = pytest.importorskip("hypothesis")
    from hypothesis import strategies as st

    from tests.api.test_fuzz import DTYPES, SCENES, make_image

    @hypothesis.settings(max_examples=40, derandomize=True, deadline=None, database=None,
                         suppress_health_check=list(hypothesis.HealthCheck))
    @hypothesis.given(st.sampled_from(SCENES), st.sampled_from(DTYPES), st.integers(4, 24),
                      st.integers(4, 24), st.integers(0, 2**32 - 1),
                      st.sampled_from(["auto", 0.0, 1e-3, 0.5]), st.sampled_from(["range", "dtype", None]),
                      st.sampled_from(["levelset", "polygon"]))
    def check(scene, dtype, m, n, seed, mu, normalize, backend):
        image = make_image(scene, dtype, (m, n), seed)
        if seed % 2:  # or bands of 2..7 flat levels, to reach more than two regions
            rng = np.random.default_rng(seed)
            levels = rng.integers(0, rng.integers(2, 8), n)[np.arange(n) // 3 % n]
            image = (levels[None, :] + rng.normal(0, 0.02, (m, n))).astype(image.dtype)
        res = ac.segment(image, n_regions="auto", mu=mu, normalize=normalize, backend=backend,
                         max_num_iter=5, separate=False)
        assert 2 <= res.n_regions <= MAX_REGIONS
        assert res.classes.min() >= 0 and res.classes.max() < res.n_regions
        assert len(res.constants) == res.n_regions
        partition = {"regions": res.class_contours} if res.n_regions > 2 else {"contours": res.contours}
        found.append(res.n_regions)
        assert res.energy == pytest.approx(
            ac.chan_vese_energy(image, mu=res.mu, normalize=normalize, **partition), rel=1e-9, abs=1e-9)

    found = []

    check()
    assert max(found) > 2  # the cases reach more than two regions
