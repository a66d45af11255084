"""activecontour.compat.chan_vese: scikit-image's signature and return types, our energy."""

import inspect

import numpy as np
import pytest
import skimage.segmentation

import activecontour as ac
from activecontour.compat import chan_vese
from activecontour.geometry.raster import mask_to_curves
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
    assert isinstance(energies, list) and all(type(e) is float for e in energies)
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


@pytest.mark.parametrize("dtype", [np.float16, np.float32])
def test_phi_dtype_follows_scikit_image(dtype, noisy_disk):
    image = noisy_disk[0].astype(dtype)
    _, phi, _ = chan_vese(image, extended_output=True)
    assert phi.dtype == np.float32


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
    """mu, lambda1/2 pass unchanged, tol scaled so that the defaults correspond, and
    init_level_set="checkerboard" is the default start: the same result as segment's."""
    image, _ = noisy_disk
    seg, _, energies = chan_vese(image, mu=0.1, lambda1=1.0, lambda2=2.0, extended_output=True)
    result = ac.segment(image, None, mu=0.1, lambda_in=1.0, lambda_out=2.0, tol=5e-4)
    np.testing.assert_array_equal(seg, result.mask)
    assert energies[-1] == pytest.approx(
        ac.chan_vese_energy(image, result.contours, mu=0.1, lambda_out=2.0), rel=1e-12)


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
    # no positive value: no region to start from, the default start instead
    np.testing.assert_array_equal(chan_vese(image, init_level_set=-np.ones((64, 64))), seg)


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
