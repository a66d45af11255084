"""Objects of one brightness pressed together are cut at the seams between them
(:func:`activecontour.objects.contrast._seam_parts`): a valley of the intensity that ends in
waists of the outline.  A valley inside one convex object (its texture) is no seam."""

import numpy as np
import pytest

import activecontour.objects.contrast as contrast
from activecontour.objects.shapes import MIN_SPLIT_RADIUS, _concavity

RADIUS = 12.0
# the least contrast of a split by Otsu's two classes: the domes' cores and rims differ by less,
# so only the seam can cut them
LEAST = 0.25


def domes(centres, shape=(48, 64), seed=0, noise=0.02):
    """Disks of one brightness, each brightest in its middle (1.0 there, 0.6 at its rim), the
    brighter value where they overlap, a little noise; the region they cover, framed by a pixel,
    and each pixel's nearest centre (the true parts: the overlaps are lenses cut in the middle)."""
    rows, cols = np.mgrid[:shape[0], :shape[1]].astype(float)
    distance = np.array([np.hypot(rows - r, cols - c) for r, c in centres])
    values = np.max(np.where(distance <= RADIUS, 0.6 + 0.4 * (1 - (distance / RADIUS) ** 2), 0.0), axis=0)
    region = distance.min(axis=0) <= RADIUS
    values = values + np.random.default_rng(seed).normal(0, noise, shape) * region
    return region, values, np.where(region, np.argmin(distance, axis=0) + 1, 0)


def best_iou(parts, truth):
    """For each true part, the largest IoU with a part of ``parts``."""
    scores = []
    for t in range(1, truth.max() + 1):
        true = truth == t
        scores.append(max(np.count_nonzero(true & (parts == p)) / np.count_nonzero(true | (parts == p))
                          for p in range(1, parts.max() + 1)))
    return np.array(scores)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_domes_of_one_brightness_are_cut_at_their_seam(seed):
    # centres 18 px apart: the outline has a waist 4 px deep at both ends of the seam
    region, values, truth = domes([(24, 22), (24, 40)], seed=seed)
    parts = contrast._contrast_parts(region.astype(np.int32), values, LEAST, MIN_SPLIT_RADIUS)
    assert parts.max() == 2
    assert best_iou(parts, truth).min() >= 0.95


@pytest.mark.parametrize("seed", [0, 1])
def test_two_dark_objects_on_a_bright_ground_are_cut_at_the_bright_ridge_between_them(seed):
    # the same domes, darkest in their middles, inside a bright window: the seam is a ridge
    region, values, truth = domes([(24, 22), (24, 40)], seed=seed)
    dark = np.where(region, 1.6 - values, 1.0)
    parts = contrast._contrast_parts(region.astype(np.int32), dark, LEAST, MIN_SPLIT_RADIUS)
    assert parts.max() == 2
    assert best_iou(parts, truth).min() >= 0.95


def test_three_domes_pressed_around_a_point_are_three_objects():
    # a trefoil: every seam runs from a waist of the outline to the point where the three meet
    angles = 0.3 + 2 * np.pi / 3 * np.arange(3)
    centres = [(24 + 10 * np.cos(a), 32 + 10 * np.sin(a)) for a in angles]
    region, values, truth = domes(centres, shape=(56, 64))
    parts = contrast._contrast_parts(region.astype(np.int32), values, LEAST, MIN_SPLIT_RADIUS)
    assert parts.max() == 3
    assert best_iou(parts, truth).min() >= 0.9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_valley_inside_one_convex_object_is_no_seam(seed):
    # two bright domes inside one ellipse (a textured nucleus): a valley between two maxima, but
    # its ends lie on the convex outline
    rows, cols = np.mgrid[:40, :64].astype(float)
    region = ((rows - 20) / 13) ** 2 + ((cols - 32) / 24) ** 2 <= 1
    distance = np.minimum(np.hypot(rows - 20, cols - 22), np.hypot(rows - 20, cols - 42))
    values = np.where(region, 0.6 + 0.4 * np.exp(-(distance / 6) ** 2), 0.0)
    values = values + np.random.default_rng(seed).normal(0, 0.02, values.shape) * region
    parts = contrast._contrast_parts(region.astype(np.int32), values, LEAST, MIN_SPLIT_RADIUS)
    assert parts.max() == 1


def test_a_uniform_object_with_a_waist_has_no_seam():
    # two disks of one flat brightness: a waist but no valley (the neck and arc stages' case)
    region, values, _ = domes([(24, 22), (24, 40)])
    flat = np.where(region, 1.0, 0.0) + np.random.default_rng(3).normal(0, 0.02, region.shape) * region
    assert contrast._seam_parts(region, flat, LEAST, MIN_SPLIT_RADIUS) is None


def test_a_piece_closed_inside_another_merges_with_it_and_a_seam_between_waists_stands():
    # two disks side by side, cut between their waists, and a piece inside the left one (the
    # basin of a bright spot in a crater): its border reaches the outline nowhere
    region, _, truth = domes([(24, 22), (24, 40)])
    rows, cols = np.mgrid[:48, :64]
    pieces = truth.copy()
    pieces[np.hypot(rows - 24, cols - 22) <= 3] = 3
    concavity = _concavity(region, np.argwhere(region).astype(np.float64))
    merged = contrast._merge_off_waists(pieces, concavity)
    assert merged.max() == 2
    assert np.array_equal(merged, truth)
