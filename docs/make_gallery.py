"""Write the gallery: the default segmentation of real sample images, as the command line draws it.

    python docs/make_gallery.py            # writes docs/gallery/*.png and docs/gallery.md

Every image goes through ``activecontour.segment(image)`` with all its defaults (no init, mu
"auto", the polygon backend), exactly as ``activecontour segment IMAGE`` does, and its overlay is
drawn by the command line's own writer (:func:`activecontour.io.pictures.render_overlay`: the image
shown by its own range, the contour in a colour that stands out from it), shrunk to
:data:`THUMBNAIL_SIDE` pixels with a 2 px line (the command line's "auto" width is 1 px per 1024 px
of the written side) and stored as an 8-bit palette PNG to keep the files small.  The
images are scikit-image's sample images (``skimage.data``; those that need a download are skipped
when it is not available) and the fluorescence nuclei of ``sample_images/nuclei.png`` (a uint16
image holding 0..235).  Nothing in the figures is drawn by hand; the timings are of the machine
that ran the script (printed, not written into the page).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import activecontour as ac  # noqa: E402
from activecontour.io.pictures import render_overlay  # noqa: E402

#: The longest side of a gallery figure, in pixels.
THUMBNAIL_SIDE = 360

#: (name, how to get the image, what it shows) in the order of the page.
SAMPLES = [
    ("nuclei", lambda: ac.load_image(ROOT / "sample_images" / "nuclei.png"),
     "fluorescence nuclei, uint16 holding 0..235 (DSB 2018, from stardist)"),
    ("camera", "camera", "photograph, the cameraman"),
    ("coins", "coins", "Greek coins on an unevenly lit background"),
    ("moon", "moon", "low-contrast surface of the moon"),
    ("page", "page", "a scanned page under uneven light"),
    ("text", "text", "text painted on a wall"),
    ("cell", "cell", "a cell in phase contrast"),
    ("microaneurysms", "microaneurysms", "microaneurysms in a retina photograph (gray crop)"),
    ("clock", "clock", "a clock with a shaded background"),
    ("horse", "horse", "a binary silhouette (bool)"),
    ("astronaut", "astronaut", "colour photograph (segmented as gray)"),
    ("coffee", "coffee", "a red-brown cup of coffee: the line is drawn in a contrasting colour"),
    ("chelsea", "chelsea", "a cat"),
    ("rocket", "rocket", "a rocket on its launch pad"),
    ("retina", "retina", "a fundus photograph, 1411 x 1411, mostly red"),
    ("immunohistochemistry", "immunohistochemistry", "stained tissue (colour)"),
    ("hubble_deep_field", "hubble_deep_field", "galaxies of the Hubble deep field"),
    ("logo", "logo", "the scikit-image logo, RGBA (alpha is not an intensity)"),
]


def load(source):
    """The image, or None when scikit-image needs a download that is not available."""
    if callable(source):
        return source()
    import skimage.data

    try:
        return getattr(skimage.data, source)()
    except (ModuleNotFoundError, OSError, ValueError):
        return None


def write_palette_png(path, rgb):
    """An (M, N, 3) uint8 image as an 8-bit palette PNG (256 colours chosen for the image)."""
    from PIL import Image

    Image.fromarray(rgb).quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE) \
        .save(path, optimize=True)


def main():
    out = ROOT / "docs" / "gallery"
    out.mkdir(parents=True, exist_ok=True)
    rows, skipped = [], []
    for name, source, what in SAMPLES:
        image = load(source)
        if image is None:
            skipped.append(name)
            continue
        ac.segment(image, max_num_iter=1)  # warm up: imports and compiled code are not the image's
        started = time.perf_counter()
        result = ac.segment(image)
        elapsed = time.perf_counter() - started
        write_palette_png(out / f"{name}.png", render_overlay(image, result, thickness=2,
                                                                    max_side=THUMBNAIL_SIDE))
        shape = " x ".join(str(n) for n in image.shape)
        state = "converged" if result.success else result.message.rstrip(".")
        rows.append((name, what, shape, str(image.dtype), result, elapsed, state))
        print(f"{name:22s} {shape:>16s} {result.n_iter:4d} it {elapsed:6.2f} s {state}")
    write_page(rows, skipped)


def write_page(rows, skipped):
    lines = [
        "# Gallery: the defaults on real images",
        "",
        "Each figure is `activecontour.segment(image)` with every default (no initial curve,",
        "`mu=\"auto\"`, the polygon backend) on a real image, drawn by the command line's own overlay",
        "writer: the image shown by its own range, the contour in a colour that stands out from it",
        "(2 px wide in these small figures).",
        "Made by `python docs/make_gallery.py` (see its docstring); nothing is drawn by hand.",
        "Times are left out: this page is written on machines shared with other work; the",
        "benchmarks (`benchmarks/`) measure speed.",
        "",
        "The default is the two-region model (6.38) on the whole image: where the light is uneven",
        "(`page`, `coins`' background) or the scene has more than two kinds of region",
        "(photographs), the contour follows the split of the intensities into two classes, which",
        "is not always the object a person would outline. `n_regions=`, an initial curve or `roi=`",
        "say what is wanted there.",
        "",
        "| image | what | size, dtype | iterations | result |",
        "| --- | --- | --- | --- | --- |",
    ]
    for name, what, shape, dtype, result, _, state in rows:
        lines.append(f"| [{name}](#{name}) | {what} | {shape}, {dtype} | {result.n_iter} | "
                     f"{state}, {len(result.contours)} contour(s) |")
    lines.append("")
    for name, what, shape, dtype, result, _, state in rows:
        lines += [f"## {name}", "", f"{what}; {shape} {dtype}: {result.n_iter} iterations, "
                  f"{state}, mu = {result.mu:.3g}.", "",
                  f"![{name}: the default segmentation](gallery/{name}.png)", ""]
    if skipped:
        lines += [f"Skipped (scikit-image needs a download for them): {', '.join(skipped)}.", ""]
    (ROOT / "docs" / "gallery.md").write_text("\n".join(lines))
    total = sum(p.stat().st_size for p in (ROOT / "docs" / "gallery").glob("*.png"))
    print(f"docs/gallery.md: {len(rows)} images, {total / 1e6:.2f} MB of figures")


if __name__ == "__main__":
    main()
