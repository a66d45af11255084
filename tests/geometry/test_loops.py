"""Chaining oriented segments into loops, cut where a region is pinched (geometry.partition)."""

import numpy as np

from activecontour import _kernels
from activecontour.geometry.partition import chain_loops, loop_order


def _untwisted(loop, keys):
    """The definition: cut a loop at its smallest key passed twice, between the first two passes,
    into the piece between them and the rest (from the second pass on, then the start), each cut
    again until every key is passed once."""
    here = keys[loop]
    values, counts = np.unique(here, return_counts=True)
    if np.all(counts == 1):
        return [loop]
    smallest = values[np.argmax(counts > 1)]
    i, j = np.flatnonzero(here == smallest)[:2]
    return _untwisted(loop[i:j], keys) + _untwisted(np.concatenate([loop[j:], loop[:i]]), keys)


def test_untwist_is_the_recursive_definition():
    rng = np.random.default_rng(21)
    for _ in range(50):
        # loops over a few points, so that most pass some point several times
        sizes = rng.integers(1, 14, rng.integers(1, 6))
        order = rng.permutation(sizes.sum()).astype(np.intp)
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
        keys = rng.integers(0, 6, sizes.sum()) * 7 + 3  # sparse keys: ids are their ranks
        distinct, ids = np.unique(keys, return_inverse=True)
        loops = [order[a:b] for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
        twisted = np.array([len(np.unique(keys[loop])) < len(loop) for loop in loops], dtype=np.uint8)
        out, out_offsets = np.empty_like(order), np.empty(len(order) + 1, dtype=np.intp)
        ids = ids.astype(np.intp)
        count = _kernels.untwist(order, offsets, twisted, ids, len(distinct), out, out_offsets)
        expected = [piece for loop in loops for piece in _untwisted(loop, keys)]
        assert count == len(expected)
        for k, piece in enumerate(expected):
            np.testing.assert_array_equal(out[out_offsets[k]:out_offsets[k + 1]], piece)
        # every piece passes each of its points once, and the pieces use every segment once
        assert all(len(np.unique(keys[piece])) == len(piece) for piece in expected)
        np.testing.assert_array_equal(np.sort(out), np.arange(len(order)))


def test_a_pinched_square_pair_is_two_loops():
    # two unit squares of one region touching at the corner (1, 1): one walk of 8 segments that
    # passes (1, 1) twice
    points = {"a": (0, 0), "b": (0, 1), "c": (1, 1), "d": (1, 0), "e": (1, 2), "f": (2, 2), "g": (2, 1)}
    walk = ["a", "b", "c", "e", "f", "g", "c", "d"]
    key = {name: 10 * r + c for name, (r, c) in points.items()}
    starts = np.array([key[p] for p in walk])
    ends = np.roll(starts, -1)
    loops = chain_loops(starts, ends)
    assert sorted(len(loop) for loop in loops) == [4, 4]
    for loop in loops:  # each closes: a segment's end is the next one's start
        np.testing.assert_array_equal(ends[loop], starts[np.roll(loop, -1)])
    order, offsets = loop_order(starts, ends)
    np.testing.assert_array_equal(np.concatenate(loops), order)
    assert list(offsets) == [0, 4, 8]


def test_no_segments_no_loops():
    empty = np.empty(0, dtype=np.int64)
    assert chain_loops(empty, empty) == []
    order, offsets = loop_order(empty, empty)
    assert order.size == 0 and list(offsets) == [0]


def test_dense_ids_chain_as_sorting_does():
    # random closed walks over a few points (so that most pass some point several times, and
    # points have several segments leaving them), their segments shuffled: loop_order on the
    # points' dense ids (counting) gives the loops the sorting of their keys gives
    rng = np.random.default_rng(5)
    for _ in range(50):
        walks = [rng.integers(0, 8, rng.integers(2, 12)) for _ in range(rng.integers(1, 5))]
        starts = np.concatenate(walks)
        ends = np.concatenate([np.roll(walk, -1) for walk in walks])
        shuffle = rng.permutation(len(starts))
        starts, ends = starts[shuffle], ends[shuffle]
        order, offsets = loop_order(starts * 7 + 3, ends * 7 + 3)  # sparse keys: sorted
        dense_order, dense_offsets = loop_order(starts, ends, 8)
        np.testing.assert_array_equal(dense_order, order)
        np.testing.assert_array_equal(dense_offsets, offsets)
        for a, b in zip(offsets[:-1], offsets[1:], strict=True):  # closed, each point once
            loop = order[a:b]
            np.testing.assert_array_equal(ends[loop], starts[np.roll(loop, -1)])
            assert len(np.unique(starts[loop])) == len(loop)
