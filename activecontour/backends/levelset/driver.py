"""The driver: :func:`segment_levelset`, its options, the step schedule, the stages and the result."""

from __future__ import annotations

import dataclasses

import numpy as np

from activecontour.backends.levelset.initial import checkerboard_level_set, has_phi, initial_level_set
from activecontour.backends.levelset.scheme import _Problem, _swept_area
from activecontour.backends.levelset.zeroset import level_set_contours
from activecontour.backends.options import LevelSetOptions
from activecontour.result import FlowState, build_result

#: The options' defaults as a dict (the settings :class:`_Problem` reads).
DEFAULT_OPTIONS = dataclasses.asdict(LevelSetOptions())

_STAGE_TOL = 10.0  # a smoothed-force stage ends at 10 tol: the next, finer one moves faster
_WINDOW = 3  # stages end when Gamma's mean displacement over this many iterations is small
_SETTLED = 0.02  # a smoothed-force stage has settled when Gamma moves < 2% of the step per iteration
_RECHECKS = 2  # smoothed steps tried after the unsmoothed stage ends (see segment_levelset)


# --------------------------------------------------------------------------------------------
# The backend


def segment_levelset(model, init, params, *, max_num_iter, tol, callback, options=None):
    """Minimise the Chan-Vese functional (6.38) with a level set over the pixel grid.

    Called by :func:`activecontour.segment` with ``backend="levelset"``, its ``options={...}``
    read into :class:`LevelSetOptions` (names, types, defaults, ranges and their documentation).
    The scheme, the step schedule and the energy are described in
    :mod:`activecontour.backends.levelset`.

    Parameters
    ----------
    model : activecontour.imaging.tables.ImageModel
    init : None, ndarray (K, 2), list of them, bool ndarray (M, N), SegmentationResult, or str
        None: the default start (:func:`activecontour.initial.initial_curves`).  Curves, masks
        and ``"grid"`` as for the polygon backend (pixel centres with nonzero winding are
        inside).  A result of either backend: its ``phi`` when it has one (its zero set kept
        exactly: the same energy and mask), else its contours.
        ``"checkerboard"``: squares of ``checkerboard_period`` x ``checkerboard_period`` pixels,
        at most a quarter of the image's smaller side (:func:`checkerboard_level_set`); it has no
        preferred phase, so when the functional is symmetric (omega = 0, lambda_in = lambda_out,
        c free) the phase of lower energy is returned (phi or -phi: they differ by the length
        along the image border, which the inside pays), i.e. the one whose inside touches the
        border less.
    params : activecontour.energy.ChanVeseParameters
        mu, omega, lambda_in, lambda_out and optional fixed c_in, c_out of (6.38), as for the
        polygon backend.
    max_num_iter : int
        Largest number of step attempts (accepted iterations, and stage changes without one).
    tol : float
        Pixels: the flow has converged (status 0) when the zero level set moves less than
        ``tol`` pixels per iteration (swept area over length, the mean normal displacement),
        averaged over the last three iterations of the final, unsmoothed stage's tail (its steps
        grown past ``dt_min``; see :mod:`activecontour.backends.levelset`).  The run also ends
        when no step, down to the current one halved ``max_backtracks`` times, decreases the
        energy (status 4: stationary to working precision).  Either way, continuing with a
        smaller tol changes neither the energy nor the mask measurably.
    callback : callable or None
        Called with a :class:`~activecontour.result.FlowState` (contours and ``phi``) after every
        accepted iteration; returning True stops the flow (status 2).
    options : LevelSetOptions, optional
        None: the defaults.

    Returns
    -------
    SegmentationResult
        Built by :func:`activecontour.result.build_result`: ``contours`` the zero level set
        (marching squares, outer boundaries positive, holes negative), ``mask`` their inside,
        ``energy`` (6.38) of the contours by the common evaluator, ``energies`` the same energy
        before the first and after every iteration (not increasing), and ``phi`` the final
        signed distance (clipped to the band; ``-band`` everywhere when the result is empty).
        The first energy is that of the start as the level set holds it: the zero set of the
        start's phi (a drawn curve through pixel centres, sampled on the grid), which the
        scheme starts from; the drawn curve's own (6.38) can be lower, and with
        ``max_num_iter=0`` the result is that zero set, not the curve.

    Raises
    ------
    ValueError
        For an unknown ``init`` string, a mask of the wrong shape or an init with nothing inside.
        (An init that covers the whole image is a valid start.)
    """
    options = LevelSetOptions() if options is None else options
    settings = dataclasses.asdict(options)
    settings["dt_min"], settings["dt_max"] = options.step_bounds()
    shape = tuple(model.shape)
    if isinstance(init, str) and init == "checkerboard":
        # squares of at most a quarter of the smaller side: a small image gets several of them
        period = min(settings["checkerboard_period"], max(2.0, min(shape) / 4.0))
        phi = checkerboard_level_set(shape, period)  # redistanced below
    else:
        phi = initial_level_set(init, shape, band=settings["band"], values=model.image,
                                dtype=np.float32, mu=params.mu)
    # after the start: its temporaries (the default start's) are gone before the work arrays come
    problem = _Problem(model, params, settings)
    # a result restarts where it ended; the start's array (which nothing else reads) is written over
    state = problem.redistance(phi, keep_front=has_phi(init), overwrite=True)
    del phi
    current = problem.evaluate(state)
    energies, moves = [current.energy], []
    # step: pixels of travel at the typical force; ceiling: the largest step of this stage.  The
    # first step is at most the width of the start's regions (the smaller area over the length):
    # a larger one jumps past the start's own shapes into whatever basin it lands in.
    width = min(current.area, model.totals[0] - current.area) / max(current.length, 1.0)
    step = min(settings["dt"], max(0.5 * width, settings["dt_min"]))
    first_step, ceiling, grow, smooth_force = step, settings["dt_max"], True, True
    status, n_iter, stage_start, streak = 1, 0, 0, 0
    # When the unsmoothed stage ends, one smoothed step of the first size is tried (a recheck):
    # the unsmoothed flow stops at pixel-scale local minima that a smoothed step can leave.
    rechecks, pending = 0, None  # pending: the end status while a recheck runs
    # The unsmoothed stage's steps are <= dt_min until its motion falls below tol; then its tail
    # runs with steps up to the band, explicit only (see below), and converges when it too is slow.
    tail = False
    for _ in range(max_num_iter):
        if not state.positive.any():
            status = 3
            break
        force, scale = problem.force(current.c_in, current.c_out)
        if tail:
            step = min(step, max(settings["dt_min"], problem.explicit_limit(scale)))
        tau = problem.time_step(step, scale)
        # a smoothed-force stage whose step fails twice has reached its (biased) fixed point
        tries = 3 if smooth_force else settings["max_backtracks"] + 1
        for attempt in range(tries):  # noqa: B007 (attempt is read after the loop)
            stepped, changed = problem.step(state, force, tau, smooth_force)
            located = problem.locate(stepped, state, changed)  # scored before its band is grown
            evaluation = problem.evaluate(located)
            # Emptying or filling the image is left to the unsmoothed force: a smoothed step that
            # does it has flattened phi rather than followed the force.
            degenerate = smooth_force and (not located.positive.any() or located.positive.all())
            if evaluation.energy <= current.energy and not degenerate:
                trial = problem.finish(located, state)  # written into stepped where it has a front
                if trial.phi is not stepped:
                    problem.recycle(stepped)
                break
            problem.recycle(stepped)
            if located.phi is not stepped:  # a state without a front
                problem.recycle(located.phi)
            problem.recycle_sides(located, state, located)
            step, tau, grow = 0.5 * step, 0.5 * tau, False
        else:
            if smooth_force and pending is not None and len(moves) == stage_start:
                status = pending  # the recheck found no descent: the end stands
                break
            evaluation = None
        if evaluation is not None:
            n_iter += 1
            # mean normal displacement of Gamma in this iteration, pixels: swept area over length
            moves.append(_swept_area(state, trial, problem.scratch.mark)
                         / max(evaluation.length, current.length, 1.0))
            problem.recycle(state.phi)
            problem.recycle_sides(state, trial, located)
            state, current = trial, evaluation
            energies.append(current.energy)
            streak = streak + 1 if attempt == 0 else 0
            if callback is not None:
                flow_state = FlowState(
                    iteration=n_iter, contours=level_set_contours(state.phi), energy=current.energy,
                    c_in=current.c_in, c_out=current.c_out, shape=shape, max_num_iter=max_num_iter,
                    phi=state.phi.copy(),  # the backend reuses its arrays
                )
                if callback(flow_state):
                    status = 2
                    break
        window = moves[stage_start:][-_WINDOW:]
        ended = None  # the end status of the unsmoothed stage, when it ends here
        if not smooth_force:
            if evaluation is None:
                ended = 4  # no descent down to max_backtracks halvings: stationary
            elif len(window) == _WINDOW and np.mean(window) < tol:
                if tail or min(settings["band"], problem.explicit_limit(scale)) <= step:
                    ended = 0  # converged
                else:
                    # Steps of dt_min move a weak front (a small force against the length term)
                    # by a fraction of a pixel per iteration for dozens of iterations: less than
                    # tol per iteration is not stationary at that step.  The tail grows the step,
                    # doubling until a rejection, up to the band (where the force acts) and to the
                    # explicit limit (whose fixed point does not depend on the step).
                    tail, grow, stage_start, streak = True, True, len(moves), 0
        if ended is not None:
            if rechecks >= _RECHECKS:
                status = ended
                break
            rechecks, pending, smooth_force, tail = rechecks + 1, ended, True, False
            step = ceiling = first_step
            stage_start, streak = len(moves), 0
        elif smooth_force:
            # a smoothed-force stage has settled when Gamma moves by less than a small fraction
            # of the step (or 10 tol) per iteration; its fixed point is biased by the smoothing
            # of width sqrt(tau mu), so go on with a 4x smaller step, then unsmoothed
            settled = evaluation is None or (
                len(window) == _WINDOW and np.mean(window) < max(_STAGE_TOL * tol, _SETTLED * step))
            if settled:
                pending = None  # a recheck that moved on is a new descent, ended as usual
                ceiling = 0.25 * min(ceiling, 2.0 * step)
                if ceiling < settings["dt_min"]:
                    smooth_force, step = False, settings["dt_min"]
                else:
                    step = min(step, ceiling)
                stage_start, streak = len(moves), 0
            elif grow or streak >= 2:
                # accepted at once: speed up, doubling until the first rejection
                step = min(step * (2.0 if grow else 1.25), ceiling)
        elif grow or streak >= 2:
            step = min(step * (2.0 if grow else 1.25), settings["band"] if tail else settings["dt_min"])
    phi = state.phi
    if isinstance(init, str) and init == "checkerboard" and _symmetric(params):
        # The checkerboard has no preferred phase and the symmetric functional prefers one only
        # through the length along the image border, which the inside pays: take the phase of
        # lower energy (-phi is stationary too, but for that border term).
        # the result is the redistanced -phi that was scored, not -phi itself: its zero set can
        # differ by a fraction of a pixel, and the history would then end with a rise
        flipped_state = problem.redistance(-phi)
        flipped = problem.evaluate(flipped_state)
        if flipped.energy < current.energy:
            phi = flipped_state.phi
            energies.append(flipped.energy)
    result = build_result(model, params, level_set_contours(phi), energies=energies, n_iter=n_iter,
                          status=status, backend="levelset", phi=phi)
    if not result.mask.any():  # collapsed, or the empty set is lower: phi says the same
        return dataclasses.replace(result, phi=np.full(shape, -settings["band"], dtype=np.float32))
    return result


def _symmetric(params):
    return (params.omega == 0 and params.lambda_in == params.lambda_out
            and params.c_in is None and params.c_out is None)
