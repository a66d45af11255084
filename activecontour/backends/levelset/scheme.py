"""The scheme: the energy of an iterate, the force f of (6.41), the steps (a) and (b), the swept area."""

from __future__ import annotations

import numpy as np
import scipy.fft

from activecontour.backends.levelset.redistancing import _redistance
from activecontour.backends.levelset.zeroset import zero_set_edges
from activecontour.energy import evaluate


def heaviside(phi, epsilon=1.0):
    """The cosine-regularised Heaviside ``H_eps``: 0 below -eps, 1 above eps, smooth between."""
    s = np.asarray(phi, dtype=np.float64) / epsilon
    ramp = 0.5 * (1.0 + s + np.sin(np.pi * np.clip(s, -1.0, 1.0)) / np.pi)
    return np.where(s >= 1.0, 1.0, np.where(s <= -1.0, 0.0, ramp))


class _Problem:
    """Image, parameters and the pieces of the energy, the force f and the operator S."""

    def __init__(self, model, params, settings):
        self.model = model
        self.shape = tuple(model.shape)
        self.n_channels = model.n_channels
        self.values = model.values
        self.params = params
        self.band = settings["band"]
        m, n = self.shape
        stride = max(1, int(np.sqrt(m * n / 2.0**16)))
        self.sample = (slice(stride // 2, None, stride), slice(stride // 2, None, stride))
        # eigenvalues of -Laplace (5-point, Neumann) in the DCT-II basis
        wave_r = 4.0 * np.sin(np.pi * np.arange(m) / (2.0 * m)) ** 2
        wave_c = 4.0 * np.sin(np.pi * np.arange(n) / (2.0 * n)) ** 2
        self.laplace_symbol = (wave_r[:, None] + wave_c[None, :]).astype(np.float32)

    def redistance(self, phi):
        return _redistance(phi, self.band)

    def evaluate(self, state):
        """(6.38) of the zero level set by the common evaluator, as an ``Evaluation``.

        The zero set is the segment soup of :func:`zero_set_edges`: the returned contours, closed
        along the domain edge.  An empty region has the evaluator's value for the empty set.
        """
        points = zero_set_edges(state.phi).reshape(-1, 2)
        next_index = np.repeat(np.arange(1, len(points), 2), 2)  # start -> end -> itself
        return evaluate(self.model, points, next_index, self.params, empty_ok=True)

    def force(self, c_in, c_out):
        """f of (6.41) per pixel and its contrast scale.

        ``f = g_i - g_o`` (the model's :meth:`~ChanVeseParameters.load_form`; for (6.38)
        ``omega + lambda_in mean (I - c_in)^2 - lambda_out mean (I - c_out)^2``), plus ``mu`` per
        side of the image that a pixel lies on: a region that covers a border pixel closes along
        the domain edge there, and the evaluator counts that length (the wall term).  The scale
        is the mean ``|f|`` over the pixels (a regular sample of about 2^16 of them): about
        ``|c_in - c_out|^2`` once the regions have settled, the size of the force of every pixel
        before that (a checkerboard start, where ``c_in ~ c_out``).  Time steps are measured in
        pixels of travel at that force.
        """
        p = self.params
        c_in = np.nan_to_num(np.asarray(c_in, dtype=np.float64))
        c_out = np.nan_to_num(np.asarray(c_out, dtype=np.float64))
        f = p.load_form(c_in, c_out).density(self.values)
        if p.mu > 0:
            for edge in (f[0], f[-1], f[:, 0], f[:, -1]):
                edge += p.mu
        return f, max(float(np.mean(np.abs(f[self.sample]))), 1e-12)

    def time_step(self, step, scale):
        """tau for a step of ``step`` pixels at the force ``scale``: ``step / scale``.

        A front at a pixel of typical force moves ``step`` pixels.  The smoothing length
        ``sqrt(tau mu)`` of S is kept below ``step``: that binds where the force is weak against
        the length term (a checkerboard start, whose constants hardly differ), where S would
        otherwise flatten phi over the whole image at once.
        """
        tau = step / scale
        return min(tau, step * step / self.params.mu) if self.params.mu > 0 else tau

    def step(self, state, force, tau, smooth_force):
        """Step (a) ``S (phi - tau f)`` with ``smooth_force``, else (b) ``S phi - tau f``.

        ``S = (1 - tau mu Laplace)^{-1}`` by DCT-II in float32 (phi is a distance of a few pixels:
        its rounding, ~1e-6 px, is far below what matters).  In step (b) the force acts within the
        band only, so that no pixel far from Gamma (at +-band) flips on its own; and when
        ``tau mu <= 1/4`` the explicit step ``phi + tau mu Laplace(phi) - tau f`` is stable and has
        the same fixed point, so it is taken on the band's pixels alone (O(band) instead of a DCT
        pair over the image).
        """
        if not smooth_force and tau * self.params.mu <= 0.25:
            return self._explicit_step(state, force, tau)
        phi = state.phi
        rhs = (phi - tau * force if smooth_force else phi).astype(np.float32)
        if self.params.mu > 0:
            spectrum = scipy.fft.dctn(rhs, norm="ortho")
            spectrum /= 1.0 + np.float32(tau * self.params.mu) * self.laplace_symbol
            rhs = scipy.fft.idctn(spectrum, norm="ortho")
        out = rhs.astype(np.float64)
        if not smooth_force:
            near = np.abs(phi) < self.band
            out[near] -= tau * force[near]
        return out

    def _explicit_step(self, state, force, tau):
        """``phi + tau mu Laplace(phi) - tau f`` on the band (5-point, Neumann: a mirrored pixel)."""
        m, n = self.shape
        flat = state.near_flat
        values = state.phi.ravel()
        centre = values[flat]
        row, col = np.divmod(flat, n)
        laplace = (values[np.where(row > 0, flat - n, flat)] + values[np.where(row < m - 1, flat + n, flat)]
                   + values[np.where(col > 0, flat - 1, flat)] + values[np.where(col < n - 1, flat + 1, flat)]
                   - 4.0 * centre)
        moved = centre + (tau * self.params.mu) * laplace
        near = np.abs(centre) < self.band
        moved[near] -= tau * force.ravel()[flat[near]]
        out = state.phi.copy()
        out.ravel()[flat] = moved
        return out


def _swept_area(old, new):
    """Area between the zero sets of two redistanced states, ``sum_px |H_eps(new) - H_eps(old)|``.

    With eps = 1 the integer translates of H_eps sum to the exact length of a half-line (module
    docstring), so this is the exact area between two parallel straight fronts at any sub-pixel
    offset, and second-order accurate for curved ones.  Only pixels in either band can differ.
    """
    if old.near_flat.size == 0 or new.near_flat.size == 0:
        return float(np.count_nonzero(old.positive != new.positive))
    seen = np.zeros(old.phi.size, dtype=bool)  # each band holds its pixels once: mark, not sort
    seen[old.near_flat] = True
    flat = np.concatenate([old.near_flat, new.near_flat[~seen[new.near_flat]]])
    return float(np.sum(np.abs(heaviside(new.phi.ravel()[flat]) - heaviside(old.phi.ravel()[flat]))))
