import numpy as np, time
import activecontour as ac
from activecontour.backends import labelfield as lf
from activecontour.image import ImageModel, normalize_image
from activecontour.noise import auto_mu
from activecontour.models import ChanVeseParameters
from activecontour.energy import evaluate_partition
from activecontour.partition import class_boundary
rng=np.random.default_rng(0)
M=384
rr,cc=np.mgrid[:M,:M]
truth=np.zeros((M,M),int)
d=np.hypot(rr-192,cc-192)
truth[d<150]=1; truth[d<80]=2
img = truth/2.0 + rng.normal(0, (0.5/3), truth.shape)
v = normalize_image(img); model=ImageModel(v)
p = ChanVeseParameters(auto_mu(v))
E = lambda L: evaluate_partition(model, class_boundary(L), p, 3).energy
dice = lambda L: [round(2*((L==k)&(truth==k)).sum()/((L==k).sum()+(truth==k).sum()),4) for k in range(3)]
L0 = lf.order_classes(lf.initial_classes(v,3), v, 3)
print('truth', E(truth), 'init', E(L0), dice(L0))
cost = np.stack([f.density(v) for f in p.class_forms(lf._pixel_constants(L0, v, 3))]).astype(np.float32)
wall = np.zeros(truth.shape); 
for e in (wall[0], wall[-1], wall[:,0], wall[:,-1]): e += p.mu
cost[1:] += wall
t=time.perf_counter(); L1 = lf._polish(L0, cost, p.mu, 20); print('polish', time.perf_counter()-t, E(L1), dice(L1))
