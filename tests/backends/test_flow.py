"""The polygon backend on synthetic images with constructed ground truth."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.geometry.curve import signed_area
from activecontour.geometry.raster import rasterize

SIZE = (128, 128)
CENTER = (63.5, 64.0)
SHAPES = {
    "disk": synthetic.disk(CENTER, 30.0),
    "square": synthetic.rectangle((36.3, 38.6), (90.4, 91.2)),
    "star": synthetic.star(CENTER, 34.0, amplitude=0.25, arms=5),
}
# an init that contains each object, and one that lies inside it
OUTER_INIT = ac.circle(CENTER, 56.0)
INNER_INIT = ac.circle(CENTER, 12.0)


def shape_image(name, *, noise=0.0, seed=0, blur=0.0, inside=0.7, outside=0.3):
    image, truth = synthetic.render(SHAPES[name], SIZE, inside=inside, outside=outside)
    return synthetic.add_noise(image, noise, seed, blur=blur) if (noise or blur) else image, truth


@pytest.mark.parametrize("name", sorted(SHAPES))
@pytest.mark.parametrize("init", [OUTER_INIT, INNER_INIT], ids=["outer", "inner"])
@pytest.mark.parametrize("noise, seed, blur", [(0.0, 0, 0.0), (0.2, 11, 0.0), (0.1, 12, 1.5)])
def test_dice_against_ground_truth(name, init, noise, seed, blur):
    image, truth = shape_image(name, noise=noise, seed=seed, blur=blur)
    result = ac.segment(image, init)
    assert result.success, result.message
    assert synthetic.dice(result.mask, truth) >= 0.98


def test_noise_free_disk_contour_is_within_a_quarter_pixel_of_the_circle():
    radius = 30.0
    image, _ = shape_image("disk")
    for init in (OUTER_INIT, INNER_INIT):
        result = ac.segment(image, init)
        (contour,) = result.contours
        distance = np.hypot(contour[:, 0] - CENTER[0], contour[:, 1] - CENTER[1]) - radius
        assert np.abs(distance).max() <= 0.25


@pytest.mark.parametrize("velocity", ["h1", "l2"])
def test_energy_never_increases(velocity):
    image, _ = shape_image("star", noise=0.25, seed=3)
    result = ac.segment(image, OUTER_INIT, options={"velocity": velocity}, max_num_iter=300)
    assert np.all(np.diff(result.energies) <= 0.0)
    assert result.energies[-1] == result.energy
    assert len(result.energies) == result.n_iter + 1


def test_l2_velocity_segments_a_clean_image():
    # The L^2 form (6.25) has no smoothing: the fastest vertex caps each step, so it is slow in
    # noise (hence H^1 by default), but it minimises the same functional.
    image, truth = shape_image("disk")
    result = ac.segment(image, OUTER_INIT, options={"velocity": "l2"}, max_num_iter=2000)
    assert synthetic.dice(result.mask, truth) >= 0.98


def test_result_follows_the_conventions():
    image, _ = shape_image("disk", noise=0.1, seed=4)
    result = ac.segment(image)
    assert result.backend == "polygon" and result.phi is None
    assert result.mask.dtype == bool and result.mask.shape == SIZE
    assert all(signed_area(c) > 0 for c in result.contours)
    np.testing.assert_array_equal(result.mask, rasterize(result.contours, SIZE))
    # c_in, c_out are the region means (6.42): in the input's units close to the rendered
    # intensities, and in the normalised units the same affine map of them
    assert result.c_in_image == pytest.approx(0.7, abs=0.02)
    assert result.c_out_image == pytest.approx(0.3, abs=0.02)
    low, high = image.min(), image.max()
    assert result.c_in == pytest.approx((result.c_in_image - low) / (high - low), rel=1e-12)
    assert "SegmentationResult" in repr(result)


def test_fixed_constants_are_kept():
    image, truth = shape_image("disk", noise=0.1, seed=5)
    result = ac.segment(image, OUTER_INIT, c_in=0.7, c_out=0.3)
    assert (result.c_in, result.c_out) == (0.7, 0.3)
    assert synthetic.dice(result.mask, truth) >= 0.98


def test_a_larger_mu_gives_a_shorter_contour():
    image, _ = shape_image("star", noise=0.1, seed=6)
    lengths = []
    for mu in (0.1, 1.0):  # mu |star| ~ 250 stays below the fit the star gains, ~450 (see below)
        (contour,) = ac.segment(image, OUTER_INIT, mu=mu).contours
        lengths.append(np.sum(np.linalg.norm(np.roll(contour, -1, 0) - contour, axis=1)))
    assert lengths[1] < lengths[0]


def test_a_length_weight_above_the_objects_gain_gives_the_empty_set():
    # the empty set costs sum (I - mean)^2; the true star saves A (1 - A/|D|) (c_in - c_out)^2 of
    # it, about 450 here, at a length of about 250 px: from mu = 3 on, nothing beats the empty set
    image, truth = shape_image("star")
    area, total = truth.sum(), truth.size
    gain = area * (1 - area / total) * (0.7 - 0.3) ** 2
    perimeter = ac.segment(image, OUTER_INIT, mu=0.01, normalize=None).contours
    mu = 1.5 * gain / sum(np.sum(np.linalg.norm(np.roll(c, -1, 0) - c, axis=1)) for c in perimeter)
    result = ac.segment(image, OUTER_INIT, mu=mu, normalize=None)
    assert result.status == 3 and result.contours == [] and not result.mask.any()
    empty = np.sum((image - image.mean()) ** 2)
    # the pixel sum approximates the bilinear integral up to the anti-aliased rim (~1 %)
    assert result.energy == pytest.approx(empty, rel=2e-2)
    assert result.c_in == result.c_out == pytest.approx(image.mean(), rel=1e-3)


def test_positive_omega_shrinks_the_inside():
    image, _ = shape_image("disk", noise=0.05, seed=7)
    areas = [ac.segment(image, OUTER_INIT, omega=w).mask.sum() for w in (0.0, 0.05)]
    assert areas[1] < areas[0]


def test_callback_sees_every_iteration_and_can_stop():
    image, _ = shape_image("disk")
    seen = []

    def callback(state):
        seen.append((state.iteration, state.energy, state.mask.sum()))
        return state.iteration == 3

    result = ac.segment(image, OUTER_INIT, callback=callback)
    assert [s[0] for s in seen] == [1, 2, 3]
    assert result.status == 2 and not result.success and result.n_iter == 3
    assert seen[-1][1] == result.energy


def test_zero_iterations_returns_the_initial_curve():
    image, _ = shape_image("disk")
    result = ac.segment(image, OUTER_INIT, max_num_iter=0)
    assert result.n_iter == 0 and result.status == 1 and len(result.energies) == 1
    assert signed_area(result.contours[0]) == pytest.approx(np.pi * 56.0**2, rel=1e-3)


def test_flat_image_makes_the_contour_collapse():
    result = ac.segment(np.full(SIZE, 0.5), INNER_INIT)
    assert result.status == 3 and not result.success


def test_two_initial_curves_find_two_objects():
    shape = synthetic.union(synthetic.disk((40, 40), 15), synthetic.disk((85, 90), 18))
    image, truth = synthetic.render(shape, SIZE)
    result = ac.segment(image, [ac.circle((40, 40), 24), ac.circle((85, 90), 28)])
    assert len(result.contours) == 2
    assert synthetic.dice(result.mask, truth) >= 0.98


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
def test_image_dtypes(dtype):
    image, truth = shape_image("disk", noise=0.05, seed=8)
    image = np.clip(image, 0, 1)
    if np.issubdtype(dtype, np.integer):
        image = np.round(image * np.iinfo(dtype).max)
    result = ac.segment(image.astype(dtype), OUTER_INIT)
    assert synthetic.dice(result.mask, truth) >= 0.98


@pytest.mark.parametrize("channels", [3, 4])
def test_colour_images_in_gray(channels):
    image, truth = shape_image("disk", noise=0.05, seed=9)
    rgb = np.repeat(image[:, :, None], channels, axis=2)
    if channels == 4:
        rgb[:, :, 3] = 1.0
    assert synthetic.dice(ac.segment(rgb, OUTER_INIT).mask, truth) >= 0.98


def test_mask_init_and_result_init():
    image, truth = shape_image("square", noise=0.1, seed=10)
    start = np.zeros(SIZE, dtype=bool)
    start[50:80, 50:80] = True
    first = ac.segment(image, start, max_num_iter=5)
    result = ac.segment(image, first)  # a result is a valid init
    assert synthetic.dice(result.mask, truth) >= 0.98


def test_a_lobe_still_moving_holds_the_stop_while_the_mean_is_below_tol():
    # a circle of radius 300 px (2000 vertices) whose curve is still but for 4 neighbouring vertices
    # moving out by 0.2 px per iteration: the mean normal displacement (4 * 0.2 / 2000 = 4e-4 px per
    # iteration) is below tol = 5e-4, yet a part of the curve is on its way: not a slow block
    from activecontour.backends.polygon import _WINDOW, _Movement
    from activecontour.geometry.curve import stack_curves

    tol = 5e-4
    points, next_index, offsets = stack_curves([ac.circle((400.0, 400.0), 300.0, n=2000)])
    outward = points - np.array([400.0, 400.0])
    outward /= np.hypot(outward[:, 0], outward[:, 1])[:, None]
    moving = np.zeros(len(points), bool)
    moving[100:104] = True
    for speed, slow in ((0.2, 0), (0.0, 1)):  # the lobe moving; then nothing moving at all
        movement = _Movement()
        for k in range(_WINDOW + 1):
            movement.add((points + k * speed * moving[:, None] * outward, next_index, offsets))
        assert len(movement.blocks) == 1
        assert movement.still(tol) == slow


def test_lbfgs_direction_is_the_two_loop_product_of_the_dense_inverse_hessian():
    """The accelerated direction is -H f, with H built densely from its definition: H_0 = gamma b^-1
    (gamma = s.y / y.b^-1 y of the last pair), then H <- V^T H V + rho s s^T, V = I - rho y s^T,
    for each stored pair (s, y) in order; held components are zero."""
    from activecontour.backends.polygon import _Memory
    from activecontour.geometry import fem
    from activecontour.geometry.curve import stack_curves

    rng = np.random.default_rng(3)
    curves = [ac.circle((20.0, 20.0), 9.0, n=40), ac.circle((60.0, 50.0), 6.0, n=25)]
    points, next_index, offsets = stack_curves(curves)
    k = len(points)
    previous = np.arange(-1, k - 1)
    previous[offsets[:-1]] = offsets[1:] - 1
    h = np.hypot(*(points[next_index] - points).T)
    mass, stiff = fem.mass_diagonals(h, previous), fem.stiffness_diagonals(h, previous)
    diagonal, off = mass[0] + 4.0 * stiff[0], mass[1] + 4.0 * stiff[1]

    def velocity(geometry, load):
        return -fem.cyclic_solve(diagonal, off, load, offsets)

    # the dense metric on the raveled (row, col) components: one block per curve, per component
    block = np.zeros((k, k))
    for a, b in zip(offsets[:-1], offsets[1:], strict=True):
        block[a:b, a:b] = fem.cyclic_matrix(diagonal[a:b], off[a:b]).toarray()
    metric = np.kron(block, np.eye(2))
    hessian = np.diag(rng.uniform(1.0, 3.0, 2 * k))  # y = hessian s: positive curvature
    memory = _Memory(True, size=4)
    geometry = (points, next_index, offsets)
    load = rng.normal(size=(k, 2))
    for _ in range(6):  # more pairs than the memory holds: the oldest go
        moved = (points + rng.normal(scale=0.1, size=points.shape), next_index, offsets)
        new_load = load + (hessian @ (moved[0] - points).ravel()).reshape(k, 2)
        memory.remember(geometry, moved, load, new_load)
        geometry = (moved[0], next_index, offsets)
        points, load = moved[0], new_load
    held = np.zeros((k, 2), dtype=bool)
    held[[0, 7, 50], [0, 1, 1]] = True
    force = np.where(held, 0.0, rng.normal(size=(k, 2)))

    s_last, y_last = memory.pairs[-1][:2]
    inverse = np.linalg.inv(metric)
    dense = (s_last @ y_last) / (y_last @ inverse @ y_last) * inverse
    for s, y, _ in memory.pairs:
        rho = 1.0 / (s @ y)
        v = np.eye(2 * k) - rho * np.outer(y, s)
        dense = v.T @ dense @ v + rho * np.outer(s, s)
    expected = -(dense @ force.ravel()).reshape(k, 2)
    expected[held] = 0.0

    direction = memory.direction(geometry, force, held, velocity)
    assert len(memory.pairs) == 4
    assert direction is not None and np.sum(force * direction) < 0
    np.testing.assert_allclose(direction, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_border_clip_and_held_components_column_by_column():
    """The line search's clip to the image domain and the held components (vertices on the border
    pushed outward) are numpy's broadcast expressions, number for number, including vertices
    exactly on the border and beyond it."""
    from activecontour.backends.polygon import _clipped, _held

    rng = np.random.default_rng(3)
    low, high = np.array([-0.5, -0.5]), np.array([19.5, 29.5])
    points = rng.uniform(-3.0, 33.0, size=(400, 2))
    points[::7] = low
    points[3::11] = high
    points[5::13, 1] = high[1]
    load = rng.normal(size=points.shape)
    load[::17] = 0.0
    expected = ((points <= low) & (load > 0)) | ((points >= high) & (load < 0))
    np.testing.assert_array_equal(_held(points, load, low, high), expected)
    assert expected.any() and not expected.all()
    np.testing.assert_array_equal(_clipped(points.copy(), low, high), np.clip(points, low, high))
