"""An XFYZ machine tool with a laser tracker standing on its table: what the tracker reports.

XFYZ: the table carries the workpiece along X; the column carries Y and the ram Z with the tool.
The tracker stands on the table, so it sees the tool-side target relative to the workpiece —
exactly the relative position ISO 230-1 defines the errors of. Commanded axis positions q are
the tool point relative to the workpiece minus the tool (SMR) offset.

For each reading: the true target position in the table frame is
    p = q(t − L) + tool_offset + Σ_effects d(q, approach, t, temperatures)
(L the latency of the tracker's time stamps behind the true instant, so a reading stamped t on
the fly saw the tool where the controller had it L earlier), and the tracker reports it in its
own frame with its own range errors and noise. Reference nests are fixed on the table.
"""

import numpy as np

from .temperatures import log


class ReadingContext:
    """What an effect may read about each reading: commanded axes at the true instant, approach
    directions, time, velocity, the true temperature histories, and the target's offset from
    the spindle's gauge point (the Abbe arm's tool part; one (3,) for all readings or (N, 3))."""

    def __init__(self, q, approach, t, v, histories, tool_offset=None):
        self.q, self.approach, self.t, self.v, self.histories = q, approach, t, v, histories
        self.tool_offset = np.zeros(3) if tool_offset is None else np.asarray(tool_offset, dtype=float)

    def true_temperature(self, sensor):
        return self.histories[sensor](self.t)


class XFYZCell:
    def __init__(self, travel, tool_offset, tracker, histories, sensor_noise_k, effects=(), latency_s=0.0):
        self.travel = [tuple(t) for t in travel]
        self.tool_offset = np.asarray(tool_offset, dtype=float)
        self.tracker = tracker
        self.histories = histories            # name -> History (true temperature at that place)
        self.sensor_noise = sensor_noise_k    # name -> σ of the logger [K]
        self.effects = list(effects)
        self.latency = latency_s

    def simulate(self, readings, rng, noiseless=False):
        t, q, v = readings["t"], readings["q"], readings["v"]
        is_nest = readings["is_nest"]
        q_instant = q - self.latency * v                   # where the axes were when the tracker read
        # the target on the spindle: the cell's one, or each reading's (readings["tool_offset"])
        tool = np.broadcast_to(readings.get("tool_offset", self.tool_offset), q.shape)
        p = q_instant + tool
        machine = ~is_nest
        ctx = ReadingContext(q_instant[machine], readings["approach"][machine], t[machine], v[machine], self.histories,
                             tool[machine])
        d = np.zeros((machine.sum(), 3))
        for effect in self.effects:
            d += effect.displacement(ctx)
        p[machine] += d
        for i in np.where(is_nest)[0]:
            p[i] = readings["nest"][i]
        nominal = q + tool
        for i in np.where(is_nest)[0]:
            nominal[i] = readings["nest"][i]
        measured, u95, rho = self.tracker.measure(p, t, rng, noiseless)
        if noiseless:
            return {"measured": measured, "is_nest": is_nest, "range": rho}
        temperatures = {name: log(h(t), rng, self.sensor_noise[name]) for name, h in self.histories.items()
                        if name in self.sensor_noise}
        effect_table = np.zeros_like(p)
        effect_table[machine] = d
        return {"nominal": nominal, "measured": measured, "u95": u95, "range": rho, "temperatures": temperatures,
                "machine_effect": effect_table, "is_nest": is_nest, "true_point": p}

    def without_errors(self):
        """The same cell and tracker with nothing concealed."""
        return XFYZCell(self.travel, self.tool_offset, self.tracker.without_errors(), self.histories, self.sensor_noise)
