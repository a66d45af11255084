"""Where ``activecontour segment`` writes: the output stems planned before any work, and the output
directories made when the first files go into them (and removed again if nothing was written)."""

from __future__ import annotations

import os
from pathlib import Path

from ..messages import shown
from .errors import UsageError

__all__ = ["Directories", "check_can_create", "plan_outputs", "sweep_temporaries"]


def plan_outputs(images, output, formats, objects=(), stacks=()):
    """[(image path, output stem)], after checking no output overwrites an input or another one.

    The stems come from :func:`activecontour.io.output_stem`: inside the output directory,
    whatever the images are called; the files of a stem from :func:`activecontour.io.output_paths`,
    or for the inputs in ``stacks`` (segmented as sequences) from
    :func:`activecontour.io.sequence_paths`: two stacks with one stem (``disk.mp4``, ``disk.avi``)
    are refused as two images are.
    """
    from activecontour.io import output_paths, output_stem, sequence_paths

    if output is not None and os.path.exists(output) and not os.path.isdir(output):
        raise UsageError(f"output path {os.fspath(output)!r} exists and is not a directory")
    plans, owners = [], {}
    inputs = {}
    for image_path in images:
        inputs.setdefault(os.path.realpath(image_path), image_path)
    for image_path in inputs.values():  # the same file named twice is segmented once
        directory = output_directory(output, image_path)
        if directory.is_dir() and not os.access(directory, os.W_OK | os.X_OK):
            raise UsageError(f"the output directory {os.fspath(directory)!r} is not writable")
        stem = output_stem(directory, image_path)
        written = sequence_paths(stem) if image_path in stacks else output_paths(stem, formats, objects)
        for path in written:
            key = os.path.realpath(path)
            if key in inputs:
                raise UsageError(
                    f"the output {os.fspath(path)!r} of {image_path!r} would overwrite the input "
                    f"{inputs[key]!r}; choose another --output directory"
                )
            if key in owners and owners[key] != image_path:
                raise UsageError(
                    f"{owners[key]!r} and {image_path!r} would both write {os.fspath(path)!r}; "
                    "rename one or segment them into different --output directories"
                )
            owners[key] = image_path
        plans.append((image_path, stem))
    return plans


def output_directory(output, source):
    """``--output``, or by default the directory of the input ``source``."""
    return Path(output) if output is not None else Path(source).parent


def sweep_temporaries(stems):
    """Remove the temporaries that a run killed mid-write left in the output directories."""
    from activecontour.io import sweep_temporaries as sweep

    for directory in dict.fromkeys(Path(stem).parent for stem in stems):
        sweep(directory)


def check_can_create(output):
    """Before any work: the output directory exists, or its nearest existing parent is a writable
    directory (it is created when the first image's files are written)."""
    if output is None or os.path.isdir(output):
        return
    parent = Path(os.path.abspath(output))
    while not os.path.lexists(parent):
        parent = parent.parent
    if not os.path.isdir(parent):
        raise UsageError(f"cannot create the output directory {os.fspath(output)!r}: "
                         f"{os.fspath(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"cannot create the output directory {os.fspath(output)!r}: "
                         f"{os.fspath(parent)!r} is not writable")


class Directories:
    """The output directories a run makes, so that a run which ends up writing nothing leaves none
    behind.  Picklable: the workers of ``--jobs`` make their images' directories the same way."""

    def __init__(self):
        #: (leaf, topmost) of every output directory this run created
        self.created = []

    def make(self, directory):
        """Create the output directory when the first files go into it, and note the topmost
        directory made."""
        if os.path.isdir(directory):
            return
        leaf = Path(os.path.abspath(directory))
        missing = [leaf]
        while not missing[-1].parent.exists():
            missing.append(missing[-1].parent)
        topmost = None  # the first directory this run made (another run may make some at once)
        for path in reversed(missing):
            try:
                os.mkdir(path)
            except FileExistsError:
                if not os.path.isdir(path):
                    raise UsageError(f"cannot create the output directory {os.fspath(directory)!r}: "
                                     f"{shown(path)!r} is not a directory") from None
            except OSError as exc:
                raise UsageError(f"cannot create the output directory {os.fspath(directory)!r}: "
                                 f"{exc.strerror or exc}") from None
            else:
                topmost = path if topmost is None else topmost
        if topmost is not None:
            self.created.append((leaf, topmost))

    def remove_empty(self):
        """Remove the directories this run created, from the leaf up, if nothing was written in them."""
        for leaf, topmost in self.created:
            for directory in [leaf, *leaf.parents]:
                try:
                    os.rmdir(directory)  # only succeeds on an empty directory
                except OSError:
                    break
                if directory == topmost:
                    break
