"""The level-set backend: the Chan-Vese functional (6.38) on a function phi over the pixel grid.

The inside region is ``Omega_i = {phi > 0}`` and Gamma is the zero level set of phi.  The backend
minimises the same functional as the polygon backend, with the same parameters and units,

    J = mu |Gamma| + omega |Omega_i| + lambda_in  int_{Omega_i} mean_ch (I - c_in)^2
                                     + lambda_out int_{Omega_o} mean_ch (I - c_out)^2         (6.38)

but Gamma may split, merge, open holes and grow new components.  The zero level set is returned
as sub-pixel contours (marching squares) in the polygon backend's convention, so either backend
can start from the other's result (level set for the topology, polygon for a sub-pixel finish).

One iteration
-------------
1. ``c_in, c_out`` by (6.42) for the current zero set, from the common evaluator (below), unless
   they are fixed.
2. A semi-implicit step of the level-set form of the gradient flow of (6.38).  Every level line
   moves with the normal velocity ``-(mu kappa + f)``, where ``f = omega + lambda_in mean (I -
   c_in)^2 - lambda_out mean (I - c_out)^2`` is the integrand of (6.41); in level-set form
   ``phi_t = |grad phi| (mu div(grad phi / |grad phi|) - f)``, and as phi is kept a signed
   distance (``|grad phi| = 1``) this is ``phi_t = mu Laplace(phi) - f``.  (With delta(phi) in place
   of |grad phi| it would be the equation of Chan & Vese 2001; |grad phi| makes it the level-set
   motion of Osher & Sethian 1988, which moves every level line, not only those near Gamma.)  The
   pixels on the image border carry ``mu`` more per border side in f: a region that covers them
   closes along the domain edge, and (6.38) of the returned contours counts that length, as the
   polygon backend does.  Two forms of the step, with ``S = (1 - tau mu Laplace)^{-1}``:

   (a) smoothed force: ``phi^{k+1} = S (phi^k - tau f)``, i.e. the velocity
       ``S (mu Laplace(phi) - f)``: a Sobolev (H^1-type) gradient with smoothing length
       ``l = sqrt(tau mu)``, the level-set counterpart of the polygon's H^1 velocity (6.39).
       It moves whole regions at once and, with large tau, flips regions far from Gamma (see
       below); but its fixed point is biased by the smoothing, so it is only the first stage;
   (b) unsmoothed force: ``phi^{k+1} = S phi^k - tau f``: implicit curvature, explicit force, the
       L^2 flow (6.25) whose fixed point is ``mu kappa + f = 0`` on Gamma, i.e. (6.41) = 0.

   ``S`` has constant coefficients: one pair of discrete cosine transforms applies it exactly
   (Neumann boundary), unconditionally stable.  In step (b) phi changes only near Gamma (beyond
   the band it is ``+-band``, which S leaves as it is), so there S is solved on the band's pixels
   alone, phi held beyond them, by conjugate gradients, whenever that costs less than the DCT
   pair (a narrow band on a large image).
3. Reinitialisation: phi is replaced by the signed distance to its zero level set, computed in a
   narrow band ``|phi| < band`` only and clipped to ``+-band`` beyond (:func:`signed_distance`).
4. The step is accepted if (6.38) of the new zero set, by the common evaluator, is not larger;
   otherwise tau is halved and the step retried (backtracking).  The zero set of the
   reinitialised phi is fixed by the distances of the front pixels alone (marching squares reads
   no other), so a step is scored once those are known, and the band is grown for an accepted
   step only.

Steps in pixels
---------------
A step is given as ``step`` pixels of travel: ``tau = step / |f|_typ`` with ``|f|_typ`` the mean
``|f|`` over the pixels (about ``(c_in - c_out)^2`` once the regions have formed), so that a front
at a pixel of typical force moves ``step`` pixels whatever the image's contrast or the parameters'
scale; the smoothing length ``sqrt(tau mu)`` is kept below ``step`` (that binds only where the
force is weak against the length term, as on a checkerboard start).  The first step is ``dt``,
but at most half the width (area over length) of the start's regions; it doubles after every
accepted step until the first rejection, then grows by 1.25 after two first-try acceptances in a
row.  Coarse to fine, like the polygon's smoothing length: a smoothed-force stage runs with steps
up to a ceiling (first ``dt_max``) and has settled when Gamma moves less than 2 % of the step (or
10 tol) per iteration, averaged over 3 iterations, or when two halvings of its step find no
descent; the ceiling is then divided by 4, and below ``dt_min`` stage (b) follows, with steps
``<= dt_min`` and the force applied within the band only, so that no pixel far from Gamma (at
``+-band``) flips on its own.
Once Gamma moves less than ``tol`` pixels per iteration on average over 3 iterations, stage (b)
runs on as its tail: the step doubles until a rejection, up to ``band`` pixels (the width the force
acts over) and to the largest explicit step.  A step of ``dt_min`` moves a weak front (where f
hardly outweighs the length term) by a small fraction of a pixel per iteration: below ``tol`` per
iteration, yet with dozens of iterations of travel left, which a run with a smaller tol would
make (astronaut: 124 pixels in 121 iterations).  The tail converges (status 0) when it too moves
less than ``tol`` per iteration, and stage (b) ends with status 4 when ``max_backtracks`` halvings
find no descent.  Its steps are explicit on the band when ``tau mu <= 1/4`` (stable, no DCT): the
explicit step's fixed point, ``mu Laplace(phi) = f``, does not depend on tau, while the implicit
form's is ``mu Laplace(phi) = f - tau mu Laplace(f)``, so the tail stays explicit.  The unsmoothed flow can
stop in a pixel-scale local minimum that a smoothed step leaves (a continued run would then move
on), so when it ends a smoothed stage of the first step size is tried, up to twice: if its first
step finds no descent the end stands, otherwise the stages run on from there.

How far Gamma moved is measured geometrically, in pixels: the area between the old and the new
zero set, ``sum_px |H_eps(d_new) - H_eps(d_old)|`` over the band, divided by the length of Gamma,
i.e. the mean normal displacement.  ``H_eps`` is the cosine-regularised Heaviside of Zhao, Chan,
Merriman & Osher (1996),

    H_eps(s) = (1 + s/eps + sin(pi s/eps)/pi) / 2  for |s| < eps (0 and 1 beyond),  eps = 1,

whose integer translates sum to the exact length of a half-line at any sub-pixel offset (its
derivative's Fourier transform vanishes at every non-zero multiple of 2 pi): the swept area is exact
for straight fronts and second-order accurate for curved ones.  Unlike a relative energy decrease
(the energy holds the noise energy sigma^2 |D|, which grows with the pixel count) this means the
same on every image size.

Why large steps are safe and useful: ``S`` is stable for every tau, and the backtracking keeps every
accepted step a descent step.  Far from Gamma phi sits at ``+-band``, and a step (a) moves it by
about ``-tau f`` smoothed over ``l``: where a whole region inside Gamma looks like the outside (the
hole of an annulus) phi crosses zero and a hole opens without a seed, while single noisy pixels
are held by the smoothing; the energy test accepts such a change only when it pays, length
included.

Cost and memory: phi is float32 (a distance of a few pixels, rounded to ~2e-7 px, far below
what the energy or the flow resolve; the marching-squares crossings, the distances and the energy
are computed in float64 from it).  A step (a) is one DCT pair (O(MN log MN), float32, its force
computed in one compiled pass) over the band's bounding box widened by ``band + 8 sqrt(tau mu)``
(S's kernel decays as ``exp(-r / sqrt(tau mu))``: near Gamma the box's Neumann sides change the
step by < 1e-4 px), phi held beyond it, when the box is at most half the image and the step,
solved on a 4x coarser grid, flips no block beyond it; else over the image.  Where the band is a
thin ring in a large box (a large object) the step is solved on tiles along the band instead:
square cells of about twice that reach holding band pixels, each on its own tile reaching as far
beyond it (one batched DCT pair), phi held beyond the cells, when the tiles cost at most 3/4 of
the box or the image and neither the tiles' values around the cells nor the coarse grid's beyond
them come within half the band of flipping.  A step (b) works on the band only (explicit, or
conjugate gradients).  A step is written into a recycled array, which
equals phi already but for the box of the step or finish that last wrote it (the tiles' boxes, or
the band's pixels, for a step on tiles or on the band; noted per array): phi is copied there only,
not over the image; the sides (phi > 0) of a step are written likewise into the sides of a state
dropped before, set at the pixels that switched between the two.  The reinitialisation
reads the sides only where the step changed phi (its box, the image, the cells and halo pieces
a step on tiles wrote, or for a step (b) the band's pixels; the front is searched next to the
previous one and the pixels that changed side) and, for an accepted step, is written into the
stepped array itself: the previous phi copied back over those boxes (nothing for a step (b)),
then O(band) (a rejected step costs its front), with
work arrays kept between iterations; the energy is O(|Gamma|) from the cells the
reinitialisation found.  The image itself stays float64 (the model's tables and the common
evaluator are exact in float64; the polygon backend shares them).

The energy
----------
The energy of every iterate, the acceptance test and ``res.energy`` are one number: (6.38) of the
zero set by the common evaluator :func:`activecontour.energy.evaluate`, exact for the bilinear
image.  The zero set is taken as the marching-squares segments of phi padded by ``-|phi|``
(:func:`zero_set_edges`, the segments of :func:`level_set_contours`, closed along the domain edge
where a region touches it), scored as an unchained soup of oriented edges: Green's theorem makes
region and length integrals sums over edges, so this costs O(|Gamma|) after the O(MN) sign test.
A reinitialisation changes the energy only through the O(h^2 kappa) chord error of re-deriving
Gamma from a distance function, and every acceptance test compares energies after it: the history
is non-increasing at every iteration, reinitialisations included.

Modules
-------
redistancing  the signed distance to the zero set (or to curves) in a narrow band
zeroset       the zero set as marching-squares contours and as an oriented edge soup
initial       the level set of a start (curves, masks, results, a checkerboard)
scheme        the energy of an iterate, the force f of (6.41), the steps (a), (b), the swept area
driver        :func:`segment_levelset`: options, the step schedule, stages and the result
"""

from activecontour.backends.levelset.driver import DEFAULT_OPTIONS, LevelSetOptions, segment_levelset
from activecontour.backends.levelset.initial import checkerboard_level_set, initial_level_set
from activecontour.backends.levelset.redistancing import curves_level_set, signed_distance
from activecontour.backends.levelset.scheme import heaviside
from activecontour.backends.levelset.zeroset import level_set_contours, zero_set_edges

__all__ = [
    "DEFAULT_OPTIONS",
    "LevelSetOptions",
    "checkerboard_level_set",
    "curves_level_set",
    "heaviside",
    "initial_level_set",
    "level_set_contours",
    "segment_levelset",
    "signed_distance",
    "zero_set_edges",
]
