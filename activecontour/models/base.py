"""The one form every region's integrand takes, and what a model provides.

A model of the image assigns each region k of a partition an integrand ``g_k(x)`` (the fitting
term of (6.38), plus the area weight omega where it applies), so that

    J = mu |interfaces| + sum_k int_{Omega_k} g_k(x) dx.

Every model here writes ``g_k`` as a *diagonal quadratic form* in the model's feature channels
``v(x) = (v_1(x), ..., v_C(x))`` (the image's channels for the constant fit (6.42); the image, a
smooth light field b and their sum for the smooth fit):

    g_k(v) = a_k + sum_c l_kc v_c + sum_c q_kc v_c^2.

That one form is what every consumer reads, so an energy is written once:

* the common evaluator integrates it from the region moments ``int 1, int v_c, int v_c^2``
  (:meth:`QuadraticForm.integral`), which Green's theorem turns into boundary integrals;
* the compiled edge integrals (:func:`activecontour._kernels.edge_integrals`) take the difference
  ``g_i - g_o`` of the two regions on either side of a curve, the integrand of (6.41);
* the level set's force, the topological derivative (nucleation) and the label-field scheme of the
  N-region model evaluate it on pixels (:meth:`QuadraticForm.density`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["QuadraticForm"]


@dataclass(frozen=True)
class QuadraticForm:
    """``g(v) = constant + linear . v + square . v^2`` of one region (or a difference of two).

    Attributes
    ----------
    constant : float
    linear, square : ndarray (C,)
        One coefficient per feature channel.
    """

    constant: float
    linear: np.ndarray
    square: np.ndarray

    @classmethod
    def of_fit(cls, weight, constants, area_weight=0.0):
        """``area_weight + sum_c weight_c (v_c - constants_c)^2`` expanded, the integrand of a
        region of (6.38) with the constant fit (6.42)."""
        weight = np.asarray(weight, dtype=np.float64)
        constants = np.asarray(constants, dtype=np.float64)
        return cls(float(area_weight + weight @ (constants * constants)), -2.0 * weight * constants,
                   weight.copy())

    def __sub__(self, other):
        return QuadraticForm(self.constant - other.constant, self.linear - other.linear,
                             self.square - other.square)

    def density(self, values):
        """``g`` at every pixel: values (..., C) -> (...), float64."""
        out = values @ self.linear + self.constant
        if np.any(self.square != 0):
            out += (values * values) @ self.square
        return out

    def integral(self, area, first, second):
        """``int_Omega g`` from the moments ``area = int 1``, ``first_c = int v_c``,
        ``second_c = int v_c^2`` of Omega."""
        return float(self.constant * area + self.linear @ first + self.square @ second)
