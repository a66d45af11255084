"""Fixtures shared by several test modules."""

import os

import pytest


@pytest.fixture
def no_space_for_contours(monkeypatch):
    """Make moving a ``*_contours.json`` file into place fail as on a full disk."""
    real_replace = os.replace

    def failing_replace(src, dst):
        if str(dst).endswith("_contours.json"):
            raise OSError(28, "No space left on device", str(dst))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", failing_replace)


@pytest.fixture
def restore_environ():
    """Put os.environ back afterwards: a LocalCluster's nannies set OMP_NUM_THREADS,
    MALLOC_TRIM_THRESHOLD_, ... in this process for the workers they start."""
    saved = dict(os.environ)
    yield
    os.environ.clear()
    os.environ.update(saved)
