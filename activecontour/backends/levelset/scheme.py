"""The scheme: the energy of an iterate, the force f of (6.41), the steps (a) and (b), the swept area."""

from __future__ import annotations

import numpy as np
import scipy.fft

from activecontour import _kernels
from activecontour.backends.levelset.redistancing import _boxes, _locate, _Located, _redistance, _Scratch
from activecontour.backends.levelset.zeroset import _change_cells, _edge_soup
from activecontour.energy import evaluate

_EXPLICIT = 0.25  # step (b) is explicit (stable, on the band alone) up to tau mu = 1/4
_REACH = 8.0  # S's kernel decays as exp(-r / l), l = sqrt(tau mu): a box reaching 8 l beyond the band
_BOX_SHARE = 0.5  # a box over more than this share of the image: the whole image
_COARSE = 4  # the far field's test grid: blocks of 4 x 4 pixels
_TILE_MARGIN = 8  # pixels: step (a)'s tiles cover the cells within this of the band (_tiles)
_MIN_CORE = 32  # pixels: the least side of a tile's cell (more than twice the margin)
_TILE_MIN = 2**19  # pixels: a smaller box (or image) is solved as it is, without looking for tiles
_TILE_SHARE = 0.75  # tiles over more than this share of the box (or image) they replace: not used


def heaviside(phi, epsilon=1.0):
    """The cosine-regularised Heaviside ``H_eps``: 0 below -eps, 1 above eps, smooth between."""
    s = np.asarray(phi, dtype=np.float64) / epsilon
    ramp = 0.5 * (1.0 + s + np.sin(np.pi * np.clip(s, -1.0, 1.0)) / np.pi)
    return np.where(s >= 1.0, 1.0, np.where(s <= -1.0, 0.0, ramp))


def _force(values, c_in, c_out, params):
    """The integrand f of the shape derivative (6.41) at pixels of the image: ``g_i - g_o``.

    The model's :meth:`~activecontour.models.ChanVeseParameters.load_form` evaluated on
    ``values (..., C)`` (for (6.38): ``omega + lambda_in mean_ch (I - c_in)^2 - lambda_out mean_ch
    (I - c_out)^2``); returns ``(...)`` float64.  The level set's only view of the energy's
    density, which the model writes once for every consumer.
    """
    return params.load_form(c_in, c_out).density(values)


class _Problem:
    """Image, parameters and the pieces of the energy, the force f and the operator S.

    phi is float32 (a distance of a few pixels, rounded to ~2e-7 px: far below what the energy or
    the flow resolve) and the image-wide work is done in compiled passes without temporaries
    (:func:`activecontour._kernels.force_step`, :func:`~activecontour._kernels.divide_spectrum`), so
    that no float64 copy of the image is made per step; the reinitialisation reuses its work
    arrays (:class:`_Scratch`).
    """

    def __init__(self, model, params, settings):
        self.model = model
        self.shape = tuple(model.shape)
        self.values = model.values
        self.params = params
        self.band = settings["band"]
        m, n = self.shape
        stride = max(1, int(np.sqrt(m * n / 2.0**16)))
        rows = np.arange(stride // 2, m, stride)
        cols = np.arange(stride // 2, n, stride)
        sample = (rows[:, None] * n + cols[None, :]).ravel()
        self.sample_values = self.values.reshape(m * n, -1)[sample]  # gathered once
        self.sample_wall = self._wall(sample)
        self.wave_r, self.wave_c = _waves(m), _waves(n)
        self.scratch = _Scratch(self.shape)
        # image-sized float32 arrays to reuse (a new one faults in every page), each with the
        # phi it equals outside a box, when that is known (see _copy_of)
        self._spare = []
        self._agreements = {}  # id(array): (array, phi, box): array equals phi outside box
        # image-sized bool arrays (the sides of states dropped) to reuse, each with the sides it
        # equals but at the pixels listed, when that is known (see _sides_like)
        self._spare_sides = []
        self._box_buffer = None  # the smoothed step's box, reused while its size holds
        self._tile_buffer = None  # the smoothed step's tiles (_tile_step), reused while large enough
        self._coarse = None  # the far field's test grid (_coarse_tables)
        self._coarse_forced = None  # (form's constants, f on that grid) of the last step (_coarse_force)
        self._coarse_phi = None  # the block means and signs of a state's phi on that grid (_coarse_state)

    def take(self, like=None):
        """An image-sized float32 array to write into, and the box outside which it equals the
        array ``like`` already (None: not known; its contents are undefined)."""
        if not self._spare:
            return np.empty(self.shape, dtype=np.float32), None
        array, agreement = self._spare.pop()
        # its contents change: every agreement with it ends
        self._spare = [(other, None if known is not None and known[0] is array else known)
                       for other, known in self._spare]
        self._agreements = {key: entry for key, entry in self._agreements.items() if entry[1] is not array}
        return array, (agreement[1] if agreement is not None and agreement[0] is like else None)

    def recycle(self, array):
        """Hand back an image-sized float32 array that nothing refers to any more."""
        entry = self._agreements.pop(id(array), None)
        if array is not None and array.shape == self.shape and array.dtype == np.float32 \
                and len(self._spare) < 2:
            self._spare.append((array, None if entry is None else entry[1:]))

    def _sides_like(self, before):
        """An image-sized bool array equal to the sides ``before``: a recycled one set at the pixels
        where it differs (those a step switched), else any recycled one or a new one, copied (a new
        array faults in every page, a copy reads every pixel)."""
        for index, (array, base, differ) in enumerate(self._spare_sides):
            if base is before:
                del self._spare_sides[index]
                array.ravel()[differ] = before.ravel()[differ]
                break
        else:
            if not self._spare_sides:
                return before.copy()
            array = self._spare_sides.pop()[0]
            np.copyto(array, before)
        # its contents change: every note that another array equals it but somewhere ends
        self._spare_sides = [(other, None if base is array else base, differ)
                             for other, base, differ in self._spare_sides]
        return array

    def recycle_sides(self, old, new, located):
        """Hand back the sides of the state ``old``, which nothing refers to any more: they equal
        those of the state ``new`` but at the pixels that ``located`` (the step between the two,
        :meth:`locate`) switched."""
        if isinstance(located, _Located) and len(self._spare_sides) < 2:
            self._spare_sides.append((old.positive, new.positive, located.switched))

    def _agree(self, array, phi, box):
        """Note that ``array`` equals ``phi`` outside ``box`` (two slices, boxes (R, 4) or pixels as
        :meth:`step` returns them) until either is written: a step that takes it back from ``phi``
        copies there only (:meth:`_copy_of`)."""
        self._agreements[id(array)] = (array, phi, box)

    def _copy_of(self, phi, box=None):
        """An image-sized float32 array equal to ``phi`` outside ``box`` (two slices; None: all of
        it), undefined inside.  An array that a step or a finish left equal to ``phi`` outside a
        box (the step's box and the bands, :meth:`_agree`) is copied over that box only, not over
        the image (a disk at 4096^2: 10^7 pixels of phi beyond the step's box, per step)."""
        out, known = self.take(phi)
        whole = (slice(0, self.shape[0]), slice(0, self.shape[1]))
        _copy_outside(phi, out, whole if known is None else known, box)
        return out

    def redistance(self, phi, keep_front=False, overwrite=False):
        """The reinitialised state of phi (float32); ``keep_front``: phi's zero set kept exactly (a
        previous result's); ``overwrite``: written into phi (a float32 start that nothing else
        reads), see :func:`_redistance`."""
        return _redistance(phi, self.band, dtype=np.float32, scratch=self.scratch, keep_front=keep_front,
                           overwrite=overwrite)

    def locate(self, stepped, previous, changed=None):
        """The zero set of ``stepped`` (a step from the state ``previous`` that ``changed`` phi
        there only, as :meth:`step` returns it) located, and the signed distances of its front
        pixels written into ``stepped``: these alone fix the zero set of the reinitialised state,
        so :meth:`evaluate` scores it as it will be, and the band is grown (:meth:`finish`) only
        for a step that is accepted."""
        located = _locate(stepped, self.band, np.float32, self.scratch, previous, changed,
                          self._sides_like(previous.positive))
        front = None
        if isinstance(located, _Located):
            located.front_distances(self.band)
            front = located.front
        if _is_pixels(changed):  # a step on the band's pixels: those and the front were written
            self._agree(stepped, previous.phi, changed if front is None else np.concatenate([changed, front]))
        return located

    def finish(self, located, previous):
        """The reinitialised state of a located step from ``previous`` (:meth:`locate`), written
        into the stepped array itself."""
        if not isinstance(located, _Located):
            return located  # no front: final already
        self._agreements.pop(id(located.phi), None)  # written below
        state = located.finish(self.band, np.float32, self.scratch, previous)
        # the state differs from the previous one only where the step changed phi (and the front
        # pixels next to it, :meth:`step`) and on its band
        changed = _bounds(located.changed, self.shape)
        region = None  # where the state may differ from the previous one, as boxes (R, 4)
        if changed is not None and state.near_flat.size:
            if _is_pixels(located.changed):
                # a step on the band's pixels: the previous band is reset, the new one written
                self._agree(previous.phi, state.phi, np.concatenate([previous.near_flat, state.near_flat]))
            elif _is_rects(located.changed):
                # the tiles' writes: the new front lies within a pixel of them (the old one lies in
                # their cells), the band within ceil(band) + 1 rings of the front; a ring of band
                # on a large image: the rects, not their bounding box
                region = _grown_rects(located.changed, self.shape, int(np.ceil(self.band)) + 2)
                self._agree(previous.phi, state.phi, region)
            else:
                box = _union(_grown(changed, self.shape), _bounds(state.near_flat, self.shape))
                region = _boxes(box)
                self._agree(previous.phi, state.phi, box)
        self._carry_coarse(previous, state, region)
        return state

    def evaluate(self, state):
        """(6.38) of the zero level set by the common evaluator, as an ``Evaluation``.

        The zero set is the segment soup of :func:`zero_set_edges`: the returned contours, closed
        along the domain edge.  An empty region has the evaluator's value for the empty set.
        """
        cells = state.cells if state.cells is not None else _change_cells(state.positive)
        points = _edge_soup(state.phi, cells).reshape(-1, 2)
        next_index = np.repeat(np.arange(1, len(points), 2), 2)  # start -> end -> itself
        return evaluate(self.model, points, next_index, self.params, empty_ok=True)

    def force(self, c_in, c_out):
        """The constants of f (6.41) for this iteration, and f's contrast scale.

        f is :func:`_force` plus ``mu`` per side of the image that a pixel lies on: a region that
        covers a border pixel closes along the domain edge there, and the evaluator counts that
        length (the wall term).  It is evaluated where a step needs it (:meth:`force_at`, and
        :func:`activecontour._kernels.force_step` over the image).  The scale is the mean ``|f|``
        over the pixels (a regular sample of about 2^16 of them): about ``|c_in - c_out|^2`` once
        the regions have settled, the size of the force of every pixel before that (a
        checkerboard start, where ``c_in ~ c_out``).  Time steps are measured in pixels of travel
        at that force.
        """
        constants = (np.nan_to_num(np.asarray(c_in, dtype=np.float64)),
                     np.nan_to_num(np.asarray(c_out, dtype=np.float64)))
        f = _force(self.sample_values, *constants, self.params) + self.params.mu * self.sample_wall
        return constants, max(float(np.mean(np.abs(f))), 1e-12)

    def force_at(self, flat, constants):
        """f (with the wall term) at the pixels of flat indices ``flat``."""
        m, n = self.shape
        f = _force(self.values.reshape(m * n, -1)[flat], *constants, self.params)
        if self.params.mu > 0:
            f += self.params.mu * self._wall(flat)
        return f

    def _wall(self, flat):
        """How many sides of the image each pixel ``flat`` lies on (0, 1 or 2)."""
        m, n = self.shape
        row, col = np.divmod(flat, n)
        return (row == 0).astype(np.float64) + (row == m - 1) + (col == 0) + (col == n - 1)

    def time_step(self, step, scale):
        """tau for a step of ``step`` pixels at the force ``scale``: ``step / scale``.

        A front at a pixel of typical force moves ``step`` pixels.  The smoothing length
        ``sqrt(tau mu)`` of S is kept below ``step``: that binds where the force is weak against
        the length term (a checkerboard start, whose constants hardly differ), where S would
        otherwise flatten phi over the whole image at once.
        """
        tau = step / scale
        return min(tau, step * step / self.params.mu) if self.params.mu > 0 else tau

    def explicit_limit(self, scale):
        """The largest step (pixels, at the force ``scale``) that step (b) takes explicitly: ``tau mu
        <= 1/4`` (:meth:`step`).  Its fixed point ``mu Laplace(phi) = f`` does not depend on tau;
        the implicit form's, ``mu Laplace(phi) = f - tau mu Laplace(f)``, leans on the pixel-scale
        roughness of f more the larger tau is."""
        return _EXPLICIT * scale / self.params.mu if self.params.mu > 0 else np.inf

    def step(self, state, force, tau, smooth_force):
        """Step (a) ``S (phi - tau f)`` with ``smooth_force``, else (b) ``S phi - tau f``.

        ``S = (1 - tau mu Laplace)^{-1}`` by DCT-II in float32 (phi is a distance of a few pixels:
        its rounding, ~1e-6 px, is far below what matters).  In step (b) the force acts within the
        band only, so that no pixel far from Gamma (at +-band) flips on its own; when
        ``tau mu <= 1/4`` the explicit step ``phi + tau mu Laplace(phi) - tau f`` is stable and its
        fixed point is that of (6.41) for every tau (:meth:`explicit_limit`), so it is taken on the
        band's pixels alone (O(band) instead of a DCT pair over the image), and otherwise S is
        solved on the band (:meth:`_band_smooth`) when that is cheaper than the DCT pair.
        ``force``: the constants from :meth:`force`.  Returns the stepped phi and where it may
        differ from ``state.phi``: the band's pixels (flat indices), a box (two slices), the boxes
        of the tiles' writes (:class:`_Tiles`, ``rects``) or None (anywhere), so that its sides
        are read there only (:meth:`locate`).
        """
        stepped, changed = self._step(state, force, tau, smooth_force)
        box = _bounds(changed, self.shape)
        if _is_rects(changed):  # locating it writes the front's distances: one pixel beyond
            self._agree(stepped, state.phi, _grown_rects(changed, self.shape, 1))
        elif box is not None and not _is_pixels(changed):  # pixels: noted by locate (the front)
            self._agree(stepped, state.phi, _grown(box, self.shape))
        return stepped, changed

    def _step(self, state, force, tau, smooth_force):
        """:meth:`step` without the note of where the stepped array equals ``state.phi``."""
        if not smooth_force and tau * self.params.mu <= _EXPLICIT:
            return self._explicit_step(state, force, tau), state.near_flat
        if not smooth_force:
            weight = tau * self.params.mu
            # S on the band by conjugate gradients (about sqrt(1 + 8 weight) sweeps of the band)
            # or on the image by a DCT pair, whichever costs less (measured: a sweep of a band
            # pixel costs about 6 times a pixel of the DCT pair)
            flat = state.near_flat
            if flat.size * np.sqrt(1.0 + 8.0 * weight) < state.phi.size / 6.0:
                rhs, changed = self._band_smooth(state, weight), flat
            else:
                rhs, changed = self._smooth(state.phi.copy(), weight), None
            near = flat[np.abs(state.phi.ravel()[flat]) < self.band]
            rhs.ravel()[near] -= (tau * self.force_at(near, force)).astype(np.float32)
            return rhs, changed
        form = self.params.load_form(*force)
        if self.params.mu > 0:
            weight = tau * self.params.mu
            box = self._box(state, weight)
            area = self.shape[0] * self.shape[1] if box is None else _area(box)  # the DCT pair's
            tiles = self._tiles(state, weight) if area >= _TILE_MIN else None
            held = None  # the coarse grid's step (_coarse_held), computed once
            if tiles is not None and tiles.pixels <= _TILE_SHARE * area:
                held = self._coarse_held(state, form, tau)
                stepped = self._tile_step(state, form, tau, tiles, held)
                if stepped is not None:
                    return stepped, tiles.rects
            if box is not None:
                held = self._coarse_held(state, form, tau) if held is None else held
                if not self._far_flips(held, box):
                    return self._box_step(state, form, tau, box), box
        # phi - tau f over the image in one compiled pass (f: the model's form, the wall term)
        rhs = self.take()[0]
        _kernels.force_step(state.phi, self.values, form.constant, form.linear, form.square, self.params.mu,
                            tau, rhs)
        return (self._smooth(rhs, tau * self.params.mu) if self.params.mu > 0 else rhs), None

    def _box(self, state, weight):
        """The rows and columns (two slices) on which step (a) is solved, or None: the whole image.

        S's kernel decays as ``exp(-r / l)`` with ``l = sqrt(tau mu)``: beyond the band (where phi
        is ``+-band``) the step changes phi near Gamma by less than ``exp(-_REACH)`` of the force's
        jumps (~1e-4 px), so the band's bounding box widened by ``band + _REACH l`` (to a length the
        DCT is fast on) is solved alone, with Neumann sides, when it is at most ``_BOX_SHARE`` of
        the image.
        """
        if state.near_flat.size == 0:
            return None
        m, n = self.shape
        reach = int(np.ceil(self.band + _REACH * np.sqrt(weight)))
        flat = state.near_flat
        first, last = divmod(int(flat.min()), n)[0], divmod(int(flat.max()), n)[0]
        cols = flat % n
        rows = _fast_span(first - reach, last + 1 + reach, m)
        cols = _fast_span(int(cols.min()) - reach, int(cols.max()) + 1 + reach, n)
        if (rows.stop - rows.start) * (cols.stop - cols.start) > _BOX_SHARE * m * n:
            return None
        return rows, cols

    def _coarse_held(self, state, form, tau):
        """Step (a) on a grid coarser by ``_COARSE``, signed by the side of each block: block means
        of ``phi - tau f`` (f from the block means of the channels and their squares), S with the
        same length ``l = sqrt(tau mu)``, times +1 where the block's first pixel is inside and -1
        outside.  Far from Gamma phi is ``+-band`` and a block whose value comes within half the
        band of zero may flip (a hole opening without a seed): :meth:`_far_flips`."""
        k = _COARSE
        force = self._coarse_force(form)
        means, signs = self._coarse_state(state, force.shape)
        coarse = self._smooth(means - np.float32(tau) * force, tau * self.params.mu / (k * k),
                              _waves(force.shape[0]), _waves(force.shape[1]))
        # far blocks lie beyond the band: the side of the first pixel (phi > 0) is the block's
        coarse *= signs
        return coarse

    def _coarse_state(self, state, shape):
        """The block means of ``state.phi`` on the coarse grid (:meth:`_coarse_held`, of ``shape``)
        and the side of each block's first pixel (+1 inside, -1 outside), float32.

        Kept for the state (a step retried with a smaller tau, a recheck's tries) and carried to
        the next one: a state finished from it (:meth:`finish`) differs from it only in the
        boxes noted there, and only the blocks that meet them are made again, each by the same
        sums in the same order (:func:`activecontour._kernels.block_means`): the same numbers as
        made anew, for a fraction of a pass over the image (a disk at 4096^2: its ring of
        tiles)."""
        entry = self._coarse_phi
        sides = state.positive.view(np.uint8)
        if entry is None or entry[0] is not state:
            means, signs = np.empty(shape, dtype=np.float32), np.empty(shape, dtype=np.float32)
            _kernels.block_means(state.phi, _COARSE, means, None, sides, signs)
            self._coarse_phi = entry = [state, means, signs, []]
        elif entry[3]:
            _kernels.block_means(state.phi, _COARSE, entry[1], np.concatenate(entry[3]), sides, entry[2])
            entry[3] = []
        return entry[1], entry[2]

    def _carry_coarse(self, previous, state, region):
        """Note that ``state`` differs from ``previous`` only in ``region`` (boxes (R, 4), or None:
        not known): the coarse grid's block means of ``previous`` (:meth:`_coarse_state`) become
        those of ``state`` once the blocks meeting the region are made again."""
        entry = self._coarse_phi
        if entry is None or entry[0] is not previous:
            return
        if region is None:
            self._coarse_phi = None
        else:
            entry[0] = state
            entry[3].append(region)

    def _coarse_force(self, form):
        """f (6.41) of ``form`` on the coarse grid (:meth:`_coarse_tables`), float32; the last one
        is kept: a step retried with a smaller tau (backtracking) has the same constants."""
        key = (form.constant, tuple(form.linear), tuple(form.square))
        if self._coarse_forced is not None and self._coarse_forced[0] == key:
            return self._coarse_forced[1]
        means, squares, wall = self._coarse_tables()
        force = wall * np.float32(self.params.mu)  # f's terms in the kernel's order, in float32
        force += np.float32(form.constant)
        for channel, (linear, square) in enumerate(zip(form.linear, form.square, strict=True)):
            force += np.float32(linear) * means[channel]
            if square != 0:
                force += np.float32(square) * squares[channel]
        self._coarse_forced = key, force
        return force

    def _far_flips(self, held, box):
        """Whether step (a) may flip a pixel outside ``box``: there phi is ``+-band`` and the step
        is ``+-band - tau S(f)``, a region far from Gamma flipping where the smoothed force
        outweighs the band.  Tested on the coarse grid (:meth:`_coarse_held`): a far block whose
        value comes within half the band of zero sends the step to the whole image."""
        k = _COARSE
        # the blocks that reach into the box are not far: the rest are four strips around them
        rows, cols = box
        first, last = rows.start // k, -(-rows.stop // k)
        left, right = cols.start // k, -(-cols.stop // k)
        strips = (held[:first], held[last:], held[first:last, :left], held[first:last, right:])
        return any(strip.size and strip.min() < 0.5 * self.band for strip in strips)

    def _coarse_tables(self):
        """Block means (``_COARSE`` x ``_COARSE`` pixels, float32) of the channels ``(C, m, n)``, of
        their squares, and of the number of image sides a pixel lies on (the wall term); made once."""
        if self._coarse is None:
            m, n = self.shape
            k, channels = _COARSE, self.values.shape[2]
            size = (-(-m // k), -(-n // k))
            means = np.empty((channels,) + size, dtype=np.float32)
            squares = np.empty_like(means)
            _kernels.block_moments(self.values, k, means, squares)
            # a block on an image side holds one line of pixels on it: 1 / (its pixels across it)
            sides = []
            for blocks, length in zip(size, self.shape, strict=True):
                starts = np.arange(blocks) * k
                across = np.minimum(starts + k, length) - starts
                sides.append(((starts == 0).astype(np.float64) + (starts == starts[-1])) / across)
            self._coarse = means, squares, (sides[0][:, None] + sides[1][None, :]).astype(np.float32)
        return self._coarse

    def _tiles(self, state, weight):
        """The tiles on which step (a) is solved along the band (:meth:`_tile_step`), or None.

        The image is cut into square cells of ``core`` pixels (a multiple of ``_COARSE``); the
        cells holding a pixel within ``_TILE_MARGIN`` of the band are solved, each on a tile of
        ``side`` pixels reaching ``reach = band + _REACH l`` beyond it (pushed inside the image at
        its border, where the Neumann side is exact), ``side`` a length the DCT is fast on and about
        twice the reach: the cost per length of band, ``side^2 / core``, is then least.  A ring
        of band on a large image: tiles of a few 10^5 pixels instead of its whole bounding box.
        """
        if state.near_flat.size == 0:
            return None
        m, n = self.shape
        reach = int(np.ceil(self.band + _REACH * np.sqrt(weight)))
        side = scipy.fft.next_fast_len(max(4 * reach + _COARSE, 2 * reach + _MIN_CORE), real=True)
        core = (side - 2 * reach) // _COARSE * _COARSE
        if side > min(m, n):
            return None
        rows, cols = np.divmod(state.near_flat, n)
        grid = np.zeros((-(-m // core), -(-n // core)), dtype=bool)
        # a cell holds a pixel within the margin of a band pixel: the margin's corners are in it
        # or in a cell next to it (core > 2 margin)
        for row in (np.maximum(rows - _TILE_MARGIN, 0), np.minimum(rows + _TILE_MARGIN, m - 1)):
            for col in (np.maximum(cols - _TILE_MARGIN, 0), np.minimum(cols + _TILE_MARGIN, n - 1)):
                grid[row // core, col // core] = True
        cell_r, cell_c = np.nonzero(grid)
        return _Tiles(grid, cell_r, cell_c, core, side, reach, self.shape)

    def _tile_step(self, state, form, tau, tiles, held):
        """Step (a) solved on ``tiles`` (:meth:`_tiles`), phi held beyond them, or None when it may
        flip a pixel beyond their cells.

        Each tile is one DCT pair (all tiles in one batched call) with Neumann sides ``reach``
        beyond its cell: on the cell the step differs from the whole image's by < ``exp(-_REACH)``
        of the force's jumps (~1e-4 px), as on the band's box.  Beyond the cells phi is
        ``+-band``: within ``tiles.halo`` of a cell (more than ``reach / 2`` inside its tile) the
        tile's values are written as well and tested, further out the coarse grid's
        (:meth:`_far_flips`'s test, on the blocks beyond the cells widened by the halo); a value
        within half the band of zero sends the step to the band's box or the image.
        """
        count, side = len(tiles.cell_r), tiles.side
        if self._tile_buffer is None or self._tile_buffer.size < count * side * side:
            self._tile_buffer = np.empty(count * side * side, dtype=np.float32)
        stack = self._tile_buffer[: count * side * side].reshape(count, side, side)
        _kernels.force_step_tiles(state.phi, self.values, form.constant, form.linear, form.square,
                                  self.params.mu, tau, stack, tiles.top, tiles.left)
        spectrum = scipy.fft.dctn(stack, axes=(1, 2), norm="ortho", overwrite_x=True)
        waves = _waves(side)
        _kernels.divide_spectrum(spectrum.reshape(count * side, side), np.tile(waves, count), waves,
                                 np.float32(tau * self.params.mu))
        stack = scipy.fft.idctn(spectrum, axes=(1, 2), norm="ortho", overwrite_x=True)
        k = _COARSE
        # the coarse blocks beyond the cells widened by the halo (block-aligned: core and halo are
        # multiples of the block)
        near = np.zeros(held.shape, dtype=bool)
        for top, bottom, left, right in zip(*tiles.widened, strict=True):
            near[top // k: -(-bottom // k), left // k: -(-right // k)] = True
        far = held[~near]
        if far.size and far.min() < 0.5 * self.band:
            return None
        # the halo beyond the cells, from the tiles' values: a piece lies in a cell beyond the
        # band, all on the side of its first pixel
        pieces = tiles.halo_pieces
        pieces[:, 5] = np.where(state.phi[pieces[:, 1], pieces[:, 3]] > 0, 1, -1)
        if not _kernels.tile_pieces(stack, tiles.top, tiles.left, pieces, 0.5 * self.band, state.phi,
                                    False):  # tested only: phi is not written
            return None
        out = self._copy_of(state.phi)
        _kernels.tile_pieces(stack, tiles.top, tiles.left, pieces, 0.0, out, True)
        # the cells last: a tile is exact on its own cell
        _kernels.tile_pieces(stack, tiles.top, tiles.left, tiles.cells, 0.0, out, True)
        return out

    def _box_step(self, state, form, tau, box):
        """Step (a) solved on ``box`` (:meth:`_box`), phi held beyond it."""
        rows, cols = box
        size = (rows.stop - rows.start, cols.stop - cols.start)
        if self._box_buffer is None or self._box_buffer.shape != size:
            self._box_buffer = np.empty(size, dtype=np.float32)
        inner = self._box_buffer
        _kernels.force_step(state.phi, self.values, form.constant, form.linear, form.square, self.params.mu,
                            tau, inner, rows.start, cols.start)
        out = self._copy_of(state.phi, box)
        out[rows, cols] = self._smooth(inner, tau * self.params.mu, _waves(size[0]), _waves(size[1]))
        return out

    def _band_smooth(self, state, weight):
        """``S phi = (1 - weight Laplace)^{-1} phi`` on the band's pixels, phi held beyond them.

        Step (b) changes phi only near Gamma: beyond the band phi is ``+-band`` and S leaves a
        constant as it is, so the solve is restricted to the band (Dirichlet values from phi
        outside it, Neumann at the image border: a mirrored pixel adds nothing).  The matrix
        ``1 + weight (degree - adjacency)`` is symmetric positive definite with condition number
        below ``1 + 8 weight``: conjugate gradients with the diagonal as preconditioner, to
        1e-6 relative, in O(band) per iteration instead of a DCT pair over the image.
        """
        m, n = self.shape
        flat = state.near_flat
        phi = state.phi.ravel()
        # per neighbour (up, down, left, right) its band index (-1: none) or, beyond the band, its
        # pixel (held: its value joins the right-hand side)
        couplings = np.empty((4, flat.size), dtype=np.intp)
        held = np.empty((4, flat.size), dtype=np.intp)
        degree = np.empty(flat.size)
        _kernels.band_couplings(flat, m, n, self.scratch.owner, couplings, held, degree)
        right = phi[flat].astype(np.float64)
        for beyond in held:
            keep = beyond >= 0
            right[keep] += weight * phi[beyond[keep]]
        diagonal = 1.0 + weight * degree
        padded = np.zeros(flat.size + 1)  # index -1: a neighbour beyond the band contributes 0

        def apply(x):
            padded[:-1] = x
            neighbours = padded[couplings[0]] + padded[couplings[1]]
            neighbours += padded[couplings[2]]
            neighbours += padded[couplings[3]]
            neighbours *= -weight
            neighbours += diagonal * x
            return neighbours

        def dot(u, v):  # an elementwise sum: BLAS's threads spin on a shared machine
            return float(np.sum(u * v))

        x = phi[flat].astype(np.float64)
        residual = right - apply(x)
        z = residual / diagonal
        direction = z.copy()
        rz = dot(residual, z)
        limit = 1e-12 * dot(right, right)  # (1e-6 relative)^2
        for _ in range(200):
            if dot(residual, residual) <= limit:
                break
            image = apply(direction)
            alpha = rz / dot(direction, image)
            x += alpha * direction
            residual -= alpha * image
            z = residual / diagonal
            rz, previous = dot(residual, z), rz
            direction = z + (rz / previous) * direction
        out = self._copy_of(state.phi)
        out.ravel()[flat] = x
        return out

    def _smooth(self, rhs, weight, wave_r=None, wave_c=None):
        """``(1 - weight Laplace)^{-1} rhs`` (Neumann) by a DCT-II pair, in place where it can
        (``wave_r, wave_c``: :func:`_waves` of rhs's shape when it is not the image's)."""
        spectrum = scipy.fft.dctn(rhs, norm="ortho", overwrite_x=True)
        _kernels.divide_spectrum(spectrum, self.wave_r if wave_r is None else wave_r,
                                 self.wave_c if wave_c is None else wave_c, np.float32(weight))
        return scipy.fft.idctn(spectrum, norm="ortho", overwrite_x=True)

    def _explicit_step(self, state, force, tau):
        """``phi + tau mu Laplace(phi) - tau f`` on the band (5-point, Neumann: a mirrored pixel; f of
        (6.41) within ``|phi| < band`` only), one compiled pass
        (:func:`activecontour._kernels.explicit_step`)."""
        m, n = self.shape
        form = self.params.load_form(*force)
        out = self._copy_of(state.phi)
        _kernels.explicit_step(state.phi.reshape(-1), state.near_flat, m, n, tau * self.params.mu, self.band,
                               self.values.reshape(m * n, -1), form.constant, form.linear, form.square,
                               self.params.mu, tau, out.reshape(-1))
        return out


class _Tiles:
    """The cells and tiles of step (a) along the band (:meth:`_Problem._tiles`).

    ``grid``: which cells (``core`` x ``core`` pixels, the last ones cut at the image's edge) are
    solved; ``cell_r, cell_c`` their indices; ``top, left`` the first pixel of each one's tile of
    ``side`` x ``side`` pixels; ``halo`` (a multiple of ``_COARSE``, at most ``reach / 2 + 3``) how
    far beyond the cells the tiles' values are written and tested; ``cells`` and ``halo_pieces``
    the rectangles ``(tile, first row, stop row, first column, stop column, 0)`` of the cells and
    of the halo's parts that lie in cells not solved (its sides and corners, each in one
    neighbouring cell), for :func:`activecontour._kernels.tile_pieces`; ``widened`` the cells
    widened by the halo (rows and columns, first and stop, per tile); ``rects`` the cells and the
    halo's pieces, (R, 4) (first row, stop row, first column, stop column; pieces of two cells
    may overlap): the only pixels a step on the tiles writes; ``pixels`` the tiles' total size.
    """

    def __init__(self, grid, cell_r, cell_c, core, side, reach, shape):
        m, n = shape
        self.grid, self.cell_r, self.cell_c = grid, cell_r, cell_c
        self.core, self.side, self.shape = core, side, shape
        self.halo = halo = _COARSE * -(-reach // (2 * _COARSE))
        self.top = np.clip(cell_r * core - reach, 0, m - side).astype(np.intp)
        self.left = np.clip(cell_c * core - reach, 0, n - side).astype(np.intp)
        self.pixels = len(cell_r) * side * side
        spans = []  # per axis: the cell's span, and the halo before and after it, (first, stop)
        for cells, size in zip((cell_r, cell_c), shape, strict=True):
            first, stop = cells * core, np.minimum((cells + 1) * core, size)
            spans.append({-1: (first - halo, first), 0: (first, stop),
                          1: (stop, np.minimum(stop + halo, size))})
        index = np.arange(len(cell_r))
        self.cells = np.column_stack([index, *spans[0][0], *spans[1][0], 0 * index]).astype(np.intp)
        self.widened = (np.maximum(spans[0][-1][0], 0), spans[0][1][1],
                        np.maximum(spans[1][-1][0], 0), spans[1][1][1])
        solved = np.pad(grid, 1, constant_values=True)  # beyond the image: no piece
        pieces = []
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                if dr or dc:
                    keep = ~solved[cell_r + 1 + dr, cell_c + 1 + dc]
                    pieces.append(np.column_stack([index[keep], spans[0][dr][0][keep], spans[0][dr][1][keep],
                                                   spans[1][dc][0][keep], spans[1][dc][1][keep],
                                                   0 * index[keep]]))
        self.halo_pieces = np.concatenate(pieces).astype(np.intp)
        self.rects = np.ascontiguousarray(np.concatenate([self.cells, self.halo_pieces])[:, 1:5])


def _waves(size):
    """The eigenvalues of -Laplace (5-point, Neumann) in the DCT-II basis along an axis of ``size``."""
    return (4.0 * np.sin(np.pi * np.arange(size) / (2.0 * size)) ** 2).astype(np.float32)


def _copy_outside(source, target, region, box=None):
    """Copy ``source`` into ``target`` over ``region`` (two slices) except ``box`` (None: all of
    it): the rows of the region above and below the box, then its columns left and right of it.
    A region of boxes (R, 4), or of pixels (flat indices), is copied whole, ``box`` included."""
    if _is_rects(region):
        _kernels.copy_boxes(source, target, region)
        return
    if _is_pixels(region):
        target.reshape(-1)[region] = source.reshape(-1)[region]
        return
    rows, cols = region
    if box is None:
        target[rows, cols] = source[rows, cols]
        return
    top, bottom = max(box[0].start, rows.start), min(box[0].stop, rows.stop)
    left, right = max(box[1].start, cols.start), min(box[1].stop, cols.stop)
    if top >= bottom or left >= right:  # the box misses the region
        target[rows, cols] = source[rows, cols]
        return
    middle = slice(top, bottom)
    for strip in ((slice(rows.start, top), cols), (slice(bottom, rows.stop), cols),
                  (middle, slice(cols.start, left)), (middle, slice(right, cols.stop))):
        target[strip] = source[strip]


def _area(box):
    """The number of pixels of a box (two slices)."""
    return (box[0].stop - box[0].start) * (box[1].stop - box[1].start)


def _bounds(where, shape):
    """The bounding box (two slices) of ``where``: flat indices of pixels, a box or boxes (R, 4) as
    :meth:`_Problem.step` returns them; None for None."""
    if where is None or isinstance(where, tuple):
        return where
    if where.ndim == 2:
        return (slice(int(where[:, 0].min()), int(where[:, 1].max())),
                slice(int(where[:, 2].min()), int(where[:, 3].max())))
    if where.size == 0:
        return None
    n = shape[1]
    cols = where % n
    rows = slice(int(where.min()) // n, int(where.max()) // n + 1)
    return rows, slice(int(cols.min()), int(cols.max()) + 1)


def _is_rects(where):
    """Whether ``where`` (as :func:`_bounds` takes it) is boxes (R, 4)."""
    return isinstance(where, np.ndarray) and where.ndim == 2


def _is_pixels(where):
    """Whether ``where`` (as :func:`_bounds` takes it) is pixels (flat indices)."""
    return isinstance(where, np.ndarray) and where.ndim == 1


def _grown_rects(rects, shape, by):
    """Boxes (R, 4) (first row, stop row, first column, stop column) widened by ``by`` pixels on
    every side, cut to the image."""
    m, n = shape
    return np.column_stack([np.maximum(rects[:, 0] - by, 0), np.minimum(rects[:, 1] + by, m),
                            np.maximum(rects[:, 2] - by, 0), np.minimum(rects[:, 3] + by, n)]).astype(np.intp)


def _union(box, other):
    """The bounding box of two boxes (two slices each)."""
    return tuple(slice(min(a.start, b.start), max(a.stop, b.stop)) for a, b in zip(box, other, strict=True))


def _grown(box, shape):
    """``box`` widened by one pixel on every side, cut to the image."""
    return tuple(slice(max(span.start - 1, 0), min(span.stop + 1, size))
                 for span, size in zip(box, shape, strict=True))


def _fast_span(start, stop, size):
    """``start:stop`` cut to ``0:size`` and widened to a length the DCT is fast on (or the axis)."""
    start, stop = max(start, 0), min(stop, size)
    length = scipy.fft.next_fast_len(stop - start, real=True)
    if length >= size:
        return slice(0, size)
    start = min(start, size - length)
    return slice(start, start + length)


def _swept_area(old, new, mark=None):
    """Area between the zero sets of two redistanced states, ``sum_px |H_eps(new) - H_eps(old)|``.

    With eps = 1 the integer translates of H_eps sum to the exact length of a half-line (module
    docstring), so this is the exact area between two parallel straight fronts at any sub-pixel
    offset, and second-order accurate for curved ones.  Only pixels in either band can differ:
    each is counted once (compiled: :func:`activecontour._kernels.swept_area`; ``mark``: M N
    zeros, uint8, returned cleared).
    """
    if old.near_flat.size == 0 or new.near_flat.size == 0:
        return float(np.count_nonzero(old.positive != new.positive))
    mark = np.zeros(old.phi.size, dtype=np.uint8) if mark is None else mark
    return _kernels.swept_area(old.phi.reshape(-1), new.phi.reshape(-1), old.near_flat, new.near_flat, mark)
