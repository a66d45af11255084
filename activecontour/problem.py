"""The preparation: an image and its settings turned into the problem a backend solves.

``prepare(image, settings)`` is the one copy of the steps between the call and the backend, read by
:func:`activecontour.segment`, the evaluator (:func:`activecontour.chan_vese_energy`), sequences'
warm starts and ``n_regions="auto"`` (and the viewer's automatic mu):

1. the image as one image (a path is read; a stack refused), normalised to the values (6.38)
   reads (:func:`activecontour.imaging.normalize.normalize_image`), with the affine map back to
   the input's intensities;
2. the working frame: those values mapped to span [0, 1] while the backends compute
   (:func:`activecontour.imaging.frame.working_frame`: no cancellation, no overflow);
3. the noise level and the default length weight it implies (``mu="auto"``,
   :func:`activecontour.imaging.noise.auto_mu`), and the number of regions (``n_regions="auto"``,
   :func:`activecontour.models.modes.choose_regions`);
4. the parameters of (6.38), in the caller's units and in the working frame
   (:meth:`~activecontour.models.ChanVeseParameters.in_frame`), and the model of the noise
   (:func:`activecontour.models.noise_model`).

Each step is computed when first asked for, once.  A region of interest is a problem of its own,
on the crop (:meth:`Problem.restricted`).
"""

from __future__ import annotations

import dataclasses
import functools
import os

import numpy as np

from activecontour.imaging.frame import to_frame, working_frame
from activecontour.imaging.noise import auto_mu, is_auto
from activecontour.imaging.normalize import intensity_scale, normalize_image, single_image
from activecontour.imaging.roi import restrict_values
from activecontour.io.images import load_image
from activecontour.models import ChanVeseParameters, noise_model
from activecontour.models.modes import choose_regions
from activecontour.settings import Settings

__all__ = ["Problem", "prepare"]


def prepare(image, settings=None):
    """The problem of segmenting ``image`` with ``settings``.

    Parameters
    ----------
    image : ndarray (M, N) or (M, N, C), or a path
        As :func:`activecontour.segment` takes it (read by :func:`activecontour.io.images.load_image`,
        checked as one image by :func:`activecontour.imaging.normalize.single_image`).
    settings : Settings, optional
        None: the defaults.

    Returns
    -------
    Problem
    """
    settings = Settings() if settings is None else settings
    if isinstance(image, (str, os.PathLike)):
        image = load_image(image)
    image = single_image(image, settings.channel_axis)
    values = normalize_image(image, color=settings.color, normalize=settings.normalize)
    return Problem(settings, image, values, intensity_scale(image, settings.normalize))


@dataclasses.dataclass(frozen=True, eq=False)
class Problem:
    """(6.38) on one image with its settings, ready for a backend.

    Attributes
    ----------
    settings : Settings
    image : ndarray (M, N) or (M, N, C)
        The input as one image, channel-last (the whole image, also for a restricted problem:
        results are reported in its frame).
    normalised : ndarray (M', N', C)
        The values (6.38) reads, in the normalised units results report (``result.c_in``, ``mu``):
        of the whole image, or of the crop of a region of interest (in the whole image's units).
    units : tuple (offset, scale)
        An input intensity is ``offset + scale * normalised``.
    box : tuple (r0, c0, r1, c1) or None
        The crop of a region of interest (:meth:`restricted`), None for the whole image.
    domain : bool ndarray (r1 - r0, c1 - c0) or None
        The region of interest within the box, None for all of it.
    """

    settings: Settings
    image: np.ndarray
    normalised: np.ndarray
    units: tuple
    box: tuple | None = None
    domain: np.ndarray | None = None

    @property
    def shape(self):
        """(M', N'): the shape the backend works on."""
        return self.normalised.shape[:2]

    @functools.cached_property
    def frame(self):
        """``(offset, scale)`` of the working frame: ``normalised = offset + scale * values``."""
        return working_frame(self.normalised)

    @functools.cached_property
    def values(self):
        """The normalised values in the working frame, spanning [0, 1] (M', N', C)."""
        return to_frame(self.normalised, *self.frame)

    @functools.cached_property
    def auto_mu(self):
        """The default length weight in the working frame, from the noise of :attr:`values`
        (:func:`activecontour.imaging.noise.auto_mu`): ``MU_PER_NOISE_VARIANCE`` sigma^2; on a
        region of interest, of the pixels of its domain (the fill outside it has no noise)."""
        return auto_mu(self.values, self.domain)

    @functools.cached_property
    def mu(self):
        """The length weight, in normalised units: ``settings.mu``, or for ``"auto"``
        :attr:`auto_mu` carried out of the working frame (``result.mu``)."""
        return self.auto_mu * self.frame[1]**2 if is_auto(self.settings.mu) else self.settings.mu

    @functools.cached_property
    def params(self):
        """The parameters of (6.38) in normalised units."""
        settings = self.settings
        return ChanVeseParameters(self.mu, settings.omega, settings.lambda_in, settings.lambda_out,
                                  settings.c_in, settings.c_out)

    @functools.cached_property
    def working(self):
        """The parameters in the working frame (:meth:`ChanVeseParameters.in_frame`, range-checked):
        :attr:`params` itself when the frame is the identity."""
        return self.params.in_frame(*self.frame)

    @property
    def framed(self):
        """Whether the working frame differs from the normalised units (energies and constants
        are carried back)."""
        return self.working is not self.params

    @functools.cached_property
    def n_regions(self):
        """The number of regions K: ``settings.n_regions``, or for ``"auto"`` the significant
        modes of the intensities at the noise level the length weight assumes
        (:func:`activecontour.models.modes.choose_regions`)."""
        if not is_auto(self.settings.n_regions):
            return int(self.settings.n_regions)
        mu = None if is_auto(self.settings.mu) else self.settings.mu / self.frame[1]**2
        return choose_regions(self.values, self.auto_mu, mu)

    @property
    def noise_model(self):
        """``(build, fit_light)`` of the noise model (:func:`activecontour.models.noise_model`)."""
        return noise_model(self.settings.noise)

    def model(self, light=None):
        """The image model and parameters in the working frame: ``build(values, light, working)``
        of the noise model (light None: uniform, built once)."""
        return self._uniform if light is None else self.noise_model[0](self.values, light, self.working)

    @functools.cached_property
    def _uniform(self):
        return self.noise_model[0](self.values, None, self.working)

    def reweighted(self, **changes):
        """This problem under other parameters of (6.38) or noise model (``changes``: fields of
        :class:`~activecontour.settings.Settings` that leave the values alone, e.g. ``mu``, ``c_in``,
        ``noise``): the values, their working frame and the noise level are shared, not computed
        again (a sequence's warm start scores its starts on the frame it then segments)."""
        if changes.keys() & {"color", "normalize", "channel_axis"}:
            raise ValueError(f"reweighted keeps the values: {sorted(changes)} would change them")
        other = dataclasses.replace(self, settings=dataclasses.replace(self.settings, **changes))
        for name in ("frame", "values", "auto_mu"):
            if name in self.__dict__:
                other.__dict__[name] = self.__dict__[name]
        return other

    def restricted(self, box, domain):
        """The whole image's problem on the crop ``box`` of a region of interest, the pixels outside
        ``domain`` filled (:func:`activecontour.imaging.roi.restrict_values`): the domain D of (6.38)
        restricted, the rest of the functional as it is.  The crop keeps the whole image's
        normalised units and working frame, so a result on it reports ``mu``, ``c_in``, ``c_out``
        and energies in the units of a run on the whole image (continuing with ``mu=result.mu``
        on the image means the same weight), a given ``mu`` means the same on both, and the
        default mu's floor (:data:`~activecontour.imaging.noise.MU_FLOOR`) is the whole image's
        (its noise is still read on the domain's pixels, :attr:`auto_mu`).

        Parameters
        ----------
        box : tuple (r0, c0, r1, c1)
        domain : bool ndarray or None
            As :func:`activecontour.imaging.roi.resolve_roi` returns them.
        """
        part = Problem(self.settings, self.image, restrict_values(self.normalised, box, domain), self.units,
                       box, domain)
        part.__dict__["frame"] = self.frame  # the whole image's (the crop's values lie within its span)
        return part
