"""Helpers shared by the tests: numerical ones, and how a child process meets Ctrl-C."""

import numpy as np


def central_differences(function, points, step=1e-5):
    """Central finite differences of a scalar function of a (K, 2) array, vertex by vertex."""
    numeric = np.zeros_like(points)
    for i in range(len(points)):
        for d in range(2):
            plus, minus = points.copy(), points.copy()
            plus[i, d] += step
            minus[i, d] -= step
            numeric[i, d] = (function(plus) - function(minus)) / (2 * step)
    return numeric


def sigint_as_in_a_terminal():
    """``preexec_fn`` for a child that a test interrupts with Ctrl-C: SIGINT to its default action,
    as in a terminal. A process started in the background (``cmd &`` in a script, as
    benchmarks/promises.py was) inherits SIGINT ignored; Python then installs no KeyboardInterrupt
    handler, and a SIGINT sent before the library's own handler is up was lost (the child ran on
    until the test's timeout)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
