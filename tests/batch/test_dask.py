"""segment_dask on a LocalCluster of two worker processes gives exactly the serial results."""

import os

import cv2
import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.batch import segment_dask
from tests.batch.test_batch import assert_same_result, disk_images

distributed = pytest.importorskip("distributed")
da = pytest.importorskip("dask.array")

# under pytest-xdist, on one worker: the module's cluster starts once, and never beside README's
# (tests/app/test_readme.py), whose dashboard would take the same port
pytestmark = pytest.mark.xdist_group("dask")


@pytest.fixture(scope="module")
def client():
    saved = dict(os.environ)  # the nannies set OMP_NUM_THREADS etc. here for their workers
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        yield client
    os.environ.clear()
    os.environ.update(saved)


def test_a_folder_on_the_cluster_equals_the_serial_loop(client, tmp_path):
    images, truths = disk_images(3)
    for k, image in enumerate(images):
        cv2.imwrite(str(tmp_path / f"disk{k}.png"), np.round(np.clip(image, 0, 1) * 255).astype(np.uint8))
    paths = [str(tmp_path / f"disk{k}.png") for k in range(3)]
    items = list(segment_dask(tmp_path, client=client, mu=0.1))
    assert sorted(item.index for item in items) == [0, 1, 2]
    for item in items:
        assert item.ok and item.source == paths[item.index]
        assert_same_result(item.result, ac.segment(ac.load_image(paths[item.index]), mu=0.1))
        assert synthetic.dice(item.result.mask, truths[item.index]) > 0.95


def test_a_dask_array_stack_on_the_current_client(client):
    images, truths = disk_images(4)
    images[2] = np.full_like(images[2], np.nan)  # one image fails on its worker, the others do not
    stack = da.from_array(np.stack(images), chunks=(2, 24, 28))  # chunks that split the images
    items = {item.index: item for item in segment_dask(stack, max_num_iter=200)}  # client=None
    assert sorted(items) == [0, 1, 2, 3]
    assert isinstance(items[2].error, ValueError) and "NaN" in str(items[2].error)
    for index in (0, 1, 3):
        assert items[index].ok and items[index].source is None
        assert_same_result(items[index].result, ac.segment(images[index], max_num_iter=200))
        assert synthetic.dice(items[index].result.mask, truths[index]) > 0.95


def test_bad_arguments(client):
    with pytest.raises(ValueError, match=r"shape \(n, M, N\)"):
        segment_dask(da.zeros((8, 8)), client=client)
    with pytest.raises(TypeError, match="callback"):
        segment_dask([np.zeros((8, 8))], client=client, callback=print)
