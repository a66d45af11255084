"""The level set's compiled kernels against plain numpy versions of the same mathematics.

The numpy versions below are written from the definitions (marching squares with the saddle rule
of ``skimage.measure.find_contours``, the closed padding by ``-|phi|``, the inside on the left of
every segment); the kernels must give the same numbers bit for bit, on random phi with saddles,
zeros, regions on the border, in float32 and float64.
"""

import numpy as np
import pytest

from activecontour import _kernels
from activecontour.backends.levelset import heaviside
from activecontour.backends.levelset.redistancing import (
    _front_and_cells,
    _front_pixels,
    _front_segments,
    _redistance,
    _Scratch,
)
from activecontour.backends.levelset.scheme import _force, _swept_area
from activecontour.backends.levelset.zeroset import _cell_segments, _change_cells, _edge_soup
from activecontour.models import ChanVeseParameters


def _crossings(a, b, c, d, r, q):
    """The crossings on the edges top (a-b), right (b-c), bottom (d-c), left (a-d), (K, 4, 2)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.stack([np.column_stack([r, q + a / (a - b)]), np.column_stack([r + b / (b - c), q + 1.0]),
                         np.column_stack([r + 1.0, q + d / (d - c)]), np.column_stack([r + a / (a - d), q])],
                        axis=1)


def _numpy_cell_segments(a, b, c, d, r, q, width):
    """Segments (K, 2, 2, 2) and end keys (K, 2, 2) of cells with corners a, b, c, d at (r, q)."""
    sa, sb, sc, sd = a > 0, b > 0, c > 0, d > 0
    points = _crossings(a, b, c, d, r.astype(float), q.astype(float))
    cell = r * width + q
    keys = np.column_stack([2 * cell, 2 * (cell + 1) + 1, 2 * (cell + width), 2 * cell + 1])
    exists = np.column_stack([sa != sb, sb != sc, sd != sc, sa != sd])
    segments = np.full((len(a), 2, 2, 2), np.nan)
    segment_keys = np.full((len(a), 2, 2), -1, dtype=np.intp)
    for k in range(len(a)):
        edges = np.flatnonzero(exists[k])
        if len(edges) == 2:
            segments[k, 0], segment_keys[k, 0] = points[k, edges], keys[k, edges]
        elif len(edges) == 4:  # a saddle cuts off its inside corners: a and c, or b and d
            pairs = ([0, 3], [1, 2]) if sa[k] else ([0, 1], [3, 2])
            for slot, pair in enumerate(pairs):
                segments[k, slot], segment_keys[k, slot] = points[k, pair], keys[k, pair]
    return segments, segment_keys


def _numpy_edge_soup(phi):
    """The oriented segments of phi padded by -|phi| (zero counted outside), inside on the left."""
    m, n = phi.shape
    padded = np.pad(phi.astype(np.float64), 1, mode="edge")
    padded[0], padded[-1] = -np.abs(padded[0]), -np.abs(padded[-1])
    padded[:, 0], padded[:, -1] = -np.abs(padded[:, 0]), -np.abs(padded[:, -1])
    padded[padded == 0] = -1e-300
    inner = _change_cells(phi > 0)
    r, q = np.divmod(inner, n - 1)
    frame = [(row, col) for row, line in ((0, phi[0]), (m, phi[-1])) for col in range(n + 1)
             if (line[max(col - 1, 0)] > 0) | (line[min(col, n - 1)] > 0)]
    frame += [(row, 0) for row in range(1, m) if (phi[row - 1, 0] > 0) | (phi[row, 0] > 0)]
    frame += [(row, n) for row in range(1, m) if (phi[row - 1, -1] > 0) | (phi[row, -1] > 0)]
    rows = np.concatenate([r + 1, [f[0] for f in frame]]).astype(np.intp)
    cols = np.concatenate([q + 1, [f[1] for f in frame]]).astype(np.intp)
    corners = [padded[rows + dr, cols + dc] for dr, dc in ((0, 0), (0, 1), (1, 1), (1, 0))]
    segments, _ = _numpy_cell_segments(*corners, rows, cols, n + 2)
    out = []
    for k in range(len(rows)):
        inside = np.array([corner[k] > 0 for corner in corners])
        offsets = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]])
        saddle = inside.sum() == 2 and inside[0] == inside[2]
        for slot in range(2):
            start, end = segments[k, slot]
            if np.isnan(start[0]):
                continue
            if saddle:
                corner = (0 if inside[0] else 1) if slot == 0 else (2 if inside[0] else 3)
                reference = np.array([rows[k], cols[k]]) + offsets[corner]
            else:
                reference = np.array([rows[k], cols[k]]) + offsets[inside].mean(axis=0)
            tangent, offset = end - start, reference - start
            flip = offset[0] * tangent[1] - offset[1] * tangent[0] > 0
            out.append([end, start] if flip else [start, end])
    return np.array(out).reshape(-1, 2, 2) - 1.0


def _random_phi(rng, dtype):
    m, n = rng.integers(2, 14, 2)
    phi = rng.normal(size=(m, n))
    if rng.random() < 0.5:
        phi = np.round(phi)  # exact zeros: outside, as in the mask phi > 0
    return phi.astype(dtype)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cell_segments_equal_the_numpy_marching_squares(dtype):
    rng = np.random.default_rng(11)
    saddles = 0
    for _ in range(200):
        phi = _random_phi(rng, dtype)
        n = phi.shape[1]
        cells = _change_cells(phi > 0)
        r, q = np.divmod(cells, n - 1)
        corners = [phi[r + dr, q + dc].astype(np.float64) for dr, dc in ((0, 0), (0, 1), (1, 1), (1, 0))]
        expected, expected_keys = _numpy_cell_segments(*corners, r, q, n)
        segments, keys = _cell_segments(phi, cells)
        np.testing.assert_array_equal(segments, expected)
        np.testing.assert_array_equal(keys, expected_keys)
        saddles += int(np.sum(~np.isnan(expected[:, 1, 0, 0])))
    assert saddles > 0  # the saddle rule was exercised


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_edge_soup_equals_the_numpy_padding_and_orientation(dtype):
    rng = np.random.default_rng(12)
    for _ in range(200):
        phi = _random_phi(rng, dtype)
        expected = _numpy_edge_soup(phi)
        np.testing.assert_array_equal(_edge_soup(phi, _change_cells(phi > 0)), expected)
    # all inside, phi = 1 against the padding's -1: Gamma runs half a pixel beyond the outer pixel
    # centres and cuts each corner of the 3 x 4 box by a diagonal of legs 1/2, counter-clockwise
    everything = np.ones((3, 4), dtype=dtype)
    soup = _edge_soup(everything, _change_cells(everything > 0))
    tangent = soup[:, 1] - soup[:, 0]
    assert np.sum(np.hypot(*tangent.T)) == pytest.approx(2 * (2 + 3) + 4 * np.sqrt(0.5))
    area = 0.5 * np.sum(soup[:, 0, 0] * soup[:, 1, 1] - soup[:, 1, 0] * soup[:, 0, 1])
    assert area == pytest.approx(3 * 4 - 4 * 0.125)


def test_front_and_cells_near_seeds_equal_the_image_wide_search():
    # the front pixels among the seeds and their 4-neighbours are those of the image-wide test
    # there; seeded with the whole front, the cells around it are every cell with a sign change
    rng = np.random.default_rng(13)
    for _ in range(300):
        m, n = rng.integers(2, 20, 2)
        positive = rng.random((m, n)) < rng.random()
        seeds = rng.integers(0, m * n, rng.integers(0, 3 * m))
        mark = np.zeros(m * n, dtype=np.uint8)
        front, _ = _front_and_cells(positive, seeds, mark)
        rows, cols = np.divmod(seeds, n)
        near = np.zeros((m, n), dtype=bool)
        for dr, dc in ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)):
            keep = (rows + dr >= 0) & (rows + dr < m) & (cols + dc >= 0) & (cols + dc < n)
            near[rows[keep] + dr, cols[keep] + dc] = True
        np.testing.assert_array_equal(front, np.flatnonzero(near & _front_pixels(positive)))
        assert not mark.any()  # handed back cleared
        _, cells = _front_and_cells(positive, np.flatnonzero(_front_pixels(positive)), mark)
        np.testing.assert_array_equal(cells, _change_cells(positive))


def _point_segment_distance(point, start, end):
    direction, offset = end - start, point - start
    t = np.clip(offset @ direction / (direction @ direction), 0.0, 1.0)
    return np.hypot(*(offset - t * direction))


def test_nearest_segment_of_a_front_pixel_is_the_nearest_in_the_four_cells_around_it():
    rng = np.random.default_rng(14)
    for _ in range(100):
        phi = rng.normal(size=tuple(rng.integers(2, 14, 2)))
        m, n = phi.shape
        front = np.flatnonzero(_front_pixels(phi > 0))
        if front.size == 0:
            continue
        cells = _change_cells(phi > 0)
        segments, _ = _cell_segments(phi, cells)
        _, nearest = _front_segments(phi, front, cells)
        for pixel, chosen in zip(front, nearest, strict=True):
            r, c = divmod(pixel, n)
            around = [(r + dr) * (n - 1) + c + dc for dr in (-1, 0) for dc in (-1, 0)
                      if 0 <= r + dr < m - 1 and 0 <= c + dc < n - 1]
            gaps = [_point_segment_distance(np.array([r, c], float), *segments[slot, s])
                    for slot in np.flatnonzero(np.isin(cells, around)) for s in range(2)
                    if not np.isnan(segments[slot, s, 0, 0])]
            # a front pixel has a 4-neighbour on the other side: a segment crosses that edge
            assert gaps and min(gaps) <= 1.0
            picked = _point_segment_distance(np.array([r, c], float), *segments.reshape(-1, 2, 2)[chosen])
            assert picked == pytest.approx(min(gaps), abs=1e-5)  # ranked in float32


def test_swept_area_counts_each_pixel_of_either_band_once():
    rng = np.random.default_rng(15)
    rows, cols = np.indices((40, 50), dtype=np.float64)
    for _ in range(20):
        centre, radius = rng.uniform(15, 25, 2), rng.uniform(5, 12)
        old = _redistance(radius - np.hypot(rows - centre[0], cols - centre[1]), 4.0)
        moved = centre + rng.normal(size=2)
        new = _redistance(radius + rng.normal() - np.hypot(rows - moved[0], cols - moved[1]), 4.0)
        union = np.union1d(old.near_flat, new.near_flat)
        expected = np.sum(np.abs(heaviside(new.phi.ravel()[union]) - heaviside(old.phi.ravel()[union])))
        mark = np.zeros(old.phi.size, dtype=np.uint8)
        assert _swept_area(old, new, mark) == pytest.approx(expected, rel=1e-12)
        assert not mark.any()
        # beyond both bands phi is +-band on the same side in both: nothing more is swept there
        everywhere = np.sum(np.abs(heaviside(new.phi) - heaviside(old.phi)))
        assert _swept_area(old, new) == pytest.approx(everywhere, rel=1e-12)


@pytest.mark.parametrize("channels, mu, omega", [(1, 0.3, 0.0), (3, 0.2, 0.05), (1, 0.0, -0.1)])
def test_force_step_is_phi_minus_tau_f_with_the_wall_term(channels, mu, omega):
    # f: the model's density of (6.41) plus mu per side of the image a pixel lies on
    rng = np.random.default_rng(16)
    m, n = 7, 9
    values = rng.uniform(size=(m, n, channels))
    phi = rng.normal(size=(m, n)).astype(np.float32)
    params = ChanVeseParameters(mu=mu, omega=omega, lambda_in=1.3, lambda_out=0.8)
    c_in, c_out, tau = rng.uniform(size=channels), rng.uniform(size=channels), 0.37
    rows, cols = np.indices((m, n))
    wall = (rows == 0).astype(int) + (rows == m - 1) + (cols == 0) + (cols == n - 1)  # corners: 2
    f = _force(values, c_in, c_out, params) + mu * wall
    form = params.load_form(c_in, c_out)
    out = np.empty_like(phi)
    _kernels.force_step(phi, values, form.constant, form.linear, form.square, mu, tau, out)
    np.testing.assert_allclose(out, phi - tau * f, rtol=1e-6, atol=1e-6)  # float32
    # a box of the image (its last row on the image's side, its first column not): the same pixels
    box = np.empty((4, 5), dtype=np.float32)
    _kernels.force_step(phi, values, form.constant, form.linear, form.square, mu, tau, box, 3, 2)
    np.testing.assert_array_equal(box, out[3:7, 2:7])
    with pytest.raises(ValueError, match="outside the image"):
        _kernels.force_step(phi, values, form.constant, form.linear, form.square, mu, tau, box, 4, 2)


@pytest.mark.parametrize("shape, k", [((12, 8), 4), ((13, 10), 4), ((5, 7), 3)])
def test_block_means_are_the_means_of_the_blocks_cut_at_the_edge(shape, k):
    a = np.random.default_rng(19).normal(size=shape).astype(np.float32)
    out = np.empty((-(-shape[0] // k), -(-shape[1] // k)), dtype=np.float32)
    _kernels.block_means(a, k, out)
    expected = [[a[i:i + k, j:j + k].mean(dtype=np.float64) for j in range(0, shape[1], k)]
                for i in range(0, shape[0], k)]
    np.testing.assert_allclose(out, expected, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("shape, k", [((12, 8), 4), ((13, 10), 4), ((5, 7), 3)])
def test_block_means_in_boxes_remake_the_blocks_they_meet_and_keep_the_others(shape, k):
    # blocks made anew of an array that differs from the one the means were made of only in the
    # boxes: the same numbers as all blocks made anew, bit for bit; the signs are the sides of the
    # blocks' first pixels
    rng = np.random.default_rng(21)
    before = rng.normal(size=shape).astype(np.float32)
    after = before.copy()
    boxes = np.array([[1, 3, 0, 2], [shape[0] - 2, shape[0], shape[1] - 3, shape[1]]], dtype=np.intp)
    for top, bottom, left, right in boxes:
        after[top:bottom, left:right] = rng.normal(size=(bottom - top, right - left))
    size = (-(-shape[0] // k), -(-shape[1] // k))
    means, signs = np.empty(size, dtype=np.float32), np.empty(size, dtype=np.float32)
    _kernels.block_means(before, k, means, None, (before > 0).view(np.uint8), signs)
    fresh, fresh_signs = np.empty_like(means), np.empty_like(signs)
    _kernels.block_means(after, k, fresh, None, (after > 0).view(np.uint8), fresh_signs)
    assert not np.array_equal(means, fresh)
    _kernels.block_means(after, k, means, boxes, (after > 0).view(np.uint8), signs)
    np.testing.assert_array_equal(means, fresh)
    np.testing.assert_array_equal(signs, np.where(after[::k, ::k] > 0, 1.0, -1.0))
    # blocks no box meets are not read: an array that differs there leaves them as they were
    elsewhere = after.copy()
    elsewhere[-1, 0] += 5.0  # a block of the last row and first column: no box meets it
    _kernels.block_means(elsewhere, k, means, boxes, (elsewhere > 0).view(np.uint8), signs)
    np.testing.assert_array_equal(means, fresh)


@pytest.mark.parametrize("shape, k", [((12, 8, 1), 4), ((13, 10, 3), 4), ((5, 7, 2), 3)])
def test_block_moments_are_the_block_means_of_each_channel_and_its_square(shape, k):
    values = np.random.default_rng(20).normal(size=shape)
    size = (shape[2], -(-shape[0] // k), -(-shape[1] // k))
    means, squares = np.empty(size, dtype=np.float32), np.empty(size, dtype=np.float32)
    _kernels.block_moments(values, k, means, squares)
    for channel in range(shape[2]):
        rounded = values[..., channel].astype(np.float32)
        expected = np.empty(size[1:], dtype=np.float32)
        _kernels.block_means(rounded, k, expected)  # the same sums in the same order
        np.testing.assert_array_equal(means[channel], expected)
        _kernels.block_means(np.square(rounded), k, expected)
        np.testing.assert_array_equal(squares[channel], expected)


def test_force_step_on_tiles_is_force_step_on_each_tile():
    rng = np.random.default_rng(21)
    m, n = 11, 13
    values = rng.uniform(size=(m, n, 2))
    phi = rng.normal(size=(m, n)).astype(np.float32)
    form = ChanVeseParameters(mu=0.3).load_form(rng.uniform(size=2), rng.uniform(size=2))
    tops, lefts = np.array([0, 6, 3], dtype=np.intp), np.array([8, 0, 4], dtype=np.intp)
    tiles = np.empty((3, 5, 5), dtype=np.float32)
    terms = (form.constant, form.linear, form.square, 0.3, 0.7)
    _kernels.force_step_tiles(phi, values, *terms, tiles, tops, lefts)
    for tile, top, left in zip(tiles, tops, lefts, strict=True):
        expected = np.empty((5, 5), dtype=np.float32)
        _kernels.force_step(phi, values, *terms, expected, top, left)
        np.testing.assert_array_equal(tile, expected)
    with pytest.raises(ValueError, match="outside the image"):
        _kernels.force_step_tiles(phi, values, *terms, tiles, tops + 3, lefts)


def test_tile_pieces_test_the_sides_and_copy_the_rectangles():
    tiles = np.arange(2 * 4 * 4, dtype=np.float32).reshape(2, 4, 4) - 8.0  # tile 0: -8..7, tile 1: 8..23
    tops, lefts = np.array([0, 2], dtype=np.intp), np.array([1, 3], dtype=np.intp)
    out = np.zeros((6, 8), dtype=np.float32)
    # tile 1's rows 2..3 (image) hold 8..15 >= 8: inside passes at limit 8; tile 0's last row (image
    # row 3: 4..7) fails at -limit 5 if it is outside (7 > -5), passes untested
    inside = np.array([[1, 2, 4, 3, 7, 1]], dtype=np.intp)
    assert _kernels.tile_pieces(tiles, tops, lefts, inside, 8.0, out, False)
    assert not _kernels.tile_pieces(tiles, tops, lefts, inside, 8.5, out, False)
    outside = np.array([[0, 3, 4, 1, 5, -1]], dtype=np.intp)
    assert not _kernels.tile_pieces(tiles, tops, lefts, outside, 5.0, out, False)
    assert _kernels.tile_pieces(tiles, tops, lefts, outside * [1, 1, 1, 1, 1, 0], 5.0, out, False)
    assert not out.any()  # testing writes nothing
    both = np.concatenate([inside, outside])
    assert _kernels.tile_pieces(tiles, tops, lefts, both, 0.0, out, True)
    expected = np.zeros_like(out)
    expected[2:4, 3:7] = tiles[1, 0:2, 0:4]
    expected[3:4, 1:5] = tiles[0, 3:4, 0:4]
    np.testing.assert_array_equal(out, expected)
    with pytest.raises(ValueError, match="outside its tile"):
        _kernels.tile_pieces(tiles, tops, lefts, np.array([[0, 0, 5, 1, 5, 0]], dtype=np.intp), 0.0, out,
                             True)


def test_divide_spectrum_applies_the_inverse_of_one_minus_weight_laplace():
    # after the division, multiplying by 1 + weight (lambda_r + lambda_c) gives the spectrum back
    rng = np.random.default_rng(17)
    spectrum = rng.normal(size=(6, 5)).astype(np.float32)
    wave_r = rng.uniform(0, 4, 6).astype(np.float32)
    wave_c = rng.uniform(0, 4, 5).astype(np.float32)
    divided = spectrum.copy()
    _kernels.divide_spectrum(divided, wave_r, wave_c, np.float32(2.5))
    np.testing.assert_allclose(divided * (1 + 2.5 * (wave_r[:, None] + wave_c[None, :])), spectrum, rtol=1e-6)


def test_explicit_step_is_phi_plus_rate_laplace_minus_tau_f_on_the_band():
    # the 5-point Laplacian with mirrored border pixels (Neumann), f of (6.41) with the wall term
    # where |phi| < band, on the band's pixels only; every other pixel keeps phi
    rng = np.random.default_rng(18)
    m, n, band, mu, tau = 8, 11, 1.0, 0.4, 0.3
    phi = rng.normal(size=(m, n)).astype(np.float32)
    values = rng.uniform(size=(m, n, 2))
    params = ChanVeseParameters(mu=mu)
    c_in, c_out = rng.uniform(size=2), rng.uniform(size=2)
    flat = rng.permutation(m * n)[: m * n // 2]
    mirrored = np.pad(phi.astype(np.float64), 1, mode="edge")
    laplace = (mirrored[:-2, 1:-1] + mirrored[2:, 1:-1] + mirrored[1:-1, :-2] + mirrored[1:-1, 2:]
               - 4.0 * phi)
    rows, cols = np.indices((m, n))
    wall = (rows == 0).astype(int) + (rows == m - 1) + (cols == 0) + (cols == n - 1)
    f = _force(values, c_in, c_out, params) + mu * wall
    expected = phi + tau * mu * laplace - np.where(np.abs(phi) < band, tau * f, 0.0)
    form = params.load_form(c_in, c_out)
    out = phi.copy()
    _kernels.explicit_step(phi.reshape(-1), flat, m, n, tau * mu, band, values.reshape(m * n, -1),
                           form.constant, form.linear, form.square, mu, tau, out.reshape(-1))
    np.testing.assert_allclose(out.reshape(-1)[flat], expected.reshape(-1)[flat], rtol=1e-6, atol=1e-6)
    others = np.setdiff1d(np.arange(m * n), flat)
    np.testing.assert_array_equal(out.reshape(-1)[others], phi.reshape(-1)[others])


def test_band_couplings_name_each_neighbour_in_the_band_or_held_beyond_it():
    rng = np.random.default_rng(19)
    for _ in range(50):
        m, n = rng.integers(1, 9, 2)
        flat = rng.permutation(m * n)[: rng.integers(1, m * n + 1)]
        index = np.full((m + 2) * (n + 2), -1, dtype=np.int32)
        couplings = np.empty((4, flat.size), dtype=np.intp)
        held = np.empty((4, flat.size), dtype=np.intp)
        degree = np.empty(flat.size)
        _kernels.band_couplings(flat, m, n, index, couplings, held, degree)
        assert np.all(index == -1)  # handed back as it came
        position = {pixel: i for i, pixel in enumerate(flat)}
        for i, pixel in enumerate(flat):
            r, c = divmod(pixel, n)
            neighbours = [(r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)]
            inside = [(rr, cc) for rr, cc in neighbours if 0 <= rr < m and 0 <= cc < n]
            assert degree[i] == len(inside)
            for d, (rr, cc) in enumerate(neighbours):
                q = rr * n + cc if (0 <= rr < m and 0 <= cc < n) else None
                assert couplings[d, i] == (position[q] if q in position else -1)
                assert held[d, i] == (q if q is not None and q not in position else -1)


def _box_rows(*boxes):
    """Boxes ``(first row, stop row, first column, stop column)`` as the kernels take them."""
    return np.array(boxes, dtype=np.intp)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_sides_are_phi_above_zero_and_the_pixels_that_changed_side(dtype):
    rng = np.random.default_rng(20)
    phi = np.round(rng.normal(size=(50, 100))).astype(dtype)  # zeros are outside
    before = rng.random((50, 100)) < 0.5
    positive = np.empty((50, 100), dtype=bool)
    switched = np.empty(5000, dtype=np.intp)
    count = _kernels.sides(phi, before.view(np.uint8), positive.view(np.uint8), _box_rows((0, 50, 0, 100)),
                           switched)
    np.testing.assert_array_equal(positive, phi > 0)
    np.testing.assert_array_equal(switched[:count], np.flatnonzero((phi > 0) != before))


def test_sides_at_some_pixels_leave_the_rest_as_it_was():
    rng = np.random.default_rng(24)
    phi = rng.normal(size=3000).astype(np.float32)
    before = rng.random(3000) < 0.5
    flat = rng.permutation(3000)[:700]
    positive = ~before  # every pixel wrong: only those of flat are written
    switched = np.empty(flat.size, dtype=np.intp)
    count = _kernels.sides_at(phi, before.view(np.uint8), positive.view(np.uint8), flat, switched)
    at = np.zeros(3000, dtype=bool)
    at[flat] = True
    np.testing.assert_array_equal(positive, np.where(at, phi > 0, ~before))
    np.testing.assert_array_equal(switched[:count], flat[(phi[flat] > 0) != before[flat]])


def test_sides_of_a_box_leave_the_rest_as_it_was():
    # a step that changed phi in a box only: the sides are read there, the rest is left alone
    rng = np.random.default_rng(22)
    phi = rng.normal(size=(40, 60)).astype(np.float32)
    before = rng.random((40, 60)) < 0.5
    positive = ~before  # every pixel wrong: only the box's are written
    switched = np.empty(phi.size, dtype=np.intp)
    count = _kernels.sides(phi, before.view(np.uint8), positive.view(np.uint8), _box_rows((5, 17, 20, 51)),
                           switched)
    box = np.zeros(phi.shape, dtype=bool)
    box[5:17, 20:51] = True
    np.testing.assert_array_equal(positive, np.where(box, phi > 0, ~before))
    np.testing.assert_array_equal(switched[:count], np.flatnonzero(box & ((phi > 0) != before)))
    with pytest.raises(ValueError, match="outside the image"):
        _kernels.sides(phi, before.view(np.uint8), positive.view(np.uint8), _box_rows((0, 41, 0, 60)),
                       switched)


def test_sides_of_overlapping_boxes_read_each_box_and_find_a_shared_pixel_twice():
    # a step on tiles writes the cells and pieces of the halo around them, which may overlap
    rng = np.random.default_rng(23)
    phi = rng.normal(size=(40, 60)).astype(np.float32)
    before = rng.random((40, 60)) < 0.5
    positive = ~before  # every pixel wrong: only the boxes' are written
    boxes = _box_rows((5, 17, 20, 51), (10, 30, 40, 60), (7, 7, 0, 9))  # the last one empty
    inside = np.zeros((len(boxes),) + phi.shape, dtype=bool)
    for mask, (top, bottom, left, right) in zip(inside, boxes, strict=True):
        mask[top:bottom, left:right] = True
    differ = (phi > 0) != before
    switched = np.empty(int(inside.sum()), dtype=np.intp)
    count = _kernels.sides(phi, before.view(np.uint8), positive.view(np.uint8), boxes, switched)
    union = inside.any(axis=0)
    np.testing.assert_array_equal(positive, np.where(union, phi > 0, ~before))
    assert count == (inside & differ).sum()  # a pixel of two boxes twice
    np.testing.assert_array_equal(np.unique(switched[:count]), np.flatnonzero(union & differ))
    with pytest.raises(ValueError, match="no room"):
        _kernels.sides(phi, before.view(np.uint8), positive.view(np.uint8), boxes, switched[:5])


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_copy_boxes_copies_the_boxes_only(dtype):
    rng = np.random.default_rng(25)
    source = rng.normal(size=(30, 20)).astype(dtype)
    target = np.zeros((30, 20), dtype=dtype)
    boxes = _box_rows((2, 9, 3, 12), (6, 30, 10, 20))
    _kernels.copy_boxes(source, target, boxes)
    expected = np.zeros_like(target)
    expected[2:9, 3:12] = source[2:9, 3:12]
    expected[6:30, 10:20] = source[6:30, 10:20]
    np.testing.assert_array_equal(target, expected)
    with pytest.raises(ValueError, match="outside the image"):
        _kernels.copy_boxes(source, target, _box_rows((0, 31, 0, 5)))


@pytest.mark.parametrize("where", ["anywhere", "box", "boxes", "band"])
def test_a_located_step_scores_as_its_reinitialised_state(where):
    # the front pixels' distances alone fix the zero set (marching squares reads only them): a
    # step scored before its band is grown has the energy of the state it becomes.  A step that
    # changed phi in a box, in overlapping boxes or on the band only is located and finished
    # there only, in place
    from activecontour.backends.levelset.redistancing import _locate, _Located
    from activecontour.energy import evaluate
    from activecontour.imaging.tables import ImageModel

    rng = np.random.default_rng(21)
    rows, cols = np.indices((48, 56), dtype=np.float64)
    model = ImageModel(rng.uniform(size=(48, 56, 1)))
    params = ChanVeseParameters(mu=0.4)

    def energy(state):
        points = _edge_soup(state.phi, state.cells).reshape(-1, 2)
        return evaluate(model, points, np.repeat(np.arange(1, len(points), 2), 2), params).energy

    for _ in range(10):
        centre = rng.uniform(15, 35, 2)
        previous = _redistance((14 - np.hypot(rows - centre[0], cols - centre[1])).astype(np.float32), 4.0,
                               dtype=np.float32)
        noise = rng.normal(scale=0.8, size=previous.phi.shape)
        boxes = np.array([[2, 30, 1, 40], [20, 47, 30, 53], [25, 40, 3, 20]], dtype=np.intp)  # overlapping
        changed = {"anywhere": None, "box": (slice(2, 47), slice(1, 53)), "boxes": boxes,
                   "band": previous.near_flat}[where]
        if changed is not None:
            held = np.ones(noise.shape, dtype=bool)
            if where == "box":
                held[changed] = False
            elif where == "boxes":
                for top, bottom, left, right in changed:
                    held[top:bottom, left:right] = False
            else:
                held.ravel()[changed] = False
            noise[held] = 0.0
        stepped = (previous.phi + noise).astype(np.float32)
        located = _locate(stepped.copy(), 4.0, np.float32, None, previous, changed)
        assert isinstance(located, _Located)
        np.testing.assert_array_equal(located.positive, stepped > 0)
        located.front_distances(4.0)
        scored, at_front = energy(located), located.phi.ravel()[located.front].copy()
        final = located.finish(4.0, np.float32, None, previous)
        assert final.phi is located.phi
        np.testing.assert_array_equal(at_front, final.phi.ravel()[final.front])
        assert scored == energy(final)
        # and the same as reinitialising the stepped phi from scratch (an image-wide front search)
        np.testing.assert_array_equal(final.phi, _redistance(stepped, 4.0, dtype=np.float32).phi)


def test_segment_table_columns_are_start_direction_and_inverse_squared_length():
    # empty (NaN) slots start far away with no direction; a point has inverse 0; a far sentinel last
    from activecontour.backends.levelset.redistancing import _FAR, _Segments

    rng = np.random.default_rng(22)
    segments = rng.normal(size=(30, 2, 2)) * 5
    segments[::7] = np.nan
    segments[3, 1] = segments[3, 0]
    table = _Segments(segments, np.full((30, 2), -1))
    direction = np.where(np.isnan(segments[:, 1] - segments[:, 0]), 0.0, segments[:, 1] - segments[:, 0])
    length_sq = direction[:, 0] ** 2 + direction[:, 1] ** 2
    start = np.where(np.isnan(segments[:, 0]), _FAR, segments[:, 0])
    expected = [start[:, 0], start[:, 1], direction[:, 0], direction[:, 1],
                np.divide(1.0, length_sq, out=np.zeros(30), where=length_sq > 0)]
    for column, column32, values, sentinel in zip(table.columns, table.columns32, expected,
                                                  (_FAR, _FAR, 0, 0, 0), strict=True):
        np.testing.assert_array_equal(column, np.append(values, sentinel))
        np.testing.assert_array_equal(column32, np.append(values, sentinel).astype(np.float32))
    assert table.columns[4][3] == 0.0  # the point


def test_band_growth_reuses_the_scratch_work_arrays_whatever_they_hold():
    # the band's pixel list and ring scratch are kept between reinitialisations (their pages are
    # not faulted in anew): whatever a previous band left in them, the result is a fresh one's
    rows, cols = np.indices((40, 50), dtype=np.float64)
    phi = (12.0 - np.hypot(rows - 19.5, cols - 24.0)).astype(np.float32)
    scratch = _Scratch(phi.shape)
    grown, chosen = scratch.grown, scratch.chosen
    grown.fill(-7)
    chosen.fill(-7)
    state = _redistance(phi, 4.0, dtype=np.float32, scratch=scratch)
    assert scratch.grown is grown and scratch.chosen is chosen
    np.testing.assert_array_equal(state.phi, _redistance(phi, 4.0, dtype=np.float32).phi)
    np.testing.assert_array_equal(state.near_flat, _redistance(phi, 4.0, dtype=np.float32).near_flat)
