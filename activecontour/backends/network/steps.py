"""Which steps of a network's nodes keep it a partition of the image, tested before the energy
(:class:`Steps`)."""

from __future__ import annotations

import numpy as np

from activecontour import _kernels
from activecontour.backends.network.graph import as_indices


class Steps:
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
            as_indices(network.start), as_indices(network.end), face, segment, sign, m - 0.5, n - 0.5,
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
