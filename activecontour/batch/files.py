"""Image files of folders and glob patterns: what a batch takes as its inputs."""

from __future__ import annotations

import glob
import os

from activecontour.io.images import IMAGE_SUFFIXES

__all__ = ["INPUT_SUFFIXES", "find_images"]

#: File name suffixes taken as images when a folder is listed (compared in lower case): the ones
#: :func:`activecontour.io.load_image` reads.
INPUT_SUFFIXES = IMAGE_SUFFIXES


_GLOB_CHARACTERS = frozenset("*?[")


def find_images(*sources, left_out=None):
    """The image files named by paths, folders and glob patterns, in order, each once.

    Parameters
    ----------
    *sources : str or os.PathLike
        A file is taken as it is.  A folder gives the files in it (not in its sub-folders) whose
        suffix is one of :data:`INPUT_SUFFIXES`, sorted by name.  A pattern with ``*``, ``?`` or
        ``[`` that is not an existing file is expanded by :func:`glob.glob` (``**`` spans folders),
        sorted, files only.  From folders and patterns, the image outputs of ``activecontour
        segment`` next to an image ``<name>.*`` (``<name>_mask.png``, ``<name>_overlay.png`` and
        the object images ``<name>_labels.png``, ``<name>_labels.tif``, ``<name>_classes.png``)
        are left out, so that a second run over the same folder, with any ``--objects``, does not
        take them for inputs.  A file named on its own is always taken.
    left_out : list, optional
        If given, the paths left out as outputs are appended to it (so that a caller can say so).

    Returns
    -------
    list of str

    Raises
    ------
    FileNotFoundError
        For a path that does not exist and is not a pattern.
    ValueError
        For a folder without images or a pattern that matches no file.
    """
    files = []
    for source in sources:
        text = os.fspath(source)
        if os.path.isdir(text):
            found = [os.path.join(text, name) for name in sorted(os.listdir(text))
                     if name.lower().endswith(INPUT_SUFFIXES) and os.path.isfile(os.path.join(text, name))]
            found = _without_outputs(found, left_out)
            if not found:
                raise ValueError(f"no image files ({', '.join(INPUT_SUFFIXES)}) in the folder {text!r}")
        elif os.path.exists(text) or not _GLOB_CHARACTERS.intersection(text):
            if not os.path.exists(text):
                raise FileNotFoundError(f"image file not found: {text!r}")
            found = [text]
        else:
            found = _without_outputs(sorted(p for p in glob.glob(text, recursive=True) if os.path.isfile(p)),
                                     left_out)
            if not found:
                raise ValueError(f"no file matches the pattern {text!r}")
        files.extend(found)
    return list(dict.fromkeys(files))


def _without_outputs(paths, left_out=None):
    """Leave out the image files :func:`activecontour.io.save_result` writes (every output whose
    suffix is an input's: mask, overlay, object images) that sit next to an image ``<name>.*``
    (appended to ``left_out`` when it is a list)."""
    from activecontour.io import OBJECT_FORMATS, output_paths

    endings = [os.fspath(path) for path in output_paths("", (), tuple(OBJECT_FORMATS))
               if os.fspath(path).lower().endswith(INPUT_SUFFIXES)]
    stems = {os.path.splitext(p)[0] for p in paths}
    kept = []
    for path in paths:
        if any(path.endswith(e) and path[: -len(e)] in stems for e in endings):
            if left_out is not None:
                left_out.append(path)
        else:
            kept.append(path)
    return kept

