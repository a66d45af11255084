"""`SegmentationResult`: the one result type of every backend (after ``scipy.optimize.OptimizeResult``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from activecontour.energy import evaluate
from activecontour.geometry.curve import clean_curves, stack_curves
from activecontour.geometry.raster import rasterize
from activecontour.geometry.topology import region_problem, region_union

__all__ = ["ENDED", "STATUS_MESSAGES", "FlowState", "SegmentationResult", "build_result"]

#: Status codes and their messages, shared by every backend.
STATUS_MESSAGES = {
    0: "Converged: the contour moves less than tol pixels per iteration.",
    1: "Reached max_num_iter before converging.",
    2: "Stopped by the callback.",
    3: "The contour collapsed: nothing left inside (try a smaller mu or another init).",
    4: "Line search found no descent step: stationary to working precision.",
    5: ("Stalled: steps in a row were held back where interfaces meet, at a pinch the flow cannot "
        "resolve (a region thinning between two others); J no longer decreases there."),
}
#: The statuses of a flow that ended where it can go no further (``success``).
ENDED = (0, 4, 5)


@dataclass
class SegmentationResult:
    """The outcome of :func:`activecontour.segment`.

    A backend makes one in its working frame (:func:`build_result`); ``segment`` builds the one it
    returns once, at the end, with every part below in place (nothing sets a field afterwards).

    Attributes
    ----------
    mask : ndarray of bool, shape (M, N)
        The inside region Omega_i: pixels whose centre lies inside the contours.
    contours : list of ndarray (K, 2)
        Closed curves in (row, col), pixel centres at integer coordinates, each vertex once; outer
        boundaries have positive signed area, holes negative (the conventions of
        :mod:`activecontour.geometry.curve`).
    c_in, c_out : float or ndarray (C,)
        The region constants (6.42) at the end: floats for gray images, one per channel otherwise.
    energy : float
        Final value of the functional (6.38).
    energies : ndarray
        Energy before the first iteration and after every iteration, ending with ``energy``.
    n_iter : int
        Iterations performed.
    success : bool
        True when the flow ended where it can go no further (status 0, 4 or 5: :data:`ENDED`).
    status : int
        Key of :data:`STATUS_MESSAGES`.
    message : str
    backend : str
    phi : ndarray (M, N) or None
        The level-set function (``backend="levelset"``), None for the polygon backend.
    mu : float or None
        The length weight used (the value ``mu="auto"`` chose).
    c_in_image, c_out_image : float or ndarray (C,) or None
        ``c_in``, ``c_out`` in the input image's own intensity units (``c_in``/``c_out`` are in the
        normalised units the functional uses).
    labels : int32 ndarray (M, N) or None
        0 = background, 1..n one id per object (:mod:`activecontour.objects`); with
        ``separate=True`` touching objects have their own ids.
    objects : dict of str to ndarray, or None
        Per-object measurements, one row per id (``regionprops_table`` names; see
        :func:`activecontour.objects.measure` for which columns are exact).
    object_contours : list of list of ndarray, or None
        Object k (id k + 1): its outer boundary, then its holes.  Split objects share their split
        lines; ``contours`` stays the boundary of the inside region, which the energy is of.
    classes : int ndarray (M, N) or None
        The region of each pixel, 0 = background (two regions: ``mask.astype(int)``), the others
        by increasing mean intensity.
    light : ndarray (M, N) or None
        The light field b of ``fit="smooth"`` (mean 1): region k's intensity is ``c_k b``; None
        for ``fit="constant"`` and when the smooth fit found the light uniform.
    constants : ndarray (K, C) or None
        The constant of every region in normalised units (two regions: ``[c_out, c_in]``).  With
        ``n_regions > 2``, ``c_out`` is the background's and ``c_in`` the area-weighted mean of the
        others (the inside is every region but the background).
    roi : bool ndarray (M, N) or None
        With ``segment(roi=...)``: the domain D the functional was solved on
        (:mod:`activecontour.imaging.roi`); ``energy`` is (6.38) on its bounding box.
    n_regions : int or None
        The number of regions K of the model (the one ``n_regions="auto"`` chose); ``classes``
        takes values in 0..K-1 and ``constants`` has K rows.
    class_contours : list of list of ndarray, or None
        With ``n_regions > 2``: the closed curves of every region k (outer boundaries positive,
        holes negative; region 0 the background), the sub-pixel partition whose functional is
        ``energy``: ``chan_vese_energy(image, regions=result.class_contours)`` scores it.
    min_size : float or None
        The least area (px^2) of an object (``segment(min_size=...)``, the value ``"auto"``
        chose): smaller pieces of the inside are in ``mask`` and ``contours`` but not in
        ``labels`` or ``objects``.
    """

    mask: np.ndarray
    contours: list
    c_in: object
    c_out: object
    energy: float
    energies: np.ndarray
    n_iter: int
    status: int
    backend: str
    phi: np.ndarray | None = None
    mu: float | None = None
    c_in_image: object = None
    c_out_image: object = None
    labels: np.ndarray | None = None
    objects: dict | None = None
    object_contours: list | None = None
    classes: np.ndarray | None = None
    constants: np.ndarray | None = None
    light: np.ndarray | None = None
    roi: np.ndarray | None = None
    n_regions: int | None = None
    class_contours: list | None = None
    min_size: float | None = None
    success: bool = field(init=False)
    message: str = field(init=False)

    def __post_init__(self):
        self.success = self.status in ENDED
        self.message = STATUS_MESSAGES[self.status]
        self.energies = np.asarray(self.energies, dtype=np.float64)
        self.c_in = scalar_if_gray(self.c_in)
        self.c_out = scalar_if_gray(self.c_out)

    def __repr__(self):
        return (
            f"SegmentationResult(backend={self.backend!r}, success={self.success}, "
            f"n_iter={self.n_iter}, energy={self.energy:.6g}, c_in={self.c_in}, "
            f"c_out={self.c_out}, contours={len(self.contours)}, "
            f"area={int(self.mask.sum())} px, message={self.message!r})"
        )


@dataclass
class FlowState:
    """What a callback sees once per iteration.  Return True from the callback to stop."""

    iteration: int
    contours: list
    energy: float
    c_in: object
    c_out: object
    shape: tuple
    max_num_iter: int
    phi: np.ndarray | None = None

    @property
    def mask(self):
        """The current inside region, rasterised on demand (not free: O(M N))."""
        if self.phi is not None:
            return self.phi > 0
        from activecontour.geometry.raster import rasterize

        return rasterize(self.contours, self.shape)


def scalar_if_gray(value):
    """A region constant as a float (gray) or a float array (C,) (colour), -0.0 as 0.0 (a constant
    of an empty or all-zero region reads 0, inside [0, 1])."""
    value = np.asarray(value, dtype=np.float64) + 0.0
    return float(value.reshape(-1)[0]) if value.size == 1 else value


#: Energies that agree to this relative tolerance are the same number computed twice, or before and
#: after :func:`activecontour.geometry.curve.clean` (which moves the region by ~1e-9 of its extent).
_SAME_ENERGY = 1e-8


def build_result(model, params, contours, *, energies, n_iter, status, backend, phi=None):
    """The one way a backend makes its result, so that every result obeys the same invariants.

    * contours are cleaned (:func:`activecontour.geometry.curve.clean`): no repeated vertices, zero-width
      spikes, fewer than 3 vertices or zero area; curves that do not bound a region (a ring that
      touches itself, overlaps: :func:`activecontour.geometry.topology.region_problem`) are replaced by
      the boundary of the region they outline, so every contour is a simple polygon and no two
      cross;
    * ``energy`` is (6.38) of exactly these contours by the common evaluator
      (:func:`activecontour.evaluate.chan_vese_energy`), and ``energies`` ends with it;
    * when a converged flow ends above the energy of the empty set (a local minimum worse than
      no object at all; at equal energy, as on a blank image, it keeps its curves), or the
      backend reports a collapse, the result is the empty set, status 3, but only if that does
      not raise the energy: a collapse with curves left that beat the empty set keeps them
      (status 1);
    * ``mask`` is the inside of the contours (:func:`activecontour.geometry.raster.rasterize`);
    * ``c_in``, ``c_out`` are finite: the constant of an empty region is reported equal to the
      other one (its fitting term is 0 whatever it is).

    Parameters
    ----------
    model : ImageModel
    params : ChanVeseParameters
    contours : list of ndarray (K, 2)
    energies : sequence of float
        The backend's energy history (before the first iteration, then one per iteration).
    n_iter, status, backend, phi
        As in :class:`SegmentationResult`.
    """
    cleaned = clean_curves(contours)
    if cleaned and region_problem(cleaned) is not None:  # e.g. a ring that touches itself
        cleaned = clean_curves(region_union(cleaned, signed=True))
    final = _evaluate(model, params, cleaned)
    empty = _evaluate(model, params, [])
    # a collapse the backend reports is taken at equal energy; a converged flow keeps its curves then
    if cleaned and ((status == 3 and empty.energy <= final.energy)
                    or (status in ENDED and empty.energy < final.energy)):
        cleaned, final = [], empty
    if not cleaned:
        status = 3
    elif status == 3:  # the backend gave up on curves that are still better than nothing
        status = 1
    energies = list(energies)
    if energies and _same_energy(energies[-1], final.energy):
        # the backend's last energy is this one computed another way (the level set scores an
        # unchained edge soup): the history ends with the common evaluator's number, and entries
        # just below it that are the same number too (steps that left the curve in place) take it,
        # so that a last rounding difference never shows as an increase
        energies[-1] = final.energy
        before = len(energies) - 2
        while (before >= 0 and energies[before] < final.energy
               and _same_energy(energies[before], final.energy)):
            energies[before] = final.energy
            before -= 1
    else:
        energies.append(final.energy)
    return SegmentationResult(
        mask=rasterize(cleaned, model.shape), contours=cleaned, c_in=final.c_in, c_out=final.c_out,
        energy=final.energy, energies=energies, n_iter=n_iter, status=status, backend=backend,
        phi=phi,
    )


def _same_energy(first, second):
    return abs(first - second) <= _SAME_ENERGY * max(abs(second), 1.0)


def _evaluate(model, params, contours):
    points, next_index, _ = stack_curves(contours)
    return evaluate(model, points, next_index, params, empty_ok=True)
