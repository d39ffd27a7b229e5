"""ISO 230-3 thermal effects on the tool-to-workpiece displacement.

* Scale expansion (ISO 230-3, thermal distortion caused by moving linear axes: the change of the
  positioning error with temperature): an axis' scale or
  ball screw at temperature T is longer by α·(T − 20 °C) per metre (ISO 1: 20 °C is the reference
  temperature of dimensional metrology), measured from the point where it is fixed — here the
  axis zero, where the linear scale is clamped / the screw's fixed bearing sits. The read head
  counts graduations that the warm scale has spread apart, so the slide travels further than
  commanded: d = +α·q·(T − 20) (a steel scale/screw on a warming bed, α ≈ 11.5e-6 /K). A
  controller with thermal compensation set too high gives the opposite sign (α_net < 0).
* Structural growth (ISO 230-3, the environmental temperature variation error (ETVE): drift of the
  tool relative to the table measured at a fixed position): the column's height between the
  table's datum and the spindle grows with the column's mean temperature, which lags the
  sensor on its surface by a first-order time constant. d = n̂·g·(T_f − 20 °C).
"""

import numpy as np

from .geometric_errors import AXES
from .temperatures import first_order_lag


class ScaleExpansion:
    kind = "thermal_scale"

    def __init__(self, axis, alpha_per_k, sensor):
        self.axis, self.k = axis, AXES.index(axis)
        self.alpha, self.sensor = alpha_per_k, sensor

    def displacement(self, ctx):
        d = np.zeros_like(ctx.q)
        d[:, self.k] = self.alpha * ctx.q[:, self.k] * (ctx.true_temperature(self.sensor) - 20.0)
        return d

    def truth(self):
        return {"iso": "ISO 230-3 thermally induced positioning error: d = alpha*q*(T - 20 C)", "axis": self.axis,
                "alpha_per_k": self.alpha, "sensor": self.sensor, "fixed_point_m": 0.0}


class StructureGrowth:
    kind = "thermal_growth"

    def __init__(self, sensor, direction, coefficient_m_per_k, time_constant_s):
        self.sensor = sensor
        self.direction = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
        self.g, self.tau = coefficient_m_per_k, time_constant_s

    def displacement(self, ctx):
        lagged = first_order_lag(ctx.histories[self.sensor], ctx.t, self.tau) if self.tau > 0 else ctx.true_temperature(self.sensor)
        return np.outer(self.g * (lagged - 20.0), self.direction)

    def truth(self):
        return {"iso": "ISO 230-3 drift of the tool relative to the table with the structure's temperature",
                "sensor": self.sensor, "direction": self.direction.tolist(), "coefficient_m_per_k": self.g,
                "time_constant_s": self.tau}
