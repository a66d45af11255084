"""Sequences: every frame started from the previous one's result, objects tracked.

results   segment_sequence, iter_sequence and their result types
warm      the start of frame t from frame t-1
tracking  object identities from frame to frame
(the readers of stacks and videos are in :mod:`activecontour.io.stacks`)
"""

from activecontour.sequence.results import SequenceFrame, SequenceResult, iter_sequence, segment_sequence

__all__ = ["SequenceFrame", "SequenceResult", "iter_sequence", "segment_sequence"]
