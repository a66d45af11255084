import numpy as np
import activecontour as ac, skimage.data
from activecontour.backends import labelfield as lf
from activecontour.image import normalize_image
p = skimage.data.shepp_logan_phantom()
levels = np.array([0, 0.098, 0.2, 0.298, 0.4, 1.0])
truth = np.argmin(np.abs(p[...,None]-levels), axis=-1)
r,c = np.nonzero(truth==1); print(r.min(), r.max(), c.min(), c.max())
v = normalize_image(p)
L0 = lf.order_classes(lf.initial_classes(v,6), v, 6)
for k in range(6): print(k, (L0==k).sum(), (truth==k).sum(), ((L0==k)&(truth==k)).sum(), p[L0==k].mean())
res = ac.segment(p, n_regions=6, backend="levelset")
for k in range(6): print(k, (res.classes==k).sum(), ((res.classes==k)&(truth==k)).sum())
print(res.mu)
