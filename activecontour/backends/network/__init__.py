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
the closed loops through them; each is kept only if J does not rise, no two interfaces meet and
every changed segment has its regions where it says.  A junction sliding along the image's edge
slides on: the edge's segment it shrinks (every pixel has a vertex on the edge) is merged away
when it is shorter than a step can shrink it, and two junctions that meet there become one (a
triangle of region left between them goes), else the shrinking segment would cap every step and
the flow would stop as if converged.  A pinch between three
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

from activecontour.backends.network.flow import segment_network
from activecontour.backends.network.graph import Network

__all__ = ["Network", "segment_network"]
