"""A bond's load ratio under held plus growing loads, for a criterion linear in the state
(shared by the criteria and the screen of :mod:`.screen`)."""

from __future__ import annotations

import numpy as np

__all__ = ["linear_factors"]


def linear_factors(vh, vg, threshold):
    """``(ratio, excess)`` of a criterion linear in the state: ``vh + lambda vg`` reaches
    ``threshold`` at ``lambda = 1 / ratio`` (ratio 0: never); ``excess`` >= 1 where the
    held part alone reaches it (``vh / threshold``), else 0. Without a held part the
    ratio is ``vg / threshold`` exactly."""
    room = threshold - vh
    ok = room > 0
    ratio = np.zeros(len(vg))
    np.divide(vg, room, out=ratio, where=ok)
    ratio[~(ratio > 0)] = 0.0
    excess = np.zeros(len(vg))
    np.divide(vh, threshold, out=excess, where=~ok & (threshold > 0))
    excess[excess < 1.0] = 0.0
    excess[~ok & ~(threshold > 0)] = np.inf  # no strength left: fails at once
    return ratio, excess
