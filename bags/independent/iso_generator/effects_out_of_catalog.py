"""Structures no catalog term is meant to explain (the suite's out-of-catalog cases).

* A drift cycling in time with no logged cause: the spindle's chiller switching on and off
  with its hysteresis (period 30–60 min) moves the tool along Z; no sensor on the export
  follows the coolant.
* A local bump in the workspace: a dent/wear patch of a guideway or a clamp's local
  deformation — a Gaussian displacement around one place, nothing outside it.
"""

import numpy as np


class CyclingDrift:
    kind = "cycling_drift"

    def __init__(self, amplitude_m, period_s, phase_rad, direction=(0.0, 0.0, 1.0)):
        self.amplitude, self.period, self.phase = amplitude_m, period_s, phase_rad
        self.direction = np.asarray(direction, dtype=float)

    def displacement(self, ctx):
        return np.outer(self.amplitude * np.sin(2 * np.pi * ctx.t / self.period + self.phase), self.direction)

    def truth(self):
        return {"structure": "drift cycling in time (chiller hysteresis), no sensor follows it",
                "amplitude_m": self.amplitude, "period_s": self.period, "direction": self.direction.tolist()}


class LocalBump:
    kind = "local_bump"

    def __init__(self, centre_m, width_m, amplitude_m, direction):
        self.centre, self.width, self.amplitude = np.asarray(centre_m, float), width_m, amplitude_m
        self.direction = np.asarray(direction, dtype=float)

    def displacement(self, ctx):
        r2 = np.sum((ctx.q - self.centre) ** 2, axis=1)
        return np.outer(self.amplitude * np.exp(-0.5 * r2 / self.width ** 2), self.direction)

    def truth(self):
        return {"structure": "local Gaussian bump in the workspace", "centre_axes_m": self.centre.tolist(),
                "width_m": self.width, "amplitude_m": self.amplitude, "direction": self.direction.tolist()}
