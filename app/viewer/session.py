"""The viewer's runs since the init was set or reset: the result, the iterations and the energies.

A run that is paused and resumed, or taken one step at a time, continues one *session*: its
iterations count against ``max_num_iter`` together, and its energies make one history.  A run
that converged, or one after a reset or a new init, starts a new session.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STATUS_WORDS", "Session"]

STATUS_WORDS = {0: "converged", 1: "max_num_iter reached", 2: "paused", 3: "collapsed", 4: "stationary",
                5: "stalled"}


class Session:
    """The runs since the init was set or reset.

    Attributes
    ----------
    result : SegmentationResult or None
        The last run's result.
    contours : list of ndarray (K, 2)
        Its contours (empty before the first run).
    iteration : int
        Iterations since the init was set or reset (during a run: up to the latest one).
    """

    def __init__(self):
        self.clear()

    def clear(self):
        """Back to the init: no result, no contours, no history."""
        self.result = None
        self.contours = []
        self.iteration = 0
        self._history, self._live = [], []  # (iteration, energy) of finished runs; of the one going
        self._open, self._used = True, 0  # whether a run continues the session; its iterations
        self._offset = 0  # the iteration the run in progress started from

    def iterations_for(self, max_num_iter, *, step=False):
        """Iterations the next run may take: what is left of ``max_num_iter`` in the session, or
        for a new session all of it (a step: one)."""
        left = max_num_iter - self._used
        if not self._open or left <= 0:
            self._open, self._used, left = True, 0, max_num_iter
        return 1 if step else left

    def begin(self):
        """A run starts from the current iteration."""
        self._offset = self.iteration
        self._live = []

    def record(self, state):
        """A state of the run in progress (the library's callback)."""
        self.iteration = self._offset + state.iteration
        self._live.append((self.iteration, float(state.energy)))

    def end(self):
        self._live = []

    def accept(self, result, max_num_iter):
        """The run's result: its contours, iterations and energies join the session's."""
        self.result = result
        self.contours = [np.array(c, dtype=np.float64) for c in result.contours]
        self.iteration = self._offset + result.n_iter
        self._used += result.n_iter
        energies = np.asarray(result.energies, dtype=np.float64)
        points = list(zip(range(self._offset, self._offset + len(energies)), energies, strict=True))
        self._history += points[1:] if self._history else points
        self._live = []
        paused = result.status == 2 or (result.status == 1 and self._used < max_num_iter)
        self._open = paused and bool(self.contours)  # after a collapse: the init again

    @property
    def energy_history(self):
        """(iteration, energy) of the session, the run in progress included: (n, 2)."""
        return np.array(self._history + self._live, dtype=np.float64).reshape(-1, 2)

    def describe(self, result):
        """The status line after a run."""
        word = STATUS_WORDS.get(result.status, result.message)
        if result.status == 2:
            return f"paused at iteration {self.iteration}: space resumes, n steps, s saves"
        if result.status == 1 and self._open:
            return f"iteration {self.iteration}: n steps, space runs on"
        if result.status == 3:
            return (f"{word} after {self.iteration} iterations: try less smoothness or another init "
                    "(r resets)")
        count = 0 if result.objects is None else len(result.objects["label"])
        if not count:
            return f"{word} after {self.iteration} iterations"
        return (f"{word} after {self.iteration} iterations: {count} object{'s' * (count != 1)}, click one "
                "for its measurements")
