"""N regions: the partition of a label image, its energy and shape derivative, the K-means start
and the label-field backend on scenes with ground truth."""

import itertools

import numpy as np
import pytest
import skimage.data
import skimage.measure

import activecontour as ac
from activecontour.energy import evaluate_partition, partition_load
from activecontour.geometry.partition import Boundary, chain, class_boundary, class_soup
from activecontour.geometry.raster import rasterize
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.models import ChanVeseParameters
from activecontour.models.kmeans import histogram_kmeans


def _blocks():
    """A pixel-exact partition into four classes: straight interfaces from border to border along
    pixel edges, meeting at a three-region (T) and a four-region (+) junction."""
    classes = np.zeros((24, 30), dtype=np.int32)
    classes[:12, 5:14] = 1
    classes[12:, 5:14] = 2
    classes[:12, 14:] = 3
    return classes


def _bilinear_integrals(image, classes, constants, weights):
    """sum_k int_{pixel squares of class k} w_k (I - c_k)^2 of the bilinear image, by 2-point
    Gauss-Legendre per quarter pixel (the integrand is a polynomial of degree 2 per axis there)."""
    m, n = image.shape
    padded = np.pad(image, 1, mode="edge")
    nodes = np.array([0.5 - 0.5 / np.sqrt(3), 0.5 + 0.5 / np.sqrt(3)]) * 0.5
    total = 0.0
    for qr, qc in itertools.product((-0.5, 0.0), repeat=2):  # quarter's corner offset
        for gr, gc in itertools.product(nodes, repeat=2):
            r = np.arange(m)[:, None] + qr + gr
            c = np.arange(n)[None, :] + qc + gc
            i0, j0 = np.floor(r).astype(int), np.floor(c).astype(int)
            t, w = r - i0, c - j0
            value = ((1 - t) * (1 - w) * padded[i0 + 1, j0 + 1] + t * (1 - w) * padded[i0 + 2, j0 + 1]
                     + (1 - t) * w * padded[i0 + 1, j0 + 2] + t * w * padded[i0 + 2, j0 + 2])
            total += np.sum(weights[classes] * (value - constants[classes]) ** 2) * 0.25 * 0.25
    return total


def test_partition_of_a_label_image_tiles_the_domain():
    classes = np.random.default_rng(0).integers(0, 4, (9, 11))
    boundary = class_boundary(classes)
    areas = []
    for k in range(4):
        starts, ends = class_soup(boundary, k)
        areas.append(0.5 * np.sum(starts[:, 0] * ends[:, 1] - ends[:, 0] * starts[:, 1]))
        curves = chain(starts, ends)
        assert sum(0.5 * np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])
                   for c in curves) == pytest.approx(areas[-1])
    assert np.all(np.array(areas) > 0)
    assert sum(areas) == pytest.approx(9 * 11)


def test_blocks_energy_is_the_exact_functional():
    classes = _blocks()
    image = np.random.default_rng(1).random(classes.shape)
    model = ImageModel(normalize_image(image, normalize=None))
    params = ChanVeseParameters(mu=0.7, omega=0.2, lambda_in=1.5, lambda_out=0.5)
    constants = np.array([[0.1], [0.3], [0.6], [0.9]])
    result = evaluate_partition(model, class_boundary(classes), params, 4, constants)
    weights = np.array([0.5, 1.5, 1.5, 1.5])
    fit = _bilinear_integrals(image, classes, constants[:, 0], weights)
    # interfaces along pixel edges, each once: 4-neighbour pairs of different classes
    interfaces = np.sum(classes[1:] != classes[:-1]) + np.sum(classes[:, 1:] != classes[:, :-1])
    # and the image border where a region other than the background lies on it
    border = sum(np.sum(side > 0) for side in (classes[0], classes[-1], classes[:, 0], classes[:, -1]))
    area_inside = np.sum(classes > 0)  # the partition is the union of pixel squares
    expected = 0.7 * (interfaces + border) + 0.2 * area_inside + fit
    assert result.length == interfaces + border
    assert result.energy == pytest.approx(expected, rel=1e-12)


def test_two_classes_score_as_the_two_region_functional_of_their_contours():
    image = np.random.default_rng(2).random((30, 40))
    rows, cols = np.mgrid[:30, :40]
    classes = ((rows - 14.3) ** 2 + (cols - 20.2) ** 2 < 90).astype(np.int32)
    # marching squares of the indicator at 1/2 (outer boundaries positive after reversal)
    contours = [c[::-1][:-1] for c in skimage.measure.find_contours(classes.astype(float), 0.5)]
    by_classes = ac.chan_vese_energy(image, classes=classes, mu=0.3, omega=0.1)
    by_contours = ac.chan_vese_energy(image, contours, mu=0.3, omega=0.1)
    assert by_classes == pytest.approx(by_contours, rel=1e-12)


def test_shape_derivative_on_every_interface_and_at_junctions():
    classes = _blocks()
    image = np.random.default_rng(3).random(classes.shape)
    model = ImageModel(normalize_image(image, normalize=None))
    params = ChanVeseParameters(mu=0.4, omega=0.1, lambda_in=1.2, lambda_out=0.8)
    constants = np.array([[0.2], [0.4], [0.6], [0.8]])
    boundary = class_boundary(classes)
    load = partition_load(model, boundary, params, constants)
    ends = np.concatenate([boundary.start, boundary.end])
    interior = np.all((ends > -0.5) & (ends < np.array(classes.shape) - 0.5), axis=1)
    points, counts = np.unique(ends[interior], axis=0, return_counts=True)
    junctions = points[counts >= 3]  # three or more segments meet
    assert len(junctions) == 2
    rng = np.random.default_rng(4)
    checked = list(junctions) + list(points[rng.choice(len(points), 12, replace=False)])

    def energy(point, moved):
        start, end = boundary.start.copy(), boundary.end.copy()
        start[np.all(boundary.start == point, axis=1)] = moved
        end[np.all(boundary.end == point, axis=1)] = moved
        moved_boundary = Boundary(start, end, boundary.inner, boundary.outer)
        return evaluate_partition(model, moved_boundary, params, 4, constants).energy

    for point in checked:
        analytic = (load[:, 0][np.all(boundary.start == point, axis=1)].sum(axis=0)
                    + load[:, 1][np.all(boundary.end == point, axis=1)].sum(axis=0))
        step = 1e-6
        numeric = [(energy(point, point + step * e) - energy(point, point - step * e)) / (2 * step)
                   for e in np.eye(2)]
        np.testing.assert_allclose(numeric, analytic, atol=1e-6 * max(1.0, np.abs(analytic).max()))


def test_histogram_kmeans_is_the_global_optimum():
    rng = np.random.default_rng(5)
    clusters = ((0.1, 400), (0.5, 60), (0.55, 30), (0.9, 200))
    values = np.concatenate([rng.normal(m, 0.04, n) for m, n in clusters])
    bins = 24
    thresholds, levels = histogram_kmeans(values, 3, bins=bins)
    # brute force over every pair of cuts between the used bins
    width = (values.max() - values.min()) / bins
    index = np.minimum(((values - values.min()) / width).astype(int), bins - 1)

    def sse(cuts):
        labels = np.searchsorted(np.array(cuts), index, side="right")
        return sum(np.sum((values[labels == k] - values[labels == k].mean()) ** 2)
                   for k in range(3) if np.any(labels == k))

    best = min(sse(c) for c in itertools.combinations(range(1, bins), 2))
    labels = np.digitize(values, thresholds, right=True)
    found = sum(np.sum((values[labels == k] - values[labels == k].mean()) ** 2) for k in range(3))
    assert found == pytest.approx(best, rel=1e-9)
    assert np.all(np.diff(levels) > 0)


def _dice(found, truth, n_classes):
    return np.array([2 * np.sum((found == k) & (truth == k)) / (np.sum(found == k) + np.sum(truth == k))
                     for k in range(n_classes)])


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_three_nested_classes_at_snr_3(backend):
    m = 192
    rows, cols = np.mgrid[:m, :m]
    radius = np.hypot(rows - m / 2, cols - m / 2)
    truth = (radius < 75).astype(int) + (radius < 40)
    image = truth / 2.0 + np.random.default_rng(6).normal(0, 0.5 / 3, truth.shape)
    res = ac.segment(image, n_regions=3, backend=backend)
    assert res.success and res.backend == backend
    assert np.all(_dice(res.classes, truth, 3) > 0.99)
    assert res.energy == pytest.approx(ac.chan_vese_energy(image, regions=res.class_contours, mu=res.mu),
                                       rel=1e-12)
    if backend == "levelset":  # the partition its label image stands for
        assert res.energy == ac.chan_vese_energy(image, classes=res.classes, mu=res.mu)
    assert res.energies[-1] == res.energy
    assert np.array_equal(res.mask, res.classes > 0)
    assert np.array_equal(rasterize(res.contours, truth.shape), res.mask)
    assert res.constants.shape == (3, 1)
    means = [image[truth == k].mean() for k in range(3)]  # in the input's units
    offset, scale = image.min(), image.max() - image.min()
    np.testing.assert_allclose(offset + scale * res.constants[:, 0], means, atol=0.01)


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_shepp_logan_six_levels_with_two_small_ones(backend):
    phantom = skimage.data.shepp_logan_phantom()[::2, ::2]
    levels = np.array([0.0, 0.098, 0.2, 0.298, 0.4, 1.0])
    truth = np.argmin(np.abs(phantom[..., None] - levels), axis=-1)
    assert sorted(np.bincount(truth.ravel()))[:2] < [100, 100]  # two small levels at this size
    image = phantom + np.random.default_rng(7).normal(0, 0.01, phantom.shape)
    res = ac.segment(image, n_regions=6, backend=backend)
    assert np.mean(_dice(res.classes, truth, 6)) > 0.9


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_colour_regions_of_equal_gray(backend):
    # three colours of one luminance: only the vector-valued functional tells them apart
    rgb = np.array([[0.2, 0.5, 0.9], [0.6, 0.45, 0.3], [0.35, 0.5, 0.2]])
    gray = rgb @ np.array([0.2125, 0.7154, 0.0721])
    rgb[1] *= gray[0] / gray[1]
    rgb[2] *= gray[0] / gray[2]
    truth = np.zeros((90, 120), dtype=int)
    truth[20:70, 15:55] = 1
    truth[30:80, 70:110] = 2
    image = rgb[truth] + np.random.default_rng(8).normal(0, 0.05, truth.shape + (3,))
    res = ac.segment(image, n_regions=3, backend=backend, color="vector")
    # regions 1 and 2 have one mean gray level: match them to the truth either way
    dice = max(_dice(res.classes, truth, 3).mean(), _dice(np.array([0, 2, 1])[res.classes], truth, 3).mean())
    assert dice > 0.98
    assert res.constants.shape == (3, 3)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"n_regions": 3, "options": {"nucleate": False}}, TypeError, "options"),
        ({"n_regions": 1, "backend": "levelset"}, ValueError, "n_regions"),
        ({"n_regions": 2.5, "backend": "levelset"}, TypeError, "n_regions"),
        ({"n_regions": 3, "backend": "levelset", "c_in": 0.5}, ValueError, "c_in"),
    ],
)
def test_bad_regions_are_refused(kwargs, error, match):
    with pytest.raises(error, match=match):
        ac.segment(np.zeros((10, 10)), **kwargs)


def test_two_regions_report_classes_and_constants():
    image = np.zeros((40, 40))
    image[10:30, 12:28] = 1.0
    res = ac.segment(image)
    assert np.array_equal(res.classes, res.mask.astype(int))
    np.testing.assert_allclose(res.constants[:, 0], [res.c_out, res.c_in])
