"""activecontour.compat.chan_vese: scikit-image's signature and return types, our energy."""

import inspect

import numpy as np
import pytest
import skimage.segmentation

import activecontour as ac
from activecontour import compat
from activecontour.compat import chan_vese
from activecontour.geometry.curve import resample, signed_area
from activecontour.geometry.raster import mask_to_curves
from activecontour.imaging.strips import blurred
from activecontour.initial import DEFAULT_INIT_BLUR, threshold_split, threshold_starts
from activecontour.synthetic import add_noise, dice, disk_image


@pytest.fixture(scope="module")
def noisy_disk():
    """A disk of radius 14 at contrast 0.5 with noise sigma 0.25 (SNR 2) on a 64 x 64 image."""
    image, truth = disk_image(64, (30.0, 34.0), 14.0, inside=0.75, outside=0.25)
    return add_noise(image, 0.25, seed=3), truth


def test_signature_is_scikit_images():
    ours = inspect.signature(chan_vese).parameters
    theirs = inspect.signature(skimage.segmentation.chan_vese).parameters
    assert list(ours) == list(theirs)  # names and positional order
    for name in theirs:
        assert ours[name].kind == theirs[name].kind, name
        assert ours[name].default == theirs[name].default, name


def test_return_types(noisy_disk):
    image, _ = noisy_disk
    segmentation = chan_vese(image)
    assert isinstance(segmentation, np.ndarray)
    assert segmentation.dtype == bool and segmentation.shape == image.shape
    out = chan_vese(image, extended_output=True)
    assert isinstance(out, tuple) and len(out) == 3
    seg, phi, energies = out
    np.testing.assert_array_equal(seg, segmentation)
    assert phi.shape == image.shape and phi.dtype == np.float64
    np.testing.assert_array_equal(phi > 0, seg)
    assert isinstance(energies, list) and all(type(e) is np.float64 for e in energies)
    assert np.all(np.diff(energies) <= 1e-9 * abs(energies[0]))  # a descent method


def test_phi_is_the_signed_distance_to_the_mask_boundary():
    image = np.zeros((32, 32))
    image[8:24, 10:20] = 1.0  # a 16 x 10 rectangle, exactly found (edges between pixel centres)
    seg, phi, _ = chan_vese(image, mu=0.05, extended_output=True)
    np.testing.assert_array_equal(seg, image > 0)
    # the boundary runs half-way between pixel centres: the centre row 15/16 pixel at col 14 is
    # 14 - 9.5 = 4.5 px from the left edge, 19.5 - 14 = 5.5 from the right, 7.5 / 8.5 from the rows
    assert phi[15, 14] == pytest.approx(4.5)
    assert phi[15, 10] == pytest.approx(0.5) and phi[15, 9] == pytest.approx(-0.5)
    assert phi[15, 5] == pytest.approx(-(9.5 - 5))  # outside: distance to the left edge




def test_energy_not_above_scikit_images_on_a_small_image(noisy_disk):
    """By the common evaluator with the mapped parameters, ours ends at or below scikit-image's,
    both results outlined the same way (their masks), and is at least as close to the truth."""
    image, truth = noisy_disk
    ours = chan_vese(image)
    theirs = skimage.segmentation.chan_vese(image)
    energy_ours = ac.chan_vese_energy(image, mask_to_curves(ours), mu=0.25)
    energy_theirs = ac.chan_vese_energy(image, mask_to_curves(theirs), mu=0.25)
    assert energy_ours <= energy_theirs
    assert dice(ours, truth) >= max(dice(theirs, truth), 0.95)


def test_arguments_map_onto_segment(noisy_disk):
    """mu, lambda1/2 and tol pass unchanged (the same iterations, the same energies), and
    init_level_set="checkerboard" is the default start's threshold set: with one blur width it is
    the default start, and the same result as segment's."""
    image, _ = noisy_disk
    blurs = compat.CHECKERBOARD_BLURS
    try:
        compat.CHECKERBOARD_BLURS = (DEFAULT_INIT_BLUR,)
        seg, _, energies = chan_vese(image, mu=0.1, lambda1=1.0, lambda2=2.0, extended_output=True)
    finally:
        compat.CHECKERBOARD_BLURS = blurs
    result = ac.segment(image, None, mu=0.1, lambda_in=1.0, lambda_out=2.0, tol=1e-3)
    np.testing.assert_array_equal(seg, result.mask)
    np.testing.assert_allclose(energies, result.energies, rtol=1e-12)  # the same iterations
    assert energies[-1] == pytest.approx(
        ac.chan_vese_energy(image, result.contours, mu=0.1, lambda_out=2.0), rel=1e-12)


def test_checkerboard_takes_the_blur_whose_threshold_set_is_lowest():
    """A band of contrast 0.3 under +-0.3 speckle at mu = 0.25: blurred by 1 px its threshold set is
    ragged (long), wider blurs give a smoother band; the start is the one of lowest (6.38)."""
    image = np.zeros((64, 64))
    image[20:44, :] = 0.3
    image += 0.3 * np.where(np.random.default_rng(5).random(image.shape) > 0.5, 1.0, -1.0)
    values = image[..., None] - image.min()
    values /= values.max()
    costs = [threshold_split(blurred(values, b), values, 0.25)[2] for b in compat.CHECKERBOARD_BLURS]
    start = compat._checkerboard_start(values, 0.25).contours
    chosen = compat.CHECKERBOARD_BLURS[int(np.argmin(costs))]
    assert costs[0] > min(costs)  # the test means something: 1 px is not the best here
    expected = [resample(c, 1.0) for c in threshold_starts(values, 0.25, blurs=(chosen,))[0]]  # spacing
    assert len(start) == len(expected)
    for ours, theirs in zip(start, expected, strict=True):
        np.testing.assert_array_equal(ours, theirs)


def test_checkerboard_start_is_taken_as_the_boundary_it_is(monkeypatch):
    """The threshold set's outline is oriented by nesting and holds no crossing already: the flow
    takes it as a result's contours (:class:`activecontour.initial.Start`), without rebuilding it
    as a user's curves (region_boundary: about 3 % of a call on scikit-image's brick)."""
    import activecontour.initial

    image = np.zeros((64, 80))
    image[8:56, 10:70] = 1.0
    image[20:44, 26:54] = 0.0  # a hole: an outer boundary and a negatively oriented one

    def rebuilt(curves):
        raise AssertionError("the checkerboard start was rebuilt as a user's curves")

    monkeypatch.setattr(activecontour.initial, "region_boundary", rebuilt)
    start = compat._checkerboard_start(image[..., None], 0.25)
    assert sorted(np.sign(signed_area(c)) for c in start.contours) == [-1.0, 1.0]
    assert dice(start.mask, image > 0.5) > 0.98  # the inside of the contours
    assert dice(chan_vese(image), image > 0.5) > 0.98


@pytest.mark.parametrize("init_level_set", ["disk", "small disk"])
def test_disk_starts_find_the_disk(init_level_set, noisy_disk):
    image, truth = noisy_disk
    assert dice(chan_vese(image, init_level_set=init_level_set), truth) >= 0.95


def test_array_start_is_its_positive_region(noisy_disk):
    image, truth = noisy_disk
    rr, cc = np.mgrid[:64, :64]
    phi = 10.0 - np.hypot(rr - 30, cc - 34)  # a disk of radius 10 inside the object
    assert dice(chan_vese(image, init_level_set=phi), truth) >= 0.95
    # phi of a previous run restarts from its own result
    seg, phi_out, _ = chan_vese(image, extended_output=True)
    assert dice(chan_vese(image, init_level_set=phi_out), seg) >= 0.99


def test_integer_and_float_images_give_one_segmentation(noisy_disk):
    """Both rescale by the image's own range, as scikit-image does."""
    image = noisy_disk[0]
    as_uint8 = np.round(255 * (image - image.min()) / np.ptp(image)).astype(np.uint8)
    np.testing.assert_array_equal(chan_vese(as_uint8), chan_vese(as_uint8 / 255.0 * 7.0 - 3.0))


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(image=np.zeros((8, 8, 3))), ValueError, "2-D"),
    (dict(image=np.zeros(8)), ValueError, "2-D"),
    (dict(mu=-1.0), ValueError, "mu"),
    (dict(lambda1=0.0), ValueError, "lambda1"),
    (dict(lambda2=-1.0), ValueError, "lambda2"),
    (dict(lambda1=np.nan), ValueError, "lambda1"),
    (dict(tol=-1e-3), ValueError, "tol"),
    (dict(tol="small"), ValueError, "tol"),
    (dict(max_num_iter=1.5), TypeError, "max_num_iter"),
    (dict(max_num_iter=-1), ValueError, "max_num_iter"),
    (dict(dt=0.0), ValueError, "dt"),
    (dict(dt=np.inf), ValueError, "dt"),
    (dict(init_level_set="circle"), ValueError, "init_level_set must be one of"),
    (dict(init_level_set=np.ones((4, 4))), ValueError, "init_level_set has shape"),
    (dict(init_level_set=[[1.0]]), TypeError, "init_level_set"),
])
def test_bad_arguments_name_the_parameter(kwargs, error, match):
    arguments = dict(image=np.random.default_rng(0).random((16, 16)))
    arguments.update(kwargs)
    with pytest.raises(error, match=match):
        chan_vese(**arguments)


def test_readme_example_runs():
    """README's "Coming from scikit-image" block runs as written and returns what it says."""
    from tests.app.test_readme import python_blocks, run_blocks

    (block,) = [code for code in python_blocks() if "activecontour.compat" in code]
    namespace = run_blocks(block)
    segmentation, phi = namespace["segmentation"], namespace["phi"]
    assert segmentation.dtype == bool and segmentation.shape == namespace["image"].shape
    np.testing.assert_array_equal(phi > 0, segmentation)


# scikit-image 0.26's tests/skimage/segmentation/test_chan_vese.py, intent by intent, against the
# drop-in (the same images, arguments and expectations)

def _square(size=10):
    image = np.zeros((size, size))
    image[3:6, 3:6] = 1
    return image


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_skimage_flat_level_set_keeps_its_start(dtype):
    """A level set without a zero level set: everything inside stays inside, nothing stays nothing
    (no contour to move; scikit-image's flow leaves it too)."""
    image = _square().astype(dtype)
    level_set = np.full((10, 10), 1000, dtype=dtype)
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=1e-3, init_level_set=level_set),
                                  np.ones((10, 10), dtype=bool))
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=1e-3, init_level_set=-level_set),
                                  np.zeros((10, 10), dtype=bool))


def test_skimage_small_disk_level_set_finds_the_square():
    image = _square()
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=1e-3, init_level_set="small disk"), image > 0)


def test_skimage_simple_shape_from_the_checkerboard():
    image = _square()
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=1e-8), image > 0)


@pytest.mark.parametrize("dtype, float_dtype", [(np.uint8, np.float64), (np.float16, np.float32),
                                                (np.float32, np.float32), (np.float64, np.float64)])
def test_skimage_extended_output_floats(dtype, float_dtype):
    """phi and every energy in scikit-image's float type: float32 for float16/float32 images."""
    result = chan_vese(_square().astype(dtype), mu=0.0, tol=1e-8, extended_output=True)
    assert len(result) == 3
    assert result[1].dtype == float_dtype
    assert result[2] and all(energy.dtype == float_dtype for energy in result[2])


def test_skimage_remove_noise():
    """A one-pixel speck outside the rounded square is noise at mu = 0.3: not in the result."""
    reference = np.zeros((10, 10))
    reference[1:6, 1:6] = np.array([[0, 1, 1, 1, 0],
                                     [1, 1, 1, 1, 1],
                                     [1, 1, 1, 1, 1],
                                     [1, 1, 1, 1, 1],
                                     [0, 1, 1, 1, 0]])
    image = reference.copy()
    image[8, 3] = 1
    result = chan_vese(image, mu=0.3, tol=1e-3, max_num_iter=100, dt=10, init_level_set="disk")
    np.testing.assert_array_equal(result, reference > 0)


def test_skimage_incorrect_image_type():
    with pytest.raises(ValueError):
        chan_vese(np.zeros((10, 10, 3)), mu=0.0, init_level_set=np.zeros((10, 9)))


def test_skimage_gap_closing():
    """A one-pixel gap across a band is closed at mu = 0.7."""
    reference = np.zeros((20, 20))
    reference[8:15, :] = 1
    image = reference.copy()
    image[:, 6] = 0
    result = chan_vese(image, mu=0.7, tol=1e-3, max_num_iter=1000, dt=1000, init_level_set="disk")
    np.testing.assert_array_equal(result, reference > 0)


def test_skimage_incorrect_level_set():
    with pytest.raises(ValueError):
        chan_vese(np.zeros((10, 10)), mu=0.0, init_level_set=np.zeros((10, 9)))
    with pytest.raises(ValueError):
        chan_vese(np.zeros((10, 10)), mu=0.0, init_level_set="a")


def test_skimage_blank_image_keeps_its_start():
    """On a blank image at mu = 0 every region has the same (6.38): the start stays.  scikit-image's
    case (a positive level set) and one with a zero level set through a random pattern."""
    image = np.zeros((10, 10))
    level_set = np.random.RandomState(1651833154).rand(10, 10)
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=0.0, init_level_set=level_set), level_set > 0)
    level_set = np.random.default_rng(0).random((10, 10)) - 0.5
    np.testing.assert_array_equal(chan_vese(image, mu=0.0, tol=0.0, init_level_set=level_set), level_set > 0)


def test_the_objects_pass_is_left_out(noisy_disk, monkeypatch):
    """No object ids are returned, so the drop-in runs segment's flow without the objects' pass
    (find_objects), and its segmentation and energies are segment's."""
    import activecontour._segment

    image, _ = noisy_disk
    rr, cc = np.mgrid[:64, :64]
    level_set = 10.0 - np.hypot(rr - 30, cc - 34)
    kwargs = dict(mu=0.1, max_num_iter=50, tol=1e-3)
    expected = ac.segment(image, mask_to_curves(level_set > 0), separate=False, **kwargs)

    def refuse(*args, **kwargs):
        raise AssertionError("the drop-in ran the objects' pass")

    monkeypatch.setattr(activecontour._segment, "find_objects", refuse)
    seg, _, energies = chan_vese(image, init_level_set=level_set, extended_output=True, **kwargs)
    np.testing.assert_array_equal(seg, expected.mask)
    assert energies[-1] == pytest.approx(expected.energy, rel=1e-12)


def test_solve_problem_without_objects_is_the_same_partition(noisy_disk):
    from activecontour._segment import solve_problem
    from activecontour.problem import prepare
    from activecontour.settings import Settings

    image, _ = noisy_disk
    problem = prepare(image, Settings(mu=0.1, max_num_iter=30))
    full = solve_problem(problem)
    bare = solve_problem(problem, objects=False)
    assert full.labels is not None and bare.labels is None and bare.objects is None
    np.testing.assert_array_equal(bare.mask, full.mask)
    np.testing.assert_array_equal(bare.classes, full.classes)
    assert bare.energy == full.energy


def test_distance_is_scipys_exactly():
    """The signed distance's transform gives scipy's exact Euclidean distances, bit for bit, on
    blobs of every size and on a distance beyond float32's exact range (1500 px)."""
    import scipy.ndimage

    rng = np.random.default_rng(2)
    for shape, width in (((40, 70), 1.0), ((300, 200), 3.0), ((257, 513), 12.0)):
        smooth = scipy.ndimage.gaussian_filter(rng.random(shape), width)
        blobs = smooth > np.median(smooth)
        for mask in (blobs, ~blobs):
            np.testing.assert_array_equal(compat._distance(mask), scipy.ndimage.distance_transform_edt(mask))
    far = np.ones((1, 1500), dtype=bool)
    far[0, 0] = False
    np.testing.assert_array_equal(compat._distance(far), np.arange(1500.0)[np.newaxis])


@pytest.mark.parametrize("image", ["noisy_disk", "blank"])
def test_the_checkerboard_call_checks_its_settings_once_and_flows_with_its_options(image, noisy_disk,
                                                                                   monkeypatch):
    """The settings of a checkerboard call are made and checked once (not again to set the flow's
    options), and the flow gets the checkerboard's options (a 2 px first smoothing, no global
    move) when there is a checkerboard start, segment's defaults when there is none (a blank
    image has no threshold set)."""
    from activecontour.backends.polygon import _START_SMOOTHING
    from activecontour.settings import Settings

    image = noisy_disk[0] if image == "noisy_disk" else np.full((32, 48), 0.5)
    made, flowed = [], []
    original_check, original_solve = Settings.__post_init__, compat.solve_problem

    def check(settings):
        made.append(settings.options)
        original_check(settings)

    def solve(problem, init, **keywords):
        flowed.append((init, problem.settings.backend_options))
        return original_solve(problem, init, **keywords)

    monkeypatch.setattr(Settings, "__post_init__", check)
    monkeypatch.setattr(compat, "solve_problem", solve)
    chan_vese(image)
    (init, options), = flowed
    if init is None:  # no start: the default start, flowed as segment flows it
        assert made[-1] is None
        assert options.smoothing is None and options.global_start
    else:
        assert len(made) == 1
        assert options.smoothing == _START_SMOOTHING and not options.global_start
