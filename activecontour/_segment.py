"""`segment`: the one public entry point, shared by the CLI, the viewer and pipelines.

The path from the call to the result: the keywords are checked as :class:`~activecontour.settings.Settings`;
:func:`~activecontour.problem.prepare` turns the image and the settings into the problem (values in
the working frame, mu, parameters, model); the registry's record of the backend and number of
regions (:func:`~activecontour.backends.solver_for`) runs on it (on the crop of a region of
interest, :func:`_solve`); the result is built once, at the end, in the whole image's frame and the
caller's units, with its objects (:func:`_result`).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from activecontour.backends import solver_for
from activecontour.geometry.raster import mask_to_curves
from activecontour.geometry.regions import clip_region, complement_region
from activecontour.imaging.noise import MU_BACKOFF, auto_mu, is_auto
from activecontour.imaging.roi import (
    ROI_APART,
    ROI_INIT_MARGIN,
    apart,
    crop_init,
    drawn_region,
    init_neighbourhood,
    pointed_label,
    resolve_roi,
)
from activecontour.initial import DEFAULT_INIT_MIN_AREA, Start, threshold_mask
from activecontour.objects.measure import default_min_size, find_objects
from activecontour.problem import prepare
from activecontour.result import SegmentationResult, build_result, scalar_if_gray
from activecontour.settings import Settings

__all__ = ["segment"]

#: Rounds of the smooth fit's alternation (light field, then contour) at most; a round whose
#: light step lowers J by less than the light's BIC cost ends it sooner (:func:`_smooth_light`).
_LIGHT_ROUNDS = 4

#: ``roi="init"`` tells bright objects from dark ones on block means of at most this many pixels.
_SIDE_PIXELS = 128 * 128

#: The defaults of segment's keywords (stated in :class:`~activecontour.settings.Settings`).
_DEFAULT = Settings()


def segment(image, init=None, *, backend=_DEFAULT.backend, mu=_DEFAULT.mu, omega=_DEFAULT.omega,
            lambda_in=_DEFAULT.lambda_in, lambda_out=_DEFAULT.lambda_out, max_num_iter=_DEFAULT.max_num_iter,
            tol=_DEFAULT.tol, callback=None, c_in=_DEFAULT.c_in, c_out=_DEFAULT.c_out, color=_DEFAULT.color,
            normalize=_DEFAULT.normalize, n_regions=_DEFAULT.n_regions, fit=_DEFAULT.fit,
            noise=_DEFAULT.noise, inside=_DEFAULT.inside, roi=_DEFAULT.roi, separate=_DEFAULT.separate,
            min_size=_DEFAULT.min_size, channel_axis=_DEFAULT.channel_axis, options=_DEFAULT.options):
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
        (:func:`activecontour.imaging.noise.auto_mu`), and when that run leaves no object, runs
        once more at half of it (:data:`~activecontour.imaging.noise.MU_BACKOFF`: small objects
        dim against the noise); ``result.mu`` reports the value used.
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
        its bounding box.  Intensities keep the whole image's normalisation: ``mu`` means the
        same as on the whole image, and ``result.mu``, ``c_in``, ``c_out`` and the energies are
        in the units of a run on it (:meth:`~activecontour.problem.Problem.restricted`).
    separate : bool
        Objects that touch get their own ids in ``result.labels`` (split along the necks of the
        inside region, :func:`activecontour.objects.split.split_touching`); False: one id per connected
        piece.  With ``n_regions > 2`` an object is a piece of one class (touching pieces of two
        classes are two objects; ``result.objects["class"]`` says which).  ``result.mask``,
        ``result.contours`` and the energy do not depend on it.
    min_size : float or "auto"
        Objects of a smaller area (px^2, of their sub-pixel outline) are not objects: they have no
        id in ``result.labels`` and no row in ``result.objects``.  ``"auto"`` (default): the area
        below which the length term removes a disk,
        :func:`~activecontour.objects.measure.default_min_size` (from ``mu``, which the noise
        sets, and the contrast of the two nearest regions); ``result.min_size`` reports the value
        used.  Only the objects leave out such specks: ``result.mask``, ``contours``,
        ``classes`` and ``energy`` stay those of the partition (6.38) was minimised over, so the
        energy is still that of the contours (:func:`activecontour.chan_vese_energy`) and a
        continued run starts from the same stationary point (dropping them from the contours
        too would raise or lower J and the flow's nucleation could bring them back).
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
    settings = Settings(backend=backend, mu=mu, omega=omega, lambda_in=lambda_in, lambda_out=lambda_out,
                        max_num_iter=max_num_iter, tol=tol, c_in=c_in, c_out=c_out, color=color,
                        normalize=normalize, n_regions=n_regions, fit=fit, noise=noise, inside=inside,
                        roi=roi, separate=separate, min_size=min_size, channel_axis=channel_axis,
                        options=options)
    if callback is not None and not callable(callback):
        raise TypeError("callback must be callable or None")
    return solve_problem(prepare(image, settings), init, callback)


def solve_problem(problem, init=None, callback=None, *, objects=True):
    """:func:`segment` of a prepared problem (:func:`~activecontour.problem.prepare`): what a
    caller that prepared the image already for its own use (a sequence's warm start) runs.
    ``objects=False``: the result without the objects (``labels``, ``objects`` and
    ``object_contours`` None), for a caller that reads the partition only (the scikit-image
    drop-in: the objects' pass costs up to a tenth of its call)."""
    settings = problem.settings
    solver = solver_for(settings.backend, problem.n_regions)
    run = functools.partial(solver.solve, options=settings.backend_options, n_regions=problem.n_regions,
                            max_num_iter=int(settings.max_num_iter), tol=float(settings.tol))
    if isinstance(settings.roi, str):  # "init"
        solution = _pointed(problem, run, init, callback)
    else:
        problem, solution = _solve_backing_off(problem, run, init, settings.roi, callback)
    fields, objects_of = _result_fields(problem, solution, getattr(init, "seeds", None))
    del problem, solution  # the normalised image goes before the objects' pass, the peak of memory
    if fields["classes"] is None:  # two regions: the classes of its mask
        fields["classes"] = fields["mask"].astype(np.int32)
    if not objects:
        return SegmentationResult(**fields)
    return _with_objects(fields, *objects_of)


@dataclasses.dataclass(frozen=True)
class _Solution:
    """What a backend's run gave, before the result is built: the problem it ran on (the whole
    image's, or a crop's), its result in that problem's frame (working units), the light field,
    and the inside in the whole image's frame."""

    problem: object
    result: SegmentationResult
    light: np.ndarray | None
    contours: list
    mask: np.ndarray
    phi: np.ndarray | None
    roi: np.ndarray | None


def _solve(problem, run, init, roi, callback):
    """Run the backend on the image, or on the crop of a region of interest: a :class:`_Solution`."""
    shape = problem.shape
    if roi is not None:
        box, domain = resolve_roi(roi, shape)
        problem = problem.restricted(box, domain)
        init = crop_init(init, box, shape)
        if callback is not None:
            callback = _whole_image_callback(callback, box, shape)
    if callback is not None and problem.framed:
        callback = _in_caller_units(callback, *problem.frame)
    run = functools.partial(run, callback=callback)
    if problem.settings.fit == "smooth":
        result, model, working, light = _smooth_light(problem, init, run)
    else:
        (model, working), light = problem.model(), None
        result = run(model, init, working)
    result = _make_inside(result, problem.settings.inside, model, working)
    domain = problem.domain
    if domain is not None:
        result = _rebuilt(result, clip_region(result.contours, mask_to_curves(domain)), model, working,
                          phi=None if result.phi is None else np.where(domain, result.phi, -1.0))
    return _Solution(problem, result, light, *_in_whole_image(result, problem.box, problem.domain, shape))


def _solve_backing_off(problem, run, init, roi, callback):
    """:func:`_solve`, and with ``mu="auto"`` once more at ``MU_BACKOFF`` times the weight when
    the run leaves no object: ``(problem, solution)`` of the run taken.

    The default weight (:func:`~activecontour.imaging.noise.auto_mu`) is a length prior of fixed
    strength; objects small and dim against the noise (area / perimeter below
    ``mu / (c_in - c_out)^2``) cost more length than their fit gains, and the empty set is then
    the lower (6.38), however plainly the image shows them.  The weaker weight keeps them, and
    still no noise speck (:data:`~activecontour.imaging.noise.MU_BACKOFF`).  The second run is
    taken only when it finds something, and ``result.mu`` reports the weight of the run taken; a
    result with objects at the default weight is that run's, unchanged.  A callback sees both
    runs.
    """
    solution = _solve(problem, run, init, roi, callback)
    if not is_auto(problem.settings.mu) or solution.mask.any():
        return problem, solution
    weaker = problem.reweighted(mu=MU_BACKOFF * problem.mu)
    retry = _solve(weaker, run, init, roi, callback)
    return (weaker, retry) if retry.mask.any() else (problem, solution)


def _result_fields(problem, solution, seeds=None):
    """The result's fields, in the whole image's frame and the caller's units, but the objects;
    and what the objects are found from (:func:`_with_objects`; ``seeds``: a
    :class:`~activecontour.initial.Start`'s, the objects of the frame before).  They hold neither
    the problem nor the backend's result."""
    part, result = solution.problem, solution.result
    energy, energies, c_in, c_out, constants = (result.energy, result.energies, result.c_in, result.c_out,
                                                result.constants)
    if part.framed:  # from the working frame to the normalised units
        offset, scale = part.frame
        square = scale**2
        energy, energies = energy * square, energies * square
        c_in = scalar_if_gray(offset + scale * np.asarray(c_in))
        c_out = scalar_if_gray(offset + scale * np.asarray(c_out))
        if constants is not None:
            constants = offset + scale * np.asarray(constants)
    if solution.light is None:  # an optimised constant is a region's mean (6.42): in the values' range
        values = part.normalised.reshape(-1, part.normalised.shape[-1])
        low, high = values.min(axis=0), values.max(axis=0)
        settings = problem.settings
        c_in = c_in if settings.c_in is not None else scalar_if_gray(np.clip(c_in, low, high))
        c_out = c_out if settings.c_out is not None else scalar_if_gray(np.clip(c_out, low, high))
        if constants is not None:  # N regions: every constant optimised
            constants = np.clip(constants, low, high)
    if result.classes is None:  # two regions: the inside is region 1 (the classes made after the objects)
        constants = np.array([np.atleast_1d(c_out), np.atleast_1d(c_in)])
    offset, scale = part.units
    shape = problem.shape
    pixels = _pixels(problem.image, shape)
    # objects are the connected pieces of each non-background region (N regions: of each class,
    # its sub-pixel curves)
    by_class = solution.contours if result.class_contours is None else result.class_contours[1:]
    min_size = _min_size(problem.settings.min_size, part.mu, constants, result.success)
    fields = dict(
        mask=solution.mask, contours=solution.contours, c_in=c_in, c_out=c_out, energy=energy,
        energies=energies, n_iter=result.n_iter, status=result.status, backend=result.backend,
        phi=solution.phi, mu=part.mu, c_in_image=scalar_if_gray(offset + scale * np.asarray(c_in)),
        c_out_image=scalar_if_gray(offset + scale * np.asarray(c_out)), classes=result.classes,
        constants=constants, light=solution.light, roi=solution.roi, n_regions=problem.n_regions,
        class_contours=result.class_contours, min_size=min_size)
    return fields, (by_class, shape, pixels, bool(problem.settings.separate), min_size, seeds)


def _with_objects(fields, by_class, shape, pixels, separate, min_size, seeds):
    """The result: its fields with the objects (:func:`activecontour.objects.measure.find_objects`,
    of ``min_size`` at least, split by ``seeds`` where given)."""
    object_contours, labels, objects = find_objects(by_class, shape, pixels, separate=separate,
                                                    min_size=min_size, seeds=seeds)
    return SegmentationResult(**fields, labels=labels, objects=objects, object_contours=object_contours)


def _pointed(problem, run, init, callback):
    """``roi="init"``: the object the init encloses, alone (:mod:`activecontour.imaging.roi`).

    The object pointed at is, of the objects found on a neighbourhood of the drawn region
    (:func:`init_neighbourhood`; :func:`find_objects`, touching ones apart as ``separate`` says),
    the one holding most of the drawn region (:func:`pointed_label`).  Its neighbours are not part
    of the problem: the domain D of (6.38) is the neighbourhood without them (grown by
    ``ROI_APART`` px, :func:`apart`), so the constants (6.42) are those of the object and the
    background around it, the result holds the object alone, ``result.roi`` is that domain and
    a continued run stays on the object.

    Before the run, the neighbours the default start's threshold set shows
    (:func:`~activecontour.initial.threshold_mask`: its pieces that reach outside the drawn
    region, other than the one pointed at) are taken out; after it, any other object the run
    found (a touching neighbour split off, a neighbour wholly inside the drawn curve) is, and the
    flow continues from the pointed object alone on that domain (one run in the common case, two
    when a neighbour showed up only in the first).  While the object reaches the neighbourhood's
    edge (the curve was drawn inside it, or cuts it), the neighbourhood is made again around the
    drawn region and the object together (each round it grows by a quarter of the object's
    radius at least); while the run finds no object at all (a curve drawn inside a uniform
    object), its margin doubles; up to the whole image.  A neighbour reaching the edge does not
    count.  When the run finds objects but none holds any of the drawn region (a curve drawn on
    the background), nothing was pointed at: the result is empty.

    An object that holds less than half of the drawn region and has less than half of its own
    area in it (:func:`_reaches_in`) is a neighbour reaching into the drawn curve, not the object
    drawn around (all of which is in the curve) or inside (which is all of the curve): it is
    taken out of the domain and the run repeated.  Such a neighbour becomes the object found
    when it is much brighter than the one drawn around: the constants (6.42) of the
    neighbourhood are then the bright one's and the background's, and the dim object reads as
    background.
    """
    shape = problem.shape
    drawn = drawn_region(init, shape)
    problem = dataclasses.replace(problem, settings=dataclasses.replace(problem.settings,
                                                                      inside=_objects_side(problem)))
    around, margin, reaching = drawn, ROI_INIT_MARGIN, np.zeros(shape, dtype=bool)
    while True:
        neighbourhood = init_neighbourhood(around, margin)
        domain = _without_neighbours(problem, neighbourhood, around)
        solution = _solve(problem, run, init, _apart_in_box(domain, reaching), callback)
        (r0, c0, r1, c1), objects, labels, target = _pointed_in(solution, drawn)
        mine = labels == target
        if target and _reaches_in(mine, drawn[r0:r1, c0:c1]):  # a neighbour, not the object
            reaching[r0:r1, c0:c1] |= mine
            continue
        if neighbourhood.all() or (not target and labels.any()) or (
                target and not (mine & _near_edge(neighbourhood, (r0, c0, r1, c1))).any()):
            break
        if target:  # cut by the edge: the default margin around the drawn region and the object
            around = around.copy()
            around[r0:r1, c0:c1] |= mine
            margin = ROI_INIT_MARGIN
        else:  # nothing there yet (a curve drawn inside a uniform object): look further
            margin *= 2
    if not target:  # objects, but none holds any of the drawn region: nothing was pointed at
        model, working = solution.problem.model(solution.light)
        empty = _rebuilt(solution.result, [], model, working, phi=None)
        return dataclasses.replace(solution, result=empty, contours=[], mask=np.zeros(shape, dtype=bool),
                                   phi=None)
    domain = solution.roi[r0:r1, c0:c1]
    others = (labels > 0) & ~mine
    if not others.any():
        return solution
    carved = apart(domain, others, mine)
    roi = np.zeros(shape, dtype=bool)
    roi[r0:r1, c0:c1] = carved
    offset = np.array([r0, c0], dtype=np.float64)
    start = Start([curve + offset for curve in objects[target - 1]], np.zeros(shape, dtype=bool))
    start.mask[r0:r1, c0:c1] = mine
    return _solve(problem, run, start, roi, callback)


def _reaches_in(mine, drawn):
    """Whether the object ``mine`` (bool) is a neighbour reaching into the ``drawn`` region, not
    the object drawn around or inside: it holds less than half of the drawn region (a curve
    drawn inside an object is all object) and has less than half of its own area in it (an
    object drawn around is all in it)."""
    held = 2 * np.count_nonzero(mine & drawn)
    return held < np.count_nonzero(drawn) and held < np.count_nonzero(mine)


def _apart_in_box(domain, others):
    """:func:`apart` of a whole-image ``domain`` and ``others`` (bool (M, N)), computed in the
    domain's bounding box; ``domain`` itself when ``others`` has none."""
    if not others.any():
        return domain
    r0, c0, r1, c1 = resolve_roi(domain, domain.shape)[0]
    window = (slice(r0, r1), slice(c0, c1))
    carved = np.zeros_like(domain)
    carved[window] = apart(domain[window], others[window], np.zeros_like(domain[window]))
    return carved


def _without_neighbours(problem, neighbourhood, drawn):
    """The neighbourhood without the pieces of the default start's threshold set
    (:func:`~activecontour.initial.threshold_mask` on its crop) that reach outside ``drawn`` and
    hold less of it than the one holding most (:func:`apart`)."""
    import cv2

    box, domain = resolve_roi(neighbourhood, problem.shape)
    part = problem.restricted(box, domain)
    inside = threshold_mask(part.values, part.working.mu, part.settings.inside)[0]
    if domain is not None:
        inside &= domain
    r0, c0, r1, c1 = box
    pieces = cv2.connectedComponents(inside.astype(np.uint8), connectivity=8)[1]
    within = drawn[r0:r1, c0:c1]
    target = pointed_label(pieces, within)
    others = np.isin(pieces, np.unique(pieces[~within])) & (pieces > 0) & (pieces != target)
    if not others.any():
        return neighbourhood
    carved = neighbourhood.copy()
    carved[r0:r1, c0:c1] = apart(neighbourhood[r0:r1, c0:c1], others, pieces == target)
    return carved


def _objects_side(problem):
    """``"bright"`` or ``"dark"``: the objects' side, ``inside`` or for ``"auto"`` the side of the
    whole image's default start (:func:`~activecontour.initial.threshold_mask`: the class covering
    less of the image's border), as the run on the whole image would take it; a neighbourhood's
    own border, covered by neighbours, does not say."""
    inside = problem.settings.inside
    if inside != "auto":
        return inside
    # on block means of at most _SIDE_PIXELS pixels, an image in its own right (its own noise)
    values = problem.normalised
    side = int(np.ceil(np.sqrt(values.shape[0] * values.shape[1] / _SIDE_PIXELS)))
    if side > 1:
        m, n = values.shape[0] // side * side, values.shape[1] // side * side
        values = values[:m, :n].reshape(m // side, side, n // side, side, -1).mean(axis=(1, 3))
    mask, contrast = threshold_mask(values, auto_mu(values))
    if contrast <= 0:
        return "bright"
    return "bright" if np.mean(values[mask]) > np.mean(values[~mask]) else "dark"


def _pointed_in(solution, drawn):
    """The crop box of a solution, and there its objects, their labels (all of them, specks too)
    and the id of the one the drawn region points at, of those of ``min_size`` at least
    (:func:`pointed_label`; 0 for none)."""
    part, result = solution.problem, solution.result
    r0, c0, r1, c1 = box = part.box
    objects, labels, table = find_objects(result.contours, (r1 - r0, c1 - c0),
                                          _pixels(part.image, drawn.shape)[r0:r1, c0:c1],
                                          separate=bool(part.settings.separate))
    # the least size is the same in the working frame: mu and the squared contrast scale alike
    least = _min_size(part.settings.min_size, part.working.mu, [result.c_out, result.c_in], result.success)
    eligible = np.concatenate([[False], table["area"] >= least])
    return box, objects, labels, pointed_label(np.where(eligible[labels], labels, 0), drawn[r0:r1, c0:c1])


def _min_size(setting, mu, constants, stationary):
    """The least area of an object: ``min_size``, or for ``"auto"``
    :func:`~activecontour.objects.measure.default_min_size` of ``mu`` and the regions' constants
    when the run converged (``stationary``).  The length term removes a smaller disk only at a
    stationary point of (6.38); a run stopped before one (``max_num_iter=0`` returns the start
    itself, whose constants may be nearly equal) keeps every piece of at least
    ``DEFAULT_INIT_MIN_AREA`` px^2."""
    if not is_auto(setting):
        return float(setting)
    return float(default_min_size(mu, constants) if stationary else DEFAULT_INIT_MIN_AREA)


def _near_edge(neighbourhood, box):
    """The pixels of ``box`` (r0, c0, r1, c1) within ``ROI_APART`` px of the outside of the bool
    ``neighbourhood`` (the image's border is no edge): where an object is cut by the edge, though
    the flow stopped short of it (the pixels beyond read as background,
    :func:`~activecontour.imaging.roi.restrict_values`)."""
    import scipy.ndimage

    r0, c0, r1, c1 = box
    pad = int(np.ceil(ROI_APART)) + 1
    m, n = neighbourhood.shape
    low, high = (max(r0 - pad, 0), max(c0 - pad, 0)), (min(r1 + pad, m), min(c1 + pad, n))
    # beyond the window is inside: at the image's border no edge, elsewhere farther than ROI_APART
    window = np.pad(neighbourhood[low[0]:high[0], low[1]:high[1]], 1, constant_values=True)
    near = scipy.ndimage.distance_transform_edt(window)[1:-1, 1:-1] <= ROI_APART
    return near[r0 - low[0]:r1 - low[0], c0 - low[1]:c1 - low[1]]


def _pixels(image, shape):
    """The input image channel-last, (M, N[, C]) of ``shape`` (a channel-first stack moved)."""
    pixels = np.asarray(image)
    return pixels if pixels.shape[:2] == tuple(shape) else np.moveaxis(pixels, 0, -1)


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
    """``(contours, mask, phi, roi)`` of a result on a crop in the whole image's frame (the result's
    own without a crop)."""
    if box is None:
        return result.contours, result.mask, result.phi, None
    r0, c0, r1, c1 = box
    offset = np.array([r0, c0], dtype=np.float64)
    contours = [c + offset for c in result.contours]
    mask = np.zeros(shape, dtype=bool)
    mask[r0:r1, c0:c1] = result.mask
    phi = None
    if result.phi is not None:
        phi = np.full(shape, min(float(result.phi.min()), -1.0))
        phi[r0:r1, c0:c1] = result.phi
    roi = np.zeros(shape, dtype=bool)
    roi[r0:r1, c0:c1] = True if domain is None else domain
    return contours, mask, phi, roi


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


def _smooth_light(problem, init, run):
    """``fit="smooth"``: alternate the backend's run (light fixed) and the light's update
    (partition and constants fixed: least squares, or the Poisson likelihood's optimum), the
    noise model's two parts (:attr:`activecontour.problem.Problem.noise_model`).  Returns the
    result, its image model and parameters, and the light field (None: uniform).

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
    constant fit.  When that is the constant fit's own result, the light is None.
    """
    from activecontour.imaging.noise import MU_PER_NOISE_VARIANCE
    from activecontour.models.smooth import LIGHT_TERMS

    values = problem.values
    fit_light = problem.noise_model[1]
    noise = problem.auto_mu / MU_PER_NOISE_VARIANCE
    worth = noise * (LIGHT_TERMS - 1) * np.log(values.shape[0] * values.shape[1])
    plain = (*problem.model(), None)
    result = run(plain[0], init, plain[1])
    new, drop = fit_light(values, *_classes_and_constants(result), plain[1])
    if drop <= worth:
        return result, plain[0], plain[1], None
    one_region = np.zeros(values.shape[:2], dtype=np.intp)
    whole_light = fit_light(values, one_region, np.ones((1, values.shape[2])), plain[1])[0]
    lit = (*problem.model(whole_light), whole_light)
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
        model, model_params = problem.model(light)
        result = run(model, result, model_params)
        runs.append((result, model, model_params, light))
        if result.energy >= before:  # the backend's run did not descend from the light step
            break
    return min(runs, key=lambda entry: entry[0].energy)


def _classes_and_constants(result):
    """A result's regions and their constants (two regions: the inside is region 1)."""
    if result.classes is not None:
        return result.classes, result.constants
    return result.mask.astype(np.intp), np.array([np.atleast_1d(result.c_out), np.atleast_1d(result.c_in)])
