"""Robustness of the defaults: every case from ``init=None``, ours next to the peers' defaults.

Synthetic scenes with exact ground truth (sizes 256-4096, SNR 4 to 1, dtypes, an off-centre object,
many objects touching the border, thin strokes, texture, a dim object) and scikit-image's sample
images, each segmented with defaults and no init by both backends, by
``skimage.segmentation.chan_vese`` and ``morphological_chan_vese`` with *their* defaults, and by
Otsu's threshold.  Dice is strict: the inside must be the objects.  Sample images have no ground
truth: the table shows whether the result moved from its start, the iterations and the time.

Small objects (0.1-3 % of a 512^2 image at SNR 2-5) test the default start's global split; the
user-start table runs drawn rectangles and circles on sample images and reports the iterations and
J against the default start's J.

usage: python benchmarks/bench_robust.py [--quick] [--no-peers] [--no-samples] [--backend NAME]
                                        [--init grid|circle] [--only WORD ...] [--no-user-starts]
                                        [--cpu] [--repeat N]

``--cpu`` times our runs in CPU seconds of this process (on a shared machine) instead of wall
seconds, ``--repeat N`` takes the least of N runs; with both backends the synthetic table ends
with the ratio of their times (level set / polygon, issue 24 item 4).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import activecontour as ac
from activecontour import synthetic


def _disk_image(size, center, radius, inside, outside):
    return synthetic.disk_image(size, center, radius, inside=inside, outside=outside)


def disk_scene(size, sigma=0.1, seed=0):
    """A disk of radius 0.3 size, off the centre, contrast 0.4, noise sigma per pixel."""
    image, truth = _disk_image(size, (0.45 * size, 0.55 * size), 0.3 * size, 0.7, 0.3)
    return synthetic.add_noise(image, sigma, seed), truth


def off_centre_scene(size=384, sigma=0.1, seed=1):
    """A small object in a corner, far from any centred start."""
    image, truth = _disk_image(size, (0.15 * size, 0.82 * size), 0.08 * size, 0.75, 0.35)
    return synthetic.add_noise(image, sigma, seed), truth


def many_objects_scene(size=384, sigma=0.08, seed=2):
    """Sixteen disks of different sizes and intensities, several cut by the image border."""
    rng = np.random.default_rng(seed)
    image = np.full((size, size), 0.25)
    truth = np.zeros((size, size), bool)
    centres = [(0.0, 0.1), (0.0, 0.6), (1.0, 0.35), (0.5, 1.0), (0.4, 0.0)]
    centres += [(0.2 + 0.2 * i, 0.2 + 0.25 * j) for i in range(4) for j in range(3)][:11]
    for k, (cr, cc) in enumerate(centres):
        radius = size * (0.035 + 0.03 * rng.random())
        level = 0.6 + 0.3 * (k % 4) / 3
        disk, mask = _disk_image(size, (cr * (size - 1), cc * (size - 1)), radius, level, 0.0)
        image = np.maximum(image, np.where(disk > 0, 0.25 + disk * (level - 0.25) / level, 0.0))
        truth |= mask
    return synthetic.add_noise(image, sigma, seed), truth


def strokes_scene(size=384, sigma=0.05, seed=3):
    """Thin strokes 3 px wide at contrast 0.5: a grid of lines and a diagonal."""
    r, c = np.mgrid[0:size, 0:size].astype(float)
    truth = np.zeros((size, size), bool)
    for k in range(1, 5):
        truth |= np.abs(r - k * size / 5) <= 1.0
    truth |= np.abs(c - 0.5 * size) <= 1.0
    truth |= np.abs((r - c) / np.sqrt(2)) <= 1.2
    image = 0.25 + 0.5 * truth
    return synthetic.add_noise(image, sigma, seed), truth


def texture_scene(size=384, sigma=0.05, seed=4):
    """A textured object (a grating of amplitude 0.2 around mean 0.6) on a textured background."""
    r, c = np.mgrid[0:size, 0:size].astype(float)
    base, truth = _disk_image(size, (0.5 * size, 0.45 * size), 0.28 * size, 1.0, 0.0)
    texture = 0.2 * np.sin(2 * np.pi * (r + 0.5 * c) / 6.0)
    image = 0.35 + 0.25 * base + texture * np.where(base > 0.5, 1.0, 0.5)
    return synthetic.add_noise(image, sigma, seed), truth


def dim_scene(size=384, seed=5):
    """One dim object, contrast 0.08 on a clean image (like skimage's ``cell``)."""
    image, truth = _disk_image(size, (0.55 * size, 0.62 * size), 0.1 * size, 0.38, 0.30)
    return synthetic.add_noise(image, 0.01, seed), truth


def small_object_scene(fraction, snr, size=512, seed=7):
    """One bright disk covering ``fraction`` of the image, contrast 0.4, noise 0.4 / snr."""
    radius = np.sqrt(fraction * size * size / np.pi)
    centre = np.random.default_rng(seed).uniform(radius + 5, size - radius - 5, 2)
    image, truth = _disk_image(size, tuple(centre), radius, 0.7, 0.3)
    return synthetic.add_noise(image, 0.4 / snr, seed), truth


def as_dtype(image, kind):
    """The same scene stored as a user's camera or pipeline would store it."""
    scaled = {
        "float": image,
        "float32_0_255": (image * 255).astype(np.float32),
        "uint8": np.clip(np.round(image * 255), 0, 255).astype(np.uint8),
        "uint16_12bit": np.clip(np.round(image * 4095), 0, 4095).astype(np.uint16),
        "uint16_0_235": np.clip(np.round(image * 235), 0, 235).astype(np.uint16),
        "int64": np.round(image * 1000 - 300).astype(np.int64),
    }
    return scaled[kind]


def synthetic_cases(quick=False):
    sizes = (256, 512, 1024) if quick else (256, 512, 1024, 2048, 4096)
    for size in sizes:
        yield f"disk {size} snr4", lambda size=size: disk_scene(size, 0.1)
    for snr in (2, 1):
        yield f"disk 512 snr{snr}", lambda snr=snr: disk_scene(512, 0.4 / snr)
    for kind in ("uint8", "uint16_12bit", "uint16_0_235", "int64", "float32_0_255"):
        def make(kind=kind):
            image, truth = disk_scene(384, 0.1, seed=6)
            return as_dtype(np.clip(image, 0, 1), kind), truth
        yield f"disk {kind}", make
    yield "off-centre", off_centre_scene
    yield "16 objects at border", many_objects_scene
    yield "3 px strokes", strokes_scene
    yield "texture", texture_scene
    yield "dim object", dim_scene
    for fraction, snr in SMALL_OBJECTS:
        yield f"small {100 * fraction:g}% snr{snr}", lambda f=fraction, s=snr: small_object_scene(f, s)


#: (fraction of a 512^2 image, SNR) of the one-small-object cases
SMALL_OBJECTS = [(0.001, 5), (0.001, 2), (0.003, 3), (0.01, 2), (0.015, 2.7), (0.03, 2)]
#: the user-start images and starts: a rectangle and a circle such as one draws in the viewer
USER_IMAGES = ["camera", "coins", "astronaut", "moon"]


def user_starts(shape):
    m, n = shape[:2]
    return {"rect 20-60%": ac.rectangle((0.2 * m, 0.2 * n), (0.6 * m, 0.6 * n)),
            "rect centre": ac.rectangle((0.2 * m, 0.2 * n), (0.6 * m, 0.6 * n)) + [0.2 * m, 0.2 * n],
            "circle r 30%": ac.circle(((m - 1) / 2, (n - 1) / 2), 0.3 * min(m, n)),
            "small rect": ac.rectangle((0.4 * m, 0.3 * n), (0.55 * m, 0.5 * n))}


SAMPLES = ["astronaut", "binary_blobs", "brick", "camera", "cat", "cell", "checkerboard", "chelsea",
           "clock", "coffee", "coins", "colorwheel", "grass", "gravel", "horse", "hubble_deep_field",
           "immunohistochemistry", "logo", "microaneurysms", "moon", "page", "retina", "rocket",
           "shepp_logan_phantom", "text"]


def _gray01(image):
    image = np.asarray(image)
    if image.ndim == 3:
        import skimage.color
        image = skimage.color.rgb2gray(image[..., :3])
    image = image.astype(np.float64)
    span = image.max() - image.min()
    return (image - image.min()) / span if span > 0 else image * 0


def peers(image):
    """The peers' defaults on the image (gray, range-scaled as scikit-image's chan_vese does)."""
    import skimage.filters
    import skimage.segmentation as seg

    gray = _gray01(image)
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = TIMING["clock"]()
        out["chan_vese"] = (seg.chan_vese(gray) > 0, TIMING["clock"]() - t)
        t = TIMING["clock"]()
        out["morph_cv"] = (seg.morphological_chan_vese(gray, 35) > 0, TIMING["clock"]() - t)
        t = TIMING["clock"]()
        out["otsu"] = (gray > skimage.filters.threshold_otsu(gray), TIMING["clock"]() - t)
    return out


#: how ``ours`` times a run (``--cpu``: time.process_time) and how many runs it takes the least of
TIMING = {"clock": time.perf_counter, "repeat": 1}


def ours(image, backend, init=None, **kwargs):
    if isinstance(init, str) and init == "circle":
        m, n = image.shape[:2]
        init = ac.circle(((m - 1) / 2, (n - 1) / 2), 3 / 8 * min(m, n))
    clock, best = TIMING["clock"], np.inf
    for _ in range(TIMING["repeat"]):
        t = clock()
        res = ac.segment(image, init, backend=backend, **kwargs)
        best = min(best, clock() - t)
    return res, best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="sizes up to 1024 only")
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--no-samples", action="store_true")
    ap.add_argument("--backend", action="append", help="polygon and/or levelset (default both)")
    ap.add_argument("--only", nargs="*", help="case names containing these words")
    ap.add_argument("--init", choices=("grid", "circle"), help="another start than the default")
    ap.add_argument("--no-user-starts", action="store_true",
                    help="skip the drawn starts on sample images (J and iterations vs the default start)")
    ap.add_argument("--cpu", action="store_true", help="time our runs in CPU seconds (a shared machine)")
    ap.add_argument("--repeat", type=int, default=1, help="the least time of N runs of ours (default 1)")
    args = ap.parse_args()
    TIMING.update(clock=time.process_time if args.cpu else time.perf_counter, repeat=max(1, args.repeat))
    backends = args.backend or ["polygon", "levelset"]
    both = {"polygon", "levelset"} <= set(backends)
    ac.segment(np.random.default_rng(0).random((64, 64)))  # load the compiled kernels

    names = ["case"] + [f"{b} dice" for b in backends] + [f"{b} s" for b in backends]
    if not args.no_peers:
        names += ["chan_vese", "morph_cv", "otsu", "t_cv/t_poly"]
    if both:
        names.append("t_ls/t_poly")
    print(" | ".join(names))
    worst = {b: 1.0 for b in backends}
    for name, make in synthetic_cases(args.quick):
        if args.only and not any(w in name for w in args.only):
            continue
        image, truth = make()
        row, times, seconds = [name], [], {}
        for backend in backends:
            res, elapsed = ours(image, backend, args.init)
            d = synthetic.dice(res.mask, truth)
            worst[backend] = min(worst[backend], d)
            row.append(f"{d:.4f}{'' if res.success else '*'} ({res.n_iter} it)")
            times.append(f"{elapsed:.2f}")
            seconds[backend] = elapsed
        row += times
        if not args.no_peers and image.size <= 1024**2:
            found = peers(image)
            row += [f"{synthetic.dice(m, truth):.4f}" for m, _ in found.values()]
            row.append(f"{found['chan_vese'][1] / float(times[0]):.1f}x")
        if both:
            row.append(f"{seconds['levelset'] / seconds['polygon']:.2f}x")
        print(" | ".join(row), flush=True)
    print("worst synthetic Dice:", {b: round(v, 4) for b, v in worst.items()}, "(* = not success)")
    import skimage.data

    if not args.no_user_starts:
        user_start_table(backends, args.only)
    if args.no_samples:
        return

    print("\nsample | backend | pixels changed from the start | n_iter | s | message")
    for name in SAMPLES:
        if args.only and not any(w in name for w in args.only):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            loader = getattr(skimage.data, name)
            image = loader(rng=1) if name == "binary_blobs" else loader()
        for backend in backends:
            res, elapsed = ours(image, backend, args.init)
            start, _ = ours(image, backend, args.init, max_num_iter=0)
            moved = np.count_nonzero(res.mask != start.mask)
            print(f"{name} | {backend} | {moved} | {res.n_iter} | {elapsed:.2f} | {res.message[:50]}",
                  flush=True)


def user_start_table(backends, only):
    """Drawn starts on sample images: iterations and J against the default start's J."""
    import skimage.color
    import skimage.data

    print("\nuser start | backend | n_iter | J / J(default start) | s | message")
    for name in USER_IMAGES:
        if only and not any(w in name for w in only):
            continue
        image = getattr(skimage.data, name)()
        if image.ndim == 3:
            image = skimage.color.rgb2gray(image)
        for backend in backends:
            default, _ = ours(image, backend)
            for start_name, start in user_starts(image.shape).items():
                res, elapsed = ours(image, backend, start)
                print(f"{name} {start_name} | {backend} | {res.n_iter} | {res.energy / default.energy:.4f} | "
                      f"{elapsed:.2f} | {res.message[:40]}", flush=True)


if __name__ == "__main__":
    main()
