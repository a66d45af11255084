"""The network's compiled per-iteration kernels against their numpy definitions."""

import numpy as np
import pytest

from activecontour import _kernels


def _segments(rng, count, regions):
    starts = rng.uniform(-0.5, 20.5, (count, 2))
    ends = starts + rng.normal(0.0, 1.0, (count, 2))
    ends[3] = starts[3]  # a segment of zero length: no tangent
    inner = rng.integers(0, regions, count)
    outer = rng.integers(-1, regions, count)  # -1: the image's edge
    inner[:4] = 0
    outer[:2] = -1  # the background on the edge: no length term
    return starts, ends, inner.astype(np.intp), outer.astype(np.intp)


def _loads_by_definition(starts, ends, inner, outer, parts, table, mu):
    """partition_load's numpy form: (g_i - g_o) against each end's hat function times the normal
    (dv, -du), and mu times the unit tangent where the length counts."""
    padded = np.vstack([table, np.zeros((1, table.shape[1]))])  # row -1: outside the image
    coefficients = padded[inner] - padded[outer]
    density = np.einsum("sec,sc->se", parts, coefficients[:, 1:]) + 0.5 * coefficients[:, :1]
    step = ends - starts
    length = np.hypot(step[:, 0], step[:, 1])
    weight = np.where((outer >= 0) | (inner > 0), mu, 0.0)
    tangent = step * (weight / np.where(length > 0, length, 1.0))[:, None]
    load = np.empty((len(step), 2, 2))
    load[:, :, 0] = density * step[:, 1:2]
    load[:, :, 1] = density * -step[:, 0:1]
    load[:, 0] -= tangent
    load[:, 1] += tangent
    return load


@pytest.mark.parametrize("channels", [1, 3])
def test_segment_loads_is_the_numpy_definition(channels):
    rng = np.random.default_rng(11)
    regions = 4
    starts, ends, inner, outer = _segments(rng, 60, regions)
    parts = rng.normal(size=(60, 2, 2 * channels))
    table = rng.normal(size=(regions, 1 + 2 * channels))
    load = np.empty((60, 2, 2))
    _kernels.segment_loads(starts, ends, inner, outer, parts, table, 0.7, load)
    expected = _loads_by_definition(starts, ends, inner, outer, parts, table, 0.7)
    np.testing.assert_allclose(load, expected, rtol=1e-13, atol=1e-13)
    # the zero-length segment carries no length term, and the background's edge none either
    assert np.all(load[3] == 0)
    np.testing.assert_allclose(load[:2].sum(axis=1), (parts[:2].sum(axis=1) @ table[0, 1:]
                                                       + table[0, 0])[:, None]
                               * np.column_stack([ends[:2, 1] - starts[:2, 1], starts[:2, 0] - ends[:2, 0]]))


def test_segment_loads_checks_its_shapes():
    rng = np.random.default_rng(12)
    starts, ends, inner, outer = _segments(rng, 8, 3)
    with pytest.raises(ValueError, match="table must be"):
        _kernels.segment_loads(starts, ends, inner, outer, np.zeros((8, 2, 2)), np.zeros((3, 4)), 1.0,
                               np.empty((8, 2, 2)))


def _bounds_by_definition(nodes, velocity, start, end, face, segment, sign, high, faces):
    old, turn = nodes[end] - nodes[start], velocity[end] - velocity[start]
    along = np.einsum("ij,ij->i", old, turn)
    size = np.einsum("ij,ij->i", old, old)
    shrinking = along < 0
    reverse = np.min(0.75 * size[shrinking] / -along[shrinking]) if shrinking.any() else np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(velocity > 0, (high - nodes) / velocity,
                        np.where(velocity < 0, (-0.5 - nodes) / velocity, np.inf))
    twice = nodes[start, 0] * nodes[end, 1] - nodes[end, 0] * nodes[start, 1]
    areas = 0.5 * np.bincount(face, weights=sign * twice[segment], minlength=faces)
    perimeter = np.bincount(face, weights=np.sqrt(size)[segment], minlength=faces)
    speed = np.hypot(velocity[:, 0], velocity[:, 1])
    fastest = np.zeros(faces)
    np.maximum.at(fastest, face, np.maximum(speed[start], speed[end])[segment])
    return reverse, room.min(), areas, perimeter, fastest


def test_step_bounds_is_the_numpy_definition():
    rng = np.random.default_rng(13)
    high = np.array([30.5, 40.5])
    nodes = rng.uniform(-0.5, 30.0, (50, 2))
    velocity = rng.normal(size=(50, 2))
    velocity[7] = 0.0  # a node that does not move bounds nothing
    start = rng.integers(0, 50, 70).astype(np.intp)
    end = rng.integers(0, 50, 70).astype(np.intp)
    faces = 9
    face = np.sort(rng.integers(0, faces, 120)).astype(np.intp)
    face[:faces] = np.arange(faces)  # every face has an entry
    face.sort()
    segment = rng.integers(0, 70, 120).astype(np.intp)
    sign = rng.choice([-1.0, 1.0], 120)
    areas, perimeter, speed = np.empty(faces), np.empty(faces), np.empty(faces)
    reverse, inside = _kernels.step_bounds(nodes, velocity, start, end, face, segment, sign, *high,
                                           areas, perimeter, speed)
    expected = _bounds_by_definition(nodes, velocity, start, end, face, segment, sign, high, faces)
    assert reverse == pytest.approx(expected[0], rel=1e-14)
    assert inside == pytest.approx(expected[1], rel=1e-14)
    for found, wanted in zip((areas, perimeter, speed), expected[2:], strict=True):
        np.testing.assert_allclose(found, wanted, rtol=1e-12, atol=1e-12)


def test_step_bounds_without_shrinking_segments_or_motion_is_unbounded():
    nodes = np.array([[1.0, 1.0], [1.0, 3.0], [4.0, 2.0]])
    velocity = np.zeros_like(nodes)
    start, end = np.array([0, 1, 2], dtype=np.intp), np.array([1, 2, 0], dtype=np.intp)
    face, segment, sign = np.zeros(3, dtype=np.intp), np.arange(3, dtype=np.intp), np.ones(3)
    areas, perimeter, speed = np.empty(1), np.empty(1), np.empty(1)
    reverse, inside = _kernels.step_bounds(nodes, velocity, start, end, face, segment, sign, 9.5, 9.5,
                                           areas, perimeter, speed)
    assert reverse == np.inf and inside == np.inf
    # the triangle (1,1), (1,3), (4,2): area 3 (shoelace in (row, col): negative orientation)
    assert areas[0] == pytest.approx(-3.0)
    assert perimeter[0] == pytest.approx(2.0 + 2.0 * np.sqrt(10.0))
    assert speed[0] == 0.0


def test_normal_part_is_the_numpy_definition():
    rng = np.random.default_rng(14)
    # a closed polygon (plain nodes 0..9) and a spur (node 10 -> 11) whose nodes are not plain
    angle = np.sort(rng.uniform(0, 2 * np.pi, 10))
    ring = np.column_stack([5 + 3 * np.cos(angle), 5 + 3 * np.sin(angle)])
    nodes = np.vstack([ring, [[1.0, 1.0], [2.0, 1.5]]])
    start = np.array([*range(10), 10], dtype=np.intp)
    end = np.array([*range(1, 10), 0, 11], dtype=np.intp)
    start[3], end[3] = end[3], start[3]  # one segment the other way round: its vector counts reversed
    plain = np.arange(10, dtype=np.intp)
    velocity = rng.normal(size=(12, 2))
    out = velocity.copy()
    _kernels.normal_part(nodes, out, start, end, plain)
    tangent = nodes[end] - nodes[start]
    summed = np.zeros((12, 2))
    np.add.at(summed, start, tangent)
    np.add.at(summed, end, tangent)
    normal = np.column_stack([summed[:, 1], -summed[:, 0]])[plain]
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    expected = velocity.copy()
    expected[plain] = np.einsum("ij,ij->i", velocity[plain], normal)[:, None] * normal
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12)
    # what is left is normal at the plain nodes, and the spur's velocity is untouched
    along = np.column_stack([normal[:, 1], -normal[:, 0]])
    np.testing.assert_allclose(np.einsum("ij,ij->i", out[plain], along), 0.0, atol=1e-12)
    np.testing.assert_array_equal(out[10:], velocity[10:])


def test_band_cholesky_within_the_envelopes_is_the_factor():
    # symmetric positive definite band matrices whose columns start at scattered rows (an
    # envelope narrower than the band, as chains in reverse Cuthill-McKee order): U^T U = A with U
    # numpy's upper Cholesky factor, zero above every column's envelope; a solve returns x
    rng = np.random.default_rng(4)
    for _ in range(20):
        n, w = int(rng.integers(1, 60)), int(rng.integers(1, 9))
        a = np.zeros((n, n))
        for j in range(n):
            reach = int(rng.integers(0, min(j, w) + 1))  # column j's nonzeros: rows j - reach .. j
            a[j - reach:j, j] = rng.normal(size=reach) * (rng.random(reach) < 0.7)
        a = a + a.T
        a += np.diag(np.abs(a).sum(axis=1) + 0.5 + rng.random(n))  # diagonally dominant
        band = np.zeros((n, w + 1))
        for j in range(n):
            for i in range(max(0, j - w), j + 1):
                band[j, w + i - j] = a[i, j]
        envelope = np.empty((n, 2), dtype=np.intp)
        assert _kernels.band_cholesky(band, envelope) == 0
        upper = np.linalg.cholesky(a).T
        for j in range(n):
            for i in range(max(0, j - w), j + 1):
                assert band[j, w + i - j] == pytest.approx(upper[i, j], rel=1e-12, abs=1e-12)
        x = rng.normal(size=n)
        rhs = a @ x
        _kernels.band_solve(band, envelope, rhs)
        np.testing.assert_allclose(rhs, x, rtol=1e-10, atol=1e-10)
        # the envelope: each column's first row with an entry of A, and each row's last column
        # whose envelope reaches it (where U can have entries: fill stays within the envelopes)
        nonzero = (a != 0) & (np.arange(n)[:, None] <= np.arange(n)[None, :])
        first = np.argmax(nonzero, axis=0)
        np.testing.assert_array_equal(envelope[:, 0], first)
        rows = np.arange(n)
        within = (first[None, :] <= rows[:, None]) & (rows[None, :] >= rows[:, None])
        np.testing.assert_array_equal(envelope[:, 1], n - 1 - np.argmax(within[:, ::-1], axis=1))
        assert np.all(np.abs(upper)[~within] < 1e-12)  # U within the envelopes


def test_band_cholesky_reports_a_matrix_that_is_not_positive_definite():
    band = np.array([[0.0, 1.0], [2.0, 1.0]])  # [[1, 2], [2, 1]]: the second leading minor is -3
    assert _kernels.band_cholesky(band, np.empty((2, 2), dtype=np.intp)) == 2


def test_h1_band_is_the_stiffness_matrix_in_band_form():
    # chains and a junction of segments between random nodes, some nodes held (position -1), the
    # rest in a shuffled order: the band is Network.stiffness's matrix restricted and reordered
    from activecontour.backends.network import Network, h1

    rng = np.random.default_rng(6)
    for _ in range(10):
        count = int(rng.integers(6, 40))
        nodes = rng.uniform(0.0, 20.0, (count, 2))
        start = np.arange(count - 1, dtype=np.intp)
        end = np.arange(1, count, dtype=np.intp)
        start, end = np.append(start, [0, count // 2]), np.append(end, [count // 2, count - 1])  # loops
        keep = np.flatnonzero(rng.random(count) < 0.8)
        order = rng.permutation(keep).astype(np.intp)
        position = np.full(count, -1, dtype=np.intp)
        position[order] = np.arange(order.size)
        sides = np.zeros(len(start), dtype=np.intp)
        network = Network(nodes, start, end, sides, sides + 1, (21, 21))
        dense = h1.stiffness(network, nodes).toarray()[np.ix_(order, order)]
        pairs = np.abs(position[start] - position[end])[(position[start] >= 0) & (position[end] >= 0)]
        width = int(pairs.max()) if pairs.size else 0
        band = np.zeros((order.size, width + 1))
        _kernels.h1_band(nodes, start, end, position, band)
        for j in range(order.size):
            for i in range(max(0, j - width), j + 1):
                assert band[j, width + i - j] == pytest.approx(dense[i, j], rel=1e-12, abs=1e-12)
        assert np.all(np.abs(dense[np.abs(np.subtract.outer(np.arange(order.size), np.arange(order.size)))
                                   > width]) == 0)


@pytest.mark.parametrize("channels", [1, 3])
def test_segment_integrals_take_the_known_segments_from_an_earlier_call(channels):
    from activecontour.energy import evaluate_partition
    from activecontour.geometry.partition import Boundary, Sides
    from activecontour.imaging.tables import ImageModel
    from activecontour.models import ChanVeseParameters

    rng = np.random.default_rng(12)
    model, params = ImageModel(rng.random((21, 21, channels))), ChanVeseParameters(0.3)
    starts, ends, inner, outer = _segments(rng, 40, 3)
    boundary = Boundary(starts, ends, inner, outer, Sides(inner, outer))
    earlier = evaluate_partition(model, boundary, params, 3, parts=True)
    # the same boundary, its segments reversed in order, one of them moved: the others are known
    order = np.arange(40)[::-1]
    moved_starts, moved_ends = starts[order].copy(), ends[order].copy()
    moved_ends[5] += 0.3
    later = Boundary(moved_starts, moved_ends, inner[order], outer[order], Sides(inner[order], outer[order]))
    rows = order.copy()
    rows[5] = -1
    fresh = evaluate_partition(model, later, params, 3, parts=True)
    known = evaluate_partition(model, later, params, 3, parts=True, known=(rows, earlier))
    assert known.energy == fresh.energy and known.length == fresh.length
    for name in ("areas", "first", "second", "parts", "sums"):
        np.testing.assert_array_equal(getattr(known, name), getattr(fresh, name))
    # what is known is taken, not integrated: a known segment's terms changed by d change its
    # inner region's integrals by d and its outer region's by -d
    altered = evaluate_partition(model, boundary, params, 3, parts=True)
    e = next(k for k in range(40) if rows[k] >= 0 and inner[order][k] > 0 and outer[order][k] > 0
             and inner[order][k] != outer[order][k])
    altered.sums[rows[e]] += 1.0
    shifted = evaluate_partition(model, later, params, 3, parts=True, known=(rows, altered))
    change = np.zeros((3, channels))
    change[inner[order][e]] += 1.0
    change[outer[order][e]] -= 1.0
    np.testing.assert_allclose(shifted.first - fresh.first, change, atol=1e-9)
    np.testing.assert_allclose(shifted.second - fresh.second, change, atol=1e-9)
