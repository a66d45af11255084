"""Absurd weights and constants are refused with the valid range; huge or offset intensities are
computed in a frame where the image spans [0, 1]; a sliver region is empty for its constant; a
curve around the whole image is clipped to it."""

import numpy as np
import pytest

import activecontour as ac
from activecontour.energy import evaluate
from activecontour.geometry.curve import signed_area, stack_curves
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.models import ChanVeseParameters
from activecontour.models.two_region import EMPTY_FRACTION

IMAGE = np.random.default_rng(0).random((32, 32))


@pytest.mark.parametrize("kwargs, match", [
    ({"lambda_in": 1e300}, "lambda_in must be between 1e-08 and 1e"),
    ({"lambda_out": 1e-300}, "lambda_out must be between"),
    ({"omega": 1e300}, r"\|omega\| must be at most"),
    ({"omega": -1e300}, r"\|omega\| must be at most"),
    ({"mu": 1e300}, r"\|mu\| must be at most"),
    ({"c_in": 1e300}, "c_in must be within"),
    ({"c_out": -1e300}, "c_out must be within"),
])
@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_absurd_weights_and_constants_are_refused(kwargs, match, backend):
    with pytest.raises(ValueError, match=match):
        ac.segment(IMAGE, backend=backend, **kwargs)
    with pytest.raises(ValueError, match=match):
        ac.chan_vese_energy(IMAGE, [ac.circle((16, 16), 8)], **{"mu": 0.1, **kwargs})


def test_intensities_spanning_the_float_range():
    image = np.where(np.add.outer(np.arange(16), np.arange(16)) % 2 == 0, 1.7e308, -1.7e308)
    image[4:12, 4:12] = 1.7e308
    result = ac.segment(image)  # normalize="range": the same as the same pattern in [0, 1]
    assert np.array_equal(result.mask, ac.segment((image > 0).astype(float)).mask)
    with pytest.raises(ValueError, match="overflows; pass normalize='range'"):
        ac.segment(image, normalize=None)


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_a_constant_image_far_from_zero_has_energy_zero_but_the_length(backend):
    image = np.full((32, 32), 1e8)
    curve = ac.circle((15.5, 15.5), 8, n=64)
    result = ac.segment(image, curve, normalize=None, mu=0.0, max_num_iter=0, backend=backend)
    assert result.energy == 0.0
    assert ac.chan_vese_energy(image, [curve], normalize=None, mu=0.0) == 0.0
    assert result.c_in == result.c_out == 1e8


def test_an_offset_and_scaled_image_gives_the_scaled_energy():
    # (6.38) of a + s I is s^2 (6.38) of I with mu / s^2: the same mask, energies times s^2
    offset, scale = 5e9, 2.0**27
    reference = ac.segment(IMAGE, mu=0.05, normalize=None)
    moved = ac.segment(offset + scale * IMAGE, mu=0.05 * scale**2, normalize=None)
    assert np.array_equal(moved.mask, reference.mask)
    assert moved.energy == pytest.approx(scale**2 * reference.energy, rel=1e-6)
    assert moved.c_in == pytest.approx(offset + scale * reference.c_in, rel=1e-12)
    assert moved.energy == pytest.approx(
        ac.chan_vese_energy(offset + scale * IMAGE, moved.contours, mu=moved.mu, normalize=None), rel=1e-12)


def test_a_sliver_outside_is_empty_for_its_constant():
    model = ImageModel(normalize_image(IMAGE))
    total = 32 * 32
    for sliver in (0.5 * EMPTY_FRACTION * total, 1e-9):
        # the whole domain but a triangle of area `sliver` along the right border
        height = 2 * sliver / 32
        curve = np.array([[-0.5, -0.5], [31.5, -0.5], [31.5, 31.5], [-0.5 + height, 31.5]])
        points, following, _ = stack_curves([curve])
        evaluation = evaluate(model, points, following, ChanVeseParameters(0.1), empty_ok=True)
        assert total - evaluation.area == pytest.approx(sliver, rel=1e-3)
        assert 0.0 <= evaluation.c_out[0] <= 1.0
        assert evaluation.c_out[0] == evaluation.c_in[0] == pytest.approx(IMAGE.mean() / np.ptp(IMAGE)
                                                                         - IMAGE.min() / np.ptp(IMAGE))


@pytest.mark.parametrize("curve", [ac.circle((16, 16), 1e7, n=64),
                                   np.array([[-1e9, -1e9], [1e9, -1e9], [1e9, 1e9], [-1e9, 1e9]]),
                                   ac.circle((1e6, 16), 1e6 + 10, n=1000)],
                         ids=["circle-1e7", "square-1e9", "circle-through-the-border"])
def test_a_curve_around_the_whole_image_is_the_whole_image(curve):
    image = np.zeros((32, 32))
    image[10:20, 5:15] = 1.0
    (clipped,) = ac.initial.initial_curves(curve, image.shape)
    assert signed_area(clipped) == pytest.approx(32 * 32, rel=1e-12)
    for global_start in (True, False):  # without the global move the flow shrinks onto it too
        result = ac.segment(image, curve, options={"global_start": global_start})
        assert result.success
        np.testing.assert_array_equal(result.mask, image > 0)


def test_a_curve_outside_the_image_is_said_in_one_short_line():
    with pytest.raises(ValueError, match="init curve 0 lies outside the image") as error:
        ac.segment(np.zeros((32, 32)), ac.circle((1e7, 1e7), 5.0, n=64))
    assert len(str(error.value)) <= 160 and "\n" not in str(error.value)
    # a curve partly outside is its part inside: a square cut by the border
    (part,) = ac.initial.initial_curves(ac.rectangle((-10, -10), (10, 10)), (32, 32))
    assert signed_area(part) == pytest.approx(10.5 * 10.5)
