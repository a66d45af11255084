import numpy as np, time
import activecontour as ac
rng=np.random.default_rng(0)
M=384
rr,cc=np.mgrid[:M,:M]
truth=np.zeros((M,M),int)
d=np.hypot(rr-192,cc-192)
truth[d<150]=1; truth[d<80]=2
img = truth/2.0 + rng.normal(0, (0.5/3), truth.shape)
print(ac.chan_vese_energy(img, classes=truth, mu='auto'))
from activecontour.noise import auto_mu
from activecontour.image import normalize_image
print(auto_mu(normalize_image(img)))
def cb(s): print(s.iteration, s.energy)
res = ac.segment(img, n_regions=3, backend="levelset", callback=cb)
