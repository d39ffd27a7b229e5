"""ISO 230-2 reversal error, signed, and the approach directions it depends on.

ISO 230-2 (2014) 3.3.x: the positional deviation x_ij = P_ij − P_i (actual minus target
position); the reversal value at a target is B_i = x̄_i↑ − x̄_i↓, the mean deviation reached
moving in the positive direction minus the mean reached moving in the negative direction.

* Plain lost motion (slack in the screw/nut, windup): the axis stops short of the target in the
  direction it moved, so x̄↑ < 0 < x̄↓ and B < 0.
* A controller whose backlash compensation is set larger than the real slack overshoots after
  each reversal: x̄↑ > 0 > x̄↓ and B > 0.

The deviation is split evenly between the two approaches: d_axis = (B/2)·s, s = ±1 the sign of
the axis' last motion before the reading.
"""

import numpy as np

from .geometric_errors import AXES


class ReversalError:
    kind = "backlash"

    def __init__(self, axis, reversal_value_m):
        self.axis, self.k = axis, AXES.index(axis)
        self.B = reversal_value_m

    def displacement(self, ctx):
        d = np.zeros_like(ctx.q)
        d[:, self.k] = 0.5 * self.B * ctx.approach[:, self.k]
        return d

    def truth(self):
        return {"iso": "ISO 230-2 reversal value B = mean(dev, + approach) - mean(dev, - approach)",
                "axis": self.axis, "B_m": self.B,
                "meaning": "lost motion" if self.B < 0 else "over-compensated controller backlash"}


def approach_directions(path_q, reading_index):
    """Approach direction of each axis at each reading: the sign of that axis' last non-zero
    motion along the commanded path before the reading (+1 before any motion).

    path_q: (M, 3) every commanded position the machine went through, in order (targets,
    overruns, parking); reading_index: for each reading, the index in path_q of the position it
    was taken at."""
    last = np.ones(3)
    signs = np.ones_like(path_q)
    for m in range(len(path_q)):
        if m > 0:
            step = path_q[m] - path_q[m - 1]
            last = np.where(np.abs(step) > 1e-9, np.sign(step), last)
        signs[m] = last
    return signs[np.asarray(reading_index)]
