import numpy as np, time
import activecontour as ac
from activecontour.synthetic import *
rng=np.random.default_rng(0)
M=384
rr,cc=np.mgrid[:M,:M]
truth=np.zeros((M,M),int)
d=np.hypot(rr-192,cc-192)
truth[d<150]=1; truth[d<80]=2
img = truth*0.5/2 + 0  # levels 0, .25, .5
img = truth/2.0
sigma = 0.5/3/2  # SNR 3: contrast between neighbours 0.5 / noise
img = img + rng.normal(0, (0.5/3), img.shape)
t=time.perf_counter()
res = ac.segment(img, n_regions=3, backend="levelset")
print(time.perf_counter()-t, res.n_iter, res.status, res.energy, res.energies[:3], res.energies[-3:])
for k in range(3):
    a=res.classes==k; b=truth==k
    print(k, 2*(a&b).sum()/(a.sum()+b.sum()))
print(ac.chan_vese_energy(img, classes=res.classes, mu=res.mu), res.energy)
