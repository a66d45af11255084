"""The velocity of a network's nodes: the book's H^1 problem (6.39)-(6.40) on the interfaces.

``b(V, Y) = -delta J(Y)`` with ``b`` the H^1 form ``(M + l^2 K)`` of P1 functions summed over the
interfaces (coupled at the junctions, a node on the image's border sliding along it), and
``delta J`` the shape derivative (6.41) summed at the nodes (:func:`nodal_force`).  The system is
factorised once per block of iterations (:func:`factorised`) in the reverse Cuthill-McKee order of
the network's graph, where it is a narrow band."""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.energy import partition_load

#: Half bandwidth above which :meth:`Network.factors` uses a sparse LU factorisation.
_BAND_LIMIT = 64


def stiffness(network, nodes, smoothing=1.0):
    """The matrix ``M + l^2 K`` of the H^1 form (6.39) of P1 functions on the interfaces."""
    import scipy.sparse

    a, b = network.start[network.interface], network.end[network.interface]
    h = np.linalg.norm(nodes[b] - nodes[a], axis=1)
    diagonal = h / 3.0 + smoothing**2 / h
    off = h / 6.0 - smoothing**2 / h
    rows = np.concatenate([a, b, a, b])
    cols = np.concatenate([a, b, b, a])
    size = len(nodes)
    return scipy.sparse.csc_matrix((np.concatenate([diagonal, diagonal, off, off]), (rows, cols)),
                                   shape=(size, size))


def factorised(network, nodes):
    """Cholesky factors of ``M + K`` (6.39) restricted to each component's free nodes, for
    :func:`velocity`.

    The matrix is symmetric positive definite and its graph is the network's: chains of nodes
    joined at junctions.  In the reverse Cuthill-McKee order of that graph (found once per
    network) it is a narrow band (about ten on scikit-image's pictures), so a banded Cholesky
    factorisation costs O(P bandwidth^2), without fill outside the band; a wider band falls
    back to a sparse LU factorisation.
    """
    from scipy.sparse.linalg import splu

    start, end = network._interface_ends
    nodes = np.ascontiguousarray(nodes, dtype=np.float64)
    factors = []
    for component in range(2):
        order, position, width = _band(network, component)
        size = len(order)
        if size == 0:
            factors.append((order, None))
            continue
        if width > _BAND_LIMIT:
            matrix = stiffness(network, nodes)
            factors.append((order, splu(matrix[order][:, order].tocsc())))
            continue
        band = np.zeros((size, width + 1))  # band[j, width + i - j] = A[i, j] for i <= j
        _kernels.h1_band(nodes, start, end, position, band)
        envelope = np.empty((size, 2), dtype=np.intp)
        if _kernels.band_cholesky(band, envelope) != 0:
            raise np.linalg.LinAlgError("the H^1 form is not positive definite")
        factors.append((order, (band, envelope)))
    return factors


def _band(network, component):
    """The free nodes of a component in reverse Cuthill-McKee order, each node's position in
    that order (-1: not free), and the half bandwidth of the matrix in it.  A network made
    from another by a local change (:meth:`Network.inheriting`) keeps that one's order of the nodes
    still free, unless the band got wider than ``_BAND_LIMIT``."""
    if component not in network._bands:
        free = network.free[component]
        index = np.flatnonzero(free)
        inherited = network._orders.get(component)
        order = None if inherited is None else inherited[free[inherited]]
        if order is None or order.size != index.size:
            order = _reverse_cuthill_mckee(network, index)
        position, width = _positions(network, order)
        if width > _BAND_LIMIT and inherited is not None:
            order = _reverse_cuthill_mckee(network, index)
            position, width = _positions(network, order)
        network._bands[component] = (order, position, width)
    return network._bands[component]


def _reverse_cuthill_mckee(network, index):
    """The nodes ``index`` in reverse Cuthill-McKee order of the graph of the interfaces."""
    import scipy.sparse
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    _, i, j = _interfaces_within(network, index)
    pairs = (np.concatenate([i, j]), np.concatenate([j, i]))
    graph = scipy.sparse.csr_matrix((np.ones(len(pairs[0])), pairs), shape=(index.size,) * 2)
    return index[reverse_cuthill_mckee(graph, symmetric_mode=True)] if index.size else index


def _positions(network, order):
    """Each node's position in ``order`` (-1: not in it), and the half bandwidth there."""
    position, i, j = _interfaces_within(network, order)
    return position, int(np.abs(i - j).max()) if i.size else 0


def _interfaces_within(network, index):
    """Each node's position in ``index`` (-1: not in it), and the positions of the two ends of
    every interface with both ends in it."""
    position = np.full(len(network.nodes), -1, dtype=np.intp)
    position[index] = np.arange(index.size)
    start, end = network._interface_ends
    i, j = position[start], position[end]
    inside = (i >= 0) & (j >= 0)
    return position, i[inside], j[inside]


def velocity(network, nodes, force, factors=None):
    """Solve ``b(V, Y) = -delta J(Y)`` (6.40) with the H^1 form for every free component.

    ``factors`` of :func:`factorised` at nearby nodes may be reused: the metric of a mesh whose
    edges changed a little is still an inner product, so V is still a descent direction
    (``delta J(V) = -b(V, V) < 0``, (6.27)).
    """
    factors = factorised(network, nodes) if factors is None else factors
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


def normal_part(network, nodes, velocity):
    """The velocity without its tangential part at the nodes inside an interface (degree two,
    off the border): moving along the curve changes the region only through the polygon's
    discretisation, and lets vertices bunch up."""
    start, end = network._interface_ends
    out = np.array(velocity, dtype=np.float64, order="C")
    # the normal (t_c, -t_r) of the sum of the two segments at each plain node
    _kernels.normal_part(np.ascontiguousarray(nodes, dtype=np.float64), out, start, end, network._plain)
    return out


def nodal_force(network, nodes, model, params, constants, parts=None):
    """``delta J`` with respect to every node (6.41): the segments' loads summed at their ends
    (``parts``: the integrals along :meth:`Network.moving_boundary` at these nodes, of
    :func:`activecontour.energy.partition_moments`); at the nodes held on the image's edge (which
    do not move) without the edge's segments there."""
    load = partition_load(model, network.moving_boundary(nodes), params, constants, parts)
    start, end = network._moving[:2]
    count = len(nodes)
    return np.column_stack([np.bincount(start, weights=load[:, 0, d], minlength=count)
                            + np.bincount(end, weights=load[:, 1, d], minlength=count)
                            for d in range(2)])
