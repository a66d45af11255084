"""Drop-in replacements for scikit-image functions: change one import line, keep the call.

``from activecontour.compat import chan_vese`` takes the arguments of
``skimage.segmentation.chan_vese`` in the same order with the same defaults and returns the same
types, computed by this package's polygon flow of (6.38) (section 6.5 of *The Shapes of Things*).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from activecontour._segment import solve_problem
from activecontour.problem import prepare
from activecontour.settings import Settings

__all__ = ["chan_vese"]

#: ``init_level_set`` presets of scikit-image, and what each becomes here (see :func:`chan_vese`)
INIT_LEVEL_SETS = ("checkerboard", "disk", "small disk")
#: Blur widths (px) among which the ``"checkerboard"`` start picks the one whose threshold set has
#: the lowest (6.38) (:func:`_checkerboard_start`)
CHECKERBOARD_BLURS = (1.0, 2.0, 4.0)


def chan_vese(image, mu=0.25, lambda1=1.0, lambda2=1.0, tol=1e-3, max_num_iter=500, dt=0.5,
              init_level_set="checkerboard", extended_output=False):
    """Chan-Vese segmentation with scikit-image's signature, by the polygon flow of (6.38).

    A drop-in replacement for ``skimage.segmentation.chan_vese`` (same parameters, order, defaults
    and return types): ``from activecontour.compat import chan_vese`` is the only change a caller
    makes.  Underneath it is :func:`activecontour.segment` with ``backend="polygon"`` and the
    arguments mapped as below.

    Parameters
    ----------
    image : (M, N) ndarray
        Grayscale image (bool, integer or float).  Like scikit-image, the intensities are rescaled
        by the image's own range onto [0, 1] before the functional is set up
        (``normalize="range"`` here), so ``mu`` means the same on every dtype and contrast.
        Colour images are refused as scikit-image does; :func:`activecontour.segment` takes them.
    mu : float, optional
        Length weight, passed unchanged as ``mu``: the weight of the contour's length in pixels,
        in (intensity in [0, 1])^2 per pixel.  scikit-image's scheme (Getreuer's semi-implicit
        step, its eq. 22) is a time discretisation of the gradient flow of
        ``mu * length + lambda1 * int_in (I - c1)^2 + lambda2 * int_out (I - c2)^2`` on the
        [0, 1]-rescaled image: its stationary contours satisfy ``mu kappa = lambda2 (I - c2)^2 -
        lambda1 (I - c1)^2``, the Euler-Lagrange equation of (6.38) with the same ``mu``.  (The
        *energies* scikit-image reports weigh the length by ``eps / (eps^2 + phi^2)``, which is
        pi times the regularised Dirac delta, with a smoothed Heaviside in the fit terms, so
        they are not values of (6.38); compare results with
        :func:`activecontour.chan_vese_energy` instead.)
    lambda1, lambda2 : float, optional
        Weights of the fit terms of the True and the False region: ``lambda_in`` and
        ``lambda_out``.  Must be > 0.
    tol : float, optional
        Convergence tolerance (>= 0), passed unchanged as ``tol``.  scikit-image stops when the
        RMS change of phi per iteration falls below ``tol``; here the run stops when the
        contour's mean normal displacement per iteration, in pixels, falls below ``tol``: for a
        signed-distance phi the two are the same quantity (phi changes at each pixel by the
        displacement of the nearest part of the contour), so the number means the same (a
        stricter mapping, onto :func:`activecontour.segment`'s default 5e-4, ran chelsea 156
        iterations instead of 99 and text 181 instead of 86 for (6.38) lower by at most 0.09 %).
        scikit-image's phi is not a distance (it grows without reinitialisation), so its test
        usually stops it after about 50 iterations, well before its contour has settled; this
        one stops when the contour has.
    max_num_iter : int, optional
        Iteration limit, passed unchanged (one iteration is one accepted step of the flow).
    dt : float, optional
        scikit-image's time step.  Here each step's length is chosen by a backtracking line search
        so that (6.38) decreases at every iteration ((6.31)), so no step size is needed: ``dt``
        is checked (a finite number > 0) and otherwise unused.
    init_level_set : str or (M, N) ndarray, optional
        The start:

        ``"checkerboard"``
            scikit-image's start that reaches objects anywhere in the image.  Here: the package's
            default start (:func:`activecontour.initial.default_init`), the global two-class
            split of the smoothed image traced as curves, which also starts at every object at
            once and is much closer to the minimiser; the image is smoothed by whichever of
            ``CHECKERBOARD_BLURS`` px gives that split the lowest (6.38) (a strong ``mu`` such
            as 0.25 prefers the smoother outlines of a wider blur).
        ``"disk"``
            A circle centred at pixel ``((M - 1) // 2, (N - 1) // 2)`` with radius
            ``min((M - 1) // 2, (N - 1) // 2)``: the zero level set of scikit-image's disk.
        ``"small disk"``
            The same circle with half the radius.
        (M, N) ndarray
            A level-set function: the start is the region ``init_level_set > 0``, every piece of
            it, as in scikit-image.  An array that is positive everywhere, or nowhere, has no
            zero level set and so no contour to move: the segmentation is that start, all True
            or all False (scikit-image's flow leaves it too: its tests assert it).
    extended_output : bool, optional
        Return ``(segmentation, phi, energies)`` instead of the segmentation alone.

    Returns
    -------
    segmentation : (M, N) ndarray, bool
        The inside of the final contours (pixel centres inside, as ``result.mask``).  Which of
        the two regions is True can differ from scikit-image's (see Notes).
    phi : (M, N) ndarray of floats
        Only with ``extended_output``.  The signed Euclidean distance, in pixels, from each pixel
        centre to the boundary of ``segmentation`` (half-way between inside and outside pixel
        centres), positive inside: ``phi > 0`` is ``segmentation``, and ``phi`` is a valid
        ``init_level_set`` for a restart.  float32 for float16/float32 images, float64 otherwise,
        as scikit-image.
    energies : list of floats
        Only with ``extended_output``.  (6.38) by the common evaluator
        (:func:`activecontour.chan_vese_energy` with ``mu``, ``lambda_in=lambda1``,
        ``lambda_out=lambda2``) before the first iteration and after every iteration; unlike
        scikit-image's list it ends with the final energy.  NumPy floats of ``phi``'s dtype, as
        scikit-image's.

    Raises
    ------
    ValueError
        For an image that is not 2-D, an unknown ``init_level_set`` string or an array of another
        shape, ``mu < 0``, ``lambda1``/``lambda2`` <= 0, ``tol < 0``, ``max_num_iter < 0`` or
        ``dt`` <= 0 (non-finite numbers included).
    TypeError
        For a non-integer ``max_num_iter`` or an ``init_level_set`` that is neither.

    Notes
    -----
    The contour is a polygon moved by the H^1 gradient flow (6.30)-(6.31), (6.39)-(6.41) of
    Chan-Vese's functional (6.38) (area weight ``omega = 0``, as scikit-image); region constants by
    (6.42) at every iteration.

    *Which region is True.*  Both functions return the region that evolved from the start's
    inside (``phi > 0``), so with a ``"disk"``, a ``"small disk"`` or an array the True region
    is the one the start put inside, in both.  They can differ in three cases:

    * ``"checkerboard"``: scikit-image's True region is whatever its positive squares grew into,
      often the background (on ``skimage.data.coins()`` the two masks agree on 0.4 % of the
      pixels); here the start's inside is the class covering less of the image border (the
      objects), so True is the objects.  With ``lambda1 == lambda2`` a region and its
      complement have the same (6.38): the two results are the same minimiser, one inverted.
      With ``lambda1 != lambda2`` the weights follow the True region in both, so the minimisers
      differ too.
    * Away from the contour: scikit-image's regularised delta acts on every pixel, so regions
      appear anywhere during its flow; here new regions are added only where the topological
      derivative says (6.38) drops (nucleation, once the flow has settled), so a small region
      one finds the other may not.
    * When the two flows end in different local minima (the functional is not convex), a piece
      of the image can be True in one and False in the other: compare energies, not masks.

    ``benchmarks/bench_compat.py`` compares both functions on 20 of scikit-image's sample images:
    the energy each result reaches, by the common evaluator, and the time each takes.
    """
    image = np.asarray(image)
    if image.ndim != 2:
        raise ValueError(f"image must be a 2-D (M, N) grayscale array, got shape {image.shape}")
    if not _is_number(dt) or dt <= 0:
        raise ValueError(f"dt must be a finite number > 0, got {dt!r}")
    init, arguments = _segment_arguments(image.shape, mu, lambda1, lambda2, tol, max_num_iter,
                                         init_level_set)
    if isinstance(init, _Flat):  # no zero level set: no contour to move, the start is the answer
        from activecontour.initial import rectangle

        segmentation = np.full(image.shape, init.inside)
        domain = rectangle((-0.5, -0.5), (image.shape[0] - 0.5, image.shape[1] - 0.5))
        energies = [_energy(image, [domain] if init.inside else [], arguments)]
    else:
        # segment's run without the objects' pass (no object ids are returned).  The checkerboard
        # start is flowed from as the default start is: a 2 px first smoothing, no global move.
        # Those options are set as the settings are made (they are checked once: a tenth of a
        # small image's call) and taken back in the rare case that there is no such start.
        checkerboard = isinstance(init_level_set, str) and init_level_set == "checkerboard"
        options = None
        if checkerboard:
            from activecontour.backends.polygon import _START_SMOOTHING

            options = {"global_start": False, "smoothing": _START_SMOOTHING}
        problem = prepare(image, Settings(**arguments, options=options))
        if checkerboard:
            init = _checkerboard_start(problem.normalised, mu)
            if init is None:  # segment's default start, flowed with the default options
                settings = dataclasses.replace(problem.settings, options=None)
                problem = dataclasses.replace(problem, settings=settings)
        result = solve_problem(problem, init, objects=False)
        segmentation, energies = result.mask, result.energies
    if not extended_output:
        return segmentation
    # scikit-image's float type: float32 for float16/float32 images, float64 for the others
    float_dtype = np.float32 if image.dtype in (np.float16, np.float32) else np.float64
    phi = _signed_distance(segmentation).astype(float_dtype, copy=False)
    return segmentation, phi, [float_dtype(e) for e in energies]


class _Flat:
    """An ``init_level_set`` array without a zero level set: everything inside or nothing."""

    def __init__(self, inside):
        self.inside = bool(inside)


def _energy(image, curves, arguments):
    """(6.38) of curves by the common evaluator with :func:`chan_vese`'s mapped weights."""
    from activecontour.evaluate import chan_vese_energy

    return chan_vese_energy(image, curves, mu=arguments["mu"], lambda_in=arguments["lambda_in"],
                            lambda_out=arguments["lambda_out"], normalize=arguments["normalize"])


def _segment_arguments(shape, mu, lambda1, lambda2, tol, max_num_iter, init_level_set):
    """``init`` and the keywords of :func:`activecontour.segment` for scikit-image's arguments:
    the mapping :func:`chan_vese` documents, in one place (the benchmark reuses it)."""
    for name, value in (("lambda1", lambda1), ("lambda2", lambda2)):
        if not _is_number(value) or value <= 0:
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    if not _is_number(tol) or tol < 0:
        raise ValueError(f"tol must be a finite number >= 0, got {tol!r}")
    # separate=False: no object ids are returned, so touching objects need not be split (on
    # camera() that split costs 6x the segmentation); the mask and the energy do not depend on it
    keywords = dict(backend="polygon", mu=mu, lambda_in=lambda1, lambda_out=lambda2,
                    max_num_iter=max_num_iter, tol=tol, normalize="range", separate=False)
    return _initial_region(init_level_set, shape), keywords


def _checkerboard_start(values, mu):
    """scikit-image's ``"checkerboard"`` here: the default start's threshold set, of the normalised
    image ``values`` (M, N, C) blurred by whichever of ``CHECKERBOARD_BLURS`` gives it the lowest
    (6.38) (:func:`activecontour.initial.threshold_starts`), resampled at the polygon's spacing,
    as an :class:`activecontour.initial.Start` (the outline of a region, oriented by nesting: the
    flow takes it as it is, without rebuilding it as a user's curves); None for ``mu="auto"``
    (segment's default start) or no threshold set.  It is flowed from as the default start is
    (:func:`chan_vese` sets those options)."""
    from activecontour.backends.options import PolygonOptions
    from activecontour.geometry.curve import resample
    from activecontour.geometry.raster import rasterize
    from activecontour.initial import Start, threshold_starts

    if not _is_number(mu) or mu < 0:
        return None
    spacing = PolygonOptions().spacing
    curves = [resample(c, spacing) for c in threshold_starts(values, float(mu), blurs=CHECKERBOARD_BLURS)[0]]
    return Start(curves, rasterize(curves, values.shape[:2])) if curves else None


def _is_number(value):
    return (isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
            and bool(np.isfinite(value)))


def _initial_region(init_level_set, shape):
    """The ``init`` of :func:`activecontour.segment` for scikit-image's ``init_level_set``."""
    from activecontour.geometry.raster import mask_to_curves
    from activecontour.initial import circle

    if isinstance(init_level_set, str):
        if init_level_set not in INIT_LEVEL_SETS:
            raise ValueError(f"init_level_set must be one of {INIT_LEVEL_SETS} or an (M, N) array, "
                             f"got {init_level_set!r}")
        if init_level_set == "checkerboard":
            return None
        center = ((shape[0] - 1) // 2, (shape[1] - 1) // 2)
        radius = float(min(center))
        if init_level_set == "small disk":
            radius /= 2.0
        if radius <= 0:  # an image of 1 or 2 pixels along a side: no disk fits
            return None
        return circle(center, radius)
    if not isinstance(init_level_set, np.ndarray):
        raise TypeError(f"init_level_set must be one of {INIT_LEVEL_SETS} or an (M, N) array, "
                        f"got {type(init_level_set).__name__}")
    if init_level_set.shape != tuple(shape):
        raise ValueError(f"init_level_set has shape {init_level_set.shape}, but the image has "
                         f"shape {tuple(shape)}")
    inside = init_level_set > 0
    if inside.all() or not inside.any():
        return _Flat(inside.all())
    # every piece, however small (a mask given as init drops pieces of a few pixels): the start is
    # the region ``init_level_set > 0`` exactly, as scikit-image's
    return mask_to_curves(inside)


def _signed_distance(mask):
    """Signed distance (pixels) from each pixel centre to the mask's boundary, positive inside.

    The boundary runs half-way between inside and outside pixel centres, so the distance is the
    Euclidean distance to the nearest pixel of the other class minus 1/2 (:func:`_distance`).  A
    mask without a boundary (empty or full) is -1 or +1 everywhere.
    """
    if not mask.any() or mask.all():
        return np.where(mask, 1.0, -1.0)
    return np.where(mask, _distance(mask) - 0.5, 0.5 - _distance(~mask))


#: Below this distance (px) the float32 Euclidean distance of OpenCV gives the exact one back: its
#: square is within 1024^2 * 2^-23 = 0.125 of the integer it rounds (:func:`_distance`)
_EXACT_FLOAT32 = 1024.0


def _distance(mask):
    """``scipy.ndimage.distance_transform_edt(mask)``: from each True pixel to the nearest False
    one, exactly, in about half its time.  OpenCV's exact transform (``DIST_MASK_PRECISE``) is
    float32; the squared distance is an integer, so rounding its square gives the float64
    distance ``sqrt(integer)`` scipy returns, while distances stay below ``_EXACT_FLOAT32``
    (scipy's own transform beyond)."""
    import cv2

    distance = cv2.distanceTransform(np.ascontiguousarray(mask).view(np.uint8), cv2.DIST_L2,
                                     cv2.DIST_MASK_PRECISE)
    if distance.max() >= _EXACT_FLOAT32:
        import scipy.ndimage

        return scipy.ndimage.distance_transform_edt(mask)
    squared = np.square(distance, dtype=np.float64)
    return np.sqrt(np.rint(squared, out=squared), out=squared)
