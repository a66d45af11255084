"""N regions on the polygon backend: the book's H^1 flow (6.39)-(6.40) on a network of curves.

The functional is the N-region form of (6.38) (:func:`activecontour.energy.evaluate_partition`):
``J = mu L + sum_k int_{Omega_k} g_k`` with L the interfaces, each counted once.

Why a network
-------------
The regions' boundaries are one planar graph: polylines between regions (interfaces) that meet at
junctions (three or four regions) and at the image border.  Each interface vertex is a P1 node of
one 1-D mesh, and a junction is a single node shared by the interfaces that meet there, so

* the partition stays a partition: no vacuum, no overlap, whatever the vertices do (a vertex moves
  the boundary of every region it touches);
* the energy is the exact N-region functional of the sub-pixel partition, each interface once;
* the velocity is the book's: ``b(V, Y) = -delta J(Y)`` (6.40) with the H^1 form (6.39) summed
  over every interface, ``(M + K) V = -f``, M and K assembled over the graph.  At a junction the
  weak form adds the shape derivatives of the interfaces that meet there (the natural condition:
  at a stationary junction the unit tangents weighted by mu balance, Young's law, 120 degrees for
  equal weights), and the solve couples them.  A node on the image border slides along it.
* an iteration costs O(boundary): the shape derivative (6.41) per interface is the edge integral
  of ``g_inner - g_outer`` on the image tables (:func:`activecontour.energy.partition_load`), the
  energy and constants are boundary integrals (Green), and M + K is a sparse matrix of the graph
  (a tridiagonal band per interface, coupled at the junctions), factorised once per iteration.

The alternatives were nested curves per class (Chung-Vese's multilayer model: one two-region
polygon per threshold, ``S_1 > S_2 > ...``), which charges an interface between classes k and m
``|k - m|`` times and leaves a sliver of every intermediate class along it (a halo around a bright
object on a dark background), and disjoint closed curves per region, whose coincident curves
must be kept from overlapping and gapping after every step.

Topology
--------
The network moves its vertices; its graph changes only where the flow pinches it (below).  The
topology comes first, from the
label field (:func:`activecontour.backends.labelfield.descend_labels`: the global K-means start, then
the exact descent with its merge and split moves, which create, remove and reconnect regions
freely).  Its partition (boundaries through the midpoints between pixels, junctions at cell
centres: :mod:`activecontour.geometry.partition`) is the network's start; the flow then moves every
interface and junction to sub-pixel position, lowering J from the label field's value.  So the
polygon backend's N-region result is the label field's topology with the polygon's geometry,
changed where the flow pinches it: a step held back because two interface segments would meet
(:meth:`_Flow.resolve`) joins them the other way when they bound the same two regions (a neck
or a finger's sides cut, a spike's tip dropped), or collapses a vanishing segment there, or drops
the closed loops through them; each is kept only if J does not rise.  A pinch between three
regions (a region thinning between two others, whose cut would make two junctions) is not
resolved: two steps in a row held back by such a pinch end the flow with status 5, a stall, not
convergence.

The step: dt by Armijo backtracking on J, at most the dt that moves the vertices ``max_step`` px
root-mean-square, the first trial where the parabola through the last step's J(0), slope and
J(dt) has its minimum (within half and twice that dt; that dt again after a step held back by a
crossing); a trial that reverses an interface segment, turns a face inside out, leaves the image
or makes two interfaces meet is halved (those tests cost a fraction of J's, and come first: every
iteration costs about one evaluation of J, whose boundary integrals also give the next force).
The H^1 system is solved by a banded Cholesky factorisation in the graph's reverse Cuthill-McKee
order, and crossings are found on a uniform grid: an iteration costs O(boundary), each of its
passes over the segments compiled (the integrals, the load, the normal part, the bounds of the
steps: :mod:`activecontour._kernels`).  The flow has converged when the interfaces' mean normal
displacement (the area they sweep over their length) between the start and the end of a block of
five iterations falls below ``tol`` px per iteration in two consecutive blocks.
"""

from __future__ import annotations

import weakref

import numpy as np

from activecontour import _kernels
from activecontour.energy import (
    energy_of_moments,
    evaluate_partition,
    partition_load,
    partition_moments,
)
from activecontour.geometry.partition import (
    Boundary,
    Sides,
    chain_loops,
    class_boundary,
    lattice_keys,
    loop_order,
)
from activecontour.geometry.raster import rasterize
from activecontour.result import FlowState, SegmentationResult

__all__ = ["Network", "segment_network"]

#: Root-mean-square vertex displacement of the first trial step (px).
_MAX_STEP = 0.25
#: Iterations per block of the convergence test.
_BLOCK = 5
#: Consecutive blocks below tol that make convergence: the flow's tail is linear, and one slow
#: block can be a pause (a 100x smaller tol then still lowered J by 0.1 % on noisy rings).
_STILL_BLOCKS = 2
#: Armijo's constant of the sufficient decrease.
_ARMIJO = 1e-4
#: Target length of the interfaces' segments (px), as the two-region polygon's default spacing.
_SPACING = 1.0
#: Closed loops enclosing less than this (px^2) are dropped when that does not raise J.
_ISLAND_AREA = 1.0
#: Consecutive steps held back by a pinch that cannot be resolved that end the flow (a stall).
_HELD = 2
#: Segments shorter than this (px) next to a pinch are collapsed to a node (:meth:`_Flow.resolve`).
_TINY = 0.05
#: Blocks before a remesh that raised J is tried again.
_REMESH_COOLDOWN = 4
#: Halvings of dt before the line search gives up (stationary to working precision).
_BACKTRACKS = 30
#: Half bandwidth above which :meth:`Network.factors` uses a sparse LU factorisation.
_BAND_LIMIT = 64
#: No crossing parameters: the network asks for pairs only (:func:`activecontour._kernels.segments_meet`).
_NO_WHERE = np.empty((0, 2))


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
            chosen = np.isin(face, which)
            face, segment, sign = np.searchsorted(which, face[chosen]), segment[chosen], sign[chosen]
            count = len(which)
        else:
            count = int(face.max()) + 1 if face.size else 0
        a, b = nodes[self.start[segment]], nodes[self.end[segment]]
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
        start, end = _indices(self.start[segments]), _indices(self.end[segments])
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

    def stiffness(self, nodes, smoothing=1.0):
        """The matrix ``M + l^2 K`` of the H^1 form (6.39) of P1 functions on the interfaces."""
        import scipy.sparse

        a, b = self.start[self.interface], self.end[self.interface]
        h = np.linalg.norm(nodes[b] - nodes[a], axis=1)
        diagonal = h / 3.0 + smoothing**2 / h
        off = h / 6.0 - smoothing**2 / h
        rows = np.concatenate([a, b, a, b])
        cols = np.concatenate([a, b, b, a])
        size = len(nodes)
        return scipy.sparse.csc_matrix((np.concatenate([diagonal, diagonal, off, off]), (rows, cols)),
                                       shape=(size, size))

    def factors(self, nodes):
        """Cholesky factors of ``M + K`` (6.39) restricted to each component's free nodes, for
        :meth:`velocity`.

        The matrix is symmetric positive definite and its graph is the network's: chains of nodes
        joined at junctions.  In the reverse Cuthill-McKee order of that graph (found once per
        network) it is a narrow band (about ten on scikit-image's pictures), so a banded Cholesky
        factorisation costs O(P bandwidth^2), without fill outside the band; a wider band falls
        back to a sparse LU factorisation.
        """
        from scipy.sparse.linalg import splu

        start, end = self._interface_ends
        nodes = np.ascontiguousarray(nodes, dtype=np.float64)
        factors = []
        for component in range(2):
            order, position, width = self._band(component)
            size = len(order)
            if size == 0:
                factors.append((order, None))
                continue
            if width > _BAND_LIMIT:
                matrix = self.stiffness(nodes)
                factors.append((order, splu(matrix[order][:, order].tocsc())))
                continue
            band = np.zeros((size, width + 1))  # band[j, width + i - j] = A[i, j] for i <= j
            _kernels.h1_band(nodes, start, end, position, band)
            envelope = np.empty((size, 2), dtype=np.intp)
            if _kernels.band_cholesky(band, envelope) != 0:
                raise np.linalg.LinAlgError("the H^1 form is not positive definite")
            factors.append((order, (band, envelope)))
        return factors

    def _band(self, component):
        """The free nodes of a component in reverse Cuthill-McKee order, each node's position in
        that order (-1: not free), and the half bandwidth of the matrix in it.  A network made
        from another by a local change (:meth:`inheriting`) keeps that one's order of the nodes
        still free, unless the band got wider than ``_BAND_LIMIT``."""
        if component not in self._bands:
            free = self.free[component]
            index = np.flatnonzero(free)
            inherited = self._orders.get(component)
            order = None if inherited is None else inherited[free[inherited]]
            if order is None or order.size != index.size:
                order = self._reverse_cuthill_mckee(index)
            position, width = self._positions(order)
            if width > _BAND_LIMIT and inherited is not None:
                order = self._reverse_cuthill_mckee(index)
                position, width = self._positions(order)
            self._bands[component] = (order, position, width)
        return self._bands[component]

    def inheriting(self, network, position):
        """This network, to reuse ``network``'s orders of the free nodes (:meth:`_band`) and, at
        the same nodes, its segments' integrals (:meth:`shared_rows`): made from it by a change
        that moves no node and frees no other (:meth:`reconnected`, :meth:`collapsed`,
        :meth:`subset`: the nodes they leave out are dropped from the order), ``position`` the
        index in ``network`` of each segment (changed there or not).  Where ``network`` found no
        order of its own (it was never factored: a change on a change, as a pinch resolved and
        the islands then dropped), it passes on the one it inherited."""
        self._orders = dict(network._orders)
        self._orders.update({component: band[0] for component, band in network._bands.items()})
        self._origin = (weakref.ref(network), position)
        return self

    def _reverse_cuthill_mckee(self, index):
        """The nodes ``index`` in reverse Cuthill-McKee order of the graph of the interfaces."""
        import scipy.sparse
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        _, i, j = self._interfaces_within(index)
        pairs = (np.concatenate([i, j]), np.concatenate([j, i]))
        graph = scipy.sparse.csr_matrix((np.ones(len(pairs[0])), pairs), shape=(index.size,) * 2)
        return index[reverse_cuthill_mckee(graph, symmetric_mode=True)] if index.size else index

    def _positions(self, order):
        """Each node's position in ``order`` (-1: not in it), and the half bandwidth there."""
        position, i, j = self._interfaces_within(order)
        return position, int(np.abs(i - j).max()) if i.size else 0

    def _interfaces_within(self, index):
        """Each node's position in ``index`` (-1: not in it), and the positions of the two ends of
        every interface with both ends in it."""
        position = np.full(len(self.nodes), -1, dtype=np.intp)
        position[index] = np.arange(index.size)
        start, end = self._interface_ends
        i, j = position[start], position[end]
        inside = (i >= 0) & (j >= 0)
        return position, i[inside], j[inside]

    def velocity(self, nodes, force, factors=None):
        """Solve ``b(V, Y) = -delta J(Y)`` (6.40) with the H^1 form for every free component.

        ``factors`` of :meth:`factors` at nearby nodes may be reused: the metric of a mesh whose
        edges changed a little is still an inner product, so V is still a descent direction
        (``delta J(V) = -b(V, V) < 0``, (6.27)).
        """
        factors = self.factors(nodes) if factors is None else factors
        velocity = np.zeros_like(nodes)
        for component, (order, factor) in enumerate(factors):
            if factor is None:
                continue
            rhs = -force[order, component]
            if isinstance(factor, tuple):  # a band and its envelope
                _kernels.band_solve(*factor, rhs)
            else:
                rhs = factor.solve(rhs)
            velocity[order, component] = rhs
        return velocity

    def normal_part(self, nodes, velocity):
        """The velocity without its tangential part at the nodes inside an interface (degree two,
        off the border): moving along the curve changes the region only through the polygon's
        discretisation, and lets vertices bunch up."""
        start, end = self._interface_ends
        out = np.array(velocity, dtype=np.float64, order="C")
        # the normal (t_c, -t_r) of the sum of the two segments at each plain node
        _kernels.normal_part(np.ascontiguousarray(nodes, dtype=np.float64), out, start, end, self._plain)
        return out

    def force(self, nodes, model, params, constants, parts=None):
        """``delta J`` with respect to every node (6.41): the segments' loads summed at their ends
        (``parts``: the integrals along :meth:`moving_boundary` at these nodes, of
        :func:`activecontour.energy.partition_moments`); at the nodes held on the image's edge (which
        do not move) without the edge's segments there."""
        load = partition_load(model, self.moving_boundary(nodes), params, constants, parts)
        start, end = self._moving[:2]
        count = len(nodes)
        return np.column_stack([np.bincount(start, weights=load[:, 0, d], minlength=count)
                                + np.bincount(end, weights=load[:, 1, d], minlength=count)
                                for d in range(2)])

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

    def steps(self, nodes, velocity):
        """The admissibility of the steps ``nodes + dt velocity`` of one iteration, for any dt
        (:class:`_Steps`)."""
        return _Steps(self, nodes, velocity)


class _Steps:
    """Which steps ``X + dt V`` keep a network a partition of the image (cheap tests before the
    energy; :meth:`Network.simple` is the exact one): no segment reversed or collapsed (its new
    direction keeps a quarter of its length along the old one), every vertex in the image
    domain, and no face turned inside out (each face's signed area keeps its sign, :meth:`Network.faces`).

    The first two are bounds on dt, found once for the iteration (a segment's projection on its
    old direction and a vertex's coordinates are linear in dt).  A face's area can change sign
    only where it is small: with every vertex moved by at most ``delta``, a polygon's area changes
    by at most ``delta L + n delta^2 / 2`` (L its perimeter, n its vertex count: expand the
    shoelace sum), so only the faces under that bound are measured at a trial.
    """

    #: relative margin within which a bound is checked on the trial itself (rounding)
    _MARGIN = 1e-6

    def __init__(self, network, nodes, velocity):
        face, segment, sign = network.faces()
        self.network, self.nodes = network, nodes
        self.count = network.face_counts
        # per face: the signed area (as face_areas), the perimeter, the fastest vertex's speed;
        # and the bounds on dt, in one compiled pass
        self.areas, self.perimeter, self.speed = (np.empty(len(self.count)) for _ in range(3))
        m, n = network.shape
        self.reverse, self.inside = _kernels.step_bounds(
            np.ascontiguousarray(nodes, dtype=np.float64), np.ascontiguousarray(velocity, dtype=np.float64),
            _indices(network.start), _indices(network.end), face, segment, sign, m - 0.5, n - 0.5,
            self.areas, self.perimeter, self.speed)
        self.orientation = np.sign(self.areas)

    def admissible(self, dt, trial):
        """Whether the step of ``dt`` to ``trial`` keeps the network a partition (the class's
        docstring)."""
        if not (dt < self.reverse and dt <= self.inside):
            return False
        if dt >= (1 - self._MARGIN) * min(self.reverse, self.inside):  # at a bound: the trial itself
            network, start, end = self.network, self.network.start, self.network.end
            old, new = self.nodes[end] - self.nodes[start], trial[end] - trial[start]
            m, n = network.shape
            if not (np.all(np.einsum("ij,ij->i", old, new) > 0.25 * np.einsum("ij,ij->i", old, old))
                    and np.all((trial >= -0.5) & (trial <= np.array([m - 0.5, n - 0.5])))):
                return False
        delta = dt * self.speed
        bound = delta * self.perimeter + 0.5 * self.count * delta**2
        risky = np.flatnonzero(np.abs(self.areas) <= (1 + self._MARGIN) * bound)
        if risky.size == 0:
            return True
        return bool(np.all(np.sign(self.network.face_areas(trial, risky)) == self.orientation[risky]))


def segment_network(model, init, params, *, n_regions, max_num_iter, tol, callback):
    """Minimise the N-region functional with the H^1 flow of the partition's boundary network.

    Parameters
    ----------
    model : ImageModel
    init : None, int ndarray (M, N), or SegmentationResult
        As for :func:`activecontour.backends.labelfield.segment_labels`, whose descent finds the topology.
    params : ChanVeseParameters
    n_regions : int
    max_num_iter : int
        Iterations of the label field, and of the flow.
    tol : float
        Pixels per iteration (module docstring).
    callback : callable or None
        Called with a :class:`~activecontour.result.FlowState` after every iteration (the label
        field's, then the flow's); return True to stop.

    Returns
    -------
    SegmentationResult
        ``backend="polygon"``; ``classes`` are the pixels whose centre lies in each region,
        ``class_contours`` the sub-pixel regions, ``energy`` their functional.
    """
    from activecontour.backends.labelfield import descend_labels

    start = descend_labels(model, init, params, n_regions=n_regions, max_num_iter=max_num_iter,
                           tol=tol, callback=callback)
    network = Network.of_boundary(start.boundary, start.classes.shape)
    energies = list(start.energies)
    if start.status == 2:
        return _result(model, params, network, network.nodes, n_regions, energies, start.n_iter, 2)
    flow = _Flow(network, model, params, n_regions, energies)
    status, n_iter = flow.run(max_num_iter, tol, callback, start.n_iter)
    network = _without_slivers(flow.network, flow.nodes)
    return _result(model, params, network, flow.nodes, n_regions, flow.energies, n_iter, status)


#: A region's loop is a sliver, no region, when it encloses at most this times the square of its
#: length (the common evaluator refuses a curve under 1e-12 of it as degenerate).
_SLIVER = 1e-9


def _without_slivers(network, nodes):
    """The network without the loops of region boundary that enclose no area (``_SLIVER``): three
    nearly collinear nodes that the last step left between two regions, through a pinch node,
    would be a degenerate contour of both, which no result may hold.  A loop's segments all have
    the same two sides, so leaving them out merges the sliver (about 1e-12 px^2) into the region
    around it and takes its length out of the length term."""
    keep = np.ones(len(network.start), dtype=bool)
    n_regions = int(max(network.inner.max(), network.outer.max())) + 1
    for region in range(n_regions):
        forward = np.flatnonzero((network.inner == region) & (network.outer != region))
        backward = np.flatnonzero((network.outer == region) & (network.inner != region))
        segments = np.concatenate([forward, backward])
        starts = np.concatenate([network.start[forward], network.end[backward]])
        ends = np.concatenate([network.end[forward], network.start[backward]])
        order, offsets = loop_order(starts, ends, len(nodes))
        if len(offsets) < 2:
            continue
        # every loop's area and length at once (sums in each loop's order)
        a, b = nodes.take(starts[order], axis=0), nodes.take(ends[order], axis=0)
        firsts = offsets[:-1]
        area = 0.5 * np.abs(np.add.reduceat(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1], firsts))
        perimeter = np.add.reduceat(np.hypot(*(b - a).T), firsts)
        sliver = np.repeat(area <= _SLIVER * np.maximum(1.0, perimeter) ** 2, np.diff(offsets))
        keep[segments[order[sliver]]] = False
    return network if keep.all() else network.subset(keep, nodes)


class _Flow:
    """The gradient flow (6.30)-(6.31) of a network's nodes, remeshed to ``_SPACING`` px."""

    def __init__(self, network, model, params, n_regions, energies):
        self.model, self.params, self.n_regions = model, params, n_regions
        self.network, self.nodes, self.energies = network, network.nodes.copy(), energies
        self.current = self.evaluate(network, self.nodes)
        self.remesh()

    def evaluate(self, network, nodes):
        """J at the nodes, with the segments' integrals that make the force there.  A network made
        from the current one by a local change, at the current nodes, takes the integrals of the
        segments they share from the current evaluation (:meth:`Network.shared_rows`): the same
        numbers, at the cost of the changed segments and one pass of additions."""
        boundary = network.moving_boundary(nodes)
        rows = network.shared_rows(self.network) if nodes is self.nodes else None
        return evaluate_partition(self.model, boundary, self.params, self.n_regions, parts=True,
                                  known=None if rows is None else (rows, self.current))

    def remesh(self):
        """Resample the interfaces at ``_SPACING`` px; kept only if J does not rise (else not
        tried again for ``_REMESH_COOLDOWN`` blocks)."""
        self.cooldown = _REMESH_COOLDOWN
        network, nodes = self.network.resampled(self.nodes, _SPACING)
        trial = self.evaluate(network, nodes)
        if trial.energy <= self.current.energy and network.simple(nodes):
            if trial.energy < self.current.energy:
                self.energies.append(trial.energy)
            self.network, self.nodes, self.current = network, nodes, trial

    def drop_islands(self, nodes_of_interest=None):
        """Remove the closed loops (islands, holes) that enclose less than ``_ISLAND_AREA`` px^2,
        or, given ``nodes_of_interest``, the loops through them, one at a time, each only if J
        does not rise: the network cannot change its topology by moving, so a region the flow
        shrinks to nothing would otherwise fold over itself.  Returns whether any was removed."""
        network, nodes = self.network, self.nodes
        interest = None
        if nodes_of_interest is not None:
            interest = np.zeros(len(nodes), dtype=bool)
            interest[nodes_of_interest] = True
        areas, through = network.closed_areas(nodes, interest)
        chosen = areas < _ISLAND_AREA if interest is None else through
        candidates = [network.loop_segments(k) for k in np.flatnonzero(chosen)]
        if not candidates:
            return False
        # J after a removal from the regions' moments: the island's (Green's theorem on its loop)
        # move from the region inside to the one around it, and its loop leaves the length.  The
        # islands' moments in one pass, each loop's segments oriented as its first one and
        # counted for its own label (1 + its index; 0 the unused background)
        sizes = np.array([len(loop) for loop in candidates])
        segments, owner = np.concatenate(candidates), np.repeat(np.arange(len(candidates)), sizes)
        flip = network.inner[segments] != network.inner[[loop[0] for loop in candidates]][owner]
        starts = np.where(flip[:, None], nodes[network.end[segments]], nodes[network.start[segments]])
        ends = np.where(flip[:, None], nodes[network.start[segments]], nodes[network.end[segments]])
        islands = partition_moments(self.model, Boundary(starts, ends, owner + 1, np.full(len(owner), -1)),
                                    len(candidates) + 1)
        loop_lengths = np.bincount(owner, weights=np.hypot(*(ends - starts).T), minlength=len(candidates))
        areas, first, second = self.current.areas, self.current.first, self.current.second
        length, energy = self.current.length, self.current.energy
        keep = np.ones(len(network.start), dtype=bool)
        uses = np.bincount(np.concatenate([network.start, network.end]), minlength=len(nodes))
        by_row = np.argsort(nodes[:, 0], kind="stable")
        boxed = network.boxes_hold_nodes(nodes, candidates, uses > 0, by_row)
        # one at a time: a loop may hold another part until that is gone
        for k, (loop, holds) in enumerate(zip(candidates, boxed, strict=True)):
            area, moment_1, moment_2 = (part[k + 1] for part in islands)
            sides = (network.inner[loop[0]], network.outer[loop[0]])
            inside, around = sides if area > 0 else sides[::-1]
            sign = 1.0 if area > 0 else -1.0
            trial = [part.copy() for part in (areas, first, second)]
            for part, island in zip(trial, (area, moment_1, moment_2), strict=True):
                part[inside] -= sign * island
                part[around] += sign * island
            loop_length = loop_lengths[k]
            candidate = energy_of_moments(self.model, self.params, *trial, length - loop_length)
            if candidate.energy > energy:
                continue
            # J first: most candidates stay because removing them would raise it
            uses_without = uses.copy()
            np.subtract.at(uses_without, np.concatenate([network.start[loop], network.end[loop]]), 1)
            if not (holds and network.encloses(nodes, loop, uses_without, by_row)):
                keep[loop], uses, (areas, first, second) = False, uses_without, trial
                length, energy = length - loop_length, candidate.energy
        removed = not keep.all()
        network = network.subset(keep, nodes) if removed else network
        if not removed:
            return False
        current = self.evaluate(network, nodes)  # the same J, integrated afresh
        if current.energy > self.current.energy + 1e-9 * abs(self.current.energy):
            return False
        if current.energy < self.current.energy:
            self.energies.append(current.energy)
        self.network, self.current = network, current
        return True

    def resolve(self, crossed):
        """Resolve the pinch that held the step back, where the pairs of interface segments that
        meet in the trial ``crossed`` (:meth:`Network.meeting_pairs`) tell: join them the other
        way (:meth:`Network.reconnected`), or else make one node of the ends of each segment
        shorter than ``_TINY`` px at their nodes (:meth:`Network.collapsed`: a fold about a
        vanishing segment).  Either is made at the current nodes, the closed loops through the
        pairs' nodes then dropped where that lowers J (:meth:`drop_islands`), and kept if the
        network is still simple and J has not risen; else those loops alone are dropped where
        that lowers J (a region shrinking to nothing).  Returns whether the network changed."""
        network, nodes = self.network, self.nodes
        pairs = network.meeting_pairs(crossed)
        ends = np.unique(np.concatenate([network.start[pairs], network.end[pairs]], axis=None))
        near = network.interface & (np.isin(network.start, ends) | np.isin(network.end, ends))
        lengths = np.linalg.norm(nodes.take(network.end, axis=0) - nodes.take(network.start, axis=0), axis=1)
        for changed in (lambda: network.reconnected(pairs, nodes),
                        lambda: network.collapsed(np.flatnonzero(near & (lengths < _TINY)), nodes)):
            candidate = changed()
            if (candidate is not None and candidate[0].simple_after(network, nodes)
                    and self.replace(*candidate, ends)):
                return True
        return self.drop_islands(ends)

    def replace(self, network, nodes, ends):
        """Take ``network`` at ``nodes``, the closed loops through ``ends`` dropped where that
        lowers J, if J does not rise.  Returns whether it was taken."""
        previous, current, count = (self.network, self.nodes), self.current, len(self.energies)
        self.network, self.nodes, self.current = network, nodes, self.evaluate(network, nodes)
        self.drop_islands(ends)
        if self.current.energy > current.energy:
            (self.network, self.nodes), self.current = previous, current
            del self.energies[count:]
            return False
        if self.current.energy < current.energy and len(self.energies) == count:
            self.energies.append(self.current.energy)
        return True

    def unhealthy(self):
        network, nodes = self.network, self.nodes
        chosen = network.interface
        step = nodes.take(network.end[chosen], axis=0) - nodes.take(network.start[chosen], axis=0)
        lengths = np.linalg.norm(step, axis=1)
        return lengths.size and (lengths.min() < 0.5 * _SPACING or lengths.max() > 2.0 * _SPACING)

    def run(self, max_num_iter, tol, callback, n_iter):
        """Returns the status (0 converged, 1 out of iterations, 2 callback, 4 no descent step, 5 a
        stall at a pinch that cannot be resolved) and the iteration count."""
        dt_next, block_start, block_network, still, held = None, self.nodes, self.network, 0, 0
        factors = None
        for iteration in range(1, max_num_iter + 1):
            network, nodes, current = self.network, self.nodes, self.current
            force = network.force(nodes, self.model, self.params, current.constants, current.parts)
            if factors is None:  # the metric of the block's first mesh, for the whole block
                factors = network.factors(nodes)
            velocity = network.velocity(nodes, force, factors)
            normal = network.normal_part(nodes, velocity)
            if np.sum(force * normal) < 0:  # still a descent direction (it nearly always is)
                velocity = normal
            slope = float(np.sum(force * velocity))
            moving = network.free[0] | network.free[1]
            if not moving.any():  # no interface left inside the image: nothing can move
                return 0, n_iter
            spread = np.sqrt(np.mean(np.sum(velocity[moving] ** 2, axis=1)))
            if not spread > 0 or slope >= 0:
                return 4, n_iter
            dt = _MAX_STEP / spread if dt_next is None else min(dt_next, _MAX_STEP / spread)
            crossings, steps, pinched = [], network.steps(nodes, velocity), None
            for _ in range(_BACKTRACKS):
                trial = nodes + dt * velocity
                if steps.admissible(dt, trial):
                    # the crossing test first: it costs a fraction of the energy's.  After a
                    # crossing, the segments that met are tested alone first: where two of them
                    # still meet, the shorter step crosses too, without a pass over the network
                    if pinched is not None and network.meet_among(trial, pinched):
                        crossings.append((dt, trial))
                    elif (pairs := network.meeting_pairs(trial)).size == 0:
                        candidate = self.evaluate(network, trial)
                        if candidate.energy <= current.energy + _ARMIJO * dt * slope:
                            break
                    else:
                        crossings.append((dt, trial))
                        pinched = np.unique(pairs)
                dt *= 0.5
            else:
                # a region folding over itself as the flow shrinks it: drop it and go on (the
                # first crossing trial that lowers J enough tells where)
                crossed = next((trial for step, trial in crossings if self.evaluate(network, trial).energy
                                <= current.energy + _ARMIJO * step * slope), None)
                if crossed is not None and self.drop_islands(network.crossing_nodes(crossed)):
                    factors, dt_next = None, None
                    continue
                return 4, n_iter
            ratio = (candidate.energy - current.energy) / (dt * slope)
            dt_next = dt if crossings else dt * _step_factor(ratio)
            self.nodes, self.current = trial, candidate
            n_iter += 1
            self.energies.append(candidate.energy)
            if crossings and self.resolve(crossings[-1][1]):
                factors, dt_next, held = None, None, 0
            else:
                held = held + 1 if crossings else 0
            if callback is not None and callback(_state(network, trial, candidate, n_iter, max_num_iter)):
                return 2, n_iter
            if held == _HELD:  # a stall: each step held back by a pinch that cannot be resolved
                return 5, n_iter
            if iteration % _BLOCK == 0:
                slow = block_network is network and network.swept(block_start, trial) / _BLOCK < tol
                still = still + 1 if slow else 0
                if still == _STILL_BLOCKS:
                    return 0, n_iter
                self.cooldown -= 1
                self.drop_islands()
                if self.cooldown <= 0 and self.unhealthy():
                    self.remesh()
                block_start, block_network, factors = self.nodes, self.network, None
        return 1, n_iter


def _indices(array):
    return np.ascontiguousarray(array, dtype=np.intp)


def _step_factor(ratio):
    """The next iteration's first dt over this one's accepted dt, from the decrease of J there
    against the linear one, ``ratio = (J(dt) - J(0)) / (dt delta J(V))``: along the parabola
    through J(0), its slope and J(dt), the minimum lies at ``dt / (2 (1 - ratio))``; kept within
    [1/2, 2] (the direction changes from one iteration to the next)."""
    return min(2.0, max(0.5, 0.5 / max(1.0 - ratio, 1e-3)))


def _state(network, nodes, evaluation, n_iter, max_num_iter):
    moved = Network(nodes, network.start, network.end, network.inner, network.outer, network.shape)
    inside = np.arange(len(evaluation.areas)) > 0
    c_in, c_out = _inside_constants(evaluation)
    return FlowState(n_iter, moved.region_curves(inside), evaluation.energy, c_in, c_out,
                     network.shape, max_num_iter)


def _inside_constants(evaluation):
    """``(c_in, c_out)``: the area-weighted mean of the non-background regions' constants, and the
    background's."""
    areas, constants = evaluation.areas, evaluation.constants
    inside = areas[1:].sum()
    c_in = (areas[1:, None] * constants[1:]).sum(axis=0) / inside if inside > 0 else constants[0]
    return c_in, constants[0]


def _result(model, params, network, nodes, n_regions, energies, n_iter, status):
    """The result of the moved network: regions renamed by the rule of
    :func:`activecontour.backends.labelfield.order_classes` (their order can change as they move)."""
    moved = Network(nodes, network.start, network.end, network.inner, network.outer, network.shape)
    final = evaluate_partition(model, moved.boundary(), params, n_regions)
    border = ~moved.interface
    lengths = np.linalg.norm(nodes[moved.end] - nodes[moved.start], axis=1)
    on_border = np.bincount(moved.inner[border], weights=lengths[border], minlength=n_regions)
    background = int(np.argmax(on_border))
    gray = final.constants.mean(axis=1)
    others = [k for k in np.argsort(gray, kind="stable") if k != background]
    mapping = np.empty(n_regions, dtype=np.intp)
    mapping[[background] + others] = np.arange(n_regions)
    if np.any(mapping != np.arange(n_regions)):
        moved = moved.relabelled(mapping)
        final = evaluate_partition(model, moved.boundary(), params, n_regions)
    energies = list(energies)
    energies[-1] = final.energy
    shape = network.shape
    class_contours = [moved.region_curves(np.arange(n_regions) == k) for k in range(n_regions)]
    classes = np.zeros(shape, dtype=np.int32)
    for k in range(1, n_regions):
        classes[rasterize(class_contours[k], shape)] = k
    contours = moved.region_curves(np.arange(n_regions) > 0)
    mask = rasterize(contours, shape)
    c_in, c_out = _inside_constants(final)
    return SegmentationResult(mask=mask, contours=contours, c_in=c_in, c_out=c_out,
                              energy=final.energy, energies=energies, n_iter=n_iter,
                              status=3 if not mask.any() else status, backend="polygon",
                              classes=classes, constants=final.constants,
                              class_contours=class_contours)
