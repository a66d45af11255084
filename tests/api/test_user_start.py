"""A start the user draws converges as fast as the default start, to the same energy (global move)."""

import numpy as np
import pytest
import skimage.data

import activecontour as ac
from activecontour import synthetic


@pytest.fixture(scope="module")
def camera():
    image = skimage.data.camera()
    return image, ac.segment(image)


@pytest.mark.parametrize("init", [ac.rectangle((100, 100), (300, 300)), ac.circle((256, 256), 150)],
                         ids=["rectangle", "circle"])
def test_a_drawn_start_on_camera_converges_within_150_iterations(camera, init):
    image, default = camera
    result = ac.segment(image, init, max_num_iter=150)
    assert result.success, result.message
    assert result.n_iter <= 150
    assert result.energy <= 1.01 * default.energy
    # never worse than its start, and the energy never rose on the way
    assert result.energy <= ac.chan_vese_energy(image, [init], mu=result.mu)
    assert np.all(np.diff(result.energies) <= 0)


def test_without_the_global_move_the_flow_stays_at_the_drawn_object():
    # two disks; a circle drawn around the left one: the local flow (no nucleation either) finds
    # it alone, the global
    # move (default) both, at a lower energy
    left, left_truth = synthetic.disk_image(128, (64, 32), 14, inside=0.8, outside=0.2)
    right, right_truth = synthetic.disk_image(128, (64, 96), 14, inside=0.8, outside=0.2)
    image = synthetic.add_noise(np.maximum(left, right), 0.05, seed=2)
    init = ac.circle((64, 32), 22)
    local = ac.segment(image, init, options={"global_start": False, "nucleate": False})
    both = ac.segment(image, init)
    assert synthetic.dice(local.mask, left_truth) >= 0.97
    assert synthetic.dice(both.mask, left_truth | right_truth) >= 0.97
    assert both.energy < local.energy
    # a circle on the background selects the background class
    background = ac.segment(image, ac.circle((10, 64), 6))
    assert synthetic.dice(background.mask, ~(left_truth | right_truth)) >= 0.97


def test_global_start_must_be_a_bool():
    with pytest.raises(TypeError, match="global_start"):
        ac.segment(np.eye(8), ac.circle((4, 4), 2), options={"global_start": 1})
