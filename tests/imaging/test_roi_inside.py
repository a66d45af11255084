"""inside= (which region is the objects) and roi= (the domain D of (6.38) restricted)."""

import cv2
import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.evaluate import chan_vese_energy
from activecontour.io.objects import read_label_image, read_objects_csv
from app import cli

CENTERS = [(25 + 35 * i, 25 + 35 * j) for i in range(3) for j in range(3)]
RADIUS = 11.0


@pytest.fixture(scope="module")
def blobs():
    """Nine disks on a 3 x 3 grid, noisy, and the truth of each."""
    disks = synthetic.union(*[synthetic.disk(c, RADIUS) for c in CENTERS])
    image, truth = synthetic.render(disks, (120, 120))
    truths = [synthetic.render(synthetic.disk(c, RADIUS), (120, 120))[1] for c in CENTERS]
    return synthetic.add_noise(image, 0.1, seed=3), truth, truths


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_inside_chooses_the_region(blobs, backend):
    image, truth, _ = blobs
    bright = ac.segment(image, backend=backend, inside="bright")
    dark = ac.segment(image, backend=backend, inside="dark")
    assert bright.c_in > bright.c_out and dark.c_in < dark.c_out
    assert synthetic.dice(bright.mask, truth) > 0.97
    assert synthetic.dice(dark.mask, ~truth) > 0.97
    assert bright.labels.max() == 9
    for res in (bright, dark):  # the complement is a result like any other: one energy
        assert res.energy == pytest.approx(chan_vese_energy(image, res.contours, mu=res.mu), rel=1e-9)
    # dark objects on a bright background: "dark" is what "auto" finds, "bright" its complement
    inverted = ac.segment(1.0 - image, backend=backend)
    assert synthetic.dice(inverted.mask, truth) > 0.97
    assert synthetic.dice(ac.segment(1.0 - image, backend=backend, inside="dark").mask, truth) > 0.97


def test_inside_is_checked():
    with pytest.raises(ValueError, match=r"inside must be one of \('auto', 'bright', 'dark'\)"):
        ac.segment(np.eye(8), inside="objects")


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_circle_around_one_blob_gives_that_blob_alone(blobs, backend):
    image, _, truths = blobs
    target = 4  # the centre blob: neighbours on all sides, 24 px gaps
    res = ac.segment(image, ac.circle(CENTERS[target], RADIUS + 6), roi="init", backend=backend)
    assert synthetic.dice(res.mask, truths[target]) >= 0.97
    others = np.logical_or.reduce([t for i, t in enumerate(truths) if i != target])
    assert not (res.mask & others).any()
    assert res.labels.max() == 1
    # without the roi, the same circle reaches the other blobs (the complaint)
    assert (ac.segment(image, ac.circle(CENTERS[target], RADIUS + 6), backend=backend).mask & others).any()


def test_a_curve_drawn_inside_the_object_grows_its_domain_to_hold_it():
    image, truth = synthetic.render(synthetic.disk((60, 64), 30.0), (128, 128))
    image = synthetic.add_noise(image, 0.1, seed=4)
    res = ac.segment(image, ac.circle((62.0, 60.0), 12.0), roi="init")
    assert synthetic.dice(res.mask, truth) > 0.97
    assert not (res.mask & ~res.roi).any() and not res.roi.all()  # a neighbourhood, not the image
    again = ac.segment(image, res, roi=res.roi)  # continued on the same domain: already there
    assert synthetic.dice(again.mask, res.mask) > 0.995


def test_box_roi_is_the_crop_exactly(blobs):
    image, _, truths = blobs
    box = (40, 5, 80, 45)  # holds the blob at (60, 25) only
    res = ac.segment(image, roi=box)
    np.testing.assert_array_equal(res.mask[40:80, 5:45], ac.segment(image[40:80, 5:45]).mask)
    # the crop in the whole image's normalised units (its range onto [0, 1]), which a result reports
    crop = ac.segment(((image - image.min()) / np.ptp(image))[40:80, 5:45], normalize=None)
    np.testing.assert_array_equal(res.mask[40:80, 5:45], crop.mask)
    assert not res.mask[:40].any() and not res.mask[80:].any()
    assert res.roi[40:80, 5:45].all() and res.roi.sum() == 40 * 40
    assert res.energy == pytest.approx(crop.energy, rel=1e-12)
    assert (res.mu, res.c_in, res.c_out) == pytest.approx((crop.mu, crop.c_in, crop.c_out), rel=1e-12)
    assert synthetic.dice(res.mask, truths[3]) > 0.97


@pytest.mark.parametrize("mu", ["auto", 0.05])
@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_a_roi_result_is_in_the_whole_images_units(mu, noise):
    """A crop whose own range is a quarter of the image's (a dim disk in the box, a bright one
    outside it): ``mu``, ``c_in``, ``c_out`` and the energy are those of (6.38) on the image's
    normalised intensities, the units of a run on the whole image; a given mu means the same on
    both, and a noise-free image's default mu is the whole image's floor."""
    from activecontour.imaging.noise import MU_FLOOR

    dim, bright = synthetic.disk((30, 30), 12.0), synthetic.disk((30, 90), 12.0)
    image = 0.25 * synthetic.render(dim, (60, 120))[0] + synthetic.render(bright, (60, 120))[0]
    image = synthetic.add_noise(image, noise, seed=2) if noise else image
    normalised = (image - image.min()) / np.ptp(image)
    res = ac.segment(image, roi=(5, 5, 55, 55), mu=mu)
    inside, outside = ((value - image.min()) / np.ptp(image) for value in (0.25, 0.0))
    assert res.c_in == pytest.approx(inside, abs=0.01) and res.c_out == pytest.approx(outside, abs=0.01)
    assert res.c_in_image == pytest.approx(image.min() + res.c_in * np.ptp(image), rel=1e-12)
    if mu == "auto" and not noise:
        assert res.mu == MU_FLOOR == ac.segment(image).mu
    if mu != "auto":
        assert res.mu == mu
    shifted = [c - (5, 5) for c in res.contours]
    assert res.energy == pytest.approx(chan_vese_energy(normalised[5:55, 5:55], shifted, mu=res.mu,
                                                        normalize=None), rel=1e-9)
    assert res.energy == pytest.approx(chan_vese_energy(normalised[5:55, 5:55], shifted, mu=res.mu,
                                                        c_in=res.c_in, c_out=res.c_out, normalize=None),
                                       rel=1e-9)


def test_a_masks_noise_is_read_on_its_pixels_not_its_fill(blobs):
    """The crop of a mask fills the pixels outside it with one value (no noise): the length weight
    comes from the noise of the domain's own pixels, the same as that of the pixels of the box
    that lies within the domain."""
    from activecontour.imaging.noise import auto_mu
    from activecontour.imaging.roi import resolve_roi
    from activecontour.problem import prepare

    image, _, _ = blobs
    domain = np.zeros(image.shape, bool)
    domain[20:100, 20:100] = np.hypot(*np.mgrid[-40:40, -40:40]) < 40  # a disk: most of its box filled
    part = prepare(image).restricted(*resolve_roi(domain, image.shape))
    inner = part.values[14:66, 14:66]  # a square inside the disk: the image's own pixels
    assert part.auto_mu == pytest.approx(auto_mu(inner), rel=0.15)
    assert auto_mu(part.values) < 0.8 * part.auto_mu  # the fill's zero responses pull it down


def test_mask_roi_keeps_the_result_inside_the_mask(blobs):
    image, _, truths = blobs
    domain = np.zeros(image.shape, bool)
    domain[10:95, 10:50] = True  # blobs 0 and 3 whole, 6 cut by the mask's lower edge
    res = ac.segment(image, roi=domain)
    assert not (res.mask & ~domain).any()
    assert synthetic.dice(res.mask & (truths[0] | truths[3]), truths[0] | truths[3]) > 0.97


@pytest.mark.parametrize("roi, message", [
    ("everything", "roi must be None, 'init'"), ((0, 0, 1, 5), "less than 2 x 2"),
    (np.zeros((3, 3), bool), "roi mask has shape"), (np.zeros((8, 8), bool), "roi mask is empty"),
])
def test_bad_roi_is_named(roi, message):
    with pytest.raises(ValueError, match=message):
        ac.segment(np.eye(8), roi=roi)
    with pytest.raises(ValueError, match="roi='init' needs an init"):
        ac.segment(np.eye(8), roi="init")


def test_cli_inside_and_object_files(tmp_path, capsys, blobs):
    image, truth, _ = blobs
    path = tmp_path / "blobs.png"
    cv2.imwrite(str(path), np.round(np.clip(1.0 - image, 0, 1) * 255).astype(np.uint8))
    status = cli.main(["segment", str(path), "--inside", "dark", "--objects", "labels,csv", "-q"])
    assert status == 0, capsys.readouterr().err
    labels = read_label_image(tmp_path / "blobs_labels.png")
    assert labels.max() == 9 and synthetic.dice(labels > 0, truth) > 0.97
    table = read_objects_csv(tmp_path / "blobs_objects.csv")
    np.testing.assert_allclose(np.sort(table["area"]), np.pi * RADIUS**2, rtol=0.03)
    status = cli.main(["segment", str(path), "--objects", "shapefile"])
    assert status == 2 and "unknown object format 'shapefile'" in capsys.readouterr().err
