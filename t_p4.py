import numpy as np, time
import activecontour as ac, skimage.data
p = skimage.data.shepp_logan_phantom()
levels = np.array([0, 0.098, 0.2, 0.298, 0.4, 1.0])
truth = np.argmin(np.abs(p[...,None]-levels), axis=-1)
for noise in (0, 0.033):
    img = p + np.random.default_rng(1).normal(0, noise, p.shape)
    res = ac.segment(img, n_regions=6, backend='levelset')
    print(noise, res.energy, res.n_iter, res.constants.ravel().round(3))
    print(np.array([[((res.classes==k)&(truth==j)).sum() for j in range(6)] for k in range(6)]))
