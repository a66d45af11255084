"""The default start: the global minimiser of (6.38) over threshold sets, checked by brute force,
and the small objects a local 2-means split lost to the background's noise."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.initial import SPLIT_BINS, threshold_split


def brute_force_cost(smooth, values, mu, region):
    """(6.38) of a pixel region by its definition: the class means' squared deviations (mean over
    channels) plus mu times pi/4 per 4-neighbour pair the region separates (Cauchy-Crofton)."""
    fit = 0.0
    for part in (region, ~region):
        if part.any():
            fit += np.sum((values[part] - values[part].mean(axis=0)) ** 2) / values.shape[2]
    pairs = np.count_nonzero(region[1:] != region[:-1]) + np.count_nonzero(region[:, 1:] != region[:, :-1])
    return fit + mu * np.pi / 4 * pairs


def quantised_scene(seed, levels=256):
    """A blurred noisy two-disk scene whose values are multiples of 1 / levels: every distinct value
    has its own bin of the scan (1 / levels > 1 / SPLIT_BINS), so the scan is exact."""
    image, _ = synthetic.disk_image(48, (15, 30), 7, inside=0.7, outside=0.3)
    image = synthetic.add_noise(image, 0.2, seed, blur=1.0)
    image = (image - image.min()) / (image.max() - image.min())
    return np.round(image * levels)[:, :, None] / levels


@pytest.mark.parametrize("mu", [0.0, 0.02, 0.3])
@pytest.mark.parametrize("seed", [0, 1])
def test_the_scan_finds_the_brute_force_minimiser_over_all_thresholds(mu, seed):
    assert 256 < SPLIT_BINS
    smooth = quantised_scene(seed)
    values = synthetic.add_noise(smooth[:, :, 0], 0.05, seed + 10)[:, :, None]  # the fit reads other values
    thresholds = np.unique(smooth)[1:]  # every split into two non-empty classes
    costs = [brute_force_cost(smooth, values, mu, smooth[:, :, 0] >= t) for t in thresholds]
    best = thresholds[int(np.argmin(costs))]
    direction, threshold, cost = threshold_split(smooth, values, mu)
    assert direction == pytest.approx([1.0])
    region = smooth[:, :, 0] >= threshold
    assert np.array_equal(region, smooth[:, :, 0] >= best)
    assert cost == pytest.approx(min(costs), rel=1e-9)


def test_a_vector_image_splits_along_the_object_colour():
    # red disk on a green background of the same luminance: gray has no contrast, colour does
    image, truth = synthetic.equal_gray_colour(seed=3)
    smooth = image.astype(np.float64)
    direction, threshold, cost = threshold_split(smooth, smooth, 0.01)
    region = smooth @ direction >= threshold
    assert synthetic.dice(region, truth) >= 0.9 or synthetic.dice(~region, truth) >= 0.9
    # no threshold along another direction of the principal ones does better
    for axis in np.linalg.svd(smooth.reshape(-1, 3) - smooth.reshape(-1, 3).mean(0), full_matrices=False)[2]:
        projected = smooth @ axis
        for t in np.quantile(projected, np.linspace(0.02, 0.98, 25)):
            assert cost <= brute_force_cost(smooth, smooth, 0.01, projected >= t) * (1 + 1e-9)


# (fraction of a 512^2 image, noise sigma, centre): one bright disk at contrast 0.4, SNR 0.4 / sigma
SMALL_OBJECTS = [(0.001, 0.08, (262.0, 474.0)), (0.003, 0.15, (120.0, 90.0)),
                 (0.01, 0.2, (400.0, 300.0)), (0.015, 0.15, (150.0, 330.0))]


@pytest.mark.parametrize("fraction, sigma, centre", SMALL_OBJECTS)
def test_a_small_object_at_low_snr_is_found_by_the_default_start(fraction, sigma, centre):
    radius = np.sqrt(fraction * 512**2 / np.pi)
    image, truth = synthetic.disk_image(512, centre, radius, inside=0.7, outside=0.3)
    image = synthetic.add_noise(image, sigma, seed=0)
    result = ac.segment(image)
    assert result.success, result.message
    assert synthetic.dice(result.mask, truth) >= 0.95


def test_a_sampled_scan_of_a_large_image_takes_the_rows_below_the_sample_too():
    # over 2**20 pixels the scan reads every other row, and the rows paired with them (below) may
    # hold values outside the sampled range: they belong to the end bins, not to negative ones
    rng = np.random.default_rng(5)
    smooth = rng.normal(0.3, 0.05, (1100, 1000, 1))
    smooth[1::2] += 0.5  # the unsampled rows (below each sampled one) reach far above its range
    smooth[3::4] -= 1.0  # and far below it
    direction, threshold, cost = threshold_split(smooth)
    assert np.isfinite(cost) and np.isfinite(threshold) and direction.shape == (1,)


def test_a_fine_texture_inside_an_object_does_not_split_the_default_start():
    # a 6 px grating of amplitude 0.2 on a disk of mean 0.6 (0.1 on the 0.35 background): at 1 px
    # blur the exact scan prefers the grating's peaks; at twice the scale the disk wins
    r, c = np.mgrid[0:256, 0:256].astype(float)
    base, truth = synthetic.disk_image(256, (128, 115), 72, inside=1.0, outside=0.0)
    texture = 0.2 * np.sin(2 * np.pi * (r + 0.5 * c) / 6.0)
    image = synthetic.add_noise(0.35 + 0.25 * base + texture * np.where(base > 0.5, 1.0, 0.5), 0.05, 4)
    start = ac.segment(image, max_num_iter=0)
    assert synthetic.dice(start.mask, truth) >= 0.95
    assert synthetic.dice(ac.segment(image).mask, truth) >= 0.99


def test_threshold_mask_scans_each_blur_once(monkeypatch):
    """Of several blur widths, each smoothed image is scanned once (its cost and its split are
    the same scan), plus once the 2 x 2 block means of the image (the split must hold at twice
    the scale): blurs + 1 scans, not the chosen blur's twice."""
    import activecontour.initial as initial

    image, _ = synthetic.disk_image(64, (30.0, 34.0), 14.0, inside=0.75, outside=0.25)
    values = synthetic.add_noise(image, 0.1, seed=1)[..., None]
    values = (values - values.min()) / (values.max() - values.min())
    calls = []
    scan = initial.threshold_split

    def counted(*args, **kwargs):
        calls.append(args[0].shape)
        return scan(*args, **kwargs)

    monkeypatch.setattr(initial, "threshold_split", counted)
    blurs = (1.0, 2.0, 4.0)
    mask, contrast = initial.threshold_mask(values, 0.05, blurs=blurs)
    assert contrast > 0 and mask[30, 34] and not mask[0, 0]
    assert len(calls) == len(blurs) + 1
    assert calls.count((32, 32, 1)) == 1  # the block means' scan


def test_the_default_start_holds_no_whole_blurred_image():
    """The default start holds its threshold set (1 byte per pixel) and sampled rows, never a
    float64 blur of the whole image (8 bytes per pixel): an image with 2 Mpx more peaks at less
    than 8 bytes per added pixel more (holding the blur, the block means and their blur, it took
    15)."""
    import tracemalloc

    import activecontour.initial as initial

    peaks = []
    for rows in (1024, 2048):
        rng = np.random.default_rng(rows)
        values = 0.2 + 0.2 * rng.random((rows, 2048, 1))
        values[rows // 4: rows // 2, 600:1400] += 0.4
        tracemalloc.start()
        mask, contrast = initial.threshold_mask(values, 0.1)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        assert contrast > 0 and mask[rows // 3, 1000] and not mask[0, 0]
    assert peaks[1] - peaks[0] < 8 * 1024 * 2048
