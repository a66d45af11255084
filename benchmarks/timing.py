"""Timing for the benchmarks: process CPU time (the machine may be shared), the least of repeats."""

from __future__ import annotations

import time


def least_cpu(function, *args, repeats=1, **kwargs):
    """``(value, seconds)``: ``function(*args, **kwargs)`` and the least process CPU time of
    ``repeats`` calls (the value of the last)."""
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        value = function(*args, **kwargs)
        best = min(best, time.process_time() - start)
    return value, best
