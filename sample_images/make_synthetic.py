"""Regenerate the sample images: synthetic ones with their ground truth, and two scikit-image ones.

Run from anywhere: ``python sample_images/make_synthetic.py``.  The output is deterministic (fixed
noise seeds; the same bytes for the same numpy/OpenCV versions).

Synthetic images (activecontour.synthetic: anti-aliased shapes, each pixel the covered fraction of
its square, then Gaussian blur and noise with a fixed seed, clipped to [0, 1], stored as 8-bit PNG):

``disk_noisy.png``
    256 x 256, an off-centre disk of radius 60 at (row, col) = (120, 140), intensity 0.7 on 0.3
    (contrast 0.4), noise sigma 0.25, seed 0.  The default parameters segment it well.
``shapes.png``
    256 x 256, a five-armed star, a rectangle and a ring (one hole), intensity 0.75 on 0.25, blur
    1 pixel, noise sigma 0.1, seed 1.  Three components and a hole: a test for topology.

``<name>_truth.png`` is the ground truth, 255 where the pixel centre lies inside the shape (the
convention of activecontour.geometry.raster.rasterize).

From scikit-image's data (see LICENSE.md): ``coins.png`` (303 x 384, unchanged) and
``camera.png`` (downscaled from 512 x 512 to 256 x 256 with anti-aliasing, to keep the folder small).
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from activecontour import synthetic
from activecontour.io import write_mask

HERE = Path(__file__).resolve().parent


def disk_noisy():
    image, truth = synthetic.render(synthetic.disk((120, 140), 60), (256, 256), inside=0.7, outside=0.3)
    return synthetic.add_noise(image, 0.25, seed=0), truth


def shapes():
    shape = synthetic.union(
        synthetic.star((80, 90), 45, amplitude=0.25, arms=5),
        synthetic.rectangle((150, 150), (220, 230)),
        synthetic.annulus((190, 70), 15, 38),
    )
    image, truth = synthetic.render(shape, (256, 256), inside=0.75, outside=0.25)
    return synthetic.add_noise(image, 0.1, seed=1, blur=1.0), truth


def to_uint8(image):
    return np.round(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def write_png(path, image):
    if not cv2.imwrite(str(path), image):
        raise OSError(f"could not write {path}")


def main(directory=HERE):
    import skimage.data
    import skimage.transform

    directory = Path(directory)
    for name, make in (("disk_noisy", disk_noisy), ("shapes", shapes)):
        image, truth = make()
        write_png(directory / f"{name}.png", to_uint8(image))
        write_mask(directory / f"{name}_truth.png", truth)
    write_png(directory / "coins.png", skimage.data.coins())
    camera = skimage.transform.resize(skimage.data.camera(), (256, 256), anti_aliasing=True)
    write_png(directory / "camera.png", to_uint8(camera))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
