"""`segment`: the one public entry point, shared by the CLI, the viewer and pipelines."""

from __future__ import annotations

import dataclasses
import functools
import os

import numpy as np

from activecontour.backends import BACKENDS, solver_for
from activecontour.geometry.raster import mask_to_curves
from activecontour.geometry.regions import clip_region, complement_region
from activecontour.imaging.frame import to_frame, working_frame
from activecontour.imaging.noise import auto_mu, is_auto
from activecontour.imaging.normalize import intensity_scale, normalize_image, single_image
from activecontour.imaging.roi import (
    ROI_INIT_MARGIN,
    crop_init,
    init_neighbourhood,
    resolve_roi,
    restrict_values,
)
from activecontour.io.images import load_image
from activecontour.models import ChanVeseParameters, noise_model
from activecontour.models.modes import choose_regions
from activecontour.objects.measure import find_objects
from activecontour.result import build_result, scalar_if_gray

__all__ = ["BACKENDS", "FITS", "INSIDE", "segment"]

#: The models of the regions' intensities (``fit``).
FITS = ("constant", "smooth")
#: Rounds of the smooth fit's alternation (light field, then contour) at most; a round whose
#: light step lowers J by less than the light's BIC cost ends it sooner (:func:`_smooth_light`).
_LIGHT_ROUNDS = 4

#: The choices of ``inside``: which region holds the objects.
INSIDE = ("auto", "bright", "dark")

def segment(image, init=None, *, backend="polygon", mu="auto", omega=0.0, lambda_in=1.0,
            lambda_out=1.0, max_num_iter=500, tol=5e-4, callback=None, c_in=None, c_out=None,
            color="gray", normalize="range", n_regions=2, fit="constant", noise="gaussian", inside="auto",
            roi=None, separate=True, channel_axis=None, options=None):
    """Segment an image by minimising the Chan-Vese functional (6.38) with an active contour.

    Parameters
    ----------
    image : ndarray of shape (M, N) or (M, N, C), or a path
        Gray, gray + alpha, RGB or RGBA image (see :func:`activecontour.imaging.normalize.normalize_image`),
        or the path of an image file (read by :func:`activecontour.io.images.load_image`).  A stack
        of frames (a time-lapse, a z-stack, a multi-page TIFF) is refused with one line naming
        :func:`activecontour.segment_sequence`; a (2-4, M, N) array is ambiguous (frames or
        channel-first colour) and needs ``channel_axis`` (the rule:
        :func:`activecontour.imaging.normalize.single_image`).
    init : None, ndarray (K, 2), list of ndarray, bool ndarray (M, N), SegmentationResult or str
        Initial contour(s) in (row, col), a mask, or a previous result (of either backend).  None
        (default) starts from the outlines of the two-means threshold of the lightly blurred image
        (the minimiser of (6.38) without its length term), so objects anywhere in the image are in
        the start (:func:`activecontour.initial.default_init`).  ``"grid"``: small circles all
        over the image; the level-set backend also accepts ``"checkerboard"``.
    backend : {"polygon", "levelset"}
        ``"polygon"``: the book's gradient flow (6.30)-(6.31) of a polygon with the H^1 velocity
        (6.39)-(6.40), sub-pixel.  ``"levelset"``: the same functional on the pixel grid.
    mu : float or "auto"
        Length weight (intensity^2 * pixel, intensities normalised), >= 0.  Larger gives smoother,
        shorter contours: features with a radius of curvature below about ``mu / (c_in - c_out)^2``
        pixels are smoothed away.  ``"auto"`` (default) sets it from the image's noise
        (:func:`activecontour.imaging.noise.auto_mu`); ``result.mu`` reports the value used.
    omega : float
        Area weight (intensity^2); positive shrinks, negative grows the inside.
    lambda_in, lambda_out : float
        Weights of the inside and outside fitting terms, > 0.
    max_num_iter : int
        Iteration limit.
    tol : float
        Convergence tolerance in pixels per iteration: the run has converged when the contour's
        mean normal displacement (the area it sweeps over its length), averaged over a few
        iterations, falls below ``tol`` at the finest stage.  It means the same on every image,
        whatever its size, noise or contrast; a 100x smaller ``tol`` changes neither the energy
        nor the mask measurably.  Coarse stages end at 10 tol.
    callback : callable, optional
        ``callback(state)`` with a :class:`~activecontour.result.FlowState` once per iteration;
        return True to stop.
    c_in, c_out : float or sequence, optional
        Hold the region constants fixed; by default they are updated by (6.42) every iteration.
    color : {"gray", "vector"}
        Colour images: convert to gray, or keep the channels (vector-valued functional).
    normalize : {"range", "dtype", None}
        Intensity scaling before the functional is set up: the image's own range onto [0, 1]
        (default), the dtype's range, or none (see :func:`activecontour.imaging.normalize.normalize_image`).
        ``result.c_in``/``c_out`` are in these normalised units; ``result.c_in_image`` and
        ``result.c_out_image`` in the input's own.  Whatever the choice, the backends compute
        where the image spans [0, 1] (:meth:`~activecontour.energy.ChanVeseParameters.in_frame`:
        no cancellation for intensities far from 0, no overflow), and report energies and
        constants in these units; weights and constants beyond ``PARAMETER_LIMIT`` (1e8) in
        that frame are refused.
    n_regions : int or "auto"
        The number of regions K >= 2 of the piecewise-constant model: (6.38) for two; for more,
        the sum of each region's fit term plus mu times the length of the interfaces between
        regions, each counted once (:meth:`ChanVeseParameters.class_forms`).  ``result.classes``
        holds the region of every pixel (0 = the background, the region covering most of the
        image border; the others by increasing mean intensity), ``result.constants`` their
        constants; the inside (``mask``, ``contours``) is every region but the background.
        For K > 2 both backends start from the global K-means of the intensities and find the
        regions on a label field descended on the exact partition length
        (:mod:`activecontour.backends.labelfield`, the ``"levelset"`` result); ``"polygon"``
        then moves every interface and junction to sub-pixel position by the H^1 flow of the
        boundary network (:mod:`activecontour.backends.network`).  ``result.class_contours``
        are the regions' curves.  ``c_in``/``c_out`` and ``options`` apply to two regions only.
        ``"auto"``: K in 2..6 (:data:`~activecontour.models.modes.MAX_REGIONS`), the number of
        significant modes of the intensities of the image's flat pixels, at the noise level that
        ``mu`` assumes (:mod:`activecontour.models.modes`, which says why not a penalised
        likelihood); it costs a histogram, milliseconds.  It takes the settings of K > 2 (no
        ``c_in``/``c_out``, ``roi`` or ``options``).  ``result.n_regions`` is the K used.
    fit : {"constant", "smooth"}
        ``"constant"``: each region has one intensity (6.42).  ``"smooth"``: region k's intensity
        is ``c_k b(x)``, b a smooth light field shared by all regions (a polynomial of degree 3,
        mean 1), estimated with the contour by alternating minimisation
        (:mod:`activecontour.models.smooth`): for uneven illumination, vignetting, shading.
        ``result.light`` is b; ``constants``, ``c_in``, ``c_out`` are the c_k.
    noise : {"gaussian", "poisson"}
        The fit term: ``"gaussian"``, (6.38)'s squared error; ``"poisson"``, the negative
        log-likelihood of photon counts with the rate ``c_k b`` (fluorescence: the noise grows
        with the intensity; two regions split at the logarithmic mean of their constants, not
        the arithmetic one; :mod:`activecontour.models.poisson`).  The counts' zero is the
        normalised image's zero where its values lie in [0, 1] (``normalize="range"``: its
        minimum).
    inside : {"auto", "bright", "dark"}
        Which of the two regions is the inside (the objects).  ``"auto"``: the default start takes
        the class that covers less of the image border, and given curves are the inside as drawn.
        ``"bright"``/``"dark"``: the region with the larger/smaller mean; a run that ends the
        other way round returns the complement (the rest of the image domain), its energy
        evaluated again.
    roi : None, "init", bool ndarray (M, N), or (r0, c0, r1, c1)
        Restrict the image domain D of (6.38) to a region of interest (:mod:`activecontour.imaging.roi`):
        a box (exact, by cropping), a mask, or ``"init"``: a neighbourhood of the given curves, so
        that drawing around one object gives that object (grown while the object reaches its
        edge, so a curve drawn inside the object works too).  The result is in the whole image's
        frame; ``result.roi`` is the domain used (a bool mask) and ``result.energy`` is (6.38) on
        its bounding box.
    separate : bool
        Objects that touch get their own ids in ``result.labels`` (split along the necks of the
        inside region, :func:`activecontour.objects.split.split_touching`); False: one id per connected
        piece.  With ``n_regions > 2`` an object is a piece of one class (touching pieces of two
        classes are two objects; ``result.objects["class"]`` says which).  ``result.mask``,
        ``result.contours`` and the energy do not depend on it.
    channel_axis : int, optional
        The axis holding the colour channels of a 3-D array, e.g. 0 for channel-first (3, M, N);
        None: the last, when it has 1-4 entries.
    options : dict, optional
        Backend-specific settings: the fields of the backend's options dataclass
        (:class:`activecontour.backends.polygon.PolygonOptions`,
        :class:`activecontour.backends.levelset.LevelSetOptions`; the registry
        :data:`activecontour.backends.BACKENDS`).  An unknown name is a TypeError listing the
        valid ones.

    Returns
    -------
    SegmentationResult
        With the objects: ``labels``, ``objects`` (measurements), ``object_contours``, ``classes``
        (:func:`activecontour.objects.measure.find_objects`).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {tuple(BACKENDS)}, got {backend!r}")
    if isinstance(max_num_iter, bool) or not isinstance(max_num_iter, (int, np.integer)):
        raise TypeError(f"max_num_iter must be an integer, got {max_num_iter!r}")
    if max_num_iter < 0:
        raise ValueError(f"max_num_iter must be >= 0, got {max_num_iter}")
    if not (isinstance(tol, (int, float, np.floating)) and np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be a finite number >= 0, got {tol!r}")
    if callback is not None and not callable(callback):
        raise TypeError("callback must be callable or None")
    if inside not in INSIDE:
        raise ValueError(f"inside must be one of {INSIDE}, got {inside!r}")
    if not isinstance(separate, (bool, np.bool_)):
        raise TypeError(f"separate must be True or False, got {separate!r}")
    if options is not None and not isinstance(options, dict):
        raise TypeError(f"options must be a dict or None, got {type(options).__name__}")
    _check_regions(n_regions, backend, c_in, c_out, options, roi)
    if fit not in FITS:
        raise ValueError(f"fit must be one of {FITS}, got {fit!r}")
    noise_model(noise)  # a bad name is refused before any work
    if isinstance(image, (str, os.PathLike)):
        image = load_image(image)
    image = single_image(image, channel_axis)
    values = normalize_image(image, color=color, normalize=normalize)
    shape = values.shape[:2]
    if is_auto(n_regions):
        n_regions = choose_regions(values, mu)
    chosen = solver_for(backend, n_regions)
    solver = functools.partial(chosen.solve, options=chosen.parse(options or {}), n_regions=int(n_regions))
    solve = functools.partial(
        _solve, solver, values, init, mu=mu, constants=(omega, lambda_in, lambda_out, c_in, c_out),
        inside=inside, normalize=normalize, callback=callback, fit=fit, noise=noise,
        settings=dict(max_num_iter=int(max_num_iter), tol=float(tol)))
    if isinstance(roi, str) and roi == "init":
        # the smallest neighbourhood of the init that holds the object: grown while the result
        # reaches the domain's edge (or is empty), e.g. when the curve was drawn inside the object
        margin = ROI_INIT_MARGIN
        while True:
            neighbourhood = init_neighbourhood(init, shape, margin)
            result, params, (offset, scale) = solve(neighbourhood)
            if neighbourhood.all() or not _reaches_edge(result, neighbourhood):
                break
            margin *= 2
    else:
        result, params, (offset, scale) = solve(roi)
    offset, scale = _input_units(image, normalize, offset, scale)
    result.mu = params.mu
    result.c_in_image = scalar_if_gray(offset + scale * np.asarray(result.c_in))
    result.c_out_image = scalar_if_gray(offset + scale * np.asarray(result.c_out))
    pixels = np.asarray(image)
    if pixels.shape[:2] != shape:  # a channel-first stack, read as channel-last
        pixels = np.moveaxis(pixels, 0, -1)
    # objects are the connected pieces of each non-background region (N regions: of each class,
    # its sub-pixel curves)
    by_class = result.contours if result.class_contours is None else result.class_contours[1:]
    result.object_contours, result.labels, result.objects = find_objects(
        by_class, shape, pixels, separate=bool(separate))
    if result.classes is None:  # two regions: the inside is region 1
        result.classes = result.mask.astype(np.int32)
        result.constants = np.array([np.atleast_1d(result.c_out), np.atleast_1d(result.c_in)])
    result.n_regions = int(n_regions)
    return result


def _solve(solver, values, init, roi, *, mu, constants, inside, normalize, callback, fit, noise,
           settings):
    """Run the backend on the image, or on the crop of a region of interest.

    Returns the result in the whole image's frame, the parameters used, and the affine map
    ``(low, span)`` of the crop's renormalisation (``(0, 1)`` without one).
    """
    shape = values.shape[:2]
    box, domain = (None, None) if roi is None else resolve_roi(roi, shape, init)
    rescale = (0.0, 1.0)
    if box is not None:
        values = restrict_values(values, box, domain)
        if normalize == "range":  # the crop by its own range, as segment(image[box]) would
            low, high = float(values.min()), float(values.max())
            rescale = (low, high - low if high > low else 1.0)
            values = (values - rescale[0]) / rescale[1]
        init = crop_init(init, box, shape)
        if callback is not None:
            callback = _whole_image_callback(callback, box, shape)
    # the backends compute where the image spans [0, 1] (no cancellation, no overflow)
    frame_offset, frame_scale = working_frame(values)
    values = to_frame(values, frame_offset, frame_scale)
    params = ChanVeseParameters(auto_mu(values) * frame_scale**2 if is_auto(mu) else mu, *constants)
    working = params.in_frame(frame_offset, frame_scale)
    framed = working is not params
    if callback is not None and framed:
        callback = _in_caller_units(callback, frame_offset, frame_scale)

    def run(model, init, params, max_num_iter=settings["max_num_iter"]):
        return solver(model, init, params, callback=callback, **{**settings, "max_num_iter": max_num_iter})

    build, fit_light = noise_model(noise)
    if fit == "smooth":
        result, model, working = _smooth_light(values, init, working, run, build, fit_light)
    else:
        model, working = build(values, None, working)
        result = run(model, init, working)
    result = _make_inside(result, inside, model, working)
    if domain is not None:
        domain_curves = mask_to_curves(domain)
        result = _rebuilt(result, clip_region(result.contours, domain_curves), model, working,
                          phi=None if result.phi is None else np.where(domain, result.phi, -1.0))
    if box is not None:
        result = _in_whole_image(result, box, domain, shape)
    if framed:
        square = frame_scale**2
        result.energy *= square
        result.energies = result.energies * square
        result.c_in = scalar_if_gray(frame_offset + frame_scale * np.asarray(result.c_in))
        result.c_out = scalar_if_gray(frame_offset + frame_scale * np.asarray(result.c_out))
        if getattr(result, "constants", None) is not None:
            result.constants = frame_offset + frame_scale * np.asarray(result.constants)
    return result, params, rescale


def _reaches_edge(result, domain):
    """Whether a result is empty or has pixels on the edge of its domain (not the image's)."""
    import scipy.ndimage

    edge = domain & ~scipy.ndimage.binary_erosion(domain, border_value=1)
    return result.status == 3 or bool((result.mask & edge).any())


def _input_units(image, normalize, low, span):
    """``(offset, scale)`` from the functional's units to the input's, after a crop's renormalisation
    ``(values - low) / span``."""
    offset, scale = intensity_scale(image, normalize)
    return offset + scale * low, scale * span


def _make_inside(result, inside, model, params):
    """The result, or its complement when the inside is not the class ``inside`` asks for."""
    if inside == "auto" or not result.contours or result.classes is not None:  # N regions: as found
        return result
    brighter = np.mean(np.asarray(result.c_in)) > np.mean(np.asarray(result.c_out))
    if brighter == (inside == "bright"):
        return result
    return _rebuilt(result, complement_region(result.contours, model.shape), model, params,
                    phi=None if result.phi is None else -result.phi)


def _rebuilt(result, contours, model, params, phi):
    """A result with other contours, made by :func:`build_result` (so the invariants hold)."""
    return build_result(model, params, contours, energies=result.energies, n_iter=result.n_iter,
                        status=result.status, backend=result.backend, phi=phi)


def _in_whole_image(result, box, domain, shape):
    """A result on a crop, moved into the whole image's frame (the energy stays the crop's)."""
    r0, c0, r1, c1 = box
    offset = np.array([r0, c0], dtype=np.float64)
    result.contours = [c + offset for c in result.contours]
    mask = np.zeros(shape, dtype=bool)
    mask[r0:r1, c0:c1] = result.mask
    result.mask = mask
    if result.phi is not None:
        phi = np.full(shape, min(float(result.phi.min()), -1.0))
        phi[r0:r1, c0:c1] = result.phi
        result.phi = phi
    result.roi = np.zeros(shape, dtype=bool)
    result.roi[r0:r1, c0:c1] = True if domain is None else domain
    return result


def _whole_image_callback(callback, box, shape):
    """The callback, shown states in the whole image's frame (a viewer draws them on the image)."""
    offset = np.array(box[:2], dtype=np.float64)

    def shifted(state):
        phi = state.phi
        if phi is not None:
            phi = np.full(shape, min(float(phi.min()), -1.0))
            phi[box[0]:box[2], box[1]:box[3]] = state.phi
        return callback(dataclasses.replace(state, contours=[c + offset for c in state.contours],
                                            shape=tuple(shape), phi=phi))

    return shifted


def _in_caller_units(callback, offset, scale):
    """The callback, shown each state's energy and constants in the caller's intensity units."""
    def wrapped(state):
        return callback(dataclasses.replace(
            state, energy=state.energy * scale**2,
            c_in=offset + scale * np.asarray(state.c_in), c_out=offset + scale * np.asarray(state.c_out)))

    return wrapped


def _check_regions(n_regions, backend, c_in, c_out, options, roi):
    """Refuse what ``n_regions`` cannot do; ``"auto"`` is checked as a K > 2 (it may choose one)."""
    choices = "an integer >= 2 or 'auto'"
    if isinstance(n_regions, str) and not is_auto(n_regions):
        raise ValueError(f"n_regions must be {choices}, got {n_regions!r}")
    if not is_auto(n_regions):
        if isinstance(n_regions, bool) or not isinstance(n_regions, (int, np.integer)):
            raise TypeError(f"n_regions must be {choices}, got {n_regions!r}")
        if n_regions < 2:
            raise ValueError(f"n_regions must be {choices}, got {n_regions}")
        if n_regions == 2:
            return
    if c_in is not None or c_out is not None:
        raise ValueError("c_in and c_out fix the constants of two regions; leave them None for "
                         f"n_regions={n_regions}")
    if roi is not None:
        raise ValueError(f"roi restricts the two-region model; it is not available with "
                         f"n_regions={n_regions}")
    if options:
        raise TypeError(f"options are the two-region backends' settings; n_regions={n_regions} "
                        "takes none")


def _smooth_light(values, init, params, run, build, fit_light):
    """``fit="smooth"``: alternate the backend's run (light fixed) and the light's update
    (partition and constants fixed: least squares, or the Poisson likelihood's optimum).
    ``build`` and ``fit_light`` are the noise model's (:func:`activecontour.models.noise_model`).
    Returns the result, its image model and parameters.

    When the light is worth its parameters: the light step lowers J by the drop of
    :func:`~activecontour.models.smooth.fit_light`.  Read (6.38) as
    :func:`~activecontour.imaging.noise.auto_mu` does, a MAP estimate under Gaussian noise of the variance
    sigma^2 that the default mu assumes (``auto_mu / MU_PER_NOISE_VARIANCE``): the fit term is 2 sigma^2
    times a negative log-likelihood, and the Bayesian information criterion admits the light's P - 1 free
    parameters (P basis functions, less the scale the constants absorb) only when the drop exceeds ``sigma^2
    (P - 1) ln(N)``, N the pixels.  Under uniform light and pure noise the drop is ``sigma^2`` times a
    chi-square with at most P - 1 degrees of freedom (mean <= 9; the constant field is fitted by the
    constants already), far below that (112 sigma^2 at 512^2); light of 1 % over a 512^2 image of contrast
    0.4 is above it.  (The Poisson fit term is scaled to be the squared error at the mean intensity, so the
    same bound holds to second order.)  The same bound ends the alternation: a later round that moves the
    light by less than its noise is not worth a run.  So does a round that ends above the J it started from:
    each step of an alternating minimisation lowers J, so a run that does not (the backend restarts its
    coarse stages from the previous partition and can settle higher) is not converging.

    So the constant fit always runs, and when the light its partition implies is not worth its
    parameters (flat light: the constant fit is then a stationary point of the alternation), it
    is the result, at the cost of one light fit.  Otherwise two starts for the light: uniform
    and the least-squares light of the whole image as one region (right when the objects are a
    small part of the image, as faint objects under a vignette, where the constant fit splits
    the image along the light instead; wrong when large objects make the light).  The other
    start runs when its start (the backend's default start on the image corrected by that
    light, or ``init``) has the lower energy.  The alternation continues from the better result,
    and the lowest energy of every run is returned, so the smooth fit never ends above the
    constant fit.  When that is the constant fit's own result, ``result.light`` is None.
    """
    from activecontour.imaging.noise import MU_PER_NOISE_VARIANCE
    from activecontour.models.smooth import LIGHT_TERMS

    noise = auto_mu(values) / MU_PER_NOISE_VARIANCE
    worth = noise * (LIGHT_TERMS - 1) * np.log(values.shape[0] * values.shape[1])
    plain = (*build(values, None, params), None)
    result = run(plain[0], init, plain[1])
    new, drop = fit_light(values, *_classes_and_constants(result), plain[1])
    if drop <= worth:
        result.light = None
        return result, plain[0], plain[1]
    one_region = np.zeros(values.shape[:2], dtype=np.intp)
    whole_light = fit_light(values, one_region, np.ones((1, values.shape[2])), plain[1])[0]
    lit = (*build(values, whole_light, params), whole_light)
    runs = [(result, *plain)]
    start_energy = [run(start[0], init, start[1], max_num_iter=0).energy for start in (plain, lit)]
    if start_energy[1] < start_energy[0]:
        runs.append((run(lit[0], init, lit[1]), *lit))
    result, model, model_params, light = min(runs, key=lambda entry: entry[0].energy)
    for round_ in range(_LIGHT_ROUNDS):
        if round_ > 0 or light is not None:  # the constant fit's step is known
            new, drop = fit_light(values, *_classes_and_constants(result), model_params, previous=light)
            if drop <= worth:
                break
        light, before = new, result.energy
        model, model_params = build(values, light, params)
        result = run(model, result, model_params)
        runs.append((result, model, model_params, light))
        if result.energy >= before:  # the backend's run did not descend from the light step
            break
    result, model, model_params, light = min(runs, key=lambda entry: entry[0].energy)
    result.light = light
    return result, model, model_params


def _classes_and_constants(result):
    """A result's regions and their constants (two regions: the inside is region 1)."""
    if result.classes is not None:
        return result.classes, result.constants
    return result.mask.astype(np.intp), np.array([np.atleast_1d(result.c_out), np.atleast_1d(result.c_in)])
