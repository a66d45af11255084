"""The gradient flow (6.30)-(6.31) of a network's nodes: the line search, the convergence test,
the pinches resolved and the islands dropped, remeshing, and the result (the package's docstring,
:mod:`activecontour.backends.network`, gives the reasoning)."""

from __future__ import annotations

import numpy as np

import activecontour.backends.network.h1 as h1
from activecontour.backends.network.graph import Network
from activecontour.backends.network.steps import Steps
from activecontour.energy import energy_of_moments, evaluate_partition, partition_moments
from activecontour.geometry.partition import Boundary, loop_order
from activecontour.geometry.raster import rasterize
from activecontour.result import FlowState, SegmentationResult

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
    would be a degenerate contour of both, which no result may hold.  A loop's interface segments
    all have the same two sides, so leaving them out merges the sliver (about 1e-12 px^2) into the
    region around it and takes its length out of the length term; a loop along the image's edge
    (an interface lying on the edge's segment) gives its edge segments to that region, and one
    between two regions (a run of segments along each) leaves one run between them.  A sliver next
    to one merged already has new sides: it is read again from the network without the first
    (two slivers side by side both go), never from the sides it had."""
    keep, touched = np.ones(len(network.start), dtype=bool), np.zeros(len(network.start), dtype=bool)
    again = False
    inner, outer = network.inner.copy(), network.outer.copy()
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
        for loop in np.flatnonzero(area <= _SLIVER * np.maximum(1.0, perimeter) ** 2):
            members = segments[order[offsets[loop]:offsets[loop + 1]]]
            if touched[members].any():  # next to a sliver merged already: read it again
                again = True
                continue
            on_edge = ~network.interface[members]
            other = np.where(network.inner[members] == region, network.outer[members], network.inner[members])
            around = np.unique(other[~on_edge])
            if around.size == 1:
                touched[members] = True
                keep[members[~on_edge]] = False
                inner[members[on_edge]] = around[0]
            elif around.size == 2 and not on_edge.any() and np.count_nonzero(other != np.roll(other, 1)) == 2:
                # two runs, one along each region: the first run stays, between the two
                touched[members] = True
                kept, gone = members[other == around[0]], members[other == around[1]]
                keep[gone] = False
                inner[kept] = np.where(inner[kept] == region, around[1], inner[kept])
                outer[kept] = np.where(outer[kept] == region, around[1], outer[kept])
    if keep.all():
        return network
    merged = Network(nodes, network.start[keep], network.end[keep], inner[keep], outer[keep], network.shape)
    return _without_slivers(merged, nodes) if again else merged


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
        used, by_row, boxed = uses > 0, None, None
        # one at a time: a loop may hold another part until that is gone
        for k, loop in enumerate(candidates):
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
            if boxed is None:  # the nodes by row and the loops' boxes, once one lowers J
                by_row = np.argsort(nodes[:, 0])  # (equal rows in any order: a set of nodes is asked)
                boxed = network.boxes_hold_nodes(nodes, candidates, used, by_row)
            uses_without = uses.copy()
            np.subtract.at(uses_without, np.concatenate([network.start[loop], network.end[loop]]), 1)
            if not (boxed[k] and network.encloses(nodes, loop, uses_without, by_row)):
                keep[loop], uses, (areas, first, second) = False, uses_without, trial
                length, energy = length - loop_length, candidate.energy
        removed = not keep.all()
        network = network.without_loops(keep, nodes) if removed else network
        if not removed:
            return False
        current = self.evaluate(network, nodes)  # the same J, integrated afresh
        if current.energy > self.current.energy + 1e-9 * abs(self.current.energy):
            return False
        if current.energy < self.current.energy:
            self.energies.append(current.energy)
        self.network, self.current = network, current
        return True

    def resolve(self, crossed, pairs=None):
        """Resolve the pinch that held the step back, where the pairs of interface segments that
        meet in the trial ``crossed`` (:meth:`Network.meeting_pairs`) tell: join them the other
        way (:meth:`Network.reconnected`), or else make one node of the ends of each segment
        shorter than ``_TINY`` px at their nodes (:meth:`Network.collapsed`: a fold about a
        vanishing segment).  Either is made at the current nodes, the closed loops through the
        pairs' nodes then dropped where that lowers J (:meth:`drop_islands`), and kept if the
        network is still simple and J has not risen; else those loops alone are dropped where
        that lowers J (a region shrinking to nothing).  Returns whether the network changed."""
        network, nodes = self.network, self.nodes
        pairs = network.meeting_pairs(crossed) if pairs is None else pairs
        ends = np.unique(np.concatenate([network.start[pairs], network.end[pairs]], axis=None))
        at_ends = np.zeros(len(nodes), dtype=bool)
        at_ends[ends] = True
        near = np.flatnonzero(network.interface & (at_ends[network.start] | at_ends[network.end]))
        step = nodes.take(network.end[near], axis=0) - nodes.take(network.start[near], axis=0)
        lengths = np.linalg.norm(step, axis=1)
        for changed in (lambda: network.reconnected(pairs, nodes),
                        lambda: network.collapsed(near[lengths < _TINY], nodes)):
            candidate = changed()
            if (candidate is not None and candidate[0].simple_after(network, nodes)
                    and candidate[0].sides_hold_after(network, nodes) and self.replace(*candidate, ends)):
                return True
        return self.drop_islands(ends)

    def slide_on(self):
        """Merge the ends of the border segments shorter than ``_TINY`` px
        (:meth:`Network.border_merged`): a junction sliding along the image's edge has met a
        vertex of the edge or another junction, and the shrinking segment between them would
        cap every later step.  Each merge of two junctions is tried into either end; kept only if
        the network stays simple and J does not rise.  Returns whether the network changed."""
        network, nodes = self.network, self.nodes
        chosen = np.flatnonzero(~network.interface)
        step = nodes.take(network.end[chosen], axis=0) - nodes.take(network.start[chosen], axis=0)
        tiny = chosen[np.linalg.norm(step, axis=1) < _TINY]
        ends = np.unique(np.concatenate([network.start[tiny], network.end[tiny]]))
        for into_start in (True, False):
            candidate = network.border_merged(tiny, nodes, into_start)
            if candidate is None:
                return False
            if (candidate[0].simple_after(network, nodes) and candidate[0].sides_hold_after(network, nodes)
                    and self.replace(*candidate, ends)):
                return True
        return False

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
            force = h1.nodal_force(network, nodes, self.model, self.params, current.constants, current.parts)
            if factors is None:  # the metric of the block's first mesh, for the whole block
                factors = h1.factorised(network, nodes)
            velocity = h1.velocity(network, nodes, force, factors)
            normal = h1.normal_part(network, nodes, velocity)
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
            crossings, steps, pinched = [], Steps(network, nodes, velocity), None
            for _ in range(_BACKTRACKS):
                trial = nodes + dt * velocity
                if steps.admissible(dt, trial):
                    # the crossing test first: it costs a fraction of the energy's.  After a
                    # crossing, the segments that met are tested alone first: where two of them
                    # still meet, the shorter step crosses too, without a pass over the network
                    if pinched is not None and network.meet_among(trial, pinched):
                        crossings.append((dt, trial, None))
                    elif (pairs := network.meeting_pairs(trial)).size == 0:
                        candidate = self.evaluate(network, trial)
                        if candidate.energy <= current.energy + _ARMIJO * dt * slope:
                            break
                    else:
                        crossings.append((dt, trial, pairs))
                        pinched = np.unique(pairs)
                dt *= 0.5
            else:
                # a region folding over itself as the flow shrinks it: drop it and go on (the
                # first crossing trial that lowers J enough tells where)
                crossed = next((trial for step, trial, _ in crossings if self.evaluate(network, trial).energy
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
            if crossings and self.resolve(*crossings[-1][1:]):
                factors, dt_next, held = None, None, 0
            elif not crossings and 2 * dt > steps.reverse and self.slide_on():
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
