import numpy as np, time
import activecontour as ac, skimage.data, cv2
from activecontour.backends import labelfield as lf
from activecontour.image import normalize_image
from activecontour.energy import evaluate_partition
from activecontour.partition import class_boundary
from activecontour.image import ImageModel
from activecontour.models import ChanVeseParameters
from activecontour.noise import auto_mu
from activecontour.models.kmeans import histogram_kmeans
def scenes():
    p = skimage.data.shepp_logan_phantom()
    levels = np.array([0, 0.098, 0.2, 0.298, 0.4, 1.0])
    truth = np.argmin(np.abs(p[...,None]-levels), axis=-1)
    for noise in (0, 0.02, 0.033):
        yield f'phantom{noise}', p + np.random.default_rng(1).normal(0, noise, p.shape), truth, 6
    M=384; rr,cc=np.mgrid[:M,:M]; t=np.zeros((M,M),int); d=np.hypot(rr-192,cc-192); t[d<150]=1; t[d<80]=2
    for snr in (3, 1.5):
        yield f'nested{snr}', t/2 + np.random.default_rng(0).normal(0, 0.5/snr, t.shape), t, 3
def init(v, K, mode):
    g = v.mean(axis=2).astype(np.float32)
    if mode=='gauss': g = cv2.GaussianBlur(g,(0,0),1.0)
    if mode=='median': g = cv2.medianBlur(g, 3)
    th,_ = histogram_kmeans(g, K)
    return np.digitize(g, th, right=True)
for name, img, truth, K in scenes():
    v = normalize_image(img); model = ImageModel(v); par = ChanVeseParameters(auto_mu(v))
    E = lambda L: evaluate_partition(model, class_boundary(L), par, K).energy
    out=[f'{name} mu={par.mu:.4f} Etruth={E(truth):.2f}']
    for mode in ('raw','gauss','median'):
        L0 = init(v,K,mode)
        t=time.perf_counter()
        res = ac.segment(img, L0.astype(np.int32), n_regions=K, backend='levelset')
        dt=time.perf_counter()-t
        d=[2*((res.classes==k)&(truth==k)).sum()/max((res.classes==k).sum()+(truth==k).sum(),1) for k in range(K)]
        out.append(f'{mode}: E={res.energy:.2f} dice={np.mean(d):.3f} min={np.min(d):.3f} t={dt:.2f} it={res.n_iter}')
    print(' | '.join(out))
