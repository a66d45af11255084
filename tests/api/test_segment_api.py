"""`segment`'s contract: one fault per input, each with a message that names it."""

import numpy as np
import pytest

import activecontour as ac
from activecontour.imaging.normalize import normalize_image
from activecontour.initial import initial_curves
from activecontour.io.images import load_image

IMAGE = np.zeros((40, 50))
IMAGE[10:30, 15:35] = 1.0


@pytest.mark.parametrize(
    "image, kwargs, error, match",
    [
        (IMAGE, {"backend": "snake"}, ValueError, r"backend must be one of \('polygon', 'levelset'\)"),
        (IMAGE, {"mu": -1.0}, ValueError, "mu must be a finite number >= 0 or 'auto'"),
        (IMAGE, {"lambda_out": 0}, ValueError, "lambda_out must be a finite number > 0"),
        (IMAGE, {"max_num_iter": 2.5}, TypeError, "max_num_iter must be an integer"),
        (IMAGE, {"max_num_iter": -1}, ValueError, "max_num_iter must be an integer >= 0"),
        (IMAGE, {"tol": -1e-3}, ValueError, "tol must be"),
        (IMAGE, {"callback": 3}, TypeError, "callback must be callable"),
        (IMAGE, {"options": {"velocity": "h2"}}, ValueError, r"velocity must be one of \('h1', 'l2'\)"),
        (IMAGE, {"options": {"spacing": 0}}, ValueError, r"spacing must be a number of pixels >= 0.1"),
        (IMAGE, {"options": {"smoothing": 0.5}}, ValueError, "smoothing >= min_smoothing"),
        (IMAGE, {"options": {"bogus": 1}}, TypeError, "unknown option.s. .bogus. for backend .polygon."),
        (IMAGE, {"color": "hsv"}, ValueError, r"color must be one of \('gray', 'vector'\)"),
        (np.full((40, 50), np.nan), {}, ValueError, "NaN or infinite"),
        (np.zeros(40), {}, ValueError, r"shape \(M, N\)"),
        (np.zeros((1, 40)), {}, ValueError, "at least 2 x 2"),
        (np.zeros((8, 8, 5)), {}, ValueError, "3 \\(RGB\\) or 4 \\(RGBA\\) channels"),
        (IMAGE, {"normalize": "minmax"}, ValueError, r"normalize must be one of \('range', 'dtype', None\)"),
        (np.zeros((8, 8), dtype=complex), {}, TypeError, "dtype must be bool, integer or float"),
    ],
)
def test_bad_arguments(image, kwargs, error, match):
    with pytest.raises(error, match=match):
        ac.segment(image, **kwargs)


@pytest.mark.parametrize(
    "init, match",
    [
        (np.zeros((10, 10), dtype=bool), r"init mask has shape \(10, 10\)"),
        (np.zeros((40, 50), dtype=bool), "init mask is empty"),
        (ac.circle((200.0, 200.0), 5.0), "init curve 0 lies outside the image"),
        ([ac.circle((20.0, 20.0), 5.0), [[0, 0], [1, 1]]], "init curve 1 needs at least 3"),
        ([], "empty list"),
        (np.array([[0.0, 0.0], [np.inf, 1.0], [2.0, 3.0]]), "NaN or infinite"),
        ("checkerboard", "not understood: pass None, .grid."),
    ],
)
def test_bad_init(init, match):
    with pytest.raises(ValueError, match=match):
        ac.segment(IMAGE, init)


@pytest.mark.parametrize("global_start", [True, False])
def test_a_start_around_the_whole_image_shrinks_onto_the_object(global_start):
    # the outside is empty, c_out (6.42) undefined at the start: the flow starts all the same
    # (the length term moves the curve in, then c_out is the band it left), with or without the
    # global move, and ends on the 20 x 20 square
    whole = np.array([[-0.5, -0.5], [39.5, -0.5], [39.5, 49.5], [-0.5, 49.5]])
    result = ac.segment(IMAGE, whole, options={"global_start": global_start})
    assert result.success
    np.testing.assert_array_equal(result.mask, IMAGE > 0)
    assert result.energies[1] < ac.segment(IMAGE, whole, max_num_iter=0).energy


def test_init_partly_outside_is_clipped_to_the_image():
    (curve,) = initial_curves(ac.circle((5.0, 5.0), 20.0), (40, 50))
    assert curve[:, 0].min() == -0.5 and curve[:, 1].min() == -0.5


def test_default_init_is_a_centred_circle():
    (curve,) = initial_curves(None, (40, 80))
    np.testing.assert_allclose(curve.mean(axis=0), [19.5, 39.5], atol=1e-9)
    np.testing.assert_allclose(np.hypot(*(curve - [19.5, 39.5]).T), 15.0)


def test_normalisation_of_dtypes():
    np.testing.assert_array_equal(normalize_image(np.array([[0, 255]], np.uint8).repeat(2, 0))[..., 0],
                                  [[0.0, 1.0], [0.0, 1.0]])
    # "range" (default): the image's own minimum and maximum go to 0 and 1, whatever the dtype
    ramp = np.array([[100, 200], [300, 400]])
    for dtype in (np.uint16, np.int64, np.float32):
        np.testing.assert_allclose(normalize_image(ramp.astype(dtype))[..., 0], [[0, 1 / 3], [2 / 3, 1]])
    assert normalize_image(np.full((2, 2), 65535, np.uint16)).max() == 0.0  # constant: 0
    # "dtype": integers by their dtype's range, floats as given; None: as given
    assert normalize_image(np.full((2, 2), 65535, np.uint16), normalize="dtype").max() == 1.0
    assert normalize_image(np.full((2, 2), -128, np.int8), normalize="dtype").max() == 0.0
    assert normalize_image(np.full((2, 2), 3.5, np.float32), normalize="dtype").max() == 3.5
    assert normalize_image(np.full((2, 2), 300, np.int64), normalize=None).max() == 300.0
    # gray + alpha drops the alpha; a channel-first stack is read as channel-last
    gray_alpha = np.stack([ramp, np.full_like(ramp, 7)], axis=-1)
    np.testing.assert_array_equal(normalize_image(gray_alpha), normalize_image(ramp))
    stack = np.random.default_rng(0).random((3, 9, 8))
    np.testing.assert_array_equal(normalize_image(stack), normalize_image(np.moveaxis(stack, 0, -1)))
    rgb = np.zeros((2, 2, 3))
    rgb[..., 1] = 1.0
    assert normalize_image(rgb)[0, 0, 0] == pytest.approx(0.7154)
    assert normalize_image(rgb, color="vector").shape == (2, 2, 3)


def test_8_bit_images_are_normalised_as_their_float_values():
    # the 256 levels' table gives the values the per-pixel float path gives, bit for bit
    rng = np.random.default_rng(3)
    gray = rng.integers(17, 231, size=(30, 41), dtype=np.uint8)
    for image in (gray, np.dstack([gray, gray[::-1], gray[:, ::-1]]), gray > 120):
        as_float = image.astype(np.float64)
        for keywords in ({}, {"color": "vector"}, {"normalize": None}):
            expected = normalize_image(as_float, **keywords)
            assert normalize_image(image, **keywords).tobytes() == expected.tobytes()
        by_dtype = normalize_image(image, color="vector", normalize="dtype")
        scale = 1.0 if image.dtype == bool else 255.0
        assert by_dtype.tobytes() == (as_float / scale).reshape(by_dtype.shape).tobytes()


def test_load_image_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="image file not found"):
        load_image(tmp_path / "missing.png")
    with pytest.raises(ValueError, match="directory"):
        load_image(tmp_path)
    junk = tmp_path / "junk.png"
    junk.write_text("not an image")
    with pytest.raises(ValueError, match="cannot read image"):
        load_image(junk)
