"""The boundary graph of a partition (:class:`Network`): its segments and the regions on either
side, its faces, its interfaces as polylines and closed loops; the local changes the flow makes to
it (resampling, a pinch joined the other way, a vanishing segment collapsed, an island dropped);
and the exact test that no two interfaces meet (:meth:`Network.simple`).  The flow that moves its
nodes is :mod:`activecontour.backends.network.flow`."""

from __future__ import annotations

import weakref

import numpy as np

from activecontour import _kernels
from activecontour.geometry.partition import (
    Boundary,
    Sides,
    chain_loops,
    class_boundary,
    lattice_keys,
    loop_order,
)

#: No crossing parameters: the network asks for pairs only (:func:`activecontour._kernels.segments_meet`).
_NO_WHERE = np.empty((0, 2))
#: A probe's distance off a segment, relative to the largest coordinate (:meth:`Network.sides_hold_after`).
_PROBE = 1e-9


class Network:
    """The boundary graph of a partition: nodes, and oriented segments between them with the
    region on either side (``inner`` opposite the normal ``nu = (t_c, -t_r)``, ``outer`` on its
    side, -1 outside the image).

    Parameters
    ----------
    nodes : ndarray (P, 2)
    start, end : int ndarray (S,)
        The node of each segment's ends.
    inner, outer : int ndarray (S,)
    shape : (M, N)
    """

    def __init__(self, nodes, start, end, inner, outer, shape):
        self.nodes, self.start, self.end = nodes, start, end
        self.inner, self.outer, self.shape = inner, outer, tuple(shape)
        self.interface = outer >= 0
        self.sides = Sides(inner, outer)
        self._faces = self._face_counts = self._moving = self._pieces = self._origin = None
        m, n = self.shape
        moving = np.zeros(len(nodes), dtype=bool)
        moving[start[self.interface]] = moving[end[self.interface]] = True
        on_rows = (nodes[:, 0] == -0.5) | (nodes[:, 0] == m - 0.5)
        on_cols = (nodes[:, 1] == -0.5) | (nodes[:, 1] == n - 0.5)
        # a node on the border slides along it: its component across the border is held
        self.free = (moving & ~on_rows, moving & ~on_cols)
        chosen = np.flatnonzero(self.interface)
        self._interface_ends = (np.ascontiguousarray(start[chosen], dtype=np.intp),
                                np.ascontiguousarray(end[chosen], dtype=np.intp))
        self._bands, self._orders = {}, {}
        degree = np.bincount(np.concatenate(self._interface_ends), minlength=len(nodes))
        self._plain = np.flatnonzero((degree == 2) & self.free[0] & self.free[1])

    @classmethod
    def of_classes(cls, classes):
        """The network of the partition a label image stands for (:mod:`activecontour.geometry.partition`)."""
        return cls.of_boundary(class_boundary(classes), classes.shape)

    @classmethod
    def of_boundary(cls, boundary, shape):
        """The network of a label image's partition given as its
        :func:`~activecontour.geometry.partition.class_boundary` (vertices on the half-pixel lattice)."""
        points = np.vstack([boundary.start, boundary.end])
        _, first, index = np.unique(lattice_keys(points), return_index=True, return_inverse=True)
        count = len(boundary.start)
        return cls(points[first], index[:count], index[count:], boundary.inner, boundary.outer, shape)

    def boundary(self, nodes=None):
        """The partition's :class:`~activecontour.geometry.partition.Boundary`, vertices at ``nodes``."""
        nodes = self.nodes if nodes is None else nodes
        return Boundary(nodes.take(self.start, axis=0), nodes.take(self.end, axis=0), self.inner, self.outer,
                        self.sides)

    def moving_boundary(self, nodes):
        """:meth:`boundary` without the segments that neither count in J nor move: the image's
        edge along the background between nodes held there.  The background's moments are the
        domain's less the other regions' (:func:`activecontour.energy.partition_moments`), so J
        is the same, at the cost of the interfaces and what slides along the edge."""
        start, end, inner, outer, sides, _ = self._moving_segments()
        # (take: a gather of rows ten times faster than fancy indexing, on every evaluation)
        return Boundary(nodes.take(start, axis=0), nodes.take(end, axis=0), inner, outer, sides)

    def _moving_segments(self):
        """The segments of :meth:`moving_boundary`: ``(start, end, inner, outer, sides, kept)``,
        ``kept`` their indices among all segments."""
        if self._moving is None:
            held = ~(self.free[0] | self.free[1])
            kept = np.flatnonzero(~((self.outer < 0) & (self.inner == 0) & held[self.start] & held[self.end]))
            inner, outer = self.inner[kept], self.outer[kept]
            self._moving = (self.start[kept], self.end[kept], inner, outer, Sides(inner, outer), kept)
        return self._moving

    def shared_rows(self, parent):
        """For each segment of :meth:`moving_boundary`, its row in ``parent``'s where this network
        was made from ``parent`` by a local change (:meth:`inheriting`) and the segment is the same
        there (the same ends in the same order), else -1; None when this network was not made
        from ``parent``.  At the same nodes, such a segment's integrals are the parent's."""
        kept = self._moving_segments()[5]
        origin = self._origin_of(parent, kept)
        if origin is None:
            return None
        parent_kept = parent._moving_segments()[5]
        rows = np.full(len(parent.start), -1, dtype=np.intp)
        rows[parent_kept] = np.arange(len(parent_kept))
        return np.where(origin >= 0, rows[np.maximum(origin, 0)], -1)

    def _origin_of(self, parent, segments):
        """The index in ``parent`` of each of ``segments`` where it is the same segment there (the
        same ends in the same order), else -1; None when this network was not made from
        ``parent`` (:meth:`inheriting`)."""
        if self._origin is None or self._origin[0]() is not parent:
            return None
        origin = self._origin[1][segments]
        same = (parent.start[origin] == self.start[segments]) & (parent.end[origin] == self.end[segments])
        return np.where(same, origin, -1)

    def relabelled(self, mapping):
        """The same network with region k renamed ``mapping[k]``."""
        mapping = np.append(np.asarray(mapping), -1)  # -1 (outside the image) stays
        return Network(self.nodes, self.start, self.end, mapping[self.inner], mapping[self.outer],
                       self.shape)

    def faces(self):
        """The closed boundary curves of every region, as ``(face of each entry, segment, sign)``:
        the entries of face f are its segments, traversed forward (+1) or backward (-1).  They
        do not change while the nodes move, so each face's signed area (:meth:`face_areas`) must
        keep its sign: a region turned inside out crosses no segment when it is a triangle."""
        if self._faces is None:
            # every region's entries: its segments forward (inner side), then backward (outer
            # side), each in segment order; keyed by (region, node), so that one chaining pass
            # finds the loops of every region, region by region
            backward = np.flatnonzero(self.outer >= 0)
            segment = np.concatenate([np.arange(len(self.start)), backward])
            region = np.concatenate([self.inner, self.outer[backward]])
            forward = np.arange(len(segment)) < len(self.start)
            # (a stable sort of small integers is a radix sort: O(n))
            entries = np.argsort((2 * region + ~forward).astype(np.int16), kind="stable")
            segment, region, forward = segment[entries], region[entries], forward[entries]
            tails = np.where(forward, self.start[segment], self.end[segment])
            heads = np.where(forward, self.end[segment], self.start[segment])
            count = len(self.nodes)
            order, offsets = loop_order(region * count + tails, region * count + heads,
                                        (int(region.max()) + 1) * count if region.size else 0)
            face = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
            self._faces = (face.astype(np.intp), segment[order].astype(np.intp),
                           np.where(forward[order], 1.0, -1.0))
        return self._faces

    @property
    def face_counts(self):
        """The number of segments of every face (:meth:`faces`)."""
        if self._face_counts is None:
            face = self.faces()[0]
            self._face_counts = np.bincount(face, minlength=int(face.max()) + 1 if face.size else 0)
        return self._face_counts

    def face_areas(self, nodes, which=None):
        """The signed area of every face (:meth:`faces`), or of the faces ``which`` (indices)."""
        face, segment, sign = self.faces()
        if which is not None:
            chosen = np.zeros(len(self.face_counts), dtype=bool)
            chosen[which] = True
            chosen = chosen[face]
            face, segment, sign = np.searchsorted(which, face[chosen]), segment[chosen], sign[chosen]
            count = len(which)
        else:
            count = int(face.max()) + 1 if face.size else 0
        a, b = nodes.take(self.start[segment], axis=0), nodes.take(self.end[segment], axis=0)
        twice = sign * (a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])
        return 0.5 * np.bincount(face, weights=twice, minlength=count)

    def region_curves(self, region):
        """Closed curves of a set of regions (bool per region): outer boundaries positive."""
        region = np.append(np.asarray(region, dtype=bool), False)
        inner, outer = region[self.inner], region[self.outer]
        forward, backward = inner & ~outer, outer & ~inner
        starts = np.concatenate([self.start[forward], self.end[backward]])
        ends = np.concatenate([self.end[forward], self.start[backward]])
        return [self.nodes[starts[loop]] for loop in chain_loops(starts, ends, len(self.nodes))]

    def polylines(self):
        """The interfaces as polylines of nodes between branch nodes (junctions and nodes on the
        border) or closed loops, all in one array: ``(path, offsets, inner, outer, closed)``,
        line k the nodes ``path[offsets[k]:offsets[k + 1]]`` (a closed loop without its first node
        repeated), the regions on either side of its walking direction (the same all along: a
        region changes only at a junction).  A line is walked from its end at the smaller branch
        node (then along the smaller segment), a loop from the start of its smallest segment,
        along it; lines come in that order, loops after them.

        Each interface segment is two half-edges (forward, backward); at a node of degree two a
        half-edge continues with the other segment, at a branch node it turns back on itself.  The
        cycles of that permutation are the lines there and back, and the loops once each way.
        """
        chosen = np.flatnonzero(self.interface)
        branch, tail, head, order, offsets = self._half_edge_cycles()
        cycles = len(offsets) - 1
        cycle = np.repeat(np.arange(cycles), np.diff(offsets))
        # a line's cycle turns twice (positions p < q): its runs start after each turn
        turns = np.flatnonzero(branch[head[order]]).reshape(-1, 2)
        p, q = turns[:, 0], turns[:, 1]
        lines = cycle[p]
        low, span = offsets[lines], offsets[lines + 1] - offsets[lines]
        runs = np.stack([p + 1, np.where(q + 1 < low + span, q + 1, low)])
        run_lengths = np.stack([q - p, span - (q - p)])
        first_half = order[runs]
        pick = np.lexsort((first_half // 2, tail[first_half]), axis=0)[0]  # smaller (node, segment)
        line_first = runs[pick, np.arange(len(lines))]
        line_size = run_lengths[pick, np.arange(len(lines))]
        by_start = np.lexsort((order[line_first] // 2, tail[order[line_first]]))
        line_first, line_size, lines = line_first[by_start], line_size[by_start], lines[by_start]
        # a loop: the cycle of the forward half-edge of its smallest segment, from it (the cycle's
        # smallest element); the other way round is the cycle from that segment's backward one
        has_turn = np.zeros(cycles, dtype=bool)
        has_turn[lines] = True
        loops = np.flatnonzero(~has_turn & (order[offsets[:-1]] % 2 == 0))
        firsts = np.concatenate([line_first, offsets[loops]])
        sizes = np.concatenate([line_size, np.diff(offsets)[loops]])
        owners = np.concatenate([lines, loops])
        closed = np.arange(len(firsts)) >= len(lines)
        line_offsets = np.concatenate([[0], np.cumsum(sizes)])
        within = np.arange(line_offsets[-1]) - np.repeat(line_offsets[:-1], sizes)
        low, span = np.repeat(offsets[owners], sizes), np.repeat(np.diff(offsets)[owners], sizes)
        halves = order[low + (np.repeat(firsts, sizes) - low + within) % span]
        # the nodes: a line's tails and its last head, a loop's tails
        path_offsets = np.concatenate([[0], np.cumsum(sizes + ~closed)])
        path = np.empty(path_offsets[-1], dtype=np.intp)
        path[np.repeat(path_offsets[:-1], sizes) + within] = tail[halves]
        path[path_offsets[1:][~closed] - 1] = head[halves[line_offsets[1:][~closed] - 1]]
        first_half = halves[line_offsets[:-1]]
        segment = chosen[first_half // 2]
        forward = first_half % 2 == 0
        inner = np.where(forward, self.inner[segment], self.outer[segment])
        outer = np.where(forward, self.outer[segment], self.inner[segment])
        return path, path_offsets, inner, outer, closed

    def _half_edge_cycles(self):
        """The cycles of :meth:`polylines`' half-edges: ``(branch, tail, head, order, offsets)``,
        ``branch`` per node, the half-edges' end nodes (half-edge ``2 i + d``: interface segment i
        forward, d = 0, or backward), and cycle c the half-edges ``order[offsets[c]:offsets[c + 1]]``
        (each from its smallest, in the order of those)."""
        start, end = self._interface_ends
        count = len(start)
        degree = np.bincount(np.concatenate([start, end]), minlength=len(self.nodes))
        branch = (degree != 2) | ~(self.free[0] & self.free[1])
        tail, head = np.empty(2 * count, dtype=np.intp), np.empty(2 * count, dtype=np.intp)
        tail[0::2], tail[1::2] = start, end
        head[0::2], head[1::2] = end, start
        following = np.arange(2 * count) ^ 1  # turn back at a branch node
        leaving = np.argsort(tail, kind="stable")
        leaving = leaving[~branch[tail[leaving]]].reshape(-1, 2)  # the two half-edges leaving a node
        following[leaving[:, 0] ^ 1], following[leaving[:, 1] ^ 1] = leaving[:, 1], leaving[:, 0]
        order, offsets = np.empty(2 * count, dtype=np.intp), np.empty(2 * count + 1, dtype=np.intp)
        cycles = _kernels.cycles(following, order, offsets)
        return branch, tail, head, order, offsets[:cycles + 1]

    def resampled(self, nodes, spacing):
        """The network with every interface resampled at equal arc-length steps of about
        ``spacing`` px, its branch nodes kept (mesh health, as the two-region flow's
        :func:`activecontour.geometry.curve.resample`).  Returns ``(network, nodes)``."""
        path, offsets, left, right, closed = self.polylines()
        lines = len(closed)
        interior = np.zeros(len(nodes), dtype=bool)
        sizes = np.diff(offsets)
        inside = np.ones(len(path), dtype=bool)  # a line's nodes but its two ends, every node of a loop
        inside[offsets[:-1][~closed]] = inside[offsets[1:][~closed] - 1] = False
        interior[path[inside]] = True
        kept = np.flatnonzero(~interior)
        index = np.full(len(nodes), -1)
        index[kept] = np.arange(kept.size)
        # each polyline's vertices, a loop's first one again at its end
        ring = np.insert(path, offsets[1:][closed], path[offsets[:-1][closed]])
        ring_sizes = sizes + closed
        ring_offsets = np.concatenate([[0], np.cumsum(ring_sizes)])
        points = nodes.take(ring, axis=0)
        step = np.hypot(*(points[1:] - points[:-1]).T)
        step[ring_offsets[1:-1] - 1] = 0.0  # no step from one line to the next
        arc = np.concatenate([[0.0], np.cumsum(step)])[:len(points)]
        arc -= np.repeat(arc[ring_offsets[:-1]], ring_sizes)  # from each line's start
        total = arc[ring_offsets[1:] - 1]
        # a line keeps a vertex between its ends: a region between two single segments (two
        # interfaces joining the same junctions, or one and the border) would be a 2-gon
        fewest = np.where(closed | (path[offsets[:-1]] == path[offsets[1:] - 1]), 3, 2)
        pieces = np.maximum(fewest, np.rint(total / spacing).astype(np.intp))
        new_count = pieces - ~closed  # a line's inner samples, a loop's all
        owner = np.repeat(np.arange(lines), new_count)
        k = (np.arange(new_count.sum()) - np.repeat(np.cumsum(new_count) - new_count, new_count)
             + ~closed[owner])
        at = k * (total / pieces)[owner]
        # the polyline segment of every sample, from its line's own arc (searched line by line
        # through a shift that keeps the lines apart)
        shift = np.concatenate([[0.0], np.cumsum(total + 1.0)])[:-1]
        piece = np.searchsorted(arc + np.repeat(shift, ring_sizes), at + shift[owner], side="right") - 1
        piece = np.clip(piece, ring_offsets[:-1][owner], ring_offsets[1:][owner] - 2)
        with np.errstate(invalid="ignore", divide="ignore"):
            fraction = np.where(step[piece] > 0, (at - arc[piece]) / step[piece], 0.0)
        base = points.take(piece, axis=0)
        new = base + np.clip(fraction, 0.0, 1.0)[:, None] * (points.take(piece + 1, axis=0) - base)
        # the segments: the border's, then each line's chain of nodes: a line's [start, samples,
        # end] (its ends the kept branch nodes), a loop's [samples, its first sample]
        chain_sizes = new_count + 1 + ~closed
        chain_offsets = np.concatenate([[0], np.cumsum(chain_sizes)])
        chain = np.empty(chain_offsets[-1], dtype=np.intp)
        ends = chain_offsets[1:] - 1
        samples = np.repeat(chain_offsets[:-1] + ~closed, new_count) + (k - ~closed[owner])
        chain[samples] = kept.size + np.arange(len(new))
        chain[chain_offsets[:-1][~closed]] = index[path[offsets[:-1][~closed]]]
        chain[ends[~closed]] = index[path[offsets[1:][~closed] - 1]]
        chain[ends[closed]] = chain[chain_offsets[:-1][closed]]
        link = np.ones(len(chain), dtype=bool)
        link[ends] = False  # no segment from one chain's end to the next chain
        chain_start, chain_end = chain[:-1][link[:-1]], chain[1:][link[:-1]]
        line_of = np.repeat(np.arange(lines), chain_sizes - 1)
        border = ~self.interface
        start = np.concatenate([index[self.start[border]], chain_start]).astype(np.intp)
        end = np.concatenate([index[self.end[border]], chain_end]).astype(np.intp)
        inner = np.concatenate([self.inner[border], left[line_of]]).astype(np.intp)
        outer = np.concatenate([self.outer[border], right[line_of]]).astype(np.intp)
        nodes = np.vstack([nodes.take(kept, axis=0), new])
        return Network(nodes, start, end, inner, outer, self.shape), nodes

    def meeting_pairs(self, nodes, limit=16):
        """Up to ``limit`` pairs ``(e, f)`` of interface segments (indices among all segments)
        that meet at ``nodes`` other than at a common node (:meth:`simple`'s test)."""
        start, end = self._interface_ends
        pairs = np.empty((limit, 2), dtype=np.intp)
        found = _kernels.segments_meet(np.ascontiguousarray(nodes, dtype=np.float64), start, end, True, limit,
                                       pairs, _NO_WHERE)
        return np.flatnonzero(self.interface)[pairs[:min(found, limit)]]

    def meet_among(self, nodes, segments):
        """Whether two of the interface segments ``segments`` (indices among all segments) meet at
        ``nodes`` other than at a common node (:meth:`simple`'s test, on them alone: True means
        the network is not simple there)."""
        start, end = as_indices(self.start[segments]), as_indices(self.end[segments])
        return _kernels.segments_meet(np.ascontiguousarray(nodes, dtype=np.float64), start, end, True, 1,
                                      np.empty((0, 2), dtype=np.intp), _NO_WHERE) > 0

    def reconnected(self, pairs, nodes):
        """The network with each pair of interface segments ``e = (a, b)``, ``f = (c, d)`` between
        the same two regions, oriented alike (``f`` read backwards where its sides are swapped),
        joined the other way: ``(a, d)`` and ``(c, b)``, both with ``e``'s sides.  Where the two
        face each other across a thin part of one region (a neck, or a finger's sides), that part
        is cut and the other region joins across; each new segment keeps the inner region on its
        left, so the regions stay consistent.  Where one segment ``g`` joins ``b`` and ``c``
        inside an interface (the sides of a spike cross), ``(c, b)`` and ``g`` would make a loop
        of two segments: both go, the spike's tip with them.  Pairs that share a node with an
        earlier one are skipped.  Returns ``(network, nodes)``, or None when no pair qualifies."""
        start, end, inner, outer = self.start.copy(), self.end.copy(), self.inner.copy(), self.outer.copy()
        keep, plain = np.ones(len(start), dtype=bool), np.zeros(len(nodes), dtype=bool)
        plain[self._plain] = True
        used = set()
        for e, f in pairs:
            if inner[e] == inner[f] and outer[e] == outer[f]:
                c, d = start[f], end[f]
            elif inner[e] == outer[f] and outer[e] == inner[f]:
                c, d = end[f], start[f]
            else:
                continue
            a, b = start[e], end[e]
            ends = {int(a), int(b), int(c), int(d)}
            if len(ends) < 4 or ends & used:
                continue
            used |= ends
            end[e], start[f], end[f] = d, c, b
            inner[f], outer[f] = inner[e], outer[e]
            spike = np.flatnonzero(self.interface & (((self.start == b) & (self.end == c))
                                                     | ((self.start == c) & (self.end == b))))
            if spike.size and plain[b] and plain[c]:
                keep[spike[0]] = keep[f] = False
        if not used:
            return None
        network = Network(nodes, start[keep], end[keep], inner[keep], outer[keep], self.shape)
        return network.inheriting(self, np.flatnonzero(keep)), nodes

    def collapsed(self, segments, nodes):
        """The network without the interface segments ``segments``, the two ends of each made one
        node: an end inside an interface (degree two, free) goes into the other end, which keeps
        its place.  A segment is skipped where neither end is such, where the end would close a
        loop of two segments, or where it shares a node with an earlier one.  Returns
        ``(network, nodes)``, or None when none is left."""
        start, end = self._interface_ends
        others = np.bincount(start, weights=end, minlength=len(nodes)) + np.bincount(
            end, weights=start, minlength=len(nodes))  # at a degree-two node: the sum of its neighbours
        plain = np.zeros(len(nodes), dtype=bool)
        plain[self._plain] = True
        target, keep, used = np.arange(len(nodes)), np.ones(len(self.start), dtype=bool), set()
        for s in segments:
            u, v = int(self.start[s]), int(self.end[s])
            gone, kept = (v, u) if plain[v] else (u, v)
            if not plain[gone] or {u, v} & used or others[gone] - kept == kept:
                continue
            used |= {u, v}
            target[gone], keep[s] = kept, False
        if keep.all():
            return None
        network = Network(nodes, target[self.start[keep]], target[self.end[keep]], self.inner[keep],
                          self.outer[keep], self.shape)
        return network.inheriting(self, np.flatnonzero(keep)), nodes

    def border_merged(self, segments, nodes, into_start=True):
        """The network without the border segments ``segments`` (on the image's edge, shorter than
        a step can shrink them), the two ends of each made one node, so that a junction sliding
        along the edge slides on:

        * an end that is a mere vertex of one straight edge (on no interface, at no corner of the
          image) goes into the other end: the edge's other segment there goes on to it, so the
          edge keeps its place and J its value (the two segments were collinear);
        * two junctions (interfaces meeting the edge at both ends) become one, at the segment's
          start (``into_start``) or its end: the region that touched the edge between them now
          meets it at a point.  Where that region was a triangle, the two interface segments
          from the junctions to its third node now join the same two nodes (a 2-gon, no area):
          the region goes, one segment stays with the regions on their other sides, none where
          those are the same region.

        A segment is skipped where it shares a node with an earlier one, or where its ends are
        joined otherwise too (an interface between them, or more than one common neighbour).
        Returns ``(network, nodes)``, or None when no segment is left."""
        m, n = self.shape
        uses = np.bincount(np.concatenate([self.start, self.end]), minlength=len(nodes))
        on_rows = (nodes[:, 0] == -0.5) | (nodes[:, 0] == m - 0.5)
        on_cols = (nodes[:, 1] == -0.5) | (nodes[:, 1] == n - 0.5)
        moving = self.free[0] | self.free[1]
        vertex = (uses == 2) & ~moving & (on_rows != on_cols)
        inner, outer = self.inner.copy(), self.outer.copy()
        target, keep, used = np.arange(len(nodes)), np.ones(len(self.start), dtype=bool), set()
        for s in segments:
            u, v = int(self.start[s]), int(self.end[s])
            if self.outer[s] >= 0 or {u, v} & used:
                continue
            if vertex[u] or vertex[v]:
                gone, kept = (u, v) if vertex[u] else (v, u)
                dropped = []
            elif moving[u] and moving[v]:
                gone, kept = (v, u) if into_start else (u, v)
                dropped = self._two_gon(s, keep, inner, outer)
                if dropped is None:
                    continue
            else:
                continue
            used |= {u, v}
            target[gone], keep[s] = kept, False
            keep[dropped] = False
        if keep.all():
            return None
        network = Network(nodes, target[self.start[keep]], target[self.end[keep]], inner[keep], outer[keep],
                          self.shape)
        return network.inheriting(self, np.flatnonzero(keep)), nodes

    def _two_gon(self, s, keep, inner, outer):
        """For :meth:`border_merged` of the junctions at the ends of border segment ``s``: the
        interface segments to drop where the junctions have one common neighbour (the region
        ``inner[s]`` between them a triangle), the kept one's sides renamed in ``inner``,
        ``outer``; none where they have no common neighbour; None where the merge is refused
        (an interface joins the two junctions, or they have more than one common neighbour)."""
        u, v, region = self.start[s], self.end[s], self.inner[s]
        at_u = np.flatnonzero(self.interface & keep & ((self.start == u) | (self.end == u)))
        at_v = np.flatnonzero(self.interface & keep & ((self.start == v) | (self.end == v)))
        from_u = np.where(self.start[at_u] == u, self.end[at_u], self.start[at_u])
        from_v = np.where(self.start[at_v] == v, self.end[at_v], self.start[at_v])
        common = np.intersect1d(from_u, from_v)
        if v in from_u or common.size > 1:
            return None
        if common.size == 0:
            return []
        e, f = at_u[from_u == common[0]][0], at_v[from_v == common[0]][0]
        if region not in (inner[e], outer[e]) or region not in (inner[f], outer[f]):
            return None
        # the regions on the triangle's two sides away from it
        other_e = outer[e] if inner[e] == region else inner[e]
        other_f = outer[f] if inner[f] == region else inner[f]
        if other_e == other_f:
            return [e, f]
        if inner[e] == region:
            inner[e] = other_f
        else:
            outer[e] = other_f
        return [f]

    def crossing_nodes(self, nodes):
        """The nodes of interface segments that cross another one (for the islands to drop)."""
        import shapely

        chosen = np.flatnonzero(self.interface)
        ends = np.stack([nodes[self.start[chosen]], nodes[self.end[chosen]]], axis=1)
        lines = shapely.linestrings(ends)
        first, second = shapely.STRtree(lines).query(lines, predicate="crosses")
        crossing = chosen[np.union1d(first, second)]
        return np.union1d(self.start[crossing], self.end[crossing])

    def closed_loops(self, nodes):
        """The interfaces that are closed loops (no junction, off the border), each as
        ``(segment indices, enclosed area)``: the connected pieces of the graph whose vertices are
        the interface segments, joined at the nodes of degree two (:meth:`_interface_pieces`)."""
        areas = self.closed_areas(nodes)[0]
        return [(self.loop_segments(k), area) for k, area in enumerate(areas)]

    def closed_areas(self, nodes, interest=None):
        """The enclosed area of every loop of :meth:`closed_loops` (in their order, the segments of
        loop k :meth:`loop_segments`), and, given ``interest`` (bool per node), whether each passes
        a node of it (None without): the loops' numbers, no list of their segments."""
        if self._pieces is None:
            self._pieces = self._interface_pieces()
        chosen, piece, count, closed, sign = self._pieces[:5]
        if chosen.size == 0:
            return np.zeros(0), None if interest is None else np.zeros(0, dtype=bool)
        a, b = nodes.take(self.start[chosen], axis=0), nodes.take(self.end[chosen], axis=0)
        twice_area = np.bincount(piece, weights=sign * (a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1]),
                                 minlength=count)
        through = None if interest is None else np.bincount(
            piece, weights=interest[self.start[chosen]], minlength=count)[closed] > 0
        return 0.5 * np.abs(twice_area[closed]), through

    def loop_segments(self, k):
        """The segment indices of loop k of :meth:`closed_loops` (:meth:`closed_areas`)."""
        chosen, _, _, closed, _, by_piece, bounds = self._pieces
        return chosen[by_piece[bounds[closed[k]]:bounds[closed[k] + 1]]]

    def _interface_pieces(self):
        """The graph part of :meth:`closed_loops`: the interface segments, the piece of each, the
        number of pieces, the closed ones, each segment's orientation against its piece's first,
        the segments in order of their piece and where each piece's begin.

        A piece is the half-edge cycles (:meth:`_half_edge_cycles`) of its segments: one for a
        line (there and back), two for a loop (one each way).  Pieces are numbered in the order of
        their smallest segment, the first of its cycles (it holds that segment's forward half)."""
        chosen = np.flatnonzero(self.interface)
        if chosen.size == 0:
            return chosen, chosen, 0, chosen, chosen, chosen, chosen
        branch, _, _, order, offsets = self._half_edge_cycles()
        cycle = np.empty(len(order), dtype=np.intp)
        cycle[order] = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        first_cycle = np.minimum(cycle[0::2], cycle[1::2])  # a loop's, either way
        used = np.zeros(len(offsets) - 1, dtype=bool)
        used[first_cycle] = True
        piece = (np.cumsum(used) - 1)[first_cycle]
        count = int(used.sum())
        open_piece = np.zeros(count, dtype=bool)
        open_piece[piece[branch[self.start[chosen]] | branch[self.end[chosen]]]] = True
        # a loop's segments are oriented either way, their sides named accordingly: orient them
        # all as the piece's first one
        first = np.full(count, -1)
        first[piece[::-1]] = np.arange(chosen.size)[::-1]
        sign = np.where(self.inner[chosen] == self.inner[chosen][first[piece]], 1.0, -1.0)
        by_piece = np.argsort(piece, kind="stable")
        bounds = np.searchsorted(piece[by_piece], np.arange(count + 1))
        return chosen, piece, count, np.flatnonzero(~open_piece), sign, by_piece, bounds

    def without_island(self, nodes, loop):
        """The network without the closed interface loop of segments ``loop``, the region inside
        it merged into the one around it; None when another part of the network lies inside the
        loop (its regions would need renaming)."""
        keep = np.ones(len(self.start), dtype=bool)
        keep[loop] = False
        uses = np.bincount(np.concatenate([self.start[keep], self.end[keep]]), minlength=len(nodes))
        return None if self.encloses(nodes, loop, uses) else self.subset(keep, nodes)

    def boxes_hold_nodes(self, nodes, loops, used, by_row):
        """For each closed loop of segments (indices), whether a node ``used`` lies strictly within
        its bounding box: where none does, the loop :meth:`encloses` none, whichever nodes stay in
        use.  ``by_row``: the node indices sorted by row."""
        if not loops:
            return np.zeros(0, dtype=bool)
        segment = np.concatenate(loops)
        firsts = np.concatenate([[0], np.cumsum([len(loop) for loop in loops])[:-1]])
        a, b = nodes[self.start[segment]], nodes[self.end[segment]]
        low = np.minimum.reduceat(np.minimum(a, b), firsts, axis=0)
        high = np.maximum.reduceat(np.maximum(a, b), firsts, axis=0)
        # the nodes within each box's rows, then those within its columns
        rows = nodes[by_row, 0]
        begin = np.searchsorted(rows, low[:, 0], side="right")
        counts = np.maximum(np.searchsorted(rows, high[:, 0], side="left") - begin, 0)
        owner = np.repeat(np.arange(len(loops)), counts)
        near = by_row[np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts - begin, counts)]
        within = used[near] & (nodes[near, 1] > low[owner, 1]) & (nodes[near, 1] < high[owner, 1])
        holds = np.zeros(len(loops), dtype=bool)
        holds[owner[within]] = True
        return holds

    def encloses(self, nodes, loop, uses, by_row=None):
        """Whether a node in use (``uses > 0``: an end of a segment kept) lies inside the closed
        loop of segments ``loop``, strictly within its bounding box.  ``by_row``: the node
        indices sorted by row, to find the box's nodes by bisection."""
        a, b = nodes[self.start[loop]], nodes[self.end[loop]]
        low, high = np.minimum(a, b).min(axis=0), np.maximum(a, b).max(axis=0)
        if by_row is None:
            near = np.flatnonzero(np.all((nodes > low) & (nodes < high), axis=1))
        else:
            rows = nodes[by_row, 0]
            near = by_row[np.searchsorted(rows, low[0], side="right"):
                          np.searchsorted(rows, high[0], side="left")]
            near = near[(nodes[near, 1] > low[1]) & (nodes[near, 1] < high[1])]
        near = nodes[near[uses[near] > 0]]
        if near.size == 0:
            return False
        # even-odd rule: crossings of the ray towards +c
        straddle = (a[None, :, 0] > near[:, None, 0]) != (b[None, :, 0] > near[:, None, 0])
        with np.errstate(divide="ignore", invalid="ignore"):
            at = a[None, :, 1] + (near[:, None, 0] - a[None, :, 0]) * (b[None, :, 1] - a[None, :, 1]) / (
                b[None, :, 0] - a[None, :, 0])
        return bool(np.any(np.count_nonzero(straddle & (at > near[:, None, 1]), axis=1) % 2))

    def subset(self, keep, nodes):
        """The network of the segments ``keep`` (bool), its nodes at ``nodes``."""
        return Network(nodes, self.start[keep], self.end[keep], self.inner[keep], self.outer[keep],
                       self.shape).inheriting(self, np.flatnonzero(keep))

    def without_loops(self, keep, nodes):
        """:meth:`subset` where the segments left out are whole closed loops (:meth:`closed_loops`),
        each enclosing no other part: its faces (:meth:`faces`) and interface pieces
        (:meth:`closed_areas`) are then the others', in the same order (each numbered by its
        smallest segment, and no other piece or face passes a loop's nodes), so they are carried
        over, not found again."""
        network = self.subset(keep, nodes)
        position = np.cumsum(keep) - 1  # a kept segment's index in ``network``
        if self._faces is not None:
            face, segment, sign = self._faces
            stays = keep[segment]
            network._faces = (_renumbered(face, stays), position[segment[stays]], sign[stays])
        if self._pieces is not None and self._pieces[0].size:
            chosen, piece, _, closed, sign = self._pieces[:5]
            stays = keep[chosen]
            if stays.any():
                kept = np.zeros(self._pieces[2], dtype=bool)
                kept[piece[stays]] = True
                piece = _renumbered(piece, stays)
                count = int(kept.sum())
                by_piece = np.argsort(piece, kind="stable")
                network._pieces = (position[chosen[stays]], piece, count,
                                   (np.cumsum(kept) - 1)[closed[kept[closed]]], sign[stays], by_piece,
                                   np.searchsorted(piece[by_piece], np.arange(count + 1)))
        return network

    def inheriting(self, network, position):
        """This network, to reuse ``network``'s orders of the free nodes (the H^1 system's band:
        :func:`activecontour.backends.network.h1.factorised`) and, at the same nodes, its
        segments' integrals (:meth:`shared_rows`): made from it by a change that moves no node and
        frees no other (:meth:`reconnected`, :meth:`collapsed`, :meth:`subset`: the nodes they
        leave out are dropped from the order), ``position`` the index in ``network`` of each
        segment (changed there or not).  Where ``network`` found no
        order of its own (it was never factored: a change on a change, as a pinch resolved and
        the islands then dropped), it passes on the one it inherited."""
        self._orders = dict(network._orders)
        self._orders.update({component: band[0] for component, band in network._bands.items()})
        self._origin = (weakref.ref(network), position)
        return self

    def swept(self, before, after):
        """The interfaces' mean normal displacement from ``before`` to ``after`` (px)."""
        a, b = self.start[self.interface], self.end[self.interface]
        before_a, before_b = before.take(a, axis=0), before.take(b, axis=0)
        tangent = before_b - before_a
        length = np.linalg.norm(tangent, axis=1)
        shift = 0.5 * ((after.take(a, axis=0) - before_a) + (after.take(b, axis=0) - before_b))
        normal = np.abs(shift[:, 0] * tangent[:, 1] - shift[:, 1] * tangent[:, 0])  # |shift . nu| h
        return float(normal.sum() / max(length.sum(), 1e-12))

    def simple(self, nodes):
        """No two interfaces cross: the interface segments meet only at their common nodes (no
        crossing, touch or overlap; compiled, on a uniform grid:
        :func:`activecontour._kernels.segments_meet`, O(S)).  A crossing would make an overlap of
        two regions, whose energy the functional would count with a negative area."""
        start, end = self._interface_ends
        return _kernels.segments_meet(np.ascontiguousarray(nodes, dtype=np.float64), start, end, True, 1,
                                      np.empty((0, 2), dtype=np.intp), _NO_WHERE) == 0

    def simple_after(self, parent, nodes):
        """:meth:`simple` for this network made from ``parent`` by a local change at ``nodes``
        (:meth:`reconnected`, :meth:`collapsed`: :meth:`inheriting`), where ``parent`` is simple:
        two interface segments that are both the parent's interface segments (the same ends in the
        same order) do not meet there, so only the pairs with one of the others are tested, among
        the segments whose boxes meet those others' box (:meth:`meet_among`).  The same answer as
        :meth:`simple`, at the cost of the change's neighbourhood."""
        chosen = np.flatnonzero(self.interface)
        origin = self._origin_of(parent, chosen)
        if origin is None:
            return self.simple(nodes)
        changed = chosen[(origin < 0) | ~parent.interface[origin]]
        if changed.size == 0:
            return True
        a, b = nodes.take(self.start[chosen], axis=0), nodes.take(self.end[chosen], axis=0)
        low, high = np.minimum(a, b), np.maximum(a, b)
        box_low = np.minimum(nodes[self.start[changed]], nodes[self.end[changed]]).min(axis=0)
        box_high = np.maximum(nodes[self.start[changed]], nodes[self.end[changed]]).max(axis=0)
        near = chosen[np.all((low <= box_high) & (high >= box_low), axis=1)]
        return not self.meet_among(nodes, near)


    def sides_hold_after(self, parent, nodes):
        """Whether each interface segment this network changed from ``parent`` (a local change:
        :meth:`inheriting`; every one where it was not made so) has its regions where it says:
        a probe just off its midpoint on either side lies within that region's boundary (winding
        number 1).  A change that makes no two interfaces meet (:meth:`simple_after`) can still
        leave a small loop turned inside out (the sides of a spike joined the other way, its tip
        folded back), whose regions' boundaries then wind 2 or -1 times around it."""
        chosen = np.flatnonzero(self.interface)
        origin = self._origin_of(parent, chosen)
        changed = chosen if origin is None else chosen[(origin < 0) | ~parent.interface[origin]]
        if changed.size == 0:
            return True
        a, b = nodes.take(self.start[changed], axis=0), nodes.take(self.end[changed], axis=0)
        step = b - a
        normal = np.stack([step[:, 1], -step[:, 0]], axis=1) / np.linalg.norm(step, axis=1)[:, None]
        middle, offset = 0.5 * (a + b), _PROBE * max(1.0, float(np.abs(nodes).max())) * normal
        probes = np.concatenate([middle - offset, middle + offset])
        regions = np.concatenate([self.inner[changed], self.outer[changed]])
        points = np.ascontiguousarray(nodes, dtype=np.float64)
        for region in np.unique(regions):
            forward, backward = self.inner == region, self.outer == region
            start = np.concatenate([self.start[forward], self.end[backward]])
            end = np.concatenate([self.end[forward], self.start[backward]])
            mine = np.ascontiguousarray(probes[regions == region])
            winding = np.empty(len(mine), dtype=np.int64)
            _kernels.winding_banded(points, as_indices(start), as_indices(end), mine, winding)
            if np.any(winding != 1):
                return False
        return True


def _renumbered(group, stays):
    """The groups ``group`` (dense ids) of the entries ``stays``, numbered afresh 0, 1, ... in
    their order: the groups left with no entry dropped."""
    kept = np.zeros(int(group.max()) + 1 if group.size else 0, dtype=bool)
    kept[group[stays]] = True
    return (np.cumsum(kept) - 1)[group[stays]]


def as_indices(array):
    """``array`` as a contiguous array of ``intp`` (what the compiled kernels take)."""
    return np.ascontiguousarray(array, dtype=np.intp)
