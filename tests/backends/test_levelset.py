"""Tests of the level-set backend (activecontour/backends/levelset/).

Every expected number is derived: analytic distances, areas and lengths, Dice against the ground
truth of :mod:`activecontour.synthetic`, the thresholds of the issue (Dice >= 0.99 between the
backends and their energies within 1% by the common evaluator; Dice >= 0.97 for topology).
"""

import numpy as np
import pytest

import activecontour as ac
from activecontour import _kernels
from activecontour import synthetic as sy
from activecontour.backends.levelset import (
    DEFAULT_OPTIONS,
    checkerboard_level_set,
    curves_level_set,
    heaviside,
    initial_level_set,
    level_set_contours,
    signed_distance,
)
from activecontour.backends.levelset.redistancing import _redistance
from activecontour.backends.levelset.scheme import _Problem, _swept_area, _waves
from activecontour.geometry.curve import signed_area
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.models import ChanVeseParameters

MU = 0.5


def _circle_distance(shape, center, radius):
    rr, cc = np.indices(shape, dtype=np.float64)
    return radius - np.hypot(rr - center[0], cc - center[1])


def _levelset(image, init=None, **kwargs):
    kwargs.setdefault("mu", MU)
    kwargs.setdefault("normalize", None)  # MU is in the units of the rendered intensities
    return ac.segment(image, init, backend="levelset", **kwargs)


# ---------------------------------------------------------------------------------------------
# The regularised Heaviside and delta


@pytest.mark.parametrize("epsilon", [1.0, 1.5, 2.0])
def test_integer_translates_give_exact_length_and_area(epsilon):
    # The Fourier transform of H_eps' vanishes at 2 pi k for integer or half-integer eps >= 1,
    # so sum_j H_eps(s - j) = the exact length of {x < s}: what the swept area relies on.
    offsets = np.random.default_rng(0).uniform(-0.5, 0.5, size=50)
    grid = np.arange(-20, 21)
    for s in offsets:
        # cells [j - 1/2, j + 1/2] for j = -20..20 cover [-20.5, 20.5]; {x < s} has length s + 20.5
        assert np.sum(heaviside(s - grid, epsilon)) == pytest.approx(s + 20.5, abs=1e-12)


# ---------------------------------------------------------------------------------------------
# Signed distance, reinitialisation and contours


def test_curves_level_set_is_the_distance_to_a_circle():
    shape, center, radius = (96, 96), (47.3, 49.6), 25.2
    exact = _circle_distance(shape, center, radius)
    phi = curves_level_set([ac.circle(center, radius, n=720)], shape, band=4.0)
    near = np.abs(exact) < 3.0
    # the 720-gon is within R (1 - cos(pi/720)) < 3e-4 px of the circle, and the distance to it
    # is exact in the band
    assert np.max(np.abs(phi - exact)[near]) < 1e-3
    assert np.all(np.abs(phi) <= 4.0)
    np.testing.assert_array_equal(phi > 0, exact > 0)


def test_reinitialisation_keeps_the_zero_set_and_restores_the_distance():
    shape, center, radius = (96, 96), (48.5, 47.2), 30.0
    exact = _circle_distance(shape, center, radius)
    rr, cc = np.indices(shape)
    gain = 1.5 + 0.3 * np.sin(rr / 9.0) * np.cos(cc / 11.0)  # |grad gain| <= 0.3 / 9
    phi = signed_distance(gain * exact, band=5.0)
    np.testing.assert_array_equal(phi > 0, exact > 0)
    # Marching squares puts the zero of gain * d within h^2 |phi''| / (8 |phi'|) of the circle,
    # with phi''/phi' <= 2 |grad gain| / gain + kappa = 2 (0.3/9) / 1.2 + 1/30: below 0.02 px;
    # the chords of the circle add R (1 - cos(h / (2R))) ~ h^2 / (8 R) < 0.005 px.
    near = np.abs(exact) < 3.0
    assert np.max(np.abs(phi - exact)[near]) < 0.025
    # idempotent up to the chord error: a signed distance is its own reinitialisation
    again = signed_distance(phi, band=5.0)
    assert np.max(np.abs(again - phi)[near]) < 0.01


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_reinitialisation_over_its_input_is_the_reinitialisation_into_a_new_array(dtype):
    # the start's array, which nothing else reads, takes the reinitialised phi: the same values
    rng = np.random.default_rng(5)
    phi = _circle_distance((60, 70), (31.2, 33.9), 17.3) + rng.normal(scale=0.3, size=(60, 70))
    phi = phi.astype(dtype)
    expected = _redistance(phi.copy(), 4.0, dtype=dtype)
    state = _redistance(phi, 4.0, dtype=dtype, overwrite=True)
    assert state.phi is phi
    np.testing.assert_array_equal(state.phi, expected.phi)
    np.testing.assert_array_equal(state.near_flat, expected.near_flat)
    kept = phi.astype(np.float64)  # a dtype other than the result's is left alone
    assert _redistance(kept, 4.0, dtype=np.float32, overwrite=True).phi is not kept


@pytest.mark.parametrize("band", [np.inf, 3.0])
def test_a_level_set_positive_everywhere_is_the_distance_to_the_domain_edge(band):
    # the zero set of a region that fills the image is the domain's edge, half a pixel beyond the
    # outermost pixel centres (where level_set_contours closes it)
    shape = (9, 14)
    rows, cols = np.indices(shape, dtype=np.float64)
    edge = np.minimum(np.minimum(rows, shape[0] - 1 - rows), np.minimum(cols, shape[1] - 1 - cols)) + 0.5
    np.testing.assert_allclose(signed_distance(np.full(shape, 7.0), band), np.minimum(edge, band))
    np.testing.assert_allclose(curves_level_set([ac.rectangle((-1.0, -1.0), (9.0, 14.0))], shape, band),
                               np.minimum(edge, band))


def test_reinitialisation_keeps_a_straight_front_exactly():
    shape = (40, 50)
    rr, cc = np.indices(shape, dtype=np.float64)
    normal = np.array([np.cos(0.3), np.sin(0.3)])
    exact = 20.37 - (rr * normal[0] + cc * normal[1])  # a straight front at angle 0.3
    phi = signed_distance(3.0 * exact, band=4.0)
    # where the foot of the perpendicular lies on the grid, the zero set (which ends at the
    # outermost pixel centres) is the line itself
    foot_r, foot_c = rr + exact * normal[0], cc + exact * normal[1]
    on_grid = (foot_r >= 0) & (foot_r <= shape[0] - 1) & (foot_c >= 0) & (foot_c <= shape[1] - 1)
    near = (np.abs(exact) < 3.5) & on_grid
    np.testing.assert_allclose(phi[near], exact[near], atol=1e-9)


def test_energy_does_not_change_under_reinitialisation():
    image, _ = sy.render(sy.disk((40.4, 45.1), 20.0), (96, 96), inside=0.8, outside=0.2)
    model = ImageModel(normalize_image(image))
    problem = _Problem(model, ChanVeseParameters(mu=MU), DEFAULT_OPTIONS)
    distance = _circle_distance((96, 96), (42.0, 44.0), 25.0)
    state = _redistance(distance * (1.0 + 0.5 * np.cos(np.indices((96, 96))[0] / 6.0)) ** 2, 4.0)
    again = _redistance(state.phi, 4.0)
    first, second = problem.evaluate(state).energy, problem.evaluate(again).energy
    # E depends on phi through its zero set only, and a reinitialisation moves that set by at
    # most the chord error h^2 / (8 R) < 0.005 px; |f| <= 0.6^2 and mu, so E moves by at most
    # (0.36 + mu / R) |Gamma| 0.005 with |Gamma| = 2 pi 25
    bound = (0.36 + MU / 25.0) * 2 * np.pi * 25.0 * 0.005
    assert abs(second - first) <= bound


def _smoothed_step_problem(centres, start_centre, step=8.0):
    """Two-region problem on 200^2 with bright disks of radius 12 at ``centres``, a start circle of
    radius 15 around ``start_centre``, and the smoothed step's constants and tau there."""
    shape = (200, 200)
    image = 0.2 + 0.15 * np.indices(shape)[1] / shape[1]  # a ramp: the far field is not uniform
    for centre in centres:
        image[_circle_distance(shape, centre, 12.0) > 0] = 0.8
    image = sy.add_noise(image, 0.1, 0)
    # mu = 0.05: a smoothing length sqrt(tau mu) of about 2 px, so that the band's box is small
    problem = _Problem(ImageModel(normalize_image(image)), ChanVeseParameters(mu=0.05), DEFAULT_OPTIONS)
    state = problem.redistance(_circle_distance(shape, start_centre, 15.0).astype(np.float32))
    current = problem.evaluate(state)
    force, scale = problem.force(current.c_in, current.c_out)
    return problem, state, force, problem.time_step(step, scale)


def _whole_image_step(problem, state, force, tau):
    """Step (a) ``S (phi - tau f)`` by one DCT pair over the whole image."""
    rhs = np.empty_like(state.phi)
    form = problem.params.load_form(*force)
    mu = problem.params.mu
    _kernels.force_step(state.phi, problem.values, form.constant, form.linear, form.square, mu, tau, rhs)
    return problem._smooth(rhs, tau * mu), rhs


def test_smoothed_step_on_the_band_box_is_the_whole_image_step():
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (60.0, 60.0))
    box = problem._box(state, tau * problem.params.mu)
    assert box is not None  # the box is solved alone
    rows, cols = box
    assert (rows.stop - rows.start) * (cols.stop - cols.start) < 200 * 200 / 2
    stepped, _ = problem.step(state, force, tau, True)
    whole, rhs = _whole_image_step(problem, state, force, tau)
    # the Neumann sides lie band + 8 l beyond the band and S's kernel decays as exp(-r / l): near
    # Gamma the two differ by exp(-8) of the force's jumps, the 1e-4 px the box's docstring
    # promises (a box reaching 2 l beyond the band differs by ~5e-4 px here and fails this)
    near = np.abs(whole) < problem.band
    assert np.abs(stepped[near] - whole[near]).max() <= 1e-4
    assert np.array_equal(stepped > 0, whole > 0)  # the same zero set's sides everywhere


def test_smoothed_step_that_flips_a_far_region_is_solved_on_the_whole_image():
    # a second disk far from the start: the smoothed force outweighs the band there (a region
    # flips without a seed), so the step is the whole image's, which the band's box would miss
    problem, state, force, tau = _smoothed_step_problem([(50.0, 50.0), (150.0, 150.0)], (50.0, 50.0),
                                                        step=16.0)
    rows, cols = problem._box(state, tau * problem.params.mu)
    assert not (rows.start <= 150 < rows.stop and cols.start <= 150 < cols.stop)
    stepped, _ = problem.step(state, force, tau, True)
    whole, _ = _whole_image_step(problem, state, force, tau)
    assert stepped[150, 150] > 0
    np.testing.assert_array_equal(stepped, whole)


def _ring_problem(hole, step=1.0, mu=0.05):
    """A 1024^2 two-region problem whose band is a ring: a disk of 0.8 and radius 400 on 0.2 (with
    a hole of -1 and radius 60 at its centre when ``hole``: far darker than the outside, its force
    is five times the typical one), the start the circle of radius 400, and the smoothed step's
    constants and tau for ``step`` pixels."""
    shape, centre = (1024, 1024), (511.5, 511.5)
    image = np.where(_circle_distance(shape, centre, 400.0) > 0, 0.8, 0.2)
    if hole:
        image[_circle_distance(shape, centre, 60.0) > 0] = -1.0
    image = sy.add_noise(image, 0.1, 0)
    problem = _Problem(ImageModel(normalize_image(image)), ChanVeseParameters(mu=mu), DEFAULT_OPTIONS)
    state = problem.redistance(_circle_distance(shape, centre, 400.0).astype(np.float32))
    current = problem.evaluate(state)
    force, scale = problem.force(current.c_in, current.c_out)
    return problem, state, force, problem.time_step(step, scale)


def test_smoothed_step_along_a_ring_is_solved_on_tiles_as_on_the_whole_image():
    # the ring's box is most of the image: tiles along the band cost a fraction of it, and on
    # every tile's cell the step differs from the whole image's by exp(-8) of the force's jumps
    problem, state, force, tau = _ring_problem(hole=False)
    tiles = problem._tiles(state, tau * problem.params.mu)
    assert tiles is not None and tiles.pixels < 0.5 * 1024 * 1024
    stepped, changed = problem.step(state, force, tau, True)
    np.testing.assert_array_equal(changed, tiles.rects)
    held = np.ones(state.phi.shape, dtype=bool)  # phi is held beyond the boxes the tiles write
    for top, bottom, left, right in changed:
        held[top:bottom, left:right] = False
    np.testing.assert_array_equal(stepped[held], state.phi[held])
    assert (~held).sum() < 0.5 * (2 * 400) ** 2  # under half the ring's box (radius 400)
    whole, _ = _whole_image_step(problem, state, force, tau)
    near = np.abs(whole) < problem.band
    assert np.abs(stepped[near] - whole[near]).max() <= 1e-4
    assert np.array_equal(stepped > 0, whole > 0)  # the same sides everywhere, the interior's too


def test_smoothed_step_that_opens_a_hole_inside_the_ring_is_not_solved_on_tiles():
    # the hole lies far inside the ring, beyond every tile: the coarse grid's test sees it flip,
    # and the step is solved where the hole is
    problem, state, force, tau = _ring_problem(hole=True, mu=0.01)  # l = sqrt(tau mu) < 1 px
    tiles = problem._tiles(state, tau * problem.params.mu)
    assert tiles is not None and tiles.pixels < 0.5 * 1024 * 1024  # tiles would be cheaper
    hole = (slice(500, 524), slice(500, 524))
    assert not tiles.grid[511 // tiles.core, 511 // tiles.core]  # no tile's cell there
    whole, _ = _whole_image_step(problem, state, force, tau)
    assert (whole[hole] < 0).all()  # the whole image's step opens the hole
    stepped, _ = problem.step(state, force, tau, True)
    assert (stepped[hole] < 0).all()
    assert np.array_equal(stepped > 0, whole > 0)


def test_a_step_into_a_recycled_array_copies_phi_only_where_that_array_may_differ():
    # a rejected box step leaves its array equal to phi outside the box (and the front pixels one
    # pixel beyond it): the next step into that array copies phi there only, not the image
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (60.0, 60.0))
    stepped, box = problem.step(state, force, tau, True)
    assert isinstance(box, tuple) and box[0].stop < 199 and box[1].stop < 199
    _assert_recycled_step_leaves(problem, state, force, tau, True, stepped, (199, 199))  # beyond the box


def _assert_recycled_step_leaves(problem, state, force, tau, smoothed, stepped, pixel):
    """``stepped``, recycled, is the next step's array (with half ``tau``), which leaves ``pixel``
    (where the array was noted equal to phi) as it was, and equals a fresh problem's step."""
    problem.recycle(stepped)
    stepped[pixel] = 123.0
    again, _ = problem.step(state, force, 0.5 * tau, smoothed)
    assert again is stepped and again[pixel] == 123.0  # not copied over
    again[pixel] = state.phi[pixel]
    fresh = _Problem(problem.model, problem.params, DEFAULT_OPTIONS)
    np.testing.assert_array_equal(again, fresh.step(state, force, 0.5 * tau, smoothed)[0])


def test_a_step_on_tiles_into_a_recycled_array_copies_phi_over_the_tiles_only():
    # a rejected step on tiles leaves its array equal to phi outside the tiles' boxes (and a pixel
    # beyond them): the next step copies phi there, not over the ring's bounding box, whose
    # middle (the disk's interior, beyond every tile) is not copied over
    problem, state, force, tau = _ring_problem(hole=False)
    stepped, changed = problem.step(state, force, tau, True)
    assert changed.ndim == 2  # on tiles
    _assert_recycled_step_leaves(problem, state, force, tau, True, stepped, (511, 511))  # beyond the tiles


def test_a_step_on_the_band_into_a_recycled_array_copies_phi_over_the_band_only():
    # a rejected unsmoothed step leaves its array equal to phi but on the band's pixels and the
    # front: the next step copies phi there, not over the band's bounding box, whose middle (the
    # disk's interior, beyond the band) is not copied over
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (60.0, 60.0))
    tau = min(tau, 0.2 / problem.params.mu)  # explicit on the band (tau mu <= 1/4)
    stepped, changed = problem.step(state, force, tau, False)
    assert changed.ndim == 1  # the band's pixels
    problem.locate(stepped, state, changed)
    _assert_recycled_step_leaves(problem, state, force, tau, False, stepped, (60, 60))  # beyond the band


def test_the_coarse_force_is_made_once_per_constants_and_is_the_block_means_force():
    # a step retried with a smaller tau (the same constants) reuses the coarse grid's force; new
    # constants make it anew: f of the block means of the channels, their squares and the wall
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (60.0, 60.0))
    form = problem.params.load_form(*force)
    first = problem._coarse_force(form)
    assert problem._coarse_force(problem.params.load_form(*force)) is first
    means, squares, wall = problem._coarse_tables()
    expected = (form.constant + form.linear[0] * means[0].astype(np.float64)
                + form.square[0] * squares[0].astype(np.float64) + problem.params.mu * wall)
    np.testing.assert_allclose(first, expected, rtol=1e-5, atol=1e-6)
    other = problem.params.load_form(force[0] + 0.1, force[1])
    assert problem._coarse_force(other) is not first
    problem._coarse_forced = None  # the held step with the cached force is the one made anew
    held = problem._coarse_held(state, form, tau)
    np.testing.assert_array_equal(problem._coarse_held(state, form, tau), held)


def test_the_coarse_grid_of_an_accepted_step_remakes_the_blocks_its_tiles_changed_only(monkeypatch):
    # the block means of a state's phi are kept for its retried steps and carried to the state an
    # accepted step on tiles makes: only the blocks meeting the boxes where the two states differ
    # are made again, and the held step is bit for bit a fresh problem's
    problem, state, force, tau = _ring_problem(hole=False)
    form = problem.params.load_form(*force)
    made = []
    block_means = _kernels.block_means

    def counted(a, k, out, boxes=None, *rest):  # the number of blocks made
        met = np.ones(out.shape, dtype=bool) if boxes is None else np.zeros(out.shape, dtype=bool)
        for top, bottom, left, right in [] if boxes is None else boxes:
            met[top // k: -(-bottom // k), left // k: -(-right // k)] = True
        made.append(np.count_nonzero(met))
        return block_means(a, k, out, boxes, *rest)

    monkeypatch.setattr(_kernels, "block_means", counted)
    stepped, changed = problem.step(state, force, tau, True)
    assert changed.ndim == 2 and made == [256 * 256]  # on tiles; all blocks of the first state
    problem.step(state, force, 0.5 * tau, True)  # a retry from the same state: nothing made
    assert made == [256 * 256]
    trial = problem.finish(problem.locate(stepped, state, changed), state)
    current = problem.evaluate(trial)
    force, scale = problem.force(current.c_in, current.c_out)
    form = problem.params.load_form(*force)
    held = problem._coarse_held(trial, form, tau)
    assert len(made) == 2 and made[1] < 0.5 * 256 * 256  # the ring's blocks, not the disk's inside
    fresh = _Problem(problem.model, problem.params, DEFAULT_OPTIONS)
    np.testing.assert_array_equal(held, fresh._coarse_held(trial, form, tau))
    # the held step is S of the block means less tau f, signed by the side of each block
    means = np.empty(held.shape, dtype=np.float32)
    block_means(trial.phi, 4, means)
    expected = fresh._smooth(means - np.float32(tau) * fresh._coarse_force(form),
                             tau * problem.params.mu / 16, _waves(held.shape[0]), _waves(held.shape[1]))
    np.testing.assert_array_equal(held, np.where(trial.positive[::4, ::4], expected, -expected))


def test_sides_of_steps_into_recycled_arrays_are_the_sides_of_phi():
    # the sides of a located step are written into the sides of a state dropped before (a rejected
    # step's, or the state before an accepted one), set where the two differ: they are phi > 0,
    # and no array is made anew once two are in hand
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (58.0, 61.0))
    steps = [(True, 1.0, False), (True, 1.0, True), (True, 2.0, False), (False, 0.02, True),
             (False, 0.02, False), (True, 0.5, True), (True, 0.5, False), (True, 0.25, True)]
    seen = {id(state.positive)}
    for index, (smooth, scale, accept) in enumerate(steps):
        stepped, changed = problem.step(state, force, scale * tau, smooth)
        located = problem.locate(stepped, state, changed)
        np.testing.assert_array_equal(located.positive, stepped > 0)
        if index >= 1:
            assert id(located.positive) in seen  # a recycled one
        seen.add(id(located.positive))
        if accept:
            trial = problem.finish(located, state)
            problem.recycle(state.phi)
            problem.recycle_sides(state, trial, located)
            state = trial
            current = problem.evaluate(state)
            force, _ = problem.force(current.c_in, current.c_out)
        else:
            problem.recycle(stepped)
            problem.recycle_sides(located, state, located)
        np.testing.assert_array_equal(state.positive, state.phi > 0)


def test_steps_into_recycled_arrays_equal_steps_into_new_ones():
    # the driver's sequence (smoothed and unsmoothed steps, rejected and accepted, the arrays
    # handed back and taken again): every stepped array is the one a new problem makes, so the
    # boxes noted as the only places where a recycled array and phi differ are right
    problem, state, force, tau = _smoothed_step_problem([(60.0, 60.0)], (58.0, 61.0))
    steps = [(True, 1.0, True), (True, 2.0, False), (True, 1.0, True), (False, 0.02, False),
             (False, 0.02, True), (False, 0.01, True), (True, 0.5, True), (True, 0.5, True)]
    for smooth, scale, accept in steps:  # smoothed or not, tau's factor, accepted or not
        fresh = _Problem(problem.model, problem.params, DEFAULT_OPTIONS)
        expected, _ = fresh.step(state, force, scale * tau, smooth)
        stepped, changed = problem.step(state, force, scale * tau, smooth)
        np.testing.assert_array_equal(stepped, expected)
        located = problem.locate(stepped, state, changed)
        if accept:
            trial = problem.finish(located, state)
            assert trial.phi is stepped
            problem.recycle(state.phi)
            state = trial
            current = problem.evaluate(state)
            force, _ = problem.force(current.c_in, current.c_out)
        else:
            problem.recycle(stepped)


def test_contours_are_oriented_and_measure_the_annulus():
    shape, center = (96, 96), (48.0, 47.5)
    outer = _circle_distance(shape, center, 40.0)
    inner = -_circle_distance(shape, center, 15.0)
    phi = signed_distance(np.minimum(outer, inner), band=4.0)
    contours = level_set_contours(phi)
    areas = sorted(signed_area(c) for c in contours)
    assert len(contours) == 2
    # marching squares on a distance function: chords of a polygon inscribed within ~0.01 px
    assert areas[0] == pytest.approx(-np.pi * 15.0**2, rel=0.01)
    assert areas[1] == pytest.approx(np.pi * 40.0**2, rel=0.01)
    for contour in contours:
        assert not np.array_equal(contour[0], contour[-1])  # each vertex once


@pytest.mark.parametrize("shape", [(1, 1), (1, 6), (5, 1), (9, 14)])
def test_closed_padding_is_the_edge_padding_with_a_negative_frame(shape):
    # built in one array: np.pad's "edge" mode, the frame -|phi|, and phi = 0 moved outside
    from activecontour.backends.levelset.zeroset import _closed_padding

    rng = np.random.default_rng(3)
    phi = rng.normal(size=shape).astype(np.float32)
    phi[rng.random(shape) < 0.3] = 0.0
    padded = _closed_padding(phi)
    edge = np.pad(phi.astype(np.float64), 1, mode="edge")
    frame = np.ones(edge.shape, dtype=bool)
    frame[1:-1, 1:-1] = False
    expected = np.where(frame, -np.abs(edge), edge)
    expected[expected == 0] = -1e-300
    assert padded.dtype == np.float64
    np.testing.assert_array_equal(padded, expected)
    assert not np.signbit(padded[1:-1, 1:-1][phi > 0]).any() and (padded[frame] < 0).all()


def _marching_squares_contours(phi):
    """The zero set of phi by ``skimage.measure.find_contours`` on its box padded by
    ``_closed_padding``, as level_set_contours documents it (the reference it must equal)."""
    import skimage.measure

    from activecontour.backends.levelset.zeroset import _closed_padding

    positive = phi > 0
    rows, cols = np.flatnonzero(positive.any(axis=1)), np.flatnonzero(positive.any(axis=0))
    top, left = max(rows[0] - 1, 0), max(cols[0] - 1, 0)
    padded = _closed_padding(phi[top: rows[-1] + 2, left: cols[-1] + 2])
    curves = [c[::-1][:-1] for c in skimage.measure.find_contours(padded, 0.0)]  # "high": reversed
    # level_curves: less the padding's pixel, repeated vertices and curves of no area dropped
    curves = [c - 1.0 for c in curves]
    curves = [c[np.any(c != np.roll(c, 1, axis=0), axis=1)] for c in curves]
    return [c + (top, left) for c in curves if len(c) >= 3 and signed_area(c) != 0]


@pytest.mark.parametrize("kind", ["noise32", "noise64", "disk", "border"])
def test_contours_traced_from_the_sides_are_marching_squares_bit_for_bit(kind, monkeypatch):
    # saddles, regions touching the border, float32 and float64: the curves traced from the sides
    # and placed on their edges are find_contours's, every vertex equal, in its order; and
    # find_contours does not run (its pass over every cell of the box is what this spares)
    import skimage.measure

    rng = np.random.default_rng(11)
    references, phis = [], []
    for _ in range(25):
        m, n = rng.integers(3, 50, 2)
        if kind.startswith("noise"):
            phi = rng.normal(0.3, 1.0, (m, n)).astype(np.float32 if kind == "noise32" else np.float64)
        else:
            centre = (m * rng.random(), n * rng.random()) if kind == "disk" else (0.25, n / 2 + 0.1)
            phi = np.clip(_circle_distance((m, n), centre, min(m, n) / 3 + 1.37), -4, 4).astype(np.float32)
        if (phi > 0).any():
            phis.append(phi)
            references.append(_marching_squares_contours(phi))
    monkeypatch.setattr(skimage.measure, "find_contours", None)
    for phi, reference in zip(phis, references, strict=True):
        contours = level_set_contours(phi)
        assert len(contours) == len(reference)
        for contour, expected in zip(contours, reference, strict=True):
            assert contour.dtype == np.float64
            np.testing.assert_array_equal(contour, expected)


def test_contours_of_a_level_set_with_zeros_are_those_of_marching_squares():
    # phi = 0 at pixels: crossings at grid points, which find_contours joins by equal points; the
    # sides alone do not say how, so find_contours runs
    rng = np.random.default_rng(12)
    for _ in range(20):
        phi = rng.normal(0.3, 1.0, tuple(rng.integers(3, 40, 2))).astype(np.float32)
        phi[rng.random(phi.shape) < 0.15] = 0.0
        if (phi > 0).any():
            contours, reference = level_set_contours(phi), _marching_squares_contours(phi)
            assert len(contours) == len(reference)
            for contour, expected in zip(contours, reference, strict=True):
                np.testing.assert_array_equal(contour, expected)


def test_contour_of_a_region_touching_the_border_closes_on_the_domain_edge():
    shape = (30, 40)
    rr = np.indices(shape, dtype=np.float64)[0]
    phi = 10.25 - rr  # inside: rows 0..10, the front at row 10.25
    (contour,) = level_set_contours(phi)
    assert contour[:, 0].min() == pytest.approx(-0.5)
    assert contour[:, 1].min() == pytest.approx(-0.5) and contour[:, 1].max() == pytest.approx(39.5)
    # the region [-0.5, 10.25] x [-0.5, 39.5], less the marching-squares cuts of its corners:
    # right triangles with legs 0.5 x 0.5 at the two border corners, 0.5 x 0.25 where the front
    # meets the border
    expected = 10.75 * 40.0 - 2 * 0.5 * 0.5 * 0.5 - 2 * 0.5 * 0.5 * 0.25
    assert signed_area(contour) == pytest.approx(expected)


def test_checkerboard_init_is_a_checkerboard():
    shape, period = (64, 80), 16
    phi = initial_level_set("checkerboard", shape, band=4.0, checkerboard_period=period)
    rr, cc = np.indices(shape)
    expected = (rr // period + cc // period) % 2 == 0  # squares of period x period pixels
    np.testing.assert_array_equal(phi > 0, expected)
    np.testing.assert_array_equal(checkerboard_level_set(shape, period) > 0, expected)
    # the zero lines run half-way between pixel centres (0.5 away), cut diagonally at the
    # square corners (saddles), sqrt(2)/4 away
    assert np.min(np.abs(phi)) == pytest.approx(np.sqrt(2) / 4)


# ---------------------------------------------------------------------------------------------
# Segmentation: agreement with the polygon backend, topology, energy history


@pytest.fixture(scope="module")
def noisy_disk():
    image, truth = sy.render(sy.disk((60.3, 66.7), 30.0), (128, 128), inside=0.8, outside=0.2)
    return sy.add_noise(image, 0.1, seed=3), truth


def test_convex_object_agrees_with_the_polygon_backend(noisy_disk):
    image, truth = noisy_disk
    level = _levelset(image)
    polygon = ac.segment(image, backend="polygon", mu=MU)
    assert level.success and polygon.success
    assert sy.dice(level.mask, polygon.mask) >= 0.99
    level_energy = ac.chan_vese_energy(image, level.contours, mu=MU)
    polygon_energy = ac.chan_vese_energy(image, polygon.contours, mu=MU)
    assert abs(level_energy - polygon_energy) <= 0.01 * polygon_energy
    assert sy.dice(level.mask, truth) >= 0.99


def test_one_circle_around_two_disks_splits_into_two_contours():
    truth_shape = sy.union(sy.disk((64.0, 40.0), 22.0), sy.disk((64.0, 92.0), 20.0))
    image, truth = sy.render(truth_shape, (128, 128), inside=0.75, outside=0.25)
    image = sy.add_noise(image, 0.1, seed=5)
    result = _levelset(image, ac.circle((63.5, 65.0), 58.0))
    assert len(result.contours) == 2
    assert all(signed_area(c) > 0 for c in result.contours)
    assert sy.dice(result.mask, truth) >= 0.97


def test_annulus_ends_with_an_outer_contour_and_a_hole():
    image, truth = sy.render(sy.annulus((64.0, 64.0), 18.0, 48.0), (128, 128), inside=0.75,
                             outside=0.25)
    image = sy.add_noise(image, 0.1, seed=7)
    # the default circle (radius 48) is the outer boundary: the hole must open inside it unseeded
    result = _levelset(image)
    areas = sorted(signed_area(c) for c in result.contours)
    assert len(areas) == 2
    assert areas[0] < 0 < areas[1]
    assert areas[0] == pytest.approx(-np.pi * 18.0**2, rel=0.05)
    assert areas[1] == pytest.approx(np.pi * 48.0**2, rel=0.05)
    assert sy.dice(result.mask, truth) >= 0.97


def test_energy_history_never_increases(noisy_disk):
    image, _ = noisy_disk
    result = _levelset(image)
    energies = result.energies
    assert len(energies) == result.n_iter + 1
    assert energies[-1] == result.energy
    # every iteration ends with a reinitialisation; E depends on the zero set only, so it is
    # accounted for and the history is monotone throughout
    assert np.all(np.diff(energies) <= 0.0)
    assert energies[-1] < energies[0]


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("init", ["grid", "full"])
def test_energy_history_never_increases_not_even_by_rounding(seed, init):
    # omega < 0 and a small mu on small noisy squares: runs that end with steps which leave the
    # zero set in place (equal energies), where the last energy, recomputed from the chained
    # contours, used to exceed the one before by a rounding error (1e-15 .. 1e-14)
    rng = np.random.default_rng(seed)
    m, n = rng.integers(5, 30, 2)
    image = np.zeros((m, n))
    image[m // 4: 3 * m // 4, n // 4: 3 * n // 4] = 1.0
    image += 0.3 * rng.normal(size=(m, n))
    start = "grid" if init == "grid" else np.ones((m, n), dtype=bool)
    result = ac.segment(image, start, backend="levelset", mu=0.003, omega=-0.05)
    energies = result.energies
    assert np.all(np.diff(energies) <= 0.0)  # never up, not even in the last bit
    assert energies[-1] <= energies[0]  # never worse than the start
    assert energies[-1] == result.energy
    assert result.energy == ac.chan_vese_energy(image, result.contours, mu=0.003, omega=-0.05)


@pytest.mark.parametrize("shape", [(9, 26), (15, 37), (19, 38), (13, 23)])
def test_checkerboard_on_a_ramp_scores_its_start_as_its_contours(shape):
    # the checkerboard's zero lines pass within 1e-16 of pixel centres here; the reinitialised
    # start must score (6.38) as its own marching-squares contours do (a soup of segments
    # through values ~1e-38 once scored -180 where the contours score +30), and never go up
    from activecontour.energy import evaluate
    from activecontour.geometry.curve import stack_curves

    image = np.add.outer(np.arange(shape[0]), np.arange(shape[1])).astype(float)
    model = ImageModel(normalize_image(image))
    params = ChanVeseParameters(mu=0.003)
    problem = _Problem(model, params, DEFAULT_OPTIONS)
    start = problem.redistance(checkerboard_level_set(shape, min(shape) / 4.0))
    points, next_index, _ = stack_curves(level_set_contours(start.phi))
    chained = evaluate(model, points, next_index, params, empty_ok=True).energy
    assert problem.evaluate(start).energy == pytest.approx(chained, rel=1e-9)
    result = ac.segment(image, "checkerboard", backend="levelset", mu=0.003)
    assert np.all(np.diff(result.energies) <= 0.0)


@pytest.mark.parametrize("shape, mu", [((6, 2), "auto"), ((2, 3), 0.0), ((2, 3), 0.003)])
def test_a_flipped_checkerboard_result_is_the_phase_that_was_scored(shape, mu):
    # the checkerboard's symmetric functional takes the phase of lower energy at the end; the
    # result was -phi while the energy appended was that of -phi redistanced, whose zero set can
    # lie a fraction of a pixel away: the history then ended with a rise (issue 22)
    image = np.random.default_rng(0).random(shape)
    result = ac.segment(image, "checkerboard", backend="levelset", mu=mu)
    assert np.all(np.diff(result.energies) <= 0.0), result.energies
    assert result.energies[-1] == result.energy


@pytest.mark.parametrize("start", ["mask", "rectangle"])
def test_a_start_covering_the_whole_image_finds_the_square(start):
    # The whole image inside: Gamma is the domain's edge, and the flow must move it inwards to
    # the bright 4 x 4 square (it used to stand still and end empty)
    image = np.zeros((10, 10))
    image[3:7, 3:7] = 1.0
    init = np.ones((10, 10), bool) if start == "mask" else ac.rectangle((-0.5, -0.5), (9.5, 9.5))
    result = ac.segment(image, init, backend="levelset")
    assert result.success
    assert sy.dice(result.mask, image > 0) == 1.0
    assert result.energies[-1] < result.energies[0]


def test_a_start_covering_the_whole_image_finds_a_noisy_disk():
    image, truth = sy.render(sy.disk((30.0, 34.0), 12.0), (64, 72), inside=0.8, outside=0.2)
    image = sy.add_noise(image, 0.1, seed=3)
    result = ac.segment(image, np.ones(image.shape, bool), backend="levelset")
    assert sy.dice(result.mask, truth) >= 0.97


def test_result_fields(noisy_disk):
    image, truth = noisy_disk
    result = _levelset(image)
    assert result.backend == "levelset"
    assert result.phi.shape == image.shape
    np.testing.assert_array_equal(result.mask, result.phi > 0)
    assert result.success and result.status in (0, 4)
    # phi is the signed distance clipped to the band
    assert np.max(np.abs(result.phi)) == DEFAULT_OPTIONS["band"]
    # c_in, c_out are the region means (6.42): 0.8 and 0.2 up to the noise and the boundary
    assert result.c_in == pytest.approx(0.8, abs=0.02)
    assert result.c_out == pytest.approx(0.2, abs=0.02)


def test_level_set_result_hands_over_to_the_polygon_and_back(noisy_disk):
    image, truth = noisy_disk
    level = _levelset(image)
    level_energy = ac.chan_vese_energy(image, level.contours, mu=MU)
    finish = ac.segment(image, level, backend="polygon", mu=MU)
    # the polygon starts on the level set's contours and only descends from there
    assert ac.chan_vese_energy(image, finish.contours, mu=MU) <= level_energy
    assert sy.dice(finish.mask, truth) >= 0.99
    back = _levelset(image, finish)
    assert sy.dice(back.mask, finish.mask) >= 0.99


def test_reuses_phi_of_a_level_set_result(noisy_disk):
    image, _ = noisy_disk
    first = _levelset(image)
    again = _levelset(image, first, max_num_iter=5)
    # the start is the converged state: the same zero set, so the same energy up to the chord
    # error of the reinitialisation (< 0.005 px on this radius-30 disk, |f| < 1: a relative
    # change below 2 pi 30 0.005 / E)
    assert abs(again.energies[0] - first.energy) <= 2 * np.pi * 30 * 0.005
    assert sy.dice(again.mask, first.mask) >= 0.999


def test_mask_and_curve_list_inits():
    image, truth = sy.render(sy.disk((50.0, 50.0), 20.0), (100, 100), inside=0.9, outside=0.1)
    mask = np.zeros((100, 100), dtype=bool)
    mask[25:75, 20:80] = True
    from_mask = _levelset(image, mask)
    from_curves = _levelset(image, [ac.rectangle((24.5, 19.5), (74.5, 79.5))])
    from_grid = _levelset(image, "grid")
    for result in (from_mask, from_curves, from_grid):
        assert sy.dice(result.mask, truth) >= 0.99


def test_checkerboard_start_finds_both_objects():
    # half-integer edges: no pixel centre lies on the rectangle's boundary
    truth_shape = sy.union(sy.disk((30.0, 30.0), 14.0), sy.rectangle((59.5, 54.5), (85.5, 88.5)))
    image, truth = sy.render(truth_shape, (100, 100), inside=0.8, outside=0.2)
    for period in (8, 16):
        result = _levelset(image, "checkerboard", options={"checkerboard_period": period})
        # the phase whose inside covers less of the image border is returned
        assert sy.dice(result.mask, truth) >= 0.97
        assert len(result.contours) == 2


def test_unequal_fitting_weights():
    # lambda_in = 2, lambda_out = 0.5 move the optimal edge to where 2 (I - 0.8)^2 = 0.5 (I - 0.2)^2,
    # I = 0.6, a third of a pixel inside the disk's anti-aliased edge: Dice about 1 - 0.33 / 15
    image, truth = sy.render(sy.disk((30.0, 30.0), 15.0), (64, 64), inside=0.8, outside=0.2)
    result = _levelset(image, mu=0.2, lambda_in=2.0, lambda_out=0.5)
    assert result.success
    assert sy.dice(result.mask, truth) >= 0.97


def test_fixed_constants_are_kept():
    image, truth = sy.render(sy.disk((40.0, 40.0), 18.0), (80, 80), inside=0.9, outside=0.1)
    result = _levelset(image, c_in=0.9, c_out=0.1)
    assert result.c_in == 0.9 and result.c_out == 0.1
    assert sy.dice(result.mask, truth) >= 0.99


def test_vector_valued_image():
    shape = sy.disk((40.0, 44.0), 18.0)
    red, truth = sy.render(shape, (80, 88), inside=0.9, outside=0.2)
    green, _ = sy.render(shape, (80, 88), inside=0.1, outside=0.6)
    image = np.stack([red, green, np.full_like(red, 0.5)], axis=2)
    result = _levelset(image, color="vector")
    assert np.shape(result.c_in) == (3,)
    assert sy.dice(result.mask, truth) >= 0.99


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
def test_image_dtypes_give_the_same_segmentation(dtype):
    image, truth = sy.render(sy.disk((30.0, 33.0), 14.0), (64, 64), inside=0.8, outside=0.2)
    if np.issubdtype(dtype, np.integer):
        image = np.round(image * np.iinfo(dtype).max).astype(dtype)
    else:
        image = image.astype(dtype)
    result = _levelset(image)
    assert sy.dice(result.mask, truth) >= 0.99


def test_callback_sees_every_iteration_and_can_stop(noisy_disk):
    image, _ = noisy_disk
    seen = []

    def callback(state):
        seen.append(state)
        return state.iteration == 3

    result = _levelset(image, callback=callback)
    assert result.status == 2 and not result.success
    assert result.n_iter == 3 and [s.iteration for s in seen] == [1, 2, 3]
    assert seen[-1].energy == pytest.approx(result.energy, rel=1e-9)  # the same contours
    np.testing.assert_array_equal(seen[-1].mask, result.mask)
    assert len(seen[-1].contours) == len(result.contours)


@pytest.mark.parametrize("dt", [0.5, 1024.0])
def test_a_first_step_outside_the_default_range_widens_it(noisy_disk, dt):
    image, truth = noisy_disk
    result = _levelset(image, options={"dt": dt})
    assert result.success and sy.dice(result.mask, truth) >= 0.99


def test_max_num_iter_zero_returns_the_start(noisy_disk):
    image, _ = noisy_disk
    result = _levelset(image, max_num_iter=0)
    assert result.n_iter == 0 and result.status == 1
    assert len(result.energies) == 1


@pytest.mark.parametrize(("omega", "expect_all"), [(0.05, False), (-0.05, True)])
def test_area_weight_shrinks_or_grows_a_flat_image(omega, expect_all):
    # On a constant image c_in = c_out = I, so f = omega everywhere: omega > 0 empties the
    # inside (status 3), omega < 0 fills the image
    image = np.full((40, 48), 0.5)
    result = _levelset(image, ac.circle((20.0, 24.0), 9.0), mu=0.05, omega=omega, max_num_iter=200)
    if expect_all:
        assert result.mask.all()
    else:
        assert result.status == 3 and not result.mask.any()


def test_a_huge_length_weight_collapses_the_contour():
    image, _ = sy.render(sy.disk((20.0, 20.0), 6.0), (40, 40), inside=0.6, outside=0.4)
    result = _levelset(image, mu=50.0)
    assert result.status == 3 and not result.success
    assert not result.mask.any() and result.contours == []


# ---------------------------------------------------------------------------------------------
# Bad input


def test_unknown_init_string():
    with pytest.raises(ValueError, match="valid strings are 'checkerboard', 'grid'"):
        _levelset(np.zeros((20, 20)), "chequerboard")


def test_unknown_option():
    with pytest.raises(TypeError, match="unknown option.*'reinit'.*valid options are .*band"):
        _levelset(np.zeros((20, 20)), options={"reinit": 3})


def test_wrong_mask_shape():
    with pytest.raises(ValueError, match=r"init mask has shape \(10, 10\).*\(20, 20\)"):
        _levelset(np.zeros((20, 20)), np.ones((10, 10), dtype=bool))


def test_wrong_phi_shape():
    image = np.zeros((20, 20))
    previous = ac.SegmentationResult(
        mask=np.ones((10, 10), bool), contours=[], c_in=1.0, c_out=0.0, energy=0.0, energies=[0.0],
        n_iter=0, status=0, backend="levelset", phi=np.ones((10, 10)),
    )
    with pytest.raises(ValueError, match=r"phi of shape \(10, 10\)"):
        _levelset(image, previous)


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"dt": -1.0}, ValueError, "'dt' must be a positive"),
        ({"band": "wide"}, TypeError, "'band' must be a number"),
        ({"band": 1.5}, ValueError, "'band' must be at least 2"),
        ({"max_backtracks": 2.5}, ValueError, "'max_backtracks' must be an integer"),
        ({"dt_max": 1.0}, ValueError, "dt_min <= dt <= dt_max"),
        ({"dt": 8.0, "dt_min": 16.0}, ValueError, "dt_min <= dt <= dt_max"),
    ],
)
def test_bad_option_values(options, error, match):
    with pytest.raises(error, match=match):
        _levelset(np.zeros((20, 20)), options=options)


def test_init_with_nothing_inside():
    # a thin rectangle between two rows of pixel centres
    with pytest.raises(ValueError, match="nothing would be inside"):
        _levelset(np.zeros((20, 20)), ac.rectangle((10.2, 2.0), (10.8, 15.0)))


@pytest.mark.slow
@pytest.mark.parametrize("case", ["two disks", "annulus"])
def test_beats_skimage_chan_vese_from_the_same_start(case):
    # the benchmark's comparison (benchmarks/bench_levelset.py) on 256 x 256 images: Dice against
    # the ground truth at least that of skimage's chan_vese, energy by the common evaluator at most
    skimage_segmentation = pytest.importorskip("skimage.segmentation")
    shapes = {
        "two disks": sy.union(sy.disk((128.0, 75.0), 40.0), sy.disk((128.0, 185.0), 35.0)),
        "annulus": sy.annulus((128.0, 128.0), 45.0, 110.0),
    }
    image, truth = sy.render(shapes[case], (256, 256), inside=0.75, outside=0.25)
    image = sy.add_noise(image, 0.15, seed=1, blur=1.0)
    mu = 0.2
    start = ac.initial.default_init(image.shape)
    ours = _levelset(image, start, mu=mu)
    scale = image.max() - image.min()  # chan_vese rescales the image to [0, 1]
    phi0 = curves_level_set(start, image.shape) / 96.0
    _, phi, _ = skimage_segmentation.chan_vese(image, mu=mu / scale**2, init_level_set=phi0, tol=1e-5,
                                               extended_output=True)
    assert sy.dice(ours.mask, truth) >= sy.dice(phi > 0, truth)
    assert ac.chan_vese_energy(image, ours.contours, mu=mu) <= ac.chan_vese_energy(
        image, level_set_contours(phi), mu=mu)


# ---------------------------------------------------------------------------------------------
# The zero set as an edge soup, and the swept area


def test_edge_soup_scores_exactly_as_the_chained_contours():
    # random phi: many components, holes, saddles and regions on the border; Green's theorem
    # makes (6.38) a sum over edges, so the unchained, oriented soup gives the same energy, area
    # and length as the marching-squares contours
    from activecontour.backends.levelset import zero_set_edges
    from activecontour.energy import evaluate
    from activecontour.geometry.curve import stack_curves

    rng = np.random.default_rng(4)
    phi = rng.normal(size=(40, 50))
    model = ImageModel(rng.uniform(size=(40, 50, 1)))
    params = ChanVeseParameters(mu=0.3)
    points, next_index, _ = stack_curves(level_set_contours(phi))
    chained = evaluate(model, points, next_index, params)
    soup = zero_set_edges(phi).reshape(-1, 2)
    edges = evaluate(model, soup, np.repeat(np.arange(1, len(soup), 2), 2), params)
    assert edges.energy == pytest.approx(chained.energy, rel=1e-12)
    assert edges.area == pytest.approx(chained.area, rel=1e-12)
    assert edges.length == pytest.approx(chained.length, rel=1e-12)


@pytest.mark.parametrize("shift", [0.1, 0.37, 1.5])
def test_swept_area_of_a_straight_front_is_exact(shift):
    # a vertical front moved by `shift` pixels sweeps shift x (number of rows), at any offset
    shape = (30, 40)
    cols = np.indices(shape, dtype=np.float64)[1]
    old = _redistance(17.3 - cols, 4.0)
    new = _redistance(17.3 + shift - cols, 4.0)
    assert _swept_area(old, new) == pytest.approx(shift * shape[0], rel=1e-9)
