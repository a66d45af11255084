import numpy as np, time, itertools
from activecontour.models.kmeans import histogram_kmeans
rng=np.random.default_rng(0)
v = np.concatenate([rng.normal(m,0.05,n) for m,n in [(0.1,5000),(0.4,3000),(0.45,200),(0.8,2000)]])
t=time.perf_counter(); th, lv = histogram_kmeans(v, 4, bins=64); print(time.perf_counter()-t, th, lv)
# brute force on bins
from skimage.filters import threshold_multiotsu
print(threshold_multiotsu(v, 4, nbins=64))
img = rng.random((512,512))
t=time.perf_counter(); histogram_kmeans(img, 6, bins=256); print(time.perf_counter()-t)
